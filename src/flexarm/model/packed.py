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

Threads: the kernels release the GIL and nothing they write is shared. The
packed buffer is never written; a call's workspace is its own, on the stack of
the compiled entry point (up to :data:`STACK_FLOATS` values: arms of up to 17
coordinates) or allocated by the call, so concurrent calls on one arm need no
lock. The kernels write every scratch value before reading it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numba as nb
import numpy as np
from numba import types as nt
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array
from numpy.typing import NDArray

from .._compile import njit_runtime_free
from ..errors import InvalidValueError
from .arrays import (
    AX_ROWS,
    LEN,
    N_CHAIN_COLUMNS,
    N_JOINT_COLUMNS,
    N_LINK_COLUMNS,
    ArmArrays,
    Workspace,
    workspace_size,
)
from .dynamics._dense import mass_and_bias
from .dynamics._forward import forward_dynamics
from .dynamics._points import point_state
from .kernel_checks import shape_message, state_shapes

__all__ = ["STACK_FLOATS", "PackedArm", "pack_buffer"]

F64 = NDArray[np.float64]

_HEADER = 4  # n_links, n_dof, n_joints, K; then mode_start (n_links + 1), all int64
_OWNER = "FlexibleArm"
_STATE = ("q", "dq", "tau")
_NDARRAY = np.ndarray
_FLOAT64 = np.dtype(np.float64)
_empty = np.empty  # a name lookup less than np.empty: 30 ns of a call of ~600

# Status codes of the entry points: 0 is success; otherwise 1 + 2 k + kind for
# argument k of _STATE, kind 0 a wrong shape, 1 a non-finite entry.
_OK = 0


def pack_buffer(arrays: ArmArrays) -> F64:
    """``arrays`` as one float64 buffer.

    Parameters
    ----------
    arrays : ArmArrays
        :attr:`flexarm.FlexibleArm.arrays`.

    Returns
    -------
    ndarray, shape (5 + n_links + size,)
        ``n_links, n_dof, n_joints, K`` (the most modes of a link with geometric
        stiffening) and ``mode_start`` as int64 bit patterns, then every float
        array of ``arrays`` raveled in field order. Writable (Numba takes
        writable arrays fastest), but never written.
    """
    n_links = arrays.mode_start.shape[0] - 1
    n = arrays.mass_integral.shape[0]
    header = [n_links, n, arrays.joint.shape[0], arrays.shortening_cubic.shape[-1]]
    ints = np.concatenate([np.array(header, dtype=np.int64), arrays.mode_start])
    floats = [np.ravel(getattr(arrays, f)) for f in ArmArrays._fields[1:]]
    return np.concatenate([ints.astype(np.int64).view(np.float64), *floats])


# ---------------------------------------------------------------- views, compiled
def _view_typing(typingctx, buf, offset, shape, dtype):  # type: ignore[no-untyped-def]
    """The typing and code of :func:`_view`: ``buf[offset:]`` viewed as a
    C-contiguous array of ``shape`` and ``dtype`` (``np.float64`` or
    ``np.int64``), unchecked: a view built in a few
    instructions where ``buf[a:b].reshape(shape)`` calls a checking helper (some
    12 ns a view, a third of a call of the paper's arm from Python). The caller
    guarantees that ``buf`` holds ``offset + prod(shape)`` items of 8 bytes."""
    ndim, item = len(shape), dtype.dtype
    retty = nt.Array(item, ndim, "C")

    def codegen(context, builder, sig, args):  # type: ignore[no-untyped-def]
        buf_v, offset_v, shape_v, _ = args
        src = make_array(sig.args[0])(context, builder, buf_v)  # type: ignore[no-untyped-call]
        dst = make_array(retty)(context, builder)  # type: ignore[no-untyped-call]
        intp = context.get_value_type(nt.intp)
        dims = [
            builder.sext(d, intp) if d.type.width < intp.width else d
            for d in cgutils.unpack_tuple(builder, shape_v, ndim)  # type: ignore[no-untyped-call]
        ]
        itemsize = context.get_abi_sizeof(context.get_data_type(item))
        strides: list[Any] = []
        step = context.get_constant(nt.intp, itemsize)
        for d in reversed(dims):
            strides.insert(0, step)
            step = builder.mul(step, d)
        data = builder.gep(src.data, [offset_v])
        data = builder.bitcast(data, context.get_data_type(item).as_pointer())
        itemsize_v = context.get_constant(nt.intp, itemsize)
        populate_array(  # type: ignore[no-untyped-call]
            dst, data=data, shape=dims, strides=strides, itemsize=itemsize_v, meminfo=src.meminfo
        )
        return impl_ret_borrowed(context, builder, retty, dst._getvalue())  # type: ignore[no-untyped-call]

    return retty(buf, offset, shape, dtype), codegen


