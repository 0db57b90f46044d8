"""The packed arm's one buffer, built in NumPy and seen from compiled code.

Internal to :mod:`flexarm.model.packed`: :func:`pack_buffer` lays an
:class:`~flexarm.model.arrays.ArmArrays` out in one float64 buffer and
:func:`unpack` views it as the ``ArmArrays`` again inside compiled code (views, no
copies), :func:`workspace` a flat scratch buffer as a
:class:`~flexarm.model.arrays.Workspace`; :func:`stack` puts a scratch buffer on the
stack of the compiled function that calls it; :func:`state_status` and
:func:`states_status` give the status of an entry point's arguments (:data:`OK`,
or which argument is wrong and how).
"""

from __future__ import annotations

import math
from typing import Any

import numba as nb
import numpy as np
from numba import types as nt
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array
from numpy.typing import NDArray

from .arrays import (
    AX_ROWS,
    N_CHAIN_COLUMNS,
    N_JOINT_COLUMNS,
    N_LINK_COLUMNS,
    ArmArrays,
    Workspace,
)

__all__ = [
    "OK",
    "STRIDED",
    "address",
    "contiguous",
    "own_mass",
    "pack_buffer",
    "rows_status",
    "scratch",
    "scratch_size",
    "sizes",
    "stack",
    "state_status",
    "states_status",
    "unpack",
    "unpacked",
    "vector_status",
    "view",
    "workspace",
]

F64 = NDArray[np.float64]

HEADER = 4  # n_links, n_dof, n_joints, K; then mode_start (n_links + 1), all int64
# The link and joint rows are N_LINK_COLUMNS and N_JOINT_COLUMNS wide (flexarm.model.arrays):
# compiled code takes them as constants, so a cache built with other widths is stale.

# Status codes of the entry points: 0 is success; otherwise 1 + 2 k + kind for
# argument k of (q, dq, tau), kind 0 a wrong shape, 1 a non-finite entry; or
# STRIDED: an argument is not a contiguous, aligned vector (the caller converts).
OK = 0
STRIDED = -1


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
    """The typing and code of :func:`view`: ``buf[offset:]`` viewed as a
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


view: Any = intrinsic(_view_typing)


@nb.njit(inline="always")
def unpack(buf: F64) -> ArmArrays:  # pragma: no cover - compiled
    """The :class:`ArmArrays` that :func:`pack_buffer` packed, as views of ``buf``."""
    n_links = view(buf, 0, (1,), np.int64)[0]
    o = HEADER + n_links + 1
    ints = view(buf, 0, (o,), np.int64)
    n, n_joints, k = ints[1], ints[2], ints[3]
    ms = view(buf, HEADER, (n_links + 1,), np.int64)
    link = view(buf, o, (n_links, N_LINK_COLUMNS), np.float64)
    o += n_links * N_LINK_COLUMNS
    vectors = view(buf, o, (4, n), np.float64)  # the four modal integrals
    o += 4 * n
    modal_mass = view(buf, o, (n, n), np.float64)
    o += n * n
    stiffness = view(buf, o, (n,), np.float64)
    damping = view(buf, o + n, (n,), np.float64)
    payload = view(buf, o + 2 * n, (2,), np.float64)
    o += 2 * n + 2
    joint = view(buf, o, (n_joints, N_JOINT_COLUMNS), np.float64)
    o += n_joints * N_JOINT_COLUMNS
    shortening = view(buf, o, (3, n, n), np.float64)  # tip, mass, moment
    o += 3 * n * n
    shortening_cubic = view(buf, o, (n, k, k), np.float64)
    o += n * k * k
    shortening_quartic = view(buf, o, (n, k, k, k), np.float64)
    o += n * k * k * k
    gravity = view(buf, o, (2,), np.float64)
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
        gravity=gravity,
    )


@nb.njit(inline="always")
def sizes(buf: F64) -> tuple[int, int]:  # pragma: no cover - compiled
    """``(n_links, n_dof)`` of the packed arm."""
    ints = view(buf, 0, (2,), np.int64)
    return ints[0], ints[1]


@nb.njit(inline="always")
def workspace(wbuf: F64, n: int, mass: F64) -> Workspace:  # pragma: no cover - compiled
    """``wbuf`` viewed as the :class:`Workspace` of :func:`flexarm.model.arrays.make_workspace`
    (the layout of :func:`flexarm.model.arrays.workspace_shapes`), with ``mass``
    (n, n) in place of its first array."""
    o = n * n
    bias = view(wbuf, o, (n,), np.float64)
    o += n
    jac = view(wbuf, o, (2, n), np.float64)
    o += 2 * n
    angle = view(wbuf, o, (n,), np.float64)
    o += n
    rhs = view(wbuf, o, (n,), np.float64)
    o += n
    rows = view(wbuf, o, (3, n), np.float64)
    o += 3 * n
    lmass = view(wbuf, o, (n, n), np.float64)
    o += n * n
    lbias = view(wbuf, o, (n,), np.float64)
    o += n
    inv_diag = view(wbuf, o, (n,), np.float64)
    o += n
    axial = view(wbuf, o, (AX_ROWS + 3 * n, max(n, 3)), np.float64)
    o += (AX_ROWS + 3 * n) * max(n, 3)
    chain = view(wbuf, o, (n, N_CHAIN_COLUMNS), np.float64)
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
def own_mass(wbuf: F64, n: int) -> F64:  # pragma: no cover - compiled
    """The first ``n * n`` values of ``wbuf``: the workspace's own ``mass`` (n, n)."""
    mass: F64 = view(wbuf, 0, (n, n), np.float64)
    return mass


