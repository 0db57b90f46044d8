"""The compiled closed loop: sampled-data control, zero-order hold, RK4 substeps.

One Numba function runs a whole simulation (or a chunk of one) without
returning to Python: at every control instant ``t_k = k dt`` it forms the
measurement (sensor, delay, noise, quantisation), calls the controller through
its C function pointer, saturates and holds the torque, then integrates the
plant over ``[t_k, t_k + dt]`` with ``substeps`` fixed RK4 steps
(:mod:`flexarm.sim.integrator`). Delays act at substep resolution: the exact
delay is a ring buffer of the sensed signal (delay rounded to whole substeps),
the Padé delay a discrete state-space filter discretised exactly over one
substep (zero-order hold on its input).

Everything is plain arrays, built by one factory each (:func:`sensor_arrays`,
:func:`loop_state`), by keyword; :func:`flexarm.simulate` prepares
them. The measurement and reference layouts are those of
:mod:`flexarm.control.signals`.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import NDArray

from .._compile import compiled_as, njit_runtime_free
from ..control.signals import (
    measurement_size,
    r_feedforward,
    reference_size,
    y_angles,
    y_modes,
    y_point,
    y_rates,
)
from ..errors import InvalidValueError
from ..model.arrays import ArmArrays, Workspace, make_workspace
from ..model.dynamics_points import _point_kinematics
from ..model.dynamics_two_links import _is_two_links_one_mode
from ..model.kernel_checks import check_model, check_vector, check_workspace
from .integrator import _diverged, _rk4_step, _rk4_step_two_links_one_mode

__all__ = [
    "DIVERGED",
    "OK",
    "LoopState",
    "SensorArrays",
    "loop_state",
    "prime_delay_line",
    "run",
    "sense",
    "sensor_arrays",
]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

OK, DIVERGED = 0, 1


class SensorArrays(NamedTuple):
    """The sensor as plain arrays (build with :func:`sensor_arrays`).

    Attributes
    ----------
    link : int64 (1,)
        Link of the sensed point, -1 for the joint encoders.
    rigid : int64 (1,)
        1: the point is the rigid kinematics of the encoder angles (the paper's
        sensor model), 0: the deflected point.
    distance : (1,)
        Distance of the point along its link, m.
    phi : (n_modes of link,)
        Mode shapes at the point (then, with geometric stiffening, the link's
        shortening matrix there: FlexibleArm.point_basis).
    levers : (n_links,)
        Lever lengths of the rigid kinematics of the encoder angles (the link
        lengths for the joint encoders, the point's for the paper's model), m.
    delay_steps : int64 (1,)
        Exact delay in substeps (0: none unless Padé).
    pade_ad, pade_bd, pade_cd, pade_dd : (p, p), (p,), (p,), (1,)
        Discrete Padé filter of order p; p = 0 for no Padé.
    noise : (n_steps + 1, n_channels)
        Additive noise per control instant, or (0, n_channels).
    resolution : (n_channels,)
        Quantisation steps (0: none).
    """

    link: I64
    rigid: I64
    distance: F64
    phi: F64
    levers: F64
    delay_steps: I64
    pade_ad: F64
    pade_bd: F64
    pade_cd: F64
    pade_dd: F64
    noise: F64
    resolution: F64


def sensor_arrays(
    *,
    link: int,
    rigid: bool,
    distance: float,
    phi: F64,
    levers: F64,
    delay_steps: int,
    pade: tuple[F64, F64, F64, F64] | None,
    noise: F64,
    resolution: F64,
) -> SensorArrays:
    """The one way to build :class:`SensorArrays`: by keyword, shapes checked.

    Parameters
    ----------
    link : int
        Link of the sensed point (0-based), or -1 for the joint encoders.
    rigid : bool
        The point is the rigid kinematics of the encoder angles (``levers``).
    distance : float
        Distance of the point along its link, m (0 for the encoders).
    phi : ndarray, shape (n_modes of link,) or (n_modes + n_modes**2,)
        Mode shapes at the point (empty for the encoders).
    levers : ndarray, shape (n_links,)
        Lever lengths of the rigid kinematics of the encoder angles, m.
    delay_steps : int
        Exact transport delay in substeps (>= 0).
    pade : tuple of ndarray, optional
        Discrete Padé filter ``(Ad (p, p), Bd (p,), Cd (p,), Dd (1,))``.
    noise : ndarray, shape (n_rows, n_channels) or (0, n_channels)
        Additive noise per control instant.
    resolution : ndarray, shape (n_channels,)
        Quantisation steps (0: none).
    """
    n_ch = 4 if link >= 0 else 2 * int(np.asarray(levers).shape[0])
    ad, bd, cd, dd = (
        pade if pade is not None else (np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(1))
    )
    out = SensorArrays(
        link=np.array([link], dtype=np.int64),
        rigid=np.array([int(bool(rigid))], dtype=np.int64),
        distance=np.array([distance], dtype=np.float64),
        phi=np.ascontiguousarray(phi, dtype=np.float64),
        levers=np.ascontiguousarray(levers, dtype=np.float64),
        delay_steps=np.array([delay_steps], dtype=np.int64),
        pade_ad=np.ascontiguousarray(ad, dtype=np.float64),
        pade_bd=np.ascontiguousarray(np.ravel(bd), dtype=np.float64),
        pade_cd=np.ascontiguousarray(np.ravel(cd), dtype=np.float64),
        pade_dd=np.ascontiguousarray(np.ravel(dd), dtype=np.float64),
        noise=np.ascontiguousarray(noise, dtype=np.float64),
        resolution=np.ascontiguousarray(resolution, dtype=np.float64),
    )
    p = out.pade_ad.shape[0]
    checks = {
        "pade": out.pade_ad.shape == (p, p)
        and out.pade_bd.shape == (p,)
        and out.pade_cd.shape == (p,)
        and out.pade_dd.shape == (1,),
        "noise": out.noise.ndim == 2 and out.noise.shape[1] == n_ch,
        "resolution": out.resolution.shape == (n_ch,),
        "delay_steps": delay_steps >= 0,
    }
    for name, ok in checks.items():
        if not ok:
            raise InvalidValueError(
                f"The '{name}' parameter of sensor_arrays does not fit a sensor with "
                f"{n_ch} channels and a Padé filter of order {p}."
            )
    return out


class LoopState(NamedTuple):
    """Everything that carries over between chunks (updated in place; build with
    :func:`loop_state`)."""

    q: F64  # (n,)
    dq: F64  # (n,)
    tau: F64  # (N,) held torque
    ctrl_state: F64  # (s,)
    buffer: F64  # (delay_steps + 1, n_channels) ring of sensed signals
    cursor: I64  # (1,) substeps integrated so far
    pade_x: F64  # (n_channels, p) filter states
    scratch: F64  # (6, n) RK4 stages
    ws: Workspace  # dynamics scratch
    signals: F64  # (2 n_channels + n_y + max(p, 1),) signal scratch


def loop_state(
    *,
    q: F64,
    dq: F64,
    n_links: int,
    controller_state: F64,
    sensor: SensorArrays,
    n_y: int,
) -> LoopState:
    """A fresh :class:`LoopState` for the initial ``q, dq`` (copied), a controller's
    initial state (copied), the sensor's arrays and a measurement of ``n_y``."""
    n = q.shape[0]
    n_ch = sensor.resolution.shape[0]
    order = sensor.pade_ad.shape[0]
    return LoopState(
        q=np.array(q, dtype=np.float64),
        dq=np.array(dq, dtype=np.float64),
        tau=np.zeros(n_links),
        ctrl_state=np.array(controller_state, dtype=np.float64),
        buffer=np.zeros((int(sensor.delay_steps[0]) + 1, n_ch)),
        cursor=np.zeros(1, dtype=np.int64),
        pade_x=np.zeros((n_ch, order)),
        scratch=np.zeros((6, n)),
        ws=make_workspace(n),
        signals=np.zeros(2 * n_ch + n_y + max(order, 1)),
    )