_view: Any = intrinsic(_view_typing)


@nb.njit(inline="always")
def _unpack(buf: F64) -> ArmArrays:  # pragma: no cover - compiled
    """The :class:`ArmArrays` that :func:`pack_buffer` packed, as views of ``buf``."""
    n_links = _view(buf, 0, (1,), np.int64)[0]
    o = _HEADER + n_links + 1
    ints = _view(buf, 0, (o,), np.int64)
    n, n_joints, k = ints[1], ints[2], ints[3]
    ms = _view(buf, _HEADER, (n_links + 1,), np.int64)
    link = _view(buf, o, (n_links, N_LINK_COLUMNS), np.float64)
    o += n_links * N_LINK_COLUMNS
    vectors = _view(buf, o, (4, n), np.float64)  # the four modal integrals
    o += 4 * n
    modal_mass = _view(buf, o, (n, n), np.float64)
    o += n * n
    stiffness = _view(buf, o, (n,), np.float64)
    damping = _view(buf, o + n, (n,), np.float64)
    payload = _view(buf, o + 2 * n, (2,), np.float64)
    o += 2 * n + 2
    joint = _view(buf, o, (n_joints, N_JOINT_COLUMNS), np.float64)
    o += n_joints * N_JOINT_COLUMNS
    shortening = _view(buf, o, (3, n, n), np.float64)  # tip, mass, moment
    o += 3 * n * n
    shortening_cubic = _view(buf, o, (n, k, k), np.float64)
    o += n * k * k
    shortening_quartic = _view(buf, o, (n, k, k, k), np.float64)
    return ArmArrays(
        mode_start=ms,
        link=link,
        mass_integral=vectors[0],
        moment_integral=vectors[1],
        tip_deflection=vectors[2],
        tip_slope=vectors[3],
        modal_mass=modal_mass,
        stiffness=stiffness,
        damping=damping,
        payload=payload,
        joint=joint,
        shortening_tip=shortening[0],
        shortening_mass=shortening[1],
        shortening_moment=shortening[2],
        shortening_cubic=shortening_cubic,
        shortening_quartic=shortening_quartic,
    )


@nb.njit(inline="always")
def _sizes(buf: F64) -> tuple[int, int]:  # pragma: no cover - compiled
    """``(n_links, n_dof)`` of the packed arm."""
    ints = _view(buf, 0, (2,), np.int64)
    return ints[0], ints[1]


