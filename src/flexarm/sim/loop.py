"""The compiled closed loop: sampled-data control, zero-order hold, RK4 substeps.

One Numba function runs a whole simulation (or a chunk of one) without
returning to Python: at every control instant ``t_k = k dt`` it forms the
measurement (the sensor's raw signal, delay, noise and quantisation:
:mod:`flexarm.sensing.channels`), calls the controller through its C function
pointer, saturates and holds the torque, then integrates the plant over
``[t_k, t_k + dt]`` with ``substeps`` fixed RK4 steps
(:mod:`flexarm.sim.integrator`).

Everything the loop reads and writes is one :class:`Loop` of plain arrays,
built in one place (:func:`loop_inputs`, by keyword); what changes from chunk to
chunk (the reference rows and the noise draws of the chunk's instants) is passed
beside it. :func:`flexarm.simulate` prepares it. The measurement and reference
layouts are those of :mod:`flexarm.control.signals`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import NDArray

from .._compile import njit_runtime_free
from ..control.gravity_compensation import holding_torques, scratch_size
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
from ..sensing import _channels
from ..sensing.channels import SensorArrays, check_sensor_arrays
from . import _rk4
from ._reference_kernels import ReferenceStream, stream_row
from .chunks import DIVERGED, OK

__all__ = [
    "DIVERGED",
    "OK",
    "REFERENCE_FAILED",
    "Loop",
    "LoopOutputs",
    "LoopState",
    "loop_inputs",
    "run",
]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

REFERENCE_FAILED = 2
"""Status of a chunk whose streamed reference failed (beside OK and DIVERGED)."""


class LoopState(NamedTuple):
    """Everything that carries over between chunks (updated in place)."""

    q: F64  # (n,)
    dq: F64  # (n,)
    tau: F64  # (N,) held torque
    ctrl_state: F64  # (s,)
    buffer: F64  # (delay_steps + 1, n_ch) ring of sensed signals
    cursor: I64  # (1,) substeps integrated so far
    pade_x: F64  # (n_ch, p) filter states
    scratch: F64  # (6, n) RK4 stages
    ws: Workspace  # dynamics scratch
    signals: F64  # (2 n_ch + n_y + max(p, 1),) signal scratch
    reference: F64  # (reference_size,) a streamed reference vector (feedforward 0)
    desired: F64  # (2,) a streamed desired point
    gravity: F64  # (scratch_size + N,) gravity compensation: its scratch, its torques; (0,): off


class LoopOutputs(NamedTuple):
    """The recorded rows: instant ``k`` goes to row ``ceil(k / every)``.

    ``q, dq`` (rows, n_dof); ``tau`` (rows, N) N m; ``y`` (rows, n_y) the
    measurement, or (0, n_y) when not recorded; ``r`` (rows, reference_size) and
    ``desired`` (rows, 2) m, written by the loop only for a streamed reference (else
    filled beforehand), ``r`` (0, reference_size) when not recorded; ``tip`` (rows,
    2) m, the end effector, or (0, 2) when not recorded here.
    """

    q: F64
    dq: F64
    tau: F64
    y: F64
    r: F64
    desired: F64
    tip: F64


class Loop(NamedTuple):
    """What the compiled loop reads and writes over a run (build with :func:`loop_inputs`).

    Attributes
    ----------
    model : ArmArrays
        The plant.
    params : ndarray
        The control law's parameters (``Controller.design``).
    sensor : SensorArrays
        The sensor and its delay.
    stream : ReferenceStream
        A reference computed at each instant (``no_stream()``: rows are passed).
    dt : float
        Control period, s.
    substeps, n_steps, every : int
        RK4 steps per period; periods in the run (instants ``0..n_steps``); record
        every ``every``-th instant and the last.
    torque_limit, max_deflection : ndarray, shape (N,)
        Saturation of each joint torque (N m) and the tip deflection of each link
        counted as divergence (m).
    tip_phi : ndarray
        The last link's point basis at its tip (FlexibleArm.point_basis), when the
        tip is recorded.
    state : LoopState
    out : LoopOutputs
    """

    model: ArmArrays
    params: F64
    sensor: SensorArrays
    stream: ReferenceStream
    dt: float
    substeps: int
    n_steps: int
    every: int
    torque_limit: F64
    max_deflection: F64
    tip_phi: F64
    state: LoopState
    out: LoopOutputs


def loop_inputs(
    *,
    model: ArmArrays,
    params: F64,
    sensor: SensorArrays,
    stream: ReferenceStream,
    dt: float,
    substeps: int,
    n_steps: int,
    every: int,
    torque_limit: F64,
    max_deflection: F64,
    q: F64,
    dq: F64,
    controller_state: F64,
    tip_phi: F64 | None,
    reference: tuple[F64, F64] | None,
    recorded: int,
    record_signals: bool = True,
    gravity_compensation: bool = False,
) -> Loop:
    """The one way to build a :class:`Loop`: the state at ``q, dq`` (copied) with the
    controller's initial state and the delay line at steady state, and output rows
    for ``recorded`` instants.

    ``tip_phi`` (the last link's point basis at its tip) records the end effector
    in the loop; ``reference``, the reference rows and desired points already
    recorded ``(r, desired)``, is used as the outputs as it is (else the loop or the
    caller writes them). ``record_signals=False`` records neither the measurement
    nor the reference (``y`` and ``r`` get no rows; ``reference``'s rows are not
    kept); the desired points are recorded all the same.
    ``gravity_compensation`` adds to the law's torque the holding torques of the
    measured posture (:mod:`flexarm.control.gravity_compensation`).
    """
    n, n_links = q.shape[0], model.link.shape[0]
    n_y = measurement_size(n_links, int(model.mode_start[n_links]) - n_links)
    n_ch = sensor.resolution.shape[0]
    order = sensor.pade_ad.shape[0]
    state = LoopState(
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
        gravity=np.zeros(scratch_size(n, n_links) + n_links if gravity_compensation else 0),
    )
    _channels.prime(
        state.q, state.dq, model, sensor, state.buffer, state.pade_x, state.signals[:n_ch]
    )
    signal_rows = recorded if record_signals else 0
    if reference is None:
        r, desired = np.empty((signal_rows, reference_size(n_links))), np.empty((recorded, 2))
    else:
        r, desired = reference if record_signals else (reference[0][:0], reference[1])
    out = LoopOutputs(  # every row up to the last one reached is written
        q=np.empty((recorded, n)),
        dq=np.empty((recorded, n)),
        tau=np.empty((recorded, n_links)),
        y=np.empty((signal_rows, n_y)),
        r=r,
        desired=desired,
        tip=np.empty((recorded if tip_phi is not None else 0, 2)),
    )
    return Loop(
        model=model,
        params=np.ascontiguousarray(params, dtype=np.float64),
        sensor=sensor,
        stream=stream,
        dt=float(dt),
        substeps=int(substeps),
        n_steps=int(n_steps),
        every=int(every),
        torque_limit=np.ascontiguousarray(torque_limit, dtype=np.float64),
        max_deflection=np.ascontiguousarray(max_deflection, dtype=np.float64),
        tip_phi=np.zeros(0) if tip_phi is None else np.ascontiguousarray(tip_phi, dtype=float),
        state=state,
        out=out,
    )


@njit_runtime_free(cache=True, nogil=True)
def _run(
    loop: Loop,
    control: CFunc,  # see flexarm.control.controllers.CONTROL_SIGNATURE
    reference: F64,
    noise: F64,
    k0: int,
    k1: int,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Advance the loop over control instants ``k0 <= k < k1`` (measure at each ``k``,
    then act and integrate to ``k + 1`` unless ``k == n_steps``).

    ``reference`` and ``noise`` (standard normal draws, or no rows for a noise-free
    sensor) hold the rows of instants ``k0 <= k < k1``: row ``k - k0``. With the
    loop's stream on, the reference is computed here at each instant instead
    (``reference`` is not read) and recorded with the desired point in ``out.r``
    and ``out.desired`` (not written otherwise). With rows in ``out.tip``, the end
    effector's position (deflected) is recorded there; with no rows in ``out.y``
    (``out.r``) the measurement (the streamed reference) is not recorded.

    Returns ``(status, k)``: status 0 and ``k1`` when done, 1 and the last instant
    whose state was finite when the state diverged (non-finite, rates above 1e12,
    or a link's tip deflection above ``max_deflection``), 2 and the instant whose
    streamed reference failed (out of reach or singular: the pipeline's ``rows``
    at that instant says how).
    """
    model, sensor, state, out = loop.model, loop.sensor, loop.state, loop.out
    params, substeps, n_steps, every = loop.params, loop.substeps, loop.n_steps, loop.every
    dt = loop.dt
    n = state.q.shape[0]
    n_links = model.link.shape[0]
    ms = model.mode_start
    n_modes = ms[n_links] - n_links
    h = dt / substeps
    ws = state.ws
    q, dq, tau = state.q, state.dq, state.tau
    n_ch = state.buffer.shape[1]
    n_y = out.y.shape[1]
    sig = state.signals  # views into preallocated scratch: no allocation here
    raw = sig[0:n_ch]
    delayed = sig[n_ch : 2 * n_ch]
    y = sig[2 * n_ch : 2 * n_ch + n_y]
    x_new = sig[2 * n_ch + n_y :]
    noisy = noise.shape[0] > 0
    joint_sensor = sensor.link[0] < 0
    two_links_one_mode = is_two_links_one_mode(model)
    o_angle, o_rate = y_angles(n_links), y_rates(n_links)
    o_point, o_modes = y_point(n_links), y_modes(n_links)
    o_ff = r_feedforward(n_links)
    streamed = loop.stream.spec[0] != 0.0
    record_tip = out.tip.shape[0] > 0
    record_y = out.y.shape[0] > 0
    record_r = out.r.shape[0] > 0
    last_link = n_links - 1
    tip_distance = model.link[last_link, LEN]
    compensate = state.gravity.shape[0] > 0
    hold_scratch = state.gravity[: state.gravity.shape[0] - n_links]
    hold = state.gravity[state.gravity.shape[0] - n_links :]
    for k in range(k0, k1):
        if streamed:
            code, _ = stream_row(loop.stream, k * dt, state.reference, state.desired)
            if code != OK:
                return REFERENCE_FAILED, k
        # ---- measure: the delayed sensed signal, then noise and quantisation
        _channels.sense(q, dq, model, sensor, raw)
        _channels.delayed_signal(sensor, state.buffer, state.pade_x, state.cursor[0], raw, delayed)
        if noisy:
            _channels.corrupt(sensor, True, noise[k - k0], delayed)
        else:
            _channels.corrupt(sensor, False, raw, delayed)
        if joint_sensor:  # the measured angles, and the sensor's point from them
            for i in range(n_links):
                y[o_angle + i] = delayed[i]
                y[o_rate + i] = delayed[n_links + i]
            _channels.rigid_chain_point(
                sensor.levers,
                delayed[:n_links],
                delayed[n_links : 2 * n_links],
                y[o_point : o_point + 4],
            )
        else:
            for i in range(n_links):
                a, r = _channels.collocated(q, dq, model, i, n_links)
                y[o_angle + i] = a
                y[o_rate + i] = r
            for c in range(4):
                y[o_point + c] = delayed[c]
        for j in range(n_modes):
            y[o_modes + j] = q[n_links + j]
        # ---- record
        record = k % every == 0 or k == n_steps
        row = (k + every - 1) // every
        if record:
            for r in range(n):
                out.q[row, r] = q[r]
                out.dq[row, r] = dq[r]
            if record_y:
                for c in range(y.shape[0]):
                    out.y[row, c] = y[c]
            if record_tip:
                px, py, _, _ = point_state(q, q, model, last_link, tip_distance, loop.tip_phi)
                out.tip[row, 0] = px
                out.tip[row, 1] = py
            if streamed:
                if record_r:
                    for c in range(state.reference.shape[0]):
                        out.r[row, c] = state.reference[c]
                out.desired[row, 0] = state.desired[0]
                out.desired[row, 1] = state.desired[1]
        if k == n_steps:
            for i in range(n_links):
                out.tau[row, i] = tau[i]
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
        if compensate:  # the holding torques of the measured posture
            holding_torques(y[o_angle : o_angle + n_links], model, hold_scratch, hold)
            for i in range(n_links):
                tau[i] += hold[i]
        for i in range(n_links):
            tau[i] += rk[o_ff + i]  # feedforward (zero unless asked for)
            lim = loop.torque_limit[i]
            if tau[i] > lim:
                tau[i] = lim
            elif tau[i] < -lim:
                tau[i] = -lim
            if record:
                out.tau[row, i] = tau[i]
        # ---- integrate to t_{k+1}
        for _ in range(substeps):
            _channels.advance_pade(q, dq, model, sensor, state.pade_x, raw, x_new)
            if two_links_one_mode:
                _rk4.rk4_step_two_links_one_mode(q, dq, tau, tau, tau, h, model)
            else:
                _rk4.rk4_step(q, dq, tau, tau, tau, h, model, ws, state.scratch)
            state.cursor[0] += 1
            _channels.record_sample(q, dq, model, sensor, state.buffer, state.cursor[0], raw)
            if _rk4.diverged(q, dq, model, loop.max_deflection):
                return DIVERGED, k
    return OK, k1


# ------------------------------------------------------------------ checked public face
def run(
    loop: Loop, control: CFunc, reference: F64, noise: F64, k0: int, k1: int
) -> tuple[int, int]:
    """The compiled loop over ``k0 <= k < k1`` (``_run``: its docstring has the
    semantics), every array it will index checked first (a short output would be
    written past its end).

    Parameters
    ----------
    loop : Loop
        From :func:`loop_inputs`.
    control : CFunc
        The law's compiled function (``Controller.cfunc``).
    reference : ndarray, shape (k1 - k0, reference_size)
        The reference rows of the chunk's instants (not read when streamed:
        then any (0, reference_size) array).
    noise : ndarray, shape (k1 - k0, n_ch) or (0, n_ch)
        Standard normal draws of the chunk's instants, or none.
    k0, k1 : int
        The chunk's instants, ``0 <= k0 <= k1 <= n_steps + 1``.
    """
    owner = "run"
    if not isinstance(loop, Loop):
        raise InvalidValueError(f"The 'loop' parameter of {owner} must be a Loop (loop_inputs).")
    model, state, out = loop.model, loop.state, loop.out
    n_links, n = check_model(model, owner)
    n_ch, p = check_sensor_arrays(loop.sensor, model, owner)
    k0, k1, n_steps, every = int(k0), int(k1), loop.n_steps, loop.every
    if not (0 <= k0 <= k1 <= n_steps + 1 and every >= 1 and loop.substeps >= 1 and loop.dt > 0):
        raise InvalidValueError(
            f"The 'k0', 'k1', 'n_steps', 'every', 'substeps' and 'dt' parameters of {owner} "
            "must satisfy 0 <= k0 <= k1 <= n_steps + 1, every >= 1, substeps >= 1, dt > 0. "
            f"Got {k0}, {k1}, {n_steps}, {every}, {loop.substeps}, {loop.dt} instead."
        )
    acting = max(0, min(k1, n_steps) - k0)  # instants whose reference the law reads
    params = loop.params
    check_vector(params, "params", owner, (params.shape[0],) if params.ndim == 1 else (-1,))
    if noise.ndim != 2 or noise.shape[1] != n_ch or 0 < noise.shape[0] < k1 - k0:
        raise InvalidValueError(
            f"The 'noise' parameter of {owner} must have {n_ch} columns and a row per instant "
            f"({k1 - k0}) or none. Got shape {noise.shape} instead."
        )
    check_vector(noise, "noise", owner, noise.shape)
    streamed = _check_stream(loop.stream, n_links, owner)
    if not streamed:
        _rows_at_least(reference, "reference", owner, acting, reference_size(n_links), False)
    check_vector(loop.torque_limit, "torque_limit", owner, (n_links,))
    check_vector(loop.max_deflection, "max_deflection", owner, (n_links,))
    if not isinstance(state, LoopState):
        raise InvalidValueError(f"The 'state' parameter of {owner} must be a LoopState.")
    n_y = measurement_size(n_links, int(model.mode_start[-1]) - n_links)
    check_vector(state.q, "state.q", owner, (n,), writable=True)
    check_vector(state.dq, "state.dq", owner, (n,), writable=True)
    check_vector(state.tau, "state.tau", owner, (n_links,), writable=True)
    check_vector(state.ctrl_state, "state.ctrl_state", owner, state.ctrl_state.shape, writable=True)
    delay = int(loop.sensor.delay_steps[0])
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
    off = np.size(state.gravity) == 0  # no gravity compensation
    n_hold = 0 if off else scratch_size(n, n_links) + n_links
    check_vector(state.gravity, "state.gravity", owner, (n_hold,), writable=True)
    last = min(k1, n_steps + 1) - 1  # the last instant the chunk may record
    rows = (last + every - 1) // every + 1 if last >= k0 else 0
    for name, arr, width in (
        ("out.q", out.q, n),
        ("out.dq", out.dq, n),
        ("out.tau", out.tau, n_links),
    ):
        _rows_at_least(arr, name, owner, rows, width, True)
    _rows_at_least(out.y, "out.y", owner, rows if _has_rows(out.y) else 0, n_y, True)
    if streamed:
        r_rows = rows if _has_rows(out.r) else 0  # no rows: the reference is not recorded
        _rows_at_least(out.r, "out.r", owner, r_rows, reference_size(n_links), True)
        _rows_at_least(out.desired, "out.desired", owner, rows, 2, True)
    tip_phi = loop.tip_phi
    check_vector(tip_phi, "tip_phi", owner, np.shape(tip_phi))
    if not (isinstance(out.tip, np.ndarray) and out.tip.ndim == 2 and out.tip.shape[0] == 0):
        modes = int(model.mode_start[n_links] - model.mode_start[n_links - 1])
        if tip_phi.shape not in ((modes,), (modes + modes * modes,)):
            raise InvalidValueError(
                f"The 'tip_phi' parameter of {owner} must fit the last link's {modes} modes. "
                f"Got shape {tip_phi.shape} instead."
            )
        _rows_at_least(out.tip, "out.tip", owner, rows, 2, True)
    status, k = _run(loop, control, reference, noise, k0, k1)
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


def _has_rows(arr: F64) -> bool:
    """Whether ``arr`` is a series the loop records (no rows: it does not)."""
    return not (isinstance(arr, np.ndarray) and arr.ndim == 2 and arr.shape[0] == 0)


def _rows_at_least(arr: F64, name: str, owner: str, rows: int, width: int, writable: bool) -> None:
    if not (isinstance(arr, np.ndarray) and arr.ndim == 2 and arr.shape[0] >= rows):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must have at least {rows} rows of {width}. "
            f"Got shape {getattr(arr, 'shape', None)} instead."
        )
    check_vector(arr, name, owner, (arr.shape[0], width), writable=writable)
