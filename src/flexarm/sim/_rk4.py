"""The integrator's compiled half: RK4 steps and the divergence test, unchecked.

Internal module (plain names, bare compiled kernels): what the closed loop, the
open loop, prescribed motion and the environments' step call at every substep.
:mod:`flexarm.sim.integrator` documents them and gives their checked public faces.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .._compile import njit_runtime_free
from ..model.arrays import ArmArrays, Workspace
from ..model.dynamics import forward_dynamics_general
from ..model.dynamics._two_links import accelerations_two_links_one_mode

__all__ = ["DIVERGENCE_RATE", "diverged", "rk4_step", "rk4_step_two_links_one_mode"]

F64 = NDArray[np.float64]

DIVERGENCE_RATE = 1e12
"""A coordinate rate above this (rad/s or modal units per s) counts as divergence."""


@nb.njit(cache=True, nogil=True, inline="always")
def diverged(q: F64, dq: F64, model: ArmArrays, max_deflection: F64) -> bool:  # pragma: no cover
    """Whether the state is non-finite, a rate exceeds :data:`DIVERGENCE_RATE`, or a
    link's tip deflection exceeds ``max_deflection`` (m, shape (n_links,))."""
    for r in range(q.shape[0]):
        if not (np.isfinite(q[r]) and np.isfinite(dq[r])):
            return True
        if abs(dq[r]) > DIVERGENCE_RATE:
            return True
    ms = model.mode_start
    for i in range(model.link.shape[0]):
        e = 0.0
        for r in range(ms[i], ms[i + 1]):
            e += model.tip_deflection[r] * q[r]
        if abs(e) > max_deflection[i]:
            return True
    return False


_RK4_C = (0.0, 0.5, 0.5, 1.0)
_RK4_W = (1.0, 2.0, 2.0, 1.0)


@nb.njit(cache=True, nogil=True, inline="always")
def _stage_state(q: F64, dq: F64, h: float, s: F64, stage: int) -> None:  # pragma: no cover
    """The state of RK4 stage ``stage`` into ``s[0], s[1]`` (``qs, vs``), formed in
    place from the previous stage's: ``qs = q + c vs`` before ``vs = dq + c acc``."""
    qs, vs, acc = s[0], s[1], s[2]
    if stage == 0:
        for r in range(q.shape[0]):
            qs[r] = q[r]
            vs[r] = dq[r]
    else:
        c = _RK4_C[stage] * h
        for r in range(q.shape[0]):
            qs[r] = q[r] + c * vs[r]
            vs[r] = dq[r] + c * acc[r]


@nb.njit(cache=True, nogil=True, inline="always")
def _stage_sum(s: F64, stage: int) -> None:  # pragma: no cover - compiled
    """Add stage ``stage``'s rates ``s[1], s[2]`` to the weighted sums ``s[3], s[4]``
    (the first stage starts them)."""
    vs, acc, sum_v, sum_a = s[1], s[2], s[3], s[4]
    if stage == 0:
        for r in range(vs.shape[0]):
            sum_v[r] = vs[r]
            sum_a[r] = acc[r]
    else:
        w = _RK4_W[stage]
        for r in range(vs.shape[0]):
            sum_v[r] += w * vs[r]
            sum_a[r] += w * acc[r]


@nb.njit(cache=True, nogil=True, inline="always")
def _rk4_update(q: F64, dq: F64, h: float, s: F64) -> None:  # pragma: no cover - compiled
    c6 = h / 6.0
    sum_v, sum_a = s[3], s[4]
    for r in range(q.shape[0]):
        q[r] += c6 * sum_v[r]
        dq[r] += c6 * sum_a[r]


@njit_runtime_free(cache=True, nogil=True)
def rk4_step(
    q: F64,
    dq: F64,
    tau0: F64,
    tau_mid: F64,
    tau1: F64,
    h: float,
    model: ArmArrays,
    ws: Workspace,
    s: F64,
) -> None:  # pragma: no cover - compiled
    """One classical RK4 step of ``qdd = f(q, dq, tau)`` in place; ``s`` is (6, n) scratch.

    ``tau0``, ``tau_mid``, ``tau1`` (N m, shape (n_links,)) are the torques at the
    start, the middle and the end of the step (the same array three times for a
    torque held over the step). The four stages run in a loop with a single
    call of the dynamics, so the (inlined) kernel is compiled once. This is the
    general kernel; :func:`rk4_step_two_links_one_mode` is the same step for the
    paper's structure.
    """
    for stage in range(4):
        _stage_state(q, dq, h, s, stage)
        tau = tau0 if stage == 0 else (tau_mid if stage < 3 else tau1)
        forward_dynamics_general(s[0], s[1], tau, model, ws, s[2])
        _stage_sum(s, stage)
    _rk4_update(q, dq, h, s)


@nb.njit(cache=True, nogil=True, inline="always")
def rk4_step_two_links_one_mode(
    q: F64, dq: F64, tau0: F64, tau_mid: F64, tau1: F64, h: float, model: ArmArrays
) -> None:  # pragma: no cover - compiled
    """:func:`rk4_step` for two links with one mode each and rigid joints, in scalars
    (:func:`flexarm.model.dynamics.accelerations_two_links_one_mode`): the stage
    states and sums stay in registers. Same operations in the same order as
    :func:`rk4_step`.

    Inlined into the loops that call it, so a step passes no arrays through a
    call; :func:`rk4_step` is called, not inlined, so that the general kernel is
    compiled once.
    """
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    v0, v1, v2, v3 = dq[0], dq[1], dq[2], dq[3]
    qs0, qs1, qs2, qs3 = q0, q1, q2, q3
    vs0, vs1, vs2, vs3 = v0, v1, v2, v3
    a0 = a1 = a2 = a3 = 0.0
    sv0 = sv1 = sv2 = sv3 = 0.0
    sa0 = sa1 = sa2 = sa3 = 0.0
    for stage in range(4):
        if stage > 0:
            c = _RK4_C[stage] * h
            qs0, qs1, qs2, qs3 = q0 + c * vs0, q1 + c * vs1, q2 + c * vs2, q3 + c * vs3
            vs0, vs1, vs2, vs3 = v0 + c * a0, v1 + c * a1, v2 + c * a2, v3 + c * a3
        tau = tau0 if stage == 0 else (tau_mid if stage < 3 else tau1)
        t0, t1 = tau[0], tau[1]
        a0, a1, a2, a3 = accelerations_two_links_one_mode(
            qs0, qs1, qs2, qs3, vs0, vs1, vs2, vs3, t0, t1, model
        )
        if stage == 0:
            sv0, sv1, sv2, sv3 = vs0, vs1, vs2, vs3
            sa0, sa1, sa2, sa3 = a0, a1, a2, a3
        else:
            w = _RK4_W[stage]
            sv0, sv1, sv2, sv3 = sv0 + w * vs0, sv1 + w * vs1, sv2 + w * vs2, sv3 + w * vs3
            sa0, sa1, sa2, sa3 = sa0 + w * a0, sa1 + w * a1, sa2 + w * a2, sa3 + w * a3
    c6 = h / 6.0
    q[0], q[1], q[2], q[3] = q0 + c6 * sv0, q1 + c6 * sv1, q2 + c6 * sv2, q3 + c6 * sv3
    dq[0], dq[1], dq[2], dq[3] = v0 + c6 * sa0, v1 + c6 * sa1, v2 + c6 * sa2, v3 + c6 * sa3