@nb.njit(cache=True, nogil=True, inline="always")
def _collocated(q: F64, dq: F64, model: ArmArrays, i: int, n_links: int) -> tuple[float, float]:
    """Encoder angle and rate of joint ``i``: the motor with flexible joints."""
    if model.joint.shape[0] > 0:
        m = model.mode_start[n_links] + i
        return q[m], dq[m]
    return q[i], dq[i]


@nb.njit(cache=True, nogil=True, inline="always")
def _sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw (true, undelayed) sensed signal: the encoder angles then rates, or
    the point's position then velocity (deflected, or the paper's rigid
    kinematics of the encoder angles).

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
    elif sensor.rigid[0]:
        # the paper's sensor model: rigid kinematics of the encoder angles
        px = 0.0
        py = 0.0
        vx = 0.0
        vy = 0.0
        phi = 0.0
        phid = 0.0
        for i in range(n_links):
            a, r = _collocated(q, dq, model, i, n_links)
            phi += a
            phid += r
            lever = sensor.levers[i]
            px += lever * np.cos(phi)
            py += lever * np.sin(phi)
            vx -= lever * np.sin(phi) * phid
            vy += lever * np.cos(phi) * phid
        out[0] = px
        out[1] = py
        out[2] = vx
        out[3] = vy
    else:
        _point_kinematics(q, dq, model, link, sensor.distance[0], sensor.phi, out)


