"""The compiled step of a batch of arms: one environment step of many arms in one call.

:func:`step_batch` advances arms ``i0 <= i < i1`` of a batch over one control
period each: the action (N m) is clipped to the torque limits and held (zero-order
hold) over ``substeps`` RK4 steps of the compiled dynamics
(:func:`flexarm.sim.integrator.rk4_step`, or its two-link one-mode form; gravity
in them where the arm has it), the sensed signal passes through the transport
delay at substep resolution with the closed loop's own compiled sensor
(:mod:`flexarm.sensing.channels`), then the observation, the tracking error and
the reward are formed at the new instant.
With gravity compensation (``BatchState.gravity`` not empty) the holding torques
of the posture measured at the step's start
(:func:`flexarm.control.gravity_compensation.holding_torques`) are added to the
action before the limits clip it, as the closed loop adds them to a law's torque.
:func:`reset_batch` starts arms whose state was set (the delay line primed at
steady state, as :func:`flexarm.simulate` does).

Both are ``nogil`` and allocate nothing: every array is preallocated in
:class:`BatchState` (per arm), :class:`EnvArrays` (shared, constant) and
:class:`Scratch` (per thread), so threads can step disjoint ranges of one batch
at once.

Observation layout (``n_ch`` sensed channels, then the reference)::

    obs[0:n_ch]        the sensor's channels: joint angles (rad, wrapped to [-pi, pi))
                       then rates (rad/s); or the point's x, y (m) then vx, vy (m/s);
                       delayed, noisy, quantised
    obs[n_ch:n_ch+2]   the reference's position at the current instant, m
    obs[n_ch+2:n_ch+4] its velocity, m/s

clipped into ``[low, high]`` (the observation space's bounds).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from .._compile import njit_runtime_free
from .._types import F64, I64
from ..control.gravity_compensation import holding_torques
from ..model.arrays import ArmArrays, Workspace
from ..model.dynamics._points import point_kinematics
from ..model.dynamics._two_links import is_two_links_one_mode
from ..sensing import _channels
from ..sensing.channels import SensorArrays
from ..sim import _rk4

__all__ = [
    "DIVERGED",
    "RUNNING",
    "TRUNCATED",
    "BatchState",
    "EnvArrays",
    "Scratch",
    "reset_batch",
    "step_batch",
]


RUNNING, DIVERGED, TRUNCATED = 0, 1, 2
"""Status of an arm after a step: going on, terminated by divergence, at the episode's end."""


class EnvArrays(NamedTuple):
    """What every arm of a batch shares (constant over episodes).

    Attributes
    ----------
    sensor : SensorArrays
        The sensor, its delay and its noise levels
        (:class:`flexarm.sensing.channels.SensorArrays`; the draws come from
        ``BatchState.noise``).
    target : (n_steps + 1, 4)
        The reference's x, y (m), vx, vy (m/s) at each instant.
    limit : (n_links,)
        Torque limits, N m.
    max_deflection : (n_links,)
        Tip deflections beyond which the arm diverged, m.
    tip_phi : (n_modes of the last link,)
        The last link's mode shapes at its tip.
    low, high : (n_obs,)
        Bounds of the observation.
    params : (5,)
        Control period dt (s), tracking weight (1/m**2), effort weight,
        divergence penalty, joint-rate limit (rad/s).
    counts : int64 (2,)
        RK4 substeps per period, steps per episode.
    """

    sensor: SensorArrays
    target: F64
    limit: F64
    max_deflection: F64
    tip_phi: F64
    low: F64
    high: F64
    params: F64
    counts: I64