@nb.njit(inline="always")
def _workspace(wbuf: F64, n: int, mass: F64) -> Workspace:  # pragma: no cover - compiled
    """``wbuf`` viewed as the :class:`Workspace` of :func:`flexarm.model.arrays.make_workspace`
    (the layout of :func:`flexarm.model.arrays.workspace_shapes`), with ``mass``
    (n, n) in place of its first array."""
    o = n * n
    bias = _view(wbuf, o, (n,), np.float64)
    o += n
    jac = _view(wbuf, o, (2, n), np.float64)
    o += 2 * n
    angle = _view(wbuf, o, (n,), np.float64)
    o += n
    rhs = _view(wbuf, o, (n,), np.float64)
    o += n
    rows = _view(wbuf, o, (3, n), np.float64)
    o += 3 * n
    lmass = _view(wbuf, o, (n, n), np.float64)
    o += n * n
    lbias = _view(wbuf, o, (n,), np.float64)
    o += n
    inv_diag = _view(wbuf, o, (n,), np.float64)
    o += n
    axial = _view(wbuf, o, (AX_ROWS + 3 * n, max(n, 3)), np.float64)
    o += (AX_ROWS + 3 * n) * max(n, 3)
    chain = _view(wbuf, o, (n, N_CHAIN_COLUMNS), np.float64)
    return Workspace(
        mass=mass,
        bias=bias,
        jac=jac,
        angle=angle,
        rhs=rhs,
        rows=rows,
        lmass=lmass,
        lbias=lbias,
        inv_diag=inv_diag,
        axial=axial,
        chain=chain,
    )


@nb.njit(inline="always")
def _own_mass(wbuf: F64, n: int) -> F64:  # pragma: no cover - compiled
    """The first ``n * n`` values of ``wbuf``: the workspace's own ``mass`` (n, n)."""
    mass: F64 = _view(wbuf, 0, (n, n), np.float64)
    return mass


@nb.njit(inline="always")
def _check(x: F64, n: int, arg: int) -> int:  # pragma: no cover - compiled
    """Status of one vector argument: shape ``(n,)`` and finite entries."""
    if x.shape[0] != n:
        return 1 + 2 * arg
    for r in range(n):
        if not math.isfinite(x[r]):
            return 2 + 2 * arg
    return _OK


@nb.njit(inline="always")
def _check_rows(x: F64, m: int, n: int, arg: int) -> int:  # pragma: no cover - compiled
    """Status of one batch argument: shape ``(m, n)`` and finite entries."""
    if x.shape[0] != m or x.shape[1] != n:
        return 1 + 2 * arg
    for b in range(m):
        for r in range(n):
            if not math.isfinite(x[b, r]):
                return 2 + 2 * arg
    return _OK


@nb.njit(inline="always")
def _check_state(q: F64, dq: F64, tau: F64, buf: F64) -> int:  # pragma: no cover - compiled
    """Status of a state: ``q, dq`` of shape (n_dof,), ``tau`` (n_links,), finite."""
    n_links, n = _sizes(buf)
    status = _check(q, n, 0)
    if status == _OK:
        status = _check(dq, n, 1)
    if status == _OK:
        status = _check(tau, n_links, 2)
    return status


@nb.njit(inline="always")
def _check_states(q: F64, dq: F64, tau: F64, buf: F64) -> int:  # pragma: no cover - compiled
    """:func:`_check_state` for a batch: ``(m, n_dof)``, ``(m, n_dof)``, ``(m, n_links)``."""
    n_links, n = _sizes(buf)
    m = q.shape[0]
    status = _check_rows(q, m, n, 0)
    if status == _OK:
        status = _check_rows(dq, m, n, 1)
    if status == _OK:
        status = _check_rows(tau, m, n_links, 2)
    return status


# --------------------------------------------------------------- entry points
def _stack_typing(typingctx, size):  # type: ignore[no-untyped-def]
    """The typing and code of :func:`_stack`: ``size`` float64 values on the stack of
    the compiled function that calls it (a dynamic ``alloca``), uninitialised,
    freed when that function returns. Only for the entry points below, called
    once a call and never inlined into a loop; ``size`` at most
    :data:`STACK_FLOATS`."""
    retty = nt.Array(nt.float64, 1, "C")

    def codegen(context, builder, sig, args):  # type: ignore[no-untyped-def]
        (n,) = args
        data = builder.alloca(context.get_data_type(nt.float64), size=n)
        arr = make_array(retty)(context, builder)  # type: ignore[no-untyped-call]
        eight = context.get_constant(nt.intp, 8)
        populate_array(  # type: ignore[no-untyped-call]
            arr, data=data, shape=[n], strides=[eight], itemsize=eight, meminfo=None
        )
        return arr._getvalue()

    return retty(size), codegen


