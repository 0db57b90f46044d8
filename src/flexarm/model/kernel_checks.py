"""Checks of the arguments of compiled kernels called from Python.

A compiled kernel reads and writes its arrays without bounds checks: given an
output shorter than ``n_dof`` it writes past its end and corrupts the heap.
Every public kernel (:mod:`flexarm.model.dynamics`,
:mod:`flexarm.sim.integrator`, :mod:`flexarm.fuzzy.compiled`) is therefore a
Python function that checks its arguments with these functions and then calls
the private compiled kernel; inside compiled code (a user's own Numba loop, the
simulator's) the same name is the kernel itself, unchecked, through a Numba
overload. NumPy only.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array
from ..errors import InvalidTypeError, InvalidValueError
from .arrays import ArmArrays, Workspace, field_shapes, workspace_shapes

__all__ = [
    "check_model",
    "check_state",
    "check_vector",
    "check_workspace",
    "checked_coordinates",
    "checked_state",
    "shape_message",
    "state_shapes",
]

_OWNER = "FlexibleArm"


def _array(value: object, name: str, owner: str, dtype: type, writable: bool) -> np.ndarray:
    if not isinstance(value, np.ndarray):
        raise InvalidTypeError(
            f"The '{name}' parameter of {owner} must be a NumPy array. "
            f"Got {type(value).__name__} instead."
        )
    if value.dtype != dtype:
        raise InvalidTypeError(
            f"The '{name}' parameter of {owner} must be of dtype {np.dtype(dtype).name}. "
            f"Got {value.dtype} instead."
        )
    if not value.flags.c_contiguous:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be C-contiguous "
            "(numpy.ascontiguousarray). Got a strided array instead."
        )
    if writable and not value.flags.writeable:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be writable (it is an output). "
            "Got a read-only array instead."
        )
    return value


def check_vector(
    value: object,
    name: str,
    owner: str,
    shape: tuple[int, ...],
    *,
    writable: bool = False,
    dtype: type = np.float64,
) -> np.ndarray:
    """``value`` if it is a C-contiguous array of ``dtype`` and ``shape`` (writable
    for an output); InvalidTypeError / InvalidValueError naming it otherwise."""
    arr = _array(value, name, owner, dtype, writable)
    if arr.shape != shape:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be of shape {shape}. "
            f"Got shape {arr.shape} instead."
        )
    return arr


def check_model(model: object, owner: str) -> tuple[int, int]:
    """``(n_links, n_dof)`` of ``model`` if it is a consistent :class:`ArmArrays`
    (as :func:`flexarm.model.arrays.pack_arm_arrays` builds it); otherwise an error
    naming the field that does not fit."""
    if not isinstance(model, ArmArrays):
        raise InvalidTypeError(
            f"The 'model' parameter of {owner} must be an ArmArrays (FlexibleArm.arrays). "
            f"Got {type(model).__name__} instead."
        )
    ms = _array(model.mode_start, "model.mode_start", owner, np.int64, False)
    if ms.ndim != 1 or ms.shape[0] < 2:
        raise InvalidValueError(
            f"The 'model.mode_start' parameter of {owner} must be of shape (n_links + 1,). "
            f"Got shape {ms.shape} instead."
        )
    n_links = ms.shape[0] - 1
    n = int(np.asarray(model.mass_integral).shape[0]) if np.ndim(model.mass_integral) else -1
    if not (ms[0] == n_links and np.all(np.diff(ms) >= 0) and 0 <= ms[-1] <= n):
        raise InvalidValueError(
            f"The 'model.mode_start' parameter of {owner} must start at n_links and rise to "
            f"at most n_dof ({n}). Got {ms.tolist()} instead."
        )
    k = np.asarray(model.shortening_cubic).shape[-1] if np.ndim(model.shortening_cubic) else 0
    n_joints = np.asarray(model.joint).shape[0] if np.ndim(model.joint) == 2 else -1
    shapes = field_shapes(n_links, n, k, n_joints)
    for field, shape in shapes.items():
        check_vector(getattr(model, field), f"model.{field}", owner, shape)
    if n_joints not in (0, n_links) or n != ms[-1] + n_joints:
        raise InvalidValueError(
            f"The 'model.joint' parameter of {owner} must have 0 or n_links ({n_links}) rows "
            f"and n_dof ({n}) must be the modes' end plus them. Got {n_joints} rows instead."
        )
    return n_links, n


def check_workspace(ws: object, n: int, owner: str) -> None:
    """``ws`` must be a :class:`Workspace` for ``n`` coordinates
    (:func:`flexarm.model.arrays.make_workspace`)."""
    if not isinstance(ws, Workspace):
        raise InvalidTypeError(
            f"The 'ws' parameter of {owner} must be a Workspace (make_workspace(n_dof)). "
            f"Got {type(ws).__name__} instead."
        )
    shapes = workspace_shapes(n)
    for field, shape in shapes.items():
        check_vector(getattr(ws, field), f"ws.{field}", owner, shape, writable=True)


class StateShapes(NamedTuple):
    """The shapes a state-and-torque kernel call needs."""

    n_links: int
    n_dof: int


def check_state(q: object, dq: object, tau: object, model: object, owner: str) -> StateShapes:
    """``q, dq`` of shape (n_dof,) and ``tau`` of shape (n_links,) for ``model``."""
    n_links, n = check_model(model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_vector(tau, "tau", owner, (n_links,))
    return StateShapes(n_links=n_links, n_dof=n)


def shape_message(name: str, owner: str, want: str, got: tuple[int, ...]) -> str:
    """The message of a wrong shape: ``want`` is the expected shape as text."""
    return f"The '{name}' parameter of {owner} must be of shape {want}. Got shape {got} instead."


def state_shapes(q_shape: tuple[int, ...], n_dof: int, n_links: int) -> dict[str, str]:
    """The shape each of ``q, dq, tau`` must have, as text, given ``q``'s shape (a
    batch when it has two dimensions)."""
    both = f"({n_dof},) or (m, {n_dof})"
    if len(q_shape) == 2:
        m = q_shape[0]
        return {"q": both, "dq": f"({m}, {n_dof})", "tau": f"({m}, {n_links})"}
    return {"q": both, "dq": f"({n_dof},)", "tau": f"({n_links},)"}


def checked_coordinates(
    q: ArrayLike, n_dof: int, *, real: bool, owner: str = _OWNER
) -> NDArray[Any]:
    """``q`` as an array of shape ``(n_dof,)`` or ``(m, n_dof)``, finite; complex
    kept unless ``real`` (then refused); real input as a new C-contiguous float64
    array. InvalidTypeError / InvalidValueError naming ``q`` otherwise."""
    arr = check_array(q, "q", owner, real=real)
    if arr.ndim not in (1, 2) or arr.shape[-1] != n_dof:
        raise InvalidValueError(shape_message("q", owner, f"({n_dof},) or (m, {n_dof})", arr.shape))
    return arr if arr.dtype.kind == "c" else np.array(arr, dtype=np.float64, order="C")


def checked_state(
    q: ArrayLike,
    dq: ArrayLike,
    tau: ArrayLike,
    n_dof: int,
    n_links: int,
    *,
    real: bool,
    owner: str = _OWNER,
) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    """``q, dq`` of shape ``(n_dof,)`` and ``tau`` of shape ``(n_links,)``, or a batch
    of them (``(m, n_dof)``, ``(m, n_dof)``, ``(m, n_links)``), all finite.

    Complex values are kept unless ``real`` (then refused); real input comes back
    as new C-contiguous float64 arrays. InvalidTypeError / InvalidValueError
    naming the argument otherwise.
    """
    q = checked_coordinates(q, n_dof, real=real, owner=owner)
    want = state_shapes(q.shape, n_dof, n_links)
    shapes = {"dq": q.shape, "tau": (*q.shape[:-1], n_links)}
    out = [q]
    for name, value in (("dq", dq), ("tau", tau)):
        arr = check_array(value, name, owner, real=real)
        if arr.shape != shapes[name]:
            raise InvalidValueError(shape_message(name, owner, want[name], arr.shape))
        out.append(arr if arr.dtype.kind == "c" else np.array(arr, dtype=np.float64, order="C"))
    return out[0], out[1], out[2]