class BatchState(NamedTuple):
    """The run state of ``B`` arms (row ``i`` is arm ``i``), updated in place.

    - ``q``, ``dq``: (B, n_dof) coordinates and rates.
    - ``tau``: (B, n_links) the torque held over the current period, N m.
    - ``buffer``: (B, delay_steps + 1, n_ch) ring of sensed signals (exact delay).
    - ``cursor``: int64 (B,) substeps integrated in the episode.
    - ``pade_x``: (B, n_ch, p) Padé filter states.
    - ``noise``: (B, rows, n_ch) standard normal draws (rows = 0: noise-free).
    - ``noise_row``: int64 (B,) next unused row of ``noise``.
    - ``k``: int64 (B,) control instant of the episode.
    - ``obs``: (B, n_obs) the last observation.
    - ``reward``: (B,) the last step's reward.
    - ``error``: (B,) end-effector tracking error at instant ``k``, m.
    - ``status``: int64 (B,) :data:`RUNNING`, :data:`DIVERGED` or :data:`TRUNCATED`.
    - ``angles``: (B, n_links) the joint angles measured at instant ``k``, rad (the sensor's
      delayed, noisy encoder angles, unwrapped; the collocated angles for a point or tip
      sensor).
    - ``gravity``: (B, scratch_size + n_links) gravity compensation: the scratch of
      :func:`~flexarm.control.gravity_compensation.holding_torques` (the last sag found),
      then its torques; (B, 0): off.
    """

    q: F64
    dq: F64
    tau: F64
    buffer: F64
    cursor: I64
    pade_x: F64
    noise: F64
    noise_row: I64
    k: I64
    obs: F64
    reward: F64
    error: F64
    status: I64
    angles: F64
    gravity: F64


class Scratch(NamedTuple):
    """Scratch of one thread: RK4 stages (6, n_dof), the dynamics' workspace, and
    the signal scratch (2 n_ch + max(p, 1) + 4,)."""

    stages: F64
    ws: Workspace
    signals: F64


@njit_runtime_free(cache=True, nogil=True)
def _observe(
    model: ArmArrays, env: EnvArrays, state: BatchState, i: int, sig: F64
) -> None:  # pragma: no cover - compiled
    """Observation, tracking error of arm ``i`` at its instant ``k`` (consumes a noise row)."""
    sensor = env.sensor
    n_links = model.link.shape[0]
    n_ch = sensor.levels.shape[0]
    q, dq = state.q[i], state.dq[i]
    raw = sig[0:n_ch]
    delayed = sig[n_ch : 2 * n_ch]
    point = sig[sig.shape[0] - 4 :]
    _channels.sense(q, dq, model, sensor, raw)
    _channels.delayed_signal(
        sensor, state.buffer[i], state.pade_x[i], state.cursor[i], raw, delayed
    )
    has_noise = state.noise.shape[1] > 0
    row = state.noise_row[i]
    if has_noise:
        _channels.corrupt(sensor, True, state.noise[i, row], delayed)
        state.noise_row[i] = row + 1
    else:
        _channels.corrupt(sensor, False, raw, delayed)
    joint = sensor.link[0] < 0
    angles = state.angles[i]
    for j in range(n_links):  # what the closed loop's law and compensation are given
        if joint:
            angles[j] = delayed[j]
        else:
            angles[j] = _channels.collocated(q, dq, model, j, n_links)[0]
    obs = state.obs[i]
    for c in range(n_ch):
        v = delayed[c]
        if joint and c < n_links:  # encoder angles wrapped to [-pi, pi)
            v -= 2.0 * math.pi * math.floor((v + math.pi) / (2.0 * math.pi))
        obs[c] = v
    k = state.k[i]
    for c in range(4):
        obs[n_ch + c] = env.target[k, c]
    for c in range(obs.shape[0]):
        if obs[c] < env.low[c]:
            obs[c] = env.low[c]
        elif obs[c] > env.high[c]:
            obs[c] = env.high[c]
    last = n_links - 1
    point_kinematics(q, dq, model, last, model.link[last, 0], env.tip_phi, point)
    state.error[i] = math.hypot(point[0] - env.target[k, 0], point[1] - env.target[k, 1])


