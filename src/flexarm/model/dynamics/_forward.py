"""Which forward-dynamics kernel an arm takes, compiled: :func:`forward_dynamics`.

Internal: the bare kernels behind :func:`flexarm.model.dynamics.forward_dynamics`,
:func:`flexarm.model.dynamics.forward_dynamics_general` and
:func:`flexarm.model.dynamics.forward_dynamics_recursive` (that module describes the
three algorithms and when each is taken).
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ..arrays import ArmArrays, Workspace
from ._dense import forward_dynamics_dense, generalized_forces
from ._recursive import accelerations_recursive
from ._two_links import forward_dynamics_two_links_one_mode, is_two_links_one_mode

__all__ = [
    "RECURSIVE_FROM_LINKS",
    "forward_dynamics",
    "forward_dynamics_general",
    "forward_dynamics_recursive",
    "prefers_recursive",
]

F64 = NDArray[np.float64]

RECURSIVE_FROM_LINKS = 3
"""Arms with this many links or more take the recursive algorithm (measured,
BENCHMARKS.md "Cost growth"); fewer links, the dense one."""


@nb.njit(cache=True, nogil=True, inline="always")
def forward_dynamics_recursive(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`forward_dynamics` for any structure by the articulated-body recursion
    (:mod:`._recursive`), in time linear in the links."""
    generalized_forces(q, dq, tau, arrays, ws.rhs)
    accelerations_recursive(q, dq, arrays, ws, ddq)


@nb.njit(cache=True, nogil=True, inline="always")
def prefers_recursive(arrays: ArmArrays) -> bool:  # pragma: no cover - compiled
    """Whether the recursive algorithm is the faster for this structure: from
    RECURSIVE_FROM_LINKS links on (BENCHMARKS.md, "Cost growth")."""
    return bool(arrays.link.shape[0] >= RECURSIVE_FROM_LINKS)


@nb.njit(cache=True, nogil=True, inline="always")
def forward_dynamics_general(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`forward_dynamics` for any structure: :func:`forward_dynamics_recursive`
    or :func:`forward_dynamics_dense`, whichever is the faster for it
    (:func:`prefers_recursive`); the parameters are those of
    :func:`forward_dynamics`."""
    if prefers_recursive(arrays):
        forward_dynamics_recursive(q, dq, tau, arrays, ws, ddq)
    else:
        forward_dynamics_dense(q, dq, tau, arrays, ws, ddq)


@nb.njit(cache=True, nogil=True, inline="always")
def forward_dynamics(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """``ddq = M(q)^-1 (B tau - C(q, dq) dq - K q - D dq + joint forces - dV/dq)``
    into ``ddq`` (``V`` the gravity potential, :mod:`flexarm.model.gravity`; none without).

    Two links with one mode each and rigid joints (the paper's structure) take
    the scalar kernel :func:`forward_dynamics_two_links_one_mode`, which
    computes the dense kernel's quantities in the same order; every other arm
    :func:`forward_dynamics_general` (the dense kernel up to two links, the
    recursive one from :data:`RECURSIVE_FROM_LINKS` on).

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
    tau : ndarray, shape (n_links,)
        Joint torques in N m: on the joint angles for rigid joints, on the motor
        angles for flexible joints.
    arrays : ArmArrays
    ws : Workspace
        Scratch (overwritten; not used by the scalar kernel).
    ddq : ndarray, shape (n_dof,)
        Output accelerations.
    """
    if is_two_links_one_mode(arrays):
        forward_dynamics_two_links_one_mode(q, dq, tau, arrays, ddq)
    else:
        forward_dynamics_general(q, dq, tau, arrays, ws, ddq)
