"""The compiled closed loop: sampled-data control, zero-order hold, RK4 substeps.

One Numba function runs a whole simulation (or a chunk of one) without
returning to Python: at every control instant ``t_k = k dt`` it forms the
measurement (sensor, delay, noise, quantisation), calls the controller through
its C function pointer, saturates and holds the torque, then integrates the
plant over ``[t_k, t_k + dt]`` with ``substeps`` fixed RK4 steps. Delays act at
substep resolution: the exact delay is a ring buffer of the sensed signal
(delay rounded to whole substeps), the Padé delay a discrete state-space
filter discretised exactly over one substep (zero-order hold on its input).

Everything is plain arrays; :func:`flexarm.sim.simulate.simulate` prepares them.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ..model.dynamics import (
    LEN,
    ArmArrays,
    Workspace,
    accelerations_two_links_one_mode,
    forward_dynamics_general,
    is_two_links_one_mode,
    njit_runtime_free,
    point_kinematics,
)

__all__ = ["LoopState", "SensorArrays", "run", "sense"]

F64 = NDArray[np.float64]

OK, DIVERGED = 0, 1


class SensorArrays(NamedTuple):
    """The sensor as plain arrays.

    link: int64 (1,) — link of the sensed point, -1 for the joint encoders.
    distance: (1,) — distance of the point along its link, m.
    phi: (n_modes of link,) — mode shapes at the point.
    delay_steps: int64 (1,) — exact delay in substeps (0: none unless Padé).
    pade_ad, pade_bd, pade_cd, pade_dd: discrete Padé filter (order p): (p, p), (p,),
        (p,), (1,); p = 0 for no Padé.
    noise: (n_steps + 1, n_channels) additive noise per control instant, or (0, n_channels).
    resolution: (n_channels,) quantisation steps (0: none).
    """

    link: NDArray[np.int64]
    distance: F64
    phi: F64
    delay_steps: NDArray[np.int64]
    pade_ad: F64
    pade_bd: F64
    pade_cd: F64
    pade_dd: F64
    noise: F64
    resolution: F64


class LoopState(NamedTuple):
    """Everything that carries over between chunks (updated in place)."""

    q: F64  # (n,)
    dq: F64  # (n,)
    tau: F64  # (N,) held torque
    ctrl_state: F64  # (s,)
    buffer: F64  # (delay_steps + 1, n_channels) ring of sensed signals
    cursor: NDArray[np.int64]  # (1,) substeps integrated so far
    pade_x: F64  # (n_channels, p) filter states
    scratch: F64  # (6, n) RK4 stages
    ws: Workspace  # dynamics scratch
    signals: F64  # (2 n_channels + n_y + max(p, 1),) signal scratch

    @staticmethod
    def signal_size(n_channels: int, n_y: int, order: int) -> int:
        return 2 * n_channels + n_y + max(order, 1)


@nb.njit(cache=True, nogil=True, inline="always")
def _collocated(q: F64, dq: F64, model: ArmArrays, i: int, n_links: int) -> tuple[float, float]:
    """Encoder angle and rate of joint ``i``: the motor with flexible joints."""
    if model.joint.shape[0] > 0:
        m = model.mode_start[n_links] + i
        return q[m], dq[m]
    return q[i], dq[i]


@nb.njit(cache=True, nogil=True, inline="always")
def sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw (true, undelayed) sensed signal.

    Inlined where :func:`run` calls it (the model's and the sensor's arrays would
    otherwise be passed through a call at every control step).
    """
    n_links = model.link.shape[0]
    link = sensor.link[0]
    if link < 0:
        for i in range(n_links):
            a, r = _collocated(q, dq, model, i, n_links)
            out[i] = a
            out[n_links + i] = r
    else:
        point_kinematics(q, dq, model, link, sensor.distance[0], sensor.phi, out)


@nb.njit(cache=True, nogil=True, inline="always")
def _diverged(q: F64, dq: F64, model: ArmArrays, max_deflection: F64) -> bool:
    for r in range(q.shape[0]):
        if not (np.isfinite(q[r]) and np.isfinite(dq[r])):
            return True
        if abs(dq[r]) > 1e12:
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
def _rk4(
    q: F64, dq: F64, tau: F64, h: float, model: ArmArrays, ws: Workspace, s: F64
) -> None:  # pragma: no cover - compiled
    """One classical RK4 step of ``qdd = f(q, dq, tau)`` in place; ``s`` is (6, n) scratch.

    The four stages run in a loop with a single call of the dynamics, so the
    (inlined) kernel is compiled once. This is the general kernel;
    :func:`_rk4_two_links_one_mode` is the same step for the paper's structure.
    """
    for stage in range(4):
        _stage_state(q, dq, h, s, stage)
        forward_dynamics_general(s[0], s[1], tau, model, ws, s[2])
        _stage_sum(s, stage)
    _rk4_update(q, dq, h, s)


@nb.njit(cache=True, nogil=True, inline="always")
def _rk4_two_links_one_mode(
    q: F64, dq: F64, tau: F64, h: float, model: ArmArrays
) -> None:  # pragma: no cover - compiled
    """:func:`_rk4` for two links with one mode each and rigid joints, in scalars
    (:func:`flexarm.model.dynamics.accelerations_two_links_one_mode`): the stage states
    and sums stay in registers. Same operations in the same order as :func:`_rk4`.

    Inlined into :func:`run`, so a step passes no arrays through a call; kept
    apart from :func:`_rk4` (which :func:`run` calls) so that each kernel is
    inlined into one function only, which keeps the first compilation short.
    """
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    v0, v1, v2, v3 = dq[0], dq[1], dq[2], dq[3]
    t0, t1 = tau[0], tau[1]
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