_stack: Any = intrinsic(_stack_typing)

STACK_FLOATS = 2048
"""Workspaces up to this many float64 values (16 KiB: arms of up to 17 coordinates)
live on the stack of a call, half the smallest thread stack Python allows;
larger ones are allocated by the call."""


_F1 = nt.Array(nt.float64, 1, "C")
_F2 = nt.Array(nt.float64, 2, "C")
_F3 = nt.Array(nt.float64, 3, "C")
_R1 = nt.Array(nt.float64, 1, "C", readonly=True)
_ENTRY = {"cache": True, "nogil": True}


@nb.njit(inline="always")
def _scratch_size(n: int) -> int:  # pragma: no cover - compiled
    """:func:`flexarm.model.arrays.workspace_size` of ``n`` coordinates."""
    return 2 * n * n + (10 + N_CHAIN_COLUMNS) * n + (AX_ROWS + 3 * n) * max(n, 3)


@nb.njit(inline="always")
def _scratch(out: F64, used: int, size: int) -> F64:  # pragma: no cover - compiled
    """A workspace of ``size`` values: ``out``'s tail after its first ``used`` values
    when the caller made it that long (an arm too large for the stack), else on
    the stack of the entry point."""
    if out.size >= used + size:
        wbuf: F64 = _view(out, used, (size,), np.float64)
        return wbuf
    return _stack(size)  # type: ignore[no-any-return]


# Each entry point below is compiled at import; the kernel is inlined into one
# entry for the dynamics and one for the mass matrix (30 and 7 s to compile),
# and the batch entries call those (a call of a few arrays, a few ns a state).
@njit_runtime_free([nt.int64(_F1, _F1, _F1, _F1, _F1)], **_ENTRY)
def _dynamics(buf: F64, q: F64, dq: F64, tau: F64, out: F64) -> int:  # pragma: no cover
    """:func:`flexarm.model.dynamics.forward_dynamics` of the packed arm into
    ``out[:n_dof]``; the workspace is ``out``'s tail if it has one of
    :func:`_scratch_size` values, else on this call's stack. Returns a status code
    (0: done)."""
    status = _check_state(q, dq, tau, buf)
    if status == _OK:
        n = q.shape[0]
        wbuf = _scratch(out, n, _scratch_size(n))
        ws = _workspace(wbuf, n, _own_mass(wbuf, n))
        forward_dynamics(q, dq, tau, _unpack(buf), ws, _view(out, 0, (n,), np.float64))
    return status


@njit_runtime_free([nt.int64(_F1, _F1, _F2, _F2, _F2, _F2)], **_ENTRY)
def _dynamics_rows(
    buf: F64, row: F64, q: F64, dq: F64, tau: F64, out: F64
) -> int:  # pragma: no cover - compiled
    """:func:`_dynamics` for every row of ``q, dq, tau`` (2-D) into ``out``; ``row``
    is the output of one call (``n_dof`` values, or more with the workspace)."""
    status = _check_states(q, dq, tau, buf)
    if status == _OK:
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
    n = _sizes(buf)[1]
    status = _check(q, n, 0)
    if status == _OK:
        flat = _view(out, 0, (out.size,), np.float64)
        wbuf = _scratch(flat, n * n, _scratch_size(n))
        mass = _view(flat, 0, (n, n), np.float64)
        mass_and_bias(q, q, _unpack(buf), _workspace(wbuf, n, mass))  # M needs no dq
    return status