@njit_runtime_free(cache=True, nogil=True)
def reset_batch(
    model: ArmArrays, env: EnvArrays, state: BatchState, mask: I64, i0: int, i1: int, sig: F64
) -> None:  # pragma: no cover - compiled
    """Start the episodes of arms ``i0 <= i < i1`` with ``mask[i]`` (their ``q, dq``
    and noise already set): instant 0, the delay line at steady state on the
    initial sensed signal, the first observation."""
    n_ch = env.sensor.levels.shape[0]
    raw = sig[0:n_ch]
    for i in range(i0, i1):
        if not mask[i]:
            continue
        _channels.prime(
            state.q[i], state.dq[i], model, env.sensor, state.buffer[i], state.pade_x[i], raw
        )
        for j in range(state.tau.shape[1]):
            state.tau[i, j] = 0.0
        for j in range(state.gravity.shape[1]):  # the compensation's sag: from straight
            state.gravity[i, j] = 0.0
        state.cursor[i] = 0
        state.k[i] = 0
        state.reward[i] = 0.0
        state.status[i] = RUNNING
        _observe(model, env, state, i, sig)


@njit_runtime_free(cache=True, nogil=True)
def step_batch(
    model: ArmArrays,
    env: EnvArrays,
    state: BatchState,
    action: F64,
    active: I64,
    i0: int,
    i1: int,
    scratch: Scratch,
) -> None:  # pragma: no cover - compiled
    """One control period of arms ``i0 <= i < i1`` with ``active[i]``: hold
    ``action[i]`` (N m; plus the holding torques with gravity compensation; clipped
    to the limits), integrate, observe, reward.

    Sets ``state.status[i]`` to :data:`DIVERGED` (the state left finite limits,
    a tip deflection or a joint rate its bound; the observation is left as it
    was and the reward is ``-divergence_penalty``), :data:`TRUNCATED` (the
    episode's last instant reached) or :data:`RUNNING`.
    """
    sensor = env.sensor
    n_links = model.link.shape[0]
    n_ch = sensor.levels.shape[0]
    dt = env.params[0]
    substeps = env.counts[0]
    n_steps = env.counts[1]
    h = dt / substeps
    sig = scratch.signals
    raw = sig[0:n_ch]
    x_new = sig[2 * n_ch : sig.shape[0] - 4]
    two_links_one_mode = is_two_links_one_mode(model)
    n_hold = state.gravity.shape[1]
    compensate = n_hold > 0
    for i in range(i0, i1):
        if not active[i]:
            continue
        q, dq, tau = state.q[i], state.dq[i], state.tau[i]
        hold = state.gravity[i, n_hold - n_links :]
        if compensate:  # the holding torques of the measured posture
            holding_torques(state.angles[i], model, state.gravity[i, : n_hold - n_links], hold)
        effort = 0.0
        for j in range(n_links):
            lim = env.limit[j]
            u = action[i, j]
            if compensate:
                u += hold[j]
            if u > lim:
                u = lim
            elif u < -lim:
                u = -lim
            tau[j] = u
            effort += (u / lim) ** 2
        bad = False
        for _ in range(substeps):
            _channels.advance_pade(q, dq, model, sensor, state.pade_x[i], raw, x_new)
            if two_links_one_mode:
                _rk4.rk4_step_two_links_one_mode(q, dq, tau, tau, tau, h, model)
            else:
                _rk4.rk4_step(q, dq, tau, tau, tau, h, model, scratch.ws, scratch.stages)
            state.cursor[i] += 1
            _channels.record_sample(q, dq, model, sensor, state.buffer[i], state.cursor[i], raw)
            if _rk4.diverged(q, dq, model, env.max_deflection):
                bad = True
                break
        state.k[i] += 1
        for j in range(n_links):
            if abs(dq[j]) > env.params[4]:
                bad = True
        if bad:
            state.status[i] = DIVERGED
            state.reward[i] = -env.params[3]
            continue
        _observe(model, env, state, i, sig)
        e = state.error[i]
        state.reward[i] = -(env.params[1] * e * e + env.params[2] * effort)
        state.status[i] = TRUNCATED if state.k[i] >= n_steps else RUNNING