@njit_runtime_free(cache=True, nogil=True)
def run(
    model: ArmArrays,
    control: Any,  # FunctionType: see flexarm.control.controllers.CONTROL_SIGNATURE
    params: F64,
    sensor: SensorArrays,
    reference: F64,
    dt: float,
    substeps: int,
    torque_limit: F64,
    max_deflection: F64,
    state: LoopState,
    k0: int,
    k1: int,
    out_q: F64,
    out_dq: F64,
    out_tau: F64,
    out_y: F64,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Advance the loop over control instants ``k0 <= k < k1`` (record at each ``k``,
    then act and integrate to ``k + 1`` unless ``k`` is the last row of ``reference``).

    Returns ``(status, k)``: status 0 and ``k1`` when done, 1 and the last recorded
    instant when the state diverged (non-finite, rates above 1e12, or a link's tip
    deflection above ``max_deflection``).
    """
    n = state.q.shape[0]
    n_links = model.link.shape[0]
    ms = model.mode_start
    n_modes = ms[n_links] - n_links
    n_steps = reference.shape[0] - 1
    h = dt / substeps
    ws = state.ws
    q, dq, tau = state.q, state.dq, state.tau
    n_ch = state.buffer.shape[1]
    n_y = out_y.shape[1]
    sig = state.signals  # views into preallocated scratch: no allocation here
    raw = sig[0:n_ch]
    delayed = sig[n_ch : 2 * n_ch]
    y = sig[2 * n_ch : 2 * n_ch + n_y]
    x_new = sig[2 * n_ch + n_y :]
    n_buf = state.buffer.shape[0]
    order = sensor.pade_ad.shape[0]
    has_noise = sensor.noise.shape[0] > 0
    joint_sensor = sensor.link[0] < 0
    two_links_one_mode = is_two_links_one_mode(model)
    for k in range(k0, k1):
        # ---- measure: the delayed sensed signal, then noise and quantisation
        sense(q, dq, model, sensor, raw)
        cur = state.cursor[0]
        if n_buf > 1:
            src = cur - (n_buf - 1)
            if src < 0:
                src = 0
            for c in range(n_ch):
                delayed[c] = state.buffer[src % n_buf, c]
        elif order > 0:
            for c in range(n_ch):
                acc = sensor.pade_dd[0] * raw[c]
                for j in range(order):
                    acc += sensor.pade_cd[j] * state.pade_x[c, j]
                delayed[c] = acc
        else:
            for c in range(n_ch):
                delayed[c] = raw[c]
        for c in range(n_ch):
            v = delayed[c]
            if has_noise:
                v += sensor.noise[k, c]
            res = sensor.resolution[c]
            if res > 0.0:
                v = np.round(v / res) * res
            delayed[c] = v
        if joint_sensor:
            # rigid kinematics of the measured angles
            px = 0.0
            py = 0.0
            vx = 0.0
            vy = 0.0
            phi = 0.0
            phid = 0.0
            for i in range(n_links):
                y[i] = delayed[i]
                y[n_links + i] = delayed[n_links + i]
                phi += delayed[i]
                phid += delayed[n_links + i]
                L = model.link[i, LEN]
                px += L * np.cos(phi)
                py += L * np.sin(phi)
                vx -= L * np.sin(phi) * phid
                vy += L * np.cos(phi) * phid
            y[2 * n_links] = px
            y[2 * n_links + 1] = py
            y[2 * n_links + 2] = vx
            y[2 * n_links + 3] = vy
        else:
            for i in range(n_links):
                a, r = _collocated(q, dq, model, i, n_links)
                y[i] = a
                y[n_links + i] = r
            for c in range(4):
                y[2 * n_links + c] = delayed[c]
        for j in range(n_modes):
            y[2 * n_links + 4 + j] = q[n_links + j]
        # ---- record
        for r in range(n):
            out_q[k, r] = q[r]
            out_dq[k, r] = dq[r]
        for c in range(y.shape[0]):
            out_y[k, c] = y[c]
        if k == n_steps:
            for i in range(n_links):
                out_tau[k, i] = tau[i]
            return OK, k1
        # ---- act: control law, saturation, zero-order hold
        rk = reference[k]
        control(
            k * dt,
            y.ctypes,
            y.shape[0],
            rk.ctypes,
            rk.shape[0],
            params.ctypes,
            params.shape[0],
            state.ctrl_state.ctypes,
            state.ctrl_state.shape[0],
            tau.ctypes,
            n_links,
        )
        for i in range(n_links):
            lim = torque_limit[i]
            if tau[i] > lim:
                tau[i] = lim
            elif tau[i] < -lim:
                tau[i] = -lim
            out_tau[k, i] = tau[i]
        # ---- integrate to t_{k+1}
        for _ in range(substeps):
            if order > 0:  # Padé filter: x <- Ad x + Bd u over this substep
                sense(q, dq, model, sensor, raw)
                for c in range(n_ch):
                    for j in range(order):
                        acc = sensor.pade_bd[j] * raw[c]
                        for i2 in range(order):
                            acc += sensor.pade_ad[j, i2] * state.pade_x[c, i2]
                        x_new[j] = acc
                    for j in range(order):
                        state.pade_x[c, j] = x_new[j]
            if two_links_one_mode:
                _rk4_two_links_one_mode(q, dq, tau, h, model)
            else:
                _rk4(q, dq, tau, h, model, ws, state.scratch)
            state.cursor[0] += 1
            if n_buf > 1:
                sense(q, dq, model, sensor, raw)
                slot = state.cursor[0] % n_buf
                for c in range(n_ch):
                    state.buffer[slot, c] = raw[c]
            if _diverged(q, dq, model, max_deflection):
                return DIVERGED, k
    return OK, k1