@njit_runtime_free([nt.int64(_F1, _F2, _F2, _F3)], **_ENTRY)
def _mass_matrix_rows(buf: F64, block: F64, q: F64, out: F64) -> int:  # pragma: no cover - compiled
    """:func:`_mass_matrix` for every row of ``q`` into ``out`` (m, n, n); ``block`` is
    the output of one call."""
    n, m = _sizes(buf)[1], q.shape[0]
    status = _check_rows(q, m, n, 0)
    if status == _OK:
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
    status = _check(q, _sizes(buf)[1], 0)
    if status == _OK:
        px, py, _, _ = point_state(q, q, _unpack(buf), link, distance, phi)
        out[0] = px
        out[1] = py
    return status


@njit_runtime_free([nt.int64(_F1, _F2, nt.int64, nt.float64, _R1, _F2)], **_ENTRY)
def _point_rows(
    buf: F64, q: F64, link: int, distance: float, phi: F64, out: F64
) -> int:  # pragma: no cover - compiled
    """:func:`_point` for every row of ``q`` into ``out`` (m, 2)."""
    m = q.shape[0]
    status = _check_rows(q, m, _sizes(buf)[1], 0)
    if status == _OK:
        model = _unpack(buf)
        for b in range(m):
            px, py, _, _ = point_state(q[b], q[b], model, link, distance, phi)
            out[b, 0] = px
            out[b, 1] = py
    return status


@nb.njit
def _unpacked(buf: F64) -> ArmArrays:  # pragma: no cover - compiled
    """:func:`_unpack` as a function (with the refcount runtime), for tests."""
    return _unpack(buf)


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
    square: tuple[int, int] = field(init=False, repr=False)
    tall: tuple[int, int] = field(init=False, repr=False)
    bases: dict[tuple[int, float], F64] = field(default_factory=dict, repr=False)

    MAX_BASES = 64

    def __post_init__(self) -> None:
        scratch = workspace_size(self.n_dof)
        object.__setattr__(self, "scratch", scratch)
        object.__setattr__(self, "on_stack", scratch <= STACK_FLOATS)
        n = self.n_dof
        object.__setattr__(self, "square", (n, n))
        object.__setattr__(self, "tall", (n + -(-scratch // n), n))

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
    # array: TypeError): a few tens of ns of a call of some 600.
    def forward_dynamics(self, q: Any, dq: Any, tau: Any) -> F64 | None:
        """``qddot`` of :func:`flexarm.model.dynamics.forward_dynamics`.

        Parameters
        ----------
        q, dq : ndarray, shape (n_dof,) or (m, n_dof)
            Coordinates and rates (rad, rad/s; modal units), float64.
        tau : ndarray, shape (n_links,) or (m, n_links)
            Joint (motor) torques, N m, float64.

        Returns
        -------
        ndarray, shape (n_dof,) or (m, n_dof), or None
            The accelerations (rad/s**2; modal units); None if the arguments
            are not C-contiguous, writable float64 NumPy arrays of one number
            of dimensions (1 or 2).

        Raises
        ------
        InvalidValueError
            Naming the argument of a wrong shape or with non-finite entries.
        """
        try:
            if q.dtype is not _FLOAT64 or dq.dtype is not _FLOAT64 or tau.dtype is not _FLOAT64:
                return None
            if q.ndim == 1:
                if self.on_stack:
                    out = _empty(self.n_dof)
                    status = _dynamics(self.buf, q, dq, tau, out)
                else:  # the workspace in the output's tail, the result copied out
                    big = _empty(self.n_dof + self.scratch)
                    status = _dynamics(self.buf, q, dq, tau, big)
                    out = big[: self.n_dof].copy()
            else:
                row = _empty(self.n_dof if self.on_stack else self.n_dof + self.scratch)
                out = _empty((q.shape[0], self.n_dof))
                status = _dynamics_rows(self.buf, row, q, dq, tau, out)
        except (AttributeError, TypeError):  # not arrays, strided, read-only, mixed
            return None
        if status:
            self._fail(status, q, dq, tau)
        return out

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