def _address_typing(typingctx, x):  # type: ignore[no-untyped-def]
    """The typing and code of :func:`address`: the address of ``x``'s first item."""

    def codegen(context, builder, sig, args):  # type: ignore[no-untyped-def]
        arr = make_array(sig.args[0])(context, builder, args[0])  # type: ignore[no-untyped-call]
        return builder.ptrtoint(arr.data, context.get_value_type(nt.intp))

    return nt.intp(x), codegen


address: Any = intrinsic(_address_typing)


@nb.njit(inline="always")
def contiguous(x: F64) -> bool:  # pragma: no cover - compiled
    """Whether the vector ``x`` is what its type says, contiguous and aligned: an
    entry point called without Numba's dispatch (which would have refused
    anything else) gets such arrays only if it checks."""
    return x.strides[0] == 8 and address(x) % 8 == 0


@nb.njit(inline="always")
def vector_status(x: F64, n: int, arg: int) -> int:  # pragma: no cover - compiled
    """Status of one vector argument: shape ``(n,)`` and finite entries."""
    if x.shape[0] != n:
        return 1 + 2 * arg
    for r in range(n):
        if not math.isfinite(x[r]):
            return 2 + 2 * arg
    return OK


@nb.njit(inline="always")
def rows_status(x: F64, m: int, n: int, arg: int) -> int:  # pragma: no cover - compiled
    """Status of one batch argument: shape ``(m, n)`` and finite entries."""
    if x.shape[0] != m or x.shape[1] != n:
        return 1 + 2 * arg
    for b in range(m):
        for r in range(n):
            if not math.isfinite(x[b, r]):
                return 2 + 2 * arg
    return OK


@nb.njit(inline="always")
def state_status(q: F64, dq: F64, tau: F64, buf: F64) -> int:  # pragma: no cover - compiled
    """Status of a state: ``q, dq`` of shape (n_dof,), ``tau`` (n_links,), finite;
    :data:`STRIDED` first if one of them is not contiguous and aligned."""
    if not (contiguous(q) and contiguous(dq) and contiguous(tau)):
        return STRIDED
    n_links, n = sizes(buf)
    status = vector_status(q, n, 0)
    if status == OK:
        status = vector_status(dq, n, 1)
    if status == OK:
        status = vector_status(tau, n_links, 2)
    return status


@nb.njit(inline="always")
def states_status(q: F64, dq: F64, tau: F64, buf: F64) -> int:  # pragma: no cover - compiled
    """:func:`state_status` for a batch: ``(m, n_dof)``, ``(m, n_dof)``, ``(m, n_links)``."""
    n_links, n = sizes(buf)
    m = q.shape[0]
    status = rows_status(q, m, n, 0)
    if status == OK:
        status = rows_status(dq, m, n, 1)
    if status == OK:
        status = rows_status(tau, m, n_links, 2)
    return status


def _stack_typing(typingctx, size):  # type: ignore[no-untyped-def]
    """The typing and code of :func:`stack`: ``size`` float64 values on the stack of
    the compiled function that calls it (a dynamic ``alloca``), uninitialised,
    freed when that function returns. Only for the entry points of
    :mod:`flexarm.model.packed`, called once a call and never inlined into a loop;
    ``size`` at most :data:`flexarm.model.packed.STACK_FLOATS`."""
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


stack: Any = intrinsic(_stack_typing)


@nb.njit(inline="always")
def scratch_size(n: int) -> int:  # pragma: no cover - compiled
    """:func:`flexarm.model.arrays.workspace_size` of ``n`` coordinates."""
    return 2 * n * n + (10 + N_CHAIN_COLUMNS) * n + (AX_ROWS + 3 * n) * max(n, 3)


@nb.njit(inline="always")
def scratch(out: F64, used: int, size: int) -> F64:  # pragma: no cover - compiled
    """A workspace of ``size`` values: ``out``'s tail after its first ``used`` values
    when the caller made it that long (an arm too large for the stack), else on
    the stack of the entry point."""
    if out.size >= used + size:
        wbuf: F64 = view(out, used, (size,), np.float64)
        return wbuf
    return stack(size)  # type: ignore[no-any-return]


@nb.njit
def unpacked(buf: F64) -> ArmArrays:  # pragma: no cover - compiled
    """:func:`unpack` as a function (with the refcount runtime), for tests."""
    return unpack(buf)