def prime_delay_line(model: ArmArrays, sensor: SensorArrays, state: LoopState) -> None:
    """Start the delay line at steady state on the initial sensed signal."""
    raw = np.zeros(state.buffer.shape[1])
    _sense(state.q, state.dq, model, sensor, raw)
    state.buffer[:] = raw
    order = sensor.pade_ad.shape[0]
    if order:
        # discrete steady state: x = (I - Ad)^-1 Bd u
        gain = np.linalg.solve(np.eye(order) - sensor.pade_ad, sensor.pade_bd)
        state.pade_x[:] = np.outer(raw, gain)


@njit_runtime_free(cache=True, nogil=True)
def _run(
    model: ArmArrays,
    control: CFunc,  # see flexarm.control.controllers.CONTROL_SIGNATURE
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
    n_steps: int,
    every: int,
    out_q: F64,
    out_dq: F64,
    out_tau: F64,
    out_y: F64,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Advance the loop over control instants ``k0 <= k < k1`` of a run of
    ``n_steps`` periods (measure at each ``k``, then act and integrate to ``k + 1``
    unless ``k == n_steps``).

    ``reference`` and ``sensor.noise`` (if any) hold the rows of instants
    ``k0 <= k < k1``: row ``k - k0``. The outputs record every ``every``-th instant
    and the last one (``k % every == 0`` or ``k == n_steps``): instant ``k`` goes to
    row ``ceil(k / every) - ceil(k0 / every)``.

    Returns ``(status, k)``: status 0 and ``k1`` when done, 1 and the last instant
    whose state was finite when the state diverged (non-finite, rates above 1e12,
    or a link's tip deflection above ``max_deflection``).
    """
    n = state.q.shape[0]
    n_links = model.link.shape[0]
    ms = model.mode_start
    n_modes = ms[n_links] - n_links
    row0 = (k0 + every - 1) // every
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
    two_links_one_mode = _is_two_links_one_mode(model)
    o_angle, o_rate = y_angles(n_links), y_rates(n_links)
    o_point, o_modes = y_point(n_links), y_modes(n_links)
    o_ff = r_feedforward(n_links)
    for k in range(k0, k1):
        # ---- measure: the delayed sensed signal, then noise and quantisation
        _sense(q, dq, model, sensor, raw)
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
                v += sensor.noise[k - k0, c]
            res = sensor.resolution[c]
            if res > 0.0:
                v = np.round(v / res) * res
            delayed[c] = v
        if joint_sensor:
            # rigid kinematics (lever lengths of the sensor) of the measured angles
            px = 0.0
            py = 0.0
            vx = 0.0
            vy = 0.0
            phi = 0.0
            phid = 0.0
            for i in range(n_links):
                y[o_angle + i] = delayed[i]
                y[o_rate + i] = delayed[n_links + i]
                phi += delayed[i]
                phid += delayed[n_links + i]
                lever = sensor.levers[i]
                px += lever * np.cos(phi)
                py += lever * np.sin(phi)
                vx -= lever * np.sin(phi) * phid
                vy += lever * np.cos(phi) * phid
            y[o_point] = px
            y[o_point + 1] = py
            y[o_point + 2] = vx
            y[o_point + 3] = vy
        else:
            for i in range(n_links):
                a, r = _collocated(q, dq, model, i, n_links)
                y[o_angle + i] = a
                y[o_rate + i] = r
            for c in range(4):
                y[o_point + c] = delayed[c]
        for j in range(n_modes):
            y[o_modes + j] = q[n_links + j]
        # ---- record
        record = k % every == 0 or k == n_steps
        row = (k + every - 1) // every - row0
        if record:
            for r in range(n):
                out_q[row, r] = q[r]
                out_dq[row, r] = dq[r]
            for c in range(y.shape[0]):
                out_y[row, c] = y[c]
        if k == n_steps:
            for i in range(n_links):
                out_tau[row, i] = tau[i]
            return OK, k1
        # ---- act: control law, saturation, zero-order hold
        rk = reference[k - k0]
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
            tau[i] += rk[o_ff + i]  # feedforward (zero unless asked for)
            lim = torque_limit[i]
            if tau[i] > lim:
                tau[i] = lim
            elif tau[i] < -lim:
                tau[i] = -lim
            if record:
                out_tau[row, i] = tau[i]
        # ---- integrate to t_{k+1}
        for _ in range(substeps):
            if order > 0:  # Padé filter: x <- Ad x + Bd u over this substep
                _sense(q, dq, model, sensor, raw)
                for c in range(n_ch):
                    for j in range(order):
                        acc = sensor.pade_bd[j] * raw[c]
                        for i2 in range(order):
                            acc += sensor.pade_ad[j, i2] * state.pade_x[c, i2]
                        x_new[j] = acc
                    for j in range(order):
                        state.pade_x[c, j] = x_new[j]
            if two_links_one_mode:
                _rk4_step_two_links_one_mode(q, dq, tau, tau, tau, h, model)
            else:
                _rk4_step(q, dq, tau, tau, tau, h, model, ws, state.scratch)
            state.cursor[0] += 1
            if n_buf > 1:
                _sense(q, dq, model, sensor, raw)
                slot = state.cursor[0] % n_buf
                for c in range(n_ch):
                    state.buffer[slot, c] = raw[c]
            if _diverged(q, dq, model, max_deflection):
                return DIVERGED, k
    return OK, k1


# ------------------------------------------------------------------ checked public faces
# From Python, run and sense check every array they will index (a short output
# would be written past its end); inside compiled code they are the kernels.
def _check_sensor(sensor: SensorArrays, model: ArmArrays, owner: str) -> tuple[int, int]:
    """``(n_channels, pade order)`` of ``sensor`` for ``model``."""
    if not isinstance(sensor, SensorArrays):
        raise InvalidValueError(
            f"The 'sensor' parameter of {owner} must be a SensorArrays (sensor_arrays)."
        )
    n_links, _ = check_model(model, owner)
    for name in ("link", "rigid", "delay_steps"):
        check_vector(getattr(sensor, name), f"sensor.{name}", owner, (1,), dtype=np.int64)
    check_vector(sensor.distance, "sensor.distance", owner, (1,))
    link = int(sensor.link[0])
    if not -1 <= link < n_links:
        raise InvalidValueError(
            f"The 'sensor.link' parameter of {owner} must be -1 (encoders) or a link of the "
            f"model (< {n_links}). Got {link} instead."
        )
    n_ch = 2 * n_links if link < 0 else 4
    if link >= 0:
        modes = int(model.mode_start[link + 1] - model.mode_start[link])
        if sensor.phi.shape not in ((modes,), (modes + modes * modes,)):
            raise InvalidValueError(
                f"The 'sensor.phi' parameter of {owner} must fit link {link}'s {modes} modes. "
                f"Got shape {sensor.phi.shape} instead."
            )
    check_vector(sensor.phi, "sensor.phi", owner, sensor.phi.shape)
    check_vector(sensor.levers, "sensor.levers", owner, (n_links,))
    p = sensor.pade_ad.shape[0] if sensor.pade_ad.ndim == 2 else -1
    check_vector(sensor.pade_ad, "sensor.pade_ad", owner, (p, p))
    check_vector(sensor.pade_bd, "sensor.pade_bd", owner, (p,))
    check_vector(sensor.pade_cd, "sensor.pade_cd", owner, (p,))
    check_vector(sensor.pade_dd, "sensor.pade_dd", owner, (1,))
    rows = sensor.noise.shape[0] if sensor.noise.ndim == 2 else -1
    check_vector(sensor.noise, "sensor.noise", owner, (rows, n_ch))
    check_vector(sensor.resolution, "sensor.resolution", owner, (n_ch,))
    return n_ch, p


def sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw sensed signal (``_sense``), arguments checked."""
    owner = "sense"
    _, n = check_model(model, owner)
    n_ch, _ = _check_sensor(sensor, model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_vector(out, "out", owner, (n_ch,), writable=True)
    _sense(q, dq, model, sensor, out)


def run(
    model: ArmArrays,
    control: CFunc,
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
    n_steps: int,
    every: int,
    out_q: F64,
    out_dq: F64,
    out_tau: F64,
    out_y: F64,
) -> tuple[int, int]:
    """The compiled loop (``_run``: its docstring has the semantics) over
    ``k0 <= k < k1``, every array it will index checked first."""
    owner = "run"
    n_links, n = check_model(model, owner)
    n_ch, p = _check_sensor(sensor, model, owner)
    k0, k1, n_steps, every, substeps = (int(v) for v in (k0, k1, n_steps, every, substeps))
    if not (0 <= k0 <= k1 <= n_steps + 1 and every >= 1 and substeps >= 1 and dt > 0):
        raise InvalidValueError(
            f"The 'k0', 'k1', 'n_steps', 'every', 'substeps' and 'dt' parameters of {owner} "
            "must satisfy 0 <= k0 <= k1 <= n_steps + 1, every >= 1, substeps >= 1, dt > 0. "
            f"Got {k0}, {k1}, {n_steps}, {every}, {substeps}, {dt} instead."
        )
    acting = max(0, min(k1, n_steps) - k0)  # instants whose reference the law reads
    check_vector(params, "params", owner, (params.shape[0],) if params.ndim == 1 else (-1,))
    if sensor.noise.shape[0] and sensor.noise.shape[0] < k1 - k0:
        raise InvalidValueError(
            f"The 'sensor.noise' parameter of {owner} must have a row per instant "
            f"({k1 - k0}). Got {sensor.noise.shape[0]} rows instead."
        )
    _rows_at_least(reference, "reference", owner, acting, reference_size(n_links), False)
    check_vector(torque_limit, "torque_limit", owner, (n_links,))
    check_vector(max_deflection, "max_deflection", owner, (n_links,))
    if not isinstance(state, LoopState):
        raise InvalidValueError(f"The 'state' parameter of {owner} must be a LoopState.")
    n_y = measurement_size(n_links, int(model.mode_start[-1]) - n_links)
    check_vector(state.q, "state.q", owner, (n,), writable=True)
    check_vector(state.dq, "state.dq", owner, (n,), writable=True)
    check_vector(state.tau, "state.tau", owner, (n_links,), writable=True)
    check_vector(state.ctrl_state, "state.ctrl_state", owner, state.ctrl_state.shape, writable=True)
    delay = int(sensor.delay_steps[0])
    check_vector(state.buffer, "state.buffer", owner, (delay + 1, n_ch), writable=True)
    check_vector(state.cursor, "state.cursor", owner, (1,), writable=True, dtype=np.int64)
    check_vector(state.pade_x, "state.pade_x", owner, (n_ch, p), writable=True)
    check_vector(state.scratch, "state.scratch", owner, (6, n), writable=True)
    check_workspace(state.ws, n, owner)
    check_vector(
        state.signals, "state.signals", owner, (2 * n_ch + n_y + max(p, 1),), writable=True
    )
    recorded = (
        (max(k1, k0) + every - 1) // every
        - (k0 + every - 1) // every
        + (1 if k0 <= n_steps < k1 and n_steps % every else 0)
    )
    for name, out, width in (
        ("out_q", out_q, n),
        ("out_dq", out_dq, n),
        ("out_tau", out_tau, n_links),
        ("out_y", out_y, n_y),
    ):
        _rows_at_least(out, name, owner, recorded, width, True)
    status, k = _run(
        model,
        control,
        params,
        sensor,
        reference,
        dt,
        substeps,
        torque_limit,
        max_deflection,
        state,
        k0,
        k1,
        n_steps,
        every,
        out_q,
        out_dq,
        out_tau,
        out_y,
    )
    return int(status), int(k)


def _rows_at_least(arr: F64, name: str, owner: str, rows: int, width: int, writable: bool) -> None:
    if not (isinstance(arr, np.ndarray) and arr.ndim == 2 and arr.shape[0] >= rows):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must have at least {rows} rows of {width}. "
            f"Got shape {getattr(arr, 'shape', None)} instead."
        )
    check_vector(arr, name, owner, (arr.shape[0], width), writable=writable)


@compiled_as(sense)
def _sense_compiled(q, dq, model, sensor, out):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, sensor, out: _sense(q, dq, model, sensor, out)
