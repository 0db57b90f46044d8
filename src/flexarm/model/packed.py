"""One arm's compiled kernels behind a cheap call from Python: :class:`PackedArm`.

Numba types every argument of a call from Python, some 20 ns an array. The
kernels of :mod:`flexarm.model.dynamics` take an
:class:`~flexarm.model.arrays.ArmArrays` (16 arrays) and a
:class:`~flexarm.model.arrays.Workspace` (10 more), so a call from Python spends
microseconds in dispatch before the kernel starts. :class:`PackedArm` packs an
arm's arrays once into one float64 buffer (its sizes and ``mode_start`` first,
as int64 bit patterns). Its compiled entry points take that buffer, a flat
workspace, the state and the output, a few arguments of fixed types; inside
compiled code they view the buffer as the ``ArmArrays`` and the workspace as a
``Workspace`` again (views, no copies) and call the same kernels,
so the results are those kernels' bit for bit.

:class:`flexarm.FlexibleArm` builds its :class:`PackedArm` on first use (loading
Numba then) and calls it from :meth:`~flexarm.FlexibleArm.forward_dynamics`,
:meth:`~flexarm.FlexibleArm.mass_matrix`, :meth:`~flexarm.FlexibleArm.point_position`
and :meth:`~flexarm.FlexibleArm.tip_position`. A method of :class:`PackedArm`
returns None when its arguments are not C-contiguous, writable float64 NumPy
arrays of one number of dimensions: the arm then checks and converts them
(:func:`flexarm.model.kernel_checks.checked_state`) or takes its NumPy
reference (complex input). The entry points check shapes and finiteness
themselves, so a wrong shape never reaches a kernel.

Every state may also come as a batch: ``q`` of shape ``(m, n_dof)`` is ``m``
states evaluated in one compiled call, each exactly as a call of its own.

Threads: the kernels release the GIL (batches; one state from Python holds it, a
call being shorter than the release) and nothing they write is shared. The
packed buffer is never written; a call's workspace is its own, on the stack of
the compiled entry point (up to :data:`STACK_FLOATS` values: arms of up to 17
coordinates) or allocated by the call, so concurrent calls on one arm need no
lock. The kernels write every scratch value before reading it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numba import types as nt
from numpy.typing import NDArray

from .._compile import njit_runtime_free
from ..errors import InvalidValueError
from ._buffer import (
    OK,
    STRIDED,
    contiguous,
    own_mass,
    pack_buffer,
    rows_status,
    scratch,
    scratch_size,
    sizes,
    stack,
    state_status,
    states_status,
    unpack,
    vector_status,
    view,
    workspace,
)
from .arrays import LEN, ArmArrays, workspace_size
from .dynamics._dense import mass_and_bias
from .dynamics._forward import forward_dynamics
from .dynamics._points import point_state
from .kernel_checks import shape_message, state_shapes

__all__ = ["STACK_FLOATS", "PackedArm", "pack_buffer"]

F64 = NDArray[np.float64]

_OWNER = "FlexibleArm"
_STATE = ("q", "dq", "tau")
_FLOAT64 = np.dtype(np.float64)
_empty = np.empty  # a name lookup less than np.empty: 30 ns of a call of ~600

STACK_FLOATS = 2048
"""Workspaces up to this many float64 values (16 KiB: arms of up to 17 coordinates)
live on the stack of a call, half the smallest thread stack Python allows;
larger ones are allocated by the call."""


# --------------------------------------------------------------- entry points
_F1 = nt.Array(nt.float64, 1, "C")
_F2 = nt.Array(nt.float64, 2, "C")
_F3 = nt.Array(nt.float64, 3, "C")
_R1 = nt.Array(nt.float64, 1, "C", readonly=True)
_ENTRY = {"cache": True, "nogil": True}


# Each entry point below is compiled at import; the kernel is inlined into one
# entry for the dynamics and one for the mass matrix (30 and 7 s to compile),
# and the batch entries call those (a call of a few arrays, a few ns a state).
@njit_runtime_free([nt.int64(_F1, _F1, _F1, _F1, _F1)], **_ENTRY)
def _dynamics(buf: F64, q: F64, dq: F64, tau: F64, out: F64) -> int:  # pragma: no cover
    """:func:`flexarm.model.dynamics.forward_dynamics` of the packed arm into
    ``out[:n_dof]``; the workspace is ``out``'s tail if it has one of
    :func:`scratch_size` values, else on this call's stack. The accelerations
    are computed on the stack and copied into ``out`` last, so ``out`` may
    overlap the state. Returns a status code (0: done)."""
    status = state_status(q, dq, tau, buf)
    if status == OK and not contiguous(out):
        status = STRIDED
    if status == OK:
        n = q.shape[0]
        wbuf = scratch(out, n, scratch_size(n))
        ws = workspace(wbuf, n, own_mass(wbuf, n))
        ddq = stack(n)
        forward_dynamics(q, dq, tau, unpack(buf), ws, ddq)
        for r in range(n):
            out[r] = ddq[r]
    return status


def _compiled(dispatcher: Any) -> Any:
    """The compiled function behind ``dispatcher`` (compiled for one signature),
    which unboxes its arguments without typing them first; the dispatcher itself
    where there is no such function (``NUMBA_DISABLE_JIT``)."""
    overloads = getattr(dispatcher, "overloads", None)
    if not overloads or len(overloads) != 1:
        return dispatcher
    return next(iter(overloads.values())).entry_point


@njit_runtime_free([nt.int64(_F1, _F1, _F1, _F1, _F1)], cache=True)
def _dynamics_held(buf: F64, q: F64, dq: F64, tau: F64, out: F64) -> int:  # pragma: no cover
    """:func:`_dynamics` holding the GIL: the entry of one state from Python, where
    releasing and taking back the GIL would add some 35 ns (more under load) to a
    call of well under a microsecond. Batches release it (:func:`_dynamics_rows`)."""
    return _dynamics(buf, q, dq, tau, out)


_dynamics_entry = _compiled(_dynamics_held)


@njit_runtime_free([nt.int64(_F1, _F1, _F2, _F2, _F2, _F2)], **_ENTRY)
def _dynamics_rows(
    buf: F64, row: F64, q: F64, dq: F64, tau: F64, out: F64
) -> int:  # pragma: no cover - compiled
    """:func:`_dynamics` for every row of ``q, dq, tau`` (2-D) into ``out``; ``row``
    is the output of one call (``n_dof`` values, or more with the workspace)."""
    status = states_status(q, dq, tau, buf)
    if status == OK:
        n = q.shape[1]
        for b in range(q.shape[0]):
            _dynamics(buf, q[b], dq[b], tau[b], row)
            for r in range(n):
                out[b, r] = row[r]
    return status


@njit_runtime_free([nt.int64(_F1, _F1, _F2)], **_ENTRY)
def _mass_matrix(buf: F64, q: F64, out: F64) -> int:  # pragma: no cover - compiled
    """``M(q)`` of :func:`flexarm.model.dynamics.mass_and_bias` into ``out[:n_dof]``
    (``out`` of shape (rows, n_dof): its rows after the first ``n_dof``, if enough,
    hold the workspace, else it is on this call's stack)."""
    n = sizes(buf)[1]
    status = vector_status(q, n, 0)
    if status == OK:
        flat = view(out, 0, (out.size,), np.float64)
        wbuf = scratch(flat, n * n, scratch_size(n))
        mass = view(flat, 0, (n, n), np.float64)
        mass_and_bias(q, q, unpack(buf), workspace(wbuf, n, mass))  # M needs no dq
    return status


@njit_runtime_free([nt.int64(_F1, _F2, _F2, _F3)], **_ENTRY)
def _mass_matrix_rows(buf: F64, block: F64, q: F64, out: F64) -> int:  # pragma: no cover - compiled
    """:func:`_mass_matrix` for every row of ``q`` into ``out`` (m, n, n); ``block`` is
    the output of one call."""
    n, m = sizes(buf)[1], q.shape[0]
    status = rows_status(q, m, n, 0)
    if status == OK:
        for b in range(m):
            _mass_matrix(buf, q[b], block)
            for r in range(n):
                for c in range(n):
                    out[b, r, c] = block[r, c]
    return status


@njit_runtime_free([nt.int64(_F1, _F1, nt.int64, nt.float64, _R1, _F1)], **_ENTRY)
def _point(
    buf: F64, q: F64, link: int, distance: float, phi: F64, out: F64
) -> int:  # pragma: no cover - compiled
    """Position of the point ``distance`` along ``link`` (basis ``phi``) into ``out`` (2,)."""
    status = vector_status(q, sizes(buf)[1], 0)
    if status == OK:
        px, py, _, _ = point_state(q, q, unpack(buf), link, distance, phi)
        out[0] = px
        out[1] = py
    return status


@njit_runtime_free([nt.int64(_F1, _F2, nt.int64, nt.float64, _R1, _F2)], **_ENTRY)
def _point_rows(
    buf: F64, q: F64, link: int, distance: float, phi: F64, out: F64
) -> int:  # pragma: no cover - compiled
    """:func:`_point` for every row of ``q`` into ``out`` (m, 2)."""
    m = q.shape[0]
    status = rows_status(q, m, sizes(buf)[1], 0)
    if status == OK:
        arrays = unpack(buf)
        for b in range(m):
            px, py, _, _ = point_state(q[b], q[b], arrays, link, distance, phi)
            out[b, 0] = px
            out[b, 1] = py
    return status


# ------------------------------------------------------------------ the object
@dataclass(frozen=True, eq=False, slots=True)
class PackedArm:
    """An arm packed for cheap compiled calls from Python (module docstring).

    Build it with :meth:`from_arrays`; :class:`flexarm.FlexibleArm` keeps one.

    Attributes
    ----------
    buf : ndarray, shape (size,)
        The arm (:func:`pack_buffer`); never written.
    n_links, n_dof : int
    tip : ndarray or None
        The last tip's basis (:meth:`flexarm.FlexibleArm.point_basis`), if given.
    tip_distance : float
        Length of the last link, m.
    scratch : int
        Values in a workspace (:func:`flexarm.model.arrays.workspace_size`).
    on_stack : bool
        Whether a workspace fits on a call's stack (:data:`STACK_FLOATS`);
        otherwise each call allocates it with its output.
    vector : tuple of int
        ``(n_dof,)``, the shape of the accelerations of one state.
    entry : callable
        ``entry(buf, q, dq, tau, out) -> status`` for one state, the compiled
        function behind the dispatcher of the dynamics (no typing of the
        arguments: float64 vectors only, checked by the caller; their layout
        checked inside, :data:`flexarm.model._buffer.STRIDED`).
    one_state : callable or None
        ``entry`` if ``on_stack``, else None: what the arm's fast path calls, an
        instance slot (read in a few ns, where the class attribute ``entry`` is a
        descriptor lookup of some 20). Not pickled (``__reduce__``).
    square : tuple of int
        ``(n_dof, n_dof)``, the shape of a mass matrix.
    tall : tuple of int
        A mass matrix with room for a workspace in its rows below.
    bases : dict
        Memo of point bases ``(link, distance) -> phi`` that the arm fills, at
        most ``MAX_BASES`` (the oldest goes first).
    """

    buf: F64
    n_links: int
    n_dof: int
    tip: F64 | None
    tip_distance: float
    scratch: int = field(init=False, repr=False)
    on_stack: bool = field(init=False, repr=False)
    vector: tuple[int] = field(init=False, repr=False)
    square: tuple[int, int] = field(init=False, repr=False)
    tall: tuple[int, int] = field(init=False, repr=False)
    one_state: Any = field(init=False, repr=False)
    bases: dict[tuple[int, float], F64] = field(default_factory=dict, repr=False)

    MAX_BASES = 64
    entry: ClassVar[Any] = staticmethod(_dynamics_entry)  # a class attribute: pickles

    def __post_init__(self) -> None:
        scratch = workspace_size(self.n_dof)
        object.__setattr__(self, "scratch", scratch)
        object.__setattr__(self, "on_stack", scratch <= STACK_FLOATS)
        n = self.n_dof
        object.__setattr__(self, "vector", (n,))
        object.__setattr__(self, "square", (n, n))
        object.__setattr__(self, "tall", (n + -(-scratch // n), n))
        object.__setattr__(self, "one_state", self.entry if scratch <= STACK_FLOATS else None)

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as its arguments (the compiled ``one_state`` is rebuilt, the
        memo of bases left behind)."""
        return (type(self), (self.buf, self.n_links, self.n_dof, self.tip, self.tip_distance))

    @classmethod
    def from_arrays(cls, arrays: ArmArrays, tip: F64 | None = None) -> PackedArm:
        """Pack ``arrays`` (:attr:`flexarm.FlexibleArm.arrays`, or any plant's);
        ``tip`` is the last link's basis at its tip
        (:meth:`flexarm.FlexibleArm.point_basis`), kept as ``tip``."""
        n_links, n = arrays.mode_start.shape[0] - 1, arrays.mass_integral.shape[0]
        length = float(arrays.link[n_links - 1, LEN])
        tip_basis = None if tip is None else _frozen(tip)
        return cls(pack_buffer(arrays), n_links, n, tip_basis, length)

    def remember_basis(self, link: int, distance: float, phi: F64) -> None:
        """Keep ``phi`` as the basis of the point ``(link, distance)``."""
        if len(self.bases) >= self.MAX_BASES:
            self.bases.pop(next(iter(self.bases)), None)
        self.bases[(link, distance)] = _frozen(phi)

    # ----------------------------------------------------------------- calls
    # The guards read ``dtype`` (a list has none: AttributeError) and leave the
    # rest to the compiled entry points' signatures (a strided, read-only or 3-D
    # array: TypeError): a few tens of ns of a call of some 600. One state goes to
    # ``entry``, which has no signature to refuse with: ``ndim`` is checked here
    # (unboxing writes that many shapes), the layout inside (STRIDED).
    def forward_dynamics(self, q: Any, dq: Any, tau: Any, out: Any = None) -> F64 | None:
        """``qddot`` of :func:`flexarm.model.dynamics.forward_dynamics`.

        Parameters
        ----------
        q, dq : ndarray, shape (n_dof,) or (m, n_dof)
            Coordinates and rates (rad, rad/s; modal units), float64.
        tau : ndarray, shape (n_links,) or (m, n_links)
            Joint (motor) torques, N m, float64.
        out : ndarray, shape (n_dof,), optional
            Where to write the accelerations of one state: a writable,
            C-contiguous float64 array (it may be one of the state's arrays).

        Returns
        -------
        ndarray, shape (n_dof,) or (m, n_dof), or None
            The accelerations (rad/s**2; modal units), ``out`` if given; None if
            the arguments are not C-contiguous, aligned float64 NumPy arrays of
            one number of dimensions (1 or 2), or ``out`` is given and is not
            such an array of shape (n_dof,) or the state is a batch.

        Raises
        ------
        InvalidValueError
            Naming the argument of a wrong shape or with non-finite entries.
        """
        try:
            if q.dtype is not _FLOAT64 or dq.dtype is not _FLOAT64 or tau.dtype is not _FLOAT64:
                return None
            if q.ndim == 1 and dq.ndim == 1 and tau.ndim == 1 and self.one_state is not None:
                # One state, the common case: the compiled function behind the
                # dispatcher, called directly (the dispatcher's typing of five
                # arrays is a fifth of a call). What that typing guarded, the
                # float64 vectors checked just above and their layout checked by
                # the entry point itself (STRIDED), so nothing else reaches it.
                if out is None:
                    out = _empty(self.n_dof)
                elif not (
                    out.dtype is _FLOAT64 and out.shape == self.vector and out.flags.writeable
                ):
                    return None
                status = self.one_state(self.buf, q, dq, tau, out)
            elif out is not None:
                return None
            elif q.ndim == 1:  # the workspace in the output's tail, the result copied out
                big = _empty(self.n_dof + self.scratch)
                status = _dynamics(self.buf, q, dq, tau, big)
                out = big[: self.n_dof].copy()
            else:
                row = _empty(self.n_dof if self.on_stack else self.n_dof + self.scratch)
                out = _empty((q.shape[0], self.n_dof))
                status = _dynamics_rows(self.buf, row, q, dq, tau, out)
        except (AttributeError, TypeError, IndexError):  # not arrays, strided, mixed, 0-d
            return None
        if status:
            if status == STRIDED:
                return None
            self._fail(status, q, dq, tau)
        return out  # type: ignore[no-any-return]

    def mass_matrix(self, q: Any) -> F64 | None:
        """``M(q)`` of :func:`flexarm.model.dynamics.mass_and_bias`.

        Parameters
        ----------
        q : ndarray, shape (n_dof,) or (m, n_dof)
            Coordinates, float64.

        Returns
        -------
        ndarray, shape (n_dof, n_dof) or (m, n_dof, n_dof), or None
            kg m**2 (modal units); None if ``q`` is not a C-contiguous, writable
            float64 NumPy array of 1 or 2 dimensions.
        """
        try:
            if q.dtype is not _FLOAT64:
                return None
            block = self.square if self.on_stack else self.tall
            if q.ndim == 1:
                out = _empty(block)
                status = _mass_matrix(self.buf, q, out)
                if not self.on_stack:
                    out = out[: self.n_dof].copy()
            else:
                out = _empty((q.shape[0], *self.square))
                status = _mass_matrix_rows(self.buf, _empty(block), q, out)
        except (AttributeError, TypeError):
            return None
        if status:
            self._fail(status, q)
        return out

    def point_position(self, q: Any, link: int, distance: float, phi: F64) -> F64 | None:
        """Position of the point ``distance`` m along ``link`` (0-based).

        Parameters
        ----------
        q : ndarray, shape (n_dof,) or (m, n_dof)
            Coordinates, float64.
        link : int
        distance : float
            m; checked by the caller (``0 <= distance <= L``).
        phi : ndarray
            The point's basis (:meth:`flexarm.FlexibleArm.point_basis`).

        Returns
        -------
        ndarray, shape (2,) or (m, 2), or None
            ``(x, y)`` in m, base frame; None if ``q`` is not a C-contiguous,
            writable float64 NumPy array of 1 or 2 dimensions.
        """
        try:
            if q.dtype is not _FLOAT64:
                return None
            if q.ndim == 1:
                out = _empty(2)
                status = _point(self.buf, q, link, distance, phi, out)
            else:
                out = _empty((q.shape[0], 2))
                status = _point_rows(self.buf, q, link, distance, phi, out)
        except (AttributeError, TypeError):
            return None
        if status:
            self._fail(status, q)
        return out

    def _fail(self, status: int, *state: NDArray[np.float64]) -> None:
        """Raise the error that ``status`` stands for (``state``: the arguments)."""
        k, kind = divmod(status - 1, 2)
        name = _STATE[k]
        if kind == 1:
            raise InvalidValueError(
                f"The '{name}' parameter of {_OWNER} must be finite (no NaN or inf). "
                "Got non-finite entries instead."
            )
        want = state_shapes(state[0].shape, self.n_dof, self.n_links)[name]
        raise InvalidValueError(shape_message(name, _OWNER, want, state[k].shape))


def _frozen(phi: F64) -> F64:
    """A read-only C-contiguous float64 copy of ``phi``."""
    arr = np.array(phi, dtype=np.float64, order="C")
    arr.flags.writeable = False
    return arr
