r"""Compiled dynamics of the flexible arm: plain arrays in, plain arrays out.

These Numba functions are what the simulator calls millions of times. They take
the arm packed as plain arrays, :class:`ArmArrays` (built once by
:attr:`flexarm.FlexibleArm.arrays`; their parameter ``model``), and a
:class:`Workspace` allocated once, so a call allocates nothing. The readable NumPy implementation in
:mod:`flexarm.model.arm` is their reference; the tests hold the two together.

The model (see :mod:`flexarm.model.arm` for the derivation): the kinetic energy of
link ``i`` in its clamped frame is ``1/2 nu' Mb(delta) nu`` with body velocity
``nu = (u_x, u_y, alpha_dot, delta_dot) = Jb qdot``; ``M = sum Jb' Mb Jb`` and
the velocity terms ``h = C(q, qdot) qdot = sum Jb' beta`` with ``beta`` the
body-frame inertial force at ``qddot = 0``.

Three algorithms compute ``qddot``; :func:`forward_dynamics` takes the fastest
for the arm's structure:

* the dense kernel (:func:`forward_dynamics_dense`) works in a link-major order
  of the coordinates (:func:`local_order`: joint 1, link 1's modes, joint 2,
  ...), in which each link's body Jacobian is zero beyond a prefix; it forms
  only the lower triangle of ``M`` and solves with an ``L D L'``
  factorisation. Its cost grows as the cube of the number of links;
* the recursive kernel (:func:`forward_dynamics_recursive`) is the
  articulated-body algorithm on the same body terms, linear in the number of
  links (``model/dynamics/_recursive.py`` derives it). From
  :data:`RECURSIVE_FROM_LINKS` links on it is the faster (BENCHMARKS.md, "Cost
  growth"), and :func:`forward_dynamics_general` takes it there;
* the paper's structure (two links, one mode each, rigid joints) has the dense
  computation written out in scalars.

Each public name here is a checked face: called from Python it checks its
arguments (an output shorter than ``n_dof`` would otherwise be written past its
end) and calls the bare kernel; inside compiled code (the simulator's loops, a
user's own) the same name is the bare kernel itself, unchecked, through a Numba
overload. The bare kernels live in this package's internal modules: ``_dense``
(the mass matrix and its solve), ``_recursive``, ``_two_links`` (the paper's
structure in scalars), ``_points`` (the kinematics of a point), ``_link_terms``
(one link's modal sums and foreshortening terms) and ``_forward`` (which kernel
an arm takes); flexarm's own compiled code calls those.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..._compile import compiled_as
from ...errors import InvalidValueError
from ..arrays import ArmArrays, Workspace, make_workspace
from ..kernel_checks import check_model, check_state, check_vector, check_workspace
from . import _dense, _forward, _points, _recursive, _two_links
from ._forward import RECURSIVE_FROM_LINKS

__all__ = [
    "RECURSIVE_FROM_LINKS",
    "ArmArrays",
    "Workspace",
    "accelerations_recursive",
    "accelerations_two_links_one_mode",
    "forward_dynamics",
    "forward_dynamics_dense",
    "forward_dynamics_general",
    "forward_dynamics_recursive",
    "forward_dynamics_two_links_one_mode",
    "is_two_links_one_mode",
    "joint_forces",
    "local_order",
    "make_workspace",
    "mass_and_bias",
    "point_kinematics",
]

F64 = NDArray[np.float64]


def local_order(mode_start: NDArray[np.int64], n_dof: int) -> NDArray[np.int64]:
    """The link-major order the solver works in, as indices into ``q``.

    Joint 1, link 1's modes, joint 2, link 2's modes, ..., then the motor angles
    (if any): entry ``l`` is the index in ``q`` of the coordinate at local index
    ``l``. In this order link ``i``'s kinetic energy depends on a prefix of the
    coordinates.
    """
    ms = np.asarray(mode_start, dtype=np.int64)
    order: list[int] = []
    for i in range(ms.shape[0] - 1):
        order.append(i)
        order.extend(range(int(ms[i]), int(ms[i + 1])))
    order.extend(range(int(ms[-1]), n_dof))
    return np.array(order, dtype=np.int64)


# ------------------------------------------------------------------ checked public faces
# From Python each name checks its arguments first (an output shorter than n_dof
# would otherwise be written past its end); inside compiled code (the simulator's
# loops, a user's own) the same name is the bare kernel itself, through an overload.
def forward_dynamics(q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64) -> None:
    """``ddq = M(q)^-1 (B tau - C(q, dq) dq - K q - D dq + joint forces - dV/dq)``
    into ``ddq`` (``V`` the gravity potential, :mod:`flexarm.model.gravity`; none without).

    Two links with one mode each and rigid joints (the paper's structure) take the
    scalar kernel (:func:`forward_dynamics_two_links_one_mode`), every other arm
    :func:`forward_dynamics_general`.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        Coordinates and rates, float64, C-contiguous.
    tau : ndarray, shape (n_links,)
        Joint (motor) torques, N m.
    model : ArmArrays
        :attr:`flexarm.FlexibleArm.arrays`.
    ws : Workspace
        :func:`make_workspace` ``(n_dof)`` (overwritten).
    ddq : ndarray, shape (n_dof,)
        Output accelerations (writable).

    Raises
    ------
    InvalidTypeError, InvalidValueError
        Naming the argument of the wrong type, dtype, layout or shape.
    """
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics")
    _forward.forward_dynamics(q, dq, tau, model, ws, ddq)


def _check_forward(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64, owner: str
) -> None:
    """The arguments of a forward-dynamics kernel, checked (errors name ``owner``)."""
    _, n = check_state(q, dq, tau, model, owner)
    check_workspace(ws, n, owner)
    check_vector(ddq, "ddq", owner, (n,), writable=True)


def forward_dynamics_general(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:
    """:func:`forward_dynamics` by the general kernels for any structure, the dense
    or the recursive one, whichever is the faster for it (checked)."""
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics_general")
    _forward.forward_dynamics_general(q, dq, tau, model, ws, ddq)


def forward_dynamics_dense(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:
    """:func:`forward_dynamics` by the mass matrix and its factorisation, for any
    structure (checked)."""
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics_dense")
    _dense.forward_dynamics_dense(q, dq, tau, model, ws, ddq)


def forward_dynamics_recursive(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:
    """:func:`forward_dynamics` by the articulated-body recursion, in time linear in
    the number of links, for any structure (checked)."""
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics_recursive")
    _forward.forward_dynamics_recursive(q, dq, tau, model, ws, ddq)


def mass_and_bias(q: F64, dq: F64, model: ArmArrays, ws: Workspace) -> None:
    """Fill ``ws.mass`` with ``M(q)`` and ``ws.bias`` with ``C(q, dq) dq`` (checked).

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        Coordinates (rad, modal units) and their rates.
    model : ArmArrays
        :attr:`flexarm.FlexibleArm.arrays`.
    ws : Workspace
        Overwritten: ``mass`` (n_dof, n_dof) in kg m**2 (modal units), ``bias``
        (n_dof,) in N m; the rest is scratch.
    """
    _check_coordinates(q, dq, model, ws, "mass_and_bias")
    _dense.mass_and_bias(q, dq, model, ws)


def _check_coordinates(q: F64, dq: F64, model: ArmArrays, ws: Workspace, owner: str) -> int:
    """``n_dof`` of ``model`` once ``q, dq`` and ``ws`` are checked for it."""
    _, n = check_model(model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_workspace(ws, n, owner)
    return n


def joint_forces(q: F64, dq: F64, tau: F64, model: ArmArrays, rhs: F64) -> None:
    """Add the flexible joints' generalised forces to ``rhs`` (checked)."""
    owner = "joint_forces"
    _, n = check_state(q, dq, tau, model, owner)
    check_vector(rhs, "rhs", owner, (n,), writable=True)
    _dense.joint_forces(q, dq, tau, model, rhs)


def accelerations_recursive(q: F64, dq: F64, model: ArmArrays, ws: Workspace, ddq: F64) -> None:
    """The articulated-body recursion alone (checked): ``ddq`` from ``q, dq`` and the
    generalised forces other than inertia that ``ws.rhs`` holds (order of ``q``, N m
    and modal units), as :func:`forward_dynamics_recursive` forms them first.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
    model : ArmArrays
    ws : Workspace
        ``rhs`` read; the rest is scratch.
    ddq : ndarray, shape (n_dof,)
        Output accelerations (writable).
    """
    owner = "accelerations_recursive"
    n = _check_coordinates(q, dq, model, ws, owner)
    check_vector(ddq, "ddq", owner, (n,), writable=True)
    _recursive.accelerations_recursive(q, dq, model, ws, ddq)


def is_two_links_one_mode(model: ArmArrays) -> bool:
    """Whether ``model`` has two links with one mode each and rigid joints (the
    paper's structure, which the scalar kernel handles)."""
    check_model(model, "is_two_links_one_mode")
    return bool(_two_links.is_two_links_one_mode(model))


def accelerations_two_links_one_mode(
    a1: float,
    a2: float,
    d1: float,
    d2: float,
    da1: float,
    da2: float,
    dd1: float,
    dd2: float,
    t1: float,
    t2: float,
    model: ArmArrays,
) -> tuple[float, float, float, float]:
    """``ddq`` of the paper's structure (two links, one mode each, rigid joints) from
    scalars, in the order of ``q``; ``model`` is checked.

    Parameters
    ----------
    a1, a2, d1, d2 : float
        ``q = (theta1, theta2, delta1, delta2)``: rad, then modal units.
    da1, da2, dd1, dd2 : float
        ``dq`` in the same order.
    t1, t2 : float
        Joint torques, N m.
    model : ArmArrays
        Two links with one mode each and rigid joints (:func:`is_two_links_one_mode`).

    Returns
    -------
    tuple of 4 float
        ``ddq``: rad/s**2, then modal units per s**2.
    """
    _check_paper_structure(model, "accelerations_two_links_one_mode")
    out: tuple[float, float, float, float] = _two_links.accelerations_two_links_one_mode(
        float(a1),
        float(a2),
        float(d1),
        float(d2),
        float(da1),
        float(da2),
        float(dd1),
        float(dd2),
        float(t1),
        float(t2),
        model,
    )
    return out


def forward_dynamics_two_links_one_mode(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ddq: F64
) -> None:
    """:func:`forward_dynamics` for the paper's structure only, in scalars (about 4x
    faster than the dense kernel it equals); arguments checked, ``ddq`` of shape (4,)."""
    owner = "forward_dynamics_two_links_one_mode"
    _check_paper_structure(model, owner)
    check_state(q, dq, tau, model, owner)
    check_vector(ddq, "ddq", owner, (4,), writable=True)
    _two_links.forward_dynamics_two_links_one_mode(q, dq, tau, model, ddq)


def _check_paper_structure(model: ArmArrays, owner: str) -> None:
    n_links, n = check_model(model, owner)
    if not (n_links == 2 and n == 4):
        raise InvalidValueError(
            f"The 'model' parameter of {owner} must have two links with one mode each and "
            f"rigid joints. Got {n_links} links and {n} coordinates instead."
        )
    if not _two_links.is_two_links_one_mode(model):
        raise InvalidValueError(
            f"The 'model' parameter of {owner} must have two links with one mode each, "
            "rigid joints without rotors or friction, no tip inertia on the first link "
            "and no geometric stiffening. Got another structure instead."
        )


def point_kinematics(
    q: F64, dq: F64, model: ArmArrays, link: int, distance: float, phi: F64, out: F64
) -> None:
    """Position and velocity of the point ``distance`` m along ``link``, deflection
    included, into ``out`` (checked).

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
    model : ArmArrays
    link : int
        0-based link index.
    distance : float
        Distance along the undeformed link from its joint, m.
    phi : ndarray, shape (n_modes of ``link``,) or (n_modes + n_modes**2,)
        :meth:`flexarm.FlexibleArm.point_basis`: the link's mode shapes at
        ``distance``, then (with geometric stiffening) its shortening matrix
        ``S(distance)`` row by row; without it the point's own foreshortening is
        left out.
    out : ndarray, shape (4,)
        Written: ``x, y`` (m) and ``vx, vy`` (m/s) in the base frame.
    """
    owner = "point_kinematics"
    n_links, n = check_model(model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    if not isinstance(link, int | np.integer) or not 0 <= int(link) < n_links:
        raise InvalidValueError(
            f"The 'link' parameter of {owner} must be an integer in [0, {n_links}). "
            f"Got {link!r} instead."
        )
    n_modes = int(model.mode_start[int(link) + 1] - model.mode_start[int(link)])
    sizes = (n_modes, n_modes + n_modes * n_modes)
    phi_arr = np.asarray(phi)
    if phi_arr.ndim != 1 or phi_arr.shape[0] not in sizes:
        raise InvalidValueError(
            f"The 'phi' parameter of {owner} must be of shape ({sizes[0]},) or "
            f"({sizes[1]},) for link {link}. Got shape {phi_arr.shape} instead."
        )
    check_vector(phi, "phi", owner, (phi_arr.shape[0],))
    check_vector(out, "out", owner, (4,), writable=True)
    _points.point_kinematics(q, dq, model, int(link), float(distance), phi, out)


# ------------------------------------------------------------ inside compiled code
@compiled_as(forward_dynamics, runtime_free=True)
def _forward_dynamics_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward.forward_dynamics(q, dq, tau, model, ws, ddq)


@compiled_as(forward_dynamics_general, runtime_free=True)
def _forward_dynamics_general_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward.forward_dynamics_general(
        q, dq, tau, model, ws, ddq
    )


@compiled_as(forward_dynamics_dense, runtime_free=True)
def _forward_dynamics_dense_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _dense.forward_dynamics_dense(
        q, dq, tau, model, ws, ddq
    )


@compiled_as(forward_dynamics_recursive, runtime_free=True)
def _forward_dynamics_recursive_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward.forward_dynamics_recursive(
        q, dq, tau, model, ws, ddq
    )


@compiled_as(mass_and_bias, runtime_free=True)
def _mass_and_bias_compiled(q, dq, model, ws):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, ws: _dense.mass_and_bias(q, dq, model, ws)


@compiled_as(joint_forces, runtime_free=True)
def _joint_forces_compiled(q, dq, tau, model, rhs):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, rhs: _dense.joint_forces(q, dq, tau, model, rhs)


@compiled_as(is_two_links_one_mode)
def _is_two_links_one_mode_compiled(model):  # type: ignore[no-untyped-def]
    return lambda model: _two_links.is_two_links_one_mode(model)


@compiled_as(accelerations_two_links_one_mode)
def _accelerations_compiled(a1, a2, d1, d2, da1, da2, dd1, dd2, t1, t2, model):  # type: ignore[no-untyped-def]
    return lambda a1, a2, d1, d2, da1, da2, dd1, dd2, t1, t2, model: (
        _two_links.accelerations_two_links_one_mode(
            a1, a2, d1, d2, da1, da2, dd1, dd2, t1, t2, model
        )
    )


@compiled_as(forward_dynamics_two_links_one_mode)
def _forward_dynamics_two_links_compiled(q, dq, tau, model, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ddq: _two_links.forward_dynamics_two_links_one_mode(
        q, dq, tau, model, ddq
    )


@compiled_as(point_kinematics)
def _point_kinematics_compiled(q, dq, model, link, distance, phi, out):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, link, distance, phi, out: _points.point_kinematics(
        q, dq, model, link, distance, phi, out
    )
