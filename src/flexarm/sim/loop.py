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

import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import NDArray

from .._compile import njit_runtime_free
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
from ..model.arrays import LEN, ArmArrays, Workspace, make_workspace
from ..model.dynamics._points import point_state
from ..model.dynamics._two_links import is_two_links_one_mode
from ..model.kernel_checks import check_model, check_vector, check_workspace
from ._reference_kernels import ReferenceStream, stream_row
from .integrator import _diverged, _rk4_step, _rk4_step_two_links_one_mode
from .sensed import (
    SensorArrays,
    _collocated,
    _rigid_chain_point,
    _sense,
    check_sensor_arrays,
    sense,
    sensor_arrays,
)

__all__ = [
    "DIVERGED",
    "OK",
    "REFERENCE_FAILED",
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

OK, DIVERGED, REFERENCE_FAILED = 0, 1, 2


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
    reference: F64  # (reference_size,) a streamed reference vector (feedforward 0)
    desired: F64  # (2,) a streamed desired point


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
        reference=np.zeros(reference_size(n_links)),
        desired=np.zeros(2),
    )


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
    stream: ReferenceStream,
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
    out_r: F64,
    out_desired: F64,
    tip_phi: F64,
    out_tip: F64,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Advance the loop over control instants ``k0 <= k < k1`` of a run of
    ``n_steps`` periods (measure at each ``k``, then act and integrate to ``k + 1``
    unless ``k == n_steps``).

    ``reference`` and ``sensor.noise`` (if any) hold the rows of instants
    ``k0 <= k < k1``: row ``k - k0``. With ``stream`` on, the reference is computed
    here at each instant instead (``reference`` is not read) and recorded with the
    desired point in ``out_r`` and ``out_desired`` (not written otherwise). With
    rows in ``out_tip``, the end effector's position (deflected; ``tip_phi`` the
    last link's basis at its tip, FlexibleArm.point_basis) is recorded there. The
    outputs record every ``every``-th instant and the last one (``k % every == 0``
    or ``k == n_steps``): instant ``k`` goes to row
    ``ceil(k / every) - ceil(k0 / every)``.

    Returns ``(status, k)``: status 0 and ``k1`` when done, 1 and the last instant
    whose state was finite when the state diverged (non-finite, rates above 1e12,
    or a link's tip deflection above ``max_deflection``), 2 and the instant whose
    streamed reference failed (out of reach or singular: the pipeline's
    ``rows`` at that instant says how).
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
    two_links_one_mode = is_two_links_one_mode(model)
    o_angle, o_rate = y_angles(n_links), y_rates(n_links)
    o_point, o_modes = y_point(n_links), y_modes(n_links)
    o_ff = r_feedforward(n_links)
    streamed = stream.spec[0] != 0.0
    record_tip = out_tip.shape[0] > 0
    last_link = n_links - 1
    tip_distance = model.link[last_link, LEN]
    for k in range(k0, k1):
        if streamed:
            code, _ = stream_row(stream, k * dt, state.reference, state.desired)
            if code != OK:
                return REFERENCE_FAILED, k
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
        if joint_sensor:  # the measured angles, and the sensor's point from them
            for i in range(n_links):
                y[o_angle + i] = delayed[i]
                y[o_rate + i] = delayed[n_links + i]
            _rigid_chain_point(
                sensor.levers,
                delayed[:n_links],
                delayed[n_links : 2 * n_links],
                y[o_point : o_point + 4],
            )
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
            if record_tip:
                px, py, _, _ = point_state(q, q, model, last_link, tip_distance, tip_phi)
                out_tip[row, 0] = px
                out_tip[row, 1] = py
            if streamed:
                for c in range(state.reference.shape[0]):
                    out_r[row, c] = state.reference[c]
                out_desired[row, 0] = state.desired[0]
                out_desired[row, 1] = state.desired[1]
        if k == n_steps:
            for i in range(n_links):
                out_tau[row, i] = tau[i]
            return OK, k1
        # ---- act: control law, saturation, zero-order hold
        rk = state.reference if streamed else reference[k - k0]
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
def run(
    model: ArmArrays,
    control: CFunc,
    params: F64,
    sensor: SensorArrays,
    reference: F64,
    stream: ReferenceStream,
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
    out_r: F64,
    out_desired: F64,
    tip_phi: F64,
    out_tip: F64,
) -> tuple[int, int]:
    """The compiled loop (``_run``: its docstring has the semantics) over
    ``k0 <= k < k1``, every array it will index checked first."""
    owner = "run"
    n_links, n = check_model(model, owner)
    n_ch, p = check_sensor_arrays(sensor, model, owner)
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
    streamed = _check_stream(stream, n_links, owner)
    if not streamed:
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
    check_vector(
        state.reference, "state.reference", owner, (reference_size(n_links),), writable=True
    )
    check_vector(state.desired, "state.desired", owner, (2,), writable=True)
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
    if streamed:
        _rows_at_least(out_r, "out_r", owner, recorded, reference_size(n_links), True)
        _rows_at_least(out_desired, "out_desired", owner, recorded, 2, True)
    check_vector(tip_phi, "tip_phi", owner, np.shape(tip_phi))
    if not (isinstance(out_tip, np.ndarray) and out_tip.ndim == 2 and out_tip.shape[0] == 0):
        modes = int(model.mode_start[n_links] - model.mode_start[n_links - 1])
        if tip_phi.shape not in ((modes,), (modes + modes * modes,)):
            raise InvalidValueError(
                f"The 'tip_phi' parameter of {owner} must fit the last link's {modes} modes. "
                f"Got shape {tip_phi.shape} instead."
            )
        _rows_at_least(out_tip, "out_tip", owner, recorded, 2, True)
    status, k = _run(
        model,
        control,
        params,
        sensor,
        reference,
        stream,
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
        out_r,
        out_desired,
        tip_phi,
        out_tip,
    )
    return int(status), int(k)


def _check_stream(stream: ReferenceStream, n_links: int, owner: str) -> bool:
    """Whether ``stream`` is on (then for two links, with knots it can index)."""
    if not isinstance(stream, ReferenceStream):
        raise InvalidValueError(
            f"The 'stream' parameter of {owner} must be a ReferenceStream (reference_stream "
            "or no_stream)."
        )
    check_vector(stream.spec, "stream.spec", owner, (7,))
    k = stream.knot_t.shape[0] if stream.knot_t.ndim == 1 else -1
    check_vector(stream.knot_t, "stream.knot_t", owner, (k,))
    check_vector(stream.knot_p, "stream.knot_p", owner, (k, 2))
    on = bool(stream.spec[0] != 0.0)
    if on and (n_links != 2 or k < 2):
        raise InvalidValueError(
            f"The 'stream' parameter of {owner} must be off or stream a two-link arm's "
            f"reference along at least 2 knots. Got {n_links} links and {k} knots instead."
        )
    return on


def _rows_at_least(arr: F64, name: str, owner: str, rows: int, width: int, writable: bool) -> None:
    if not (isinstance(arr, np.ndarray) and arr.ndim == 2 and arr.shape[0] >= rows):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must have at least {rows} rows of {width}. "
            f"Got shape {getattr(arr, 'shape', None)} instead."
        )
    check_vector(arr, name, owner, (arr.shape[0], width), writable=writable)
