"""Closed-loop simulation: :func:`simulate`.

The controller runs at its sample rate (period ``dt``) with zero-order hold;
the plant is integrated by fixed-step RK4 with ``substeps`` steps per period;
the whole loop is compiled (:mod:`flexarm.sim.loop`). ``method="scipy"`` runs
the same sampled-data loop with SciPy's adaptive ``solve_ivp`` (DOP853) between
control instants instead (:mod:`flexarm.sim.scipy_loop`), as the accuracy
reference for the fixed-step path.

A run is defined by the arm, the law, the path and one
:class:`~flexarm.sim.settings.SimulationSettings` (validated when made; keywords
of :func:`simulate` override its fields). :func:`simulate` is three steps: the
set-up (the reference pipeline, :class:`flexarm.sim.references.ReferencePipeline`:
trajectory, shaper, delay, joint references; the sensor's arrays; the law's
design; the loop's inputs, :func:`flexarm.sim.loop.loop_inputs`, built once), the
run in chunks (:mod:`flexarm.sim.chunks`), and the result assembly
(:func:`flexarm.sim.results.assemble_result`). A path of straight segments (the
square, lines, waypoints) without shaping, smoothing, feedforward or a sensed
point short of the end effector is not precomputed: the compiled loop computes
its reference at each instant with the pipeline's own kernels (the same
numbers), and records it with the tip, so that a run's time is the loop's (unless
the law's design reads the whole reference, as the LQG's does). Tracking errors
are always measured against the desired, unshaped, undelayed path.

Default control period: 0.2 ms (5 kHz). The paper's arm has no hub inertia, so
the inertia a joint sees instantly is small (the links' modes take up the
rest), and under the paper's Jacobian-transpose gains the collocated loop has
real closed-loop poles from about -1700 rad/s (at the default square's first
corner) to -4500 rad/s (at its far corners). A zero-order-hold loop needs
roughly ``dt |lambda| < 2``: it diverges at 1 and 2 kHz and runs at 2.5 kHz and
above. Arms with hubs (motors) tolerate longer periods.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._budget import check_memory, check_time
from .._io import JSONValue
from .._validation import check_array, check_rng
from ..control.controllers import Controller, JacobianTransposePD
from ..control.feedforward import RigidDynamics
from ..control.signals import measurement_size
from ..control.trajectories import Square, Trajectory, check_trajectory
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm
from ..model.plant import Plant, check_plant
from ..sensing.channels import Channels, channel_arrays
from ..sensing.delays import DelayModel
from ..sensing.sensors import Sensor, check_sensor
from ._reference_kernels import OK, ReferenceStream, no_stream, stream_rows
from .chunks import StopFlag, run_in_chunks
from .loop import REFERENCE_FAILED, Loop, loop_inputs, run
from .references import BLOCK, ReferencePipeline
from .results import SimulationError, SimulationResult, assemble_result
from .scipy_loop import run_scipy
from .settings import SimulationSettings

__all__ = ["SimulationError", "check_budget", "recorded_instants", "simulate"]

F64 = NDArray[np.float64]
_OWNER = "simulate"


def simulate(
    arm: Plant,
    controller: Controller | None = None,
    trajectory: Trajectory | None = None,
    settings: SimulationSettings | None = None,
    *,
    rng: np.random.Generator | int | None = None,
    progress: bool | None = None,
    stop: StopFlag | None = None,
    **overrides: object,
) -> SimulationResult:
    """Simulate ``arm`` under ``controller`` tracking ``trajectory``.

    Parameters
    ----------
    arm : FlexibleArm
        The plant (two links when the reference needs inverse kinematics).
    controller : Controller, optional
        Default: the paper's ``JacobianTransposePD.from_arm(arm)``.
    trajectory : Trajectory, optional
        Anything with ``evaluate(t) -> (position, velocity, acceleration)``
        (arrays (m, 2)), ``duration`` and ``corner_times``; default
        :class:`flexarm.control.trajectories.Square` ().
    settings : SimulationSettings, optional
        The run's settings: sensor, delay, shaper, duration, control period,
        substeps, limits, recording (:class:`~flexarm.sim.settings.SimulationSettings`,
        validated when made). Default: ``SimulationSettings()``.
    rng : numpy.random.Generator or int, optional
        Source of sensor noise (seeded runs are reproducible); default
        ``settings.seed``.
    progress : bool, optional
        Show a progress bar on stderr (default: when stderr is a terminal and
        the run is long).
    stop : threading.Event or alike, optional
        Checked between chunks of the run (about every 2**15 control instants):
        once set, the run ends with :class:`~flexarm.errors.Cancelled` (how an
        interrupted batch stops its runs promptly).
    **overrides
        Fields of :class:`~flexarm.sim.settings.SimulationSettings` that replace
        those of ``settings`` (``simulate(arm, sensor=TipSensor(), duration=2.0)``).

    Returns
    -------
    SimulationResult

    Raises
    ------
    SimulationError
        If the state diverges; the partial result is attached.
    Cancelled
        If ``stop`` was set before the run's end.
    InvalidTypeError
        For a keyword that is not a setting, or an argument of the wrong type.
    InvalidValueError
        For a bad setting for this arm, a path out of the arm's workspace, a
        control period at which the loop is sampled-data unstable, or a run that
        would need more memory or time than the limits allow
        (``flexarm._budget``: ``FLEXARM_MAX_MEMORY``, ``FLEXARM_MAX_TIME``), which is
        refused before anything is allocated.
    """
    arm = check_plant(arm, _OWNER)
    controller = JacobianTransposePD.from_arm(arm) if controller is None else controller
    if not isinstance(controller, Controller):
        raise InvalidTypeError(
            f"The 'controller' parameter of {_OWNER} must be a flexarm Controller. "
            f"Got {type(controller).__name__} instead."
        )
    trajectory = Square() if trajectory is None else trajectory
    check_trajectory(trajectory, _OWNER)
    if settings is None:
        settings = SimulationSettings()
    elif not isinstance(settings, SimulationSettings):
        raise InvalidTypeError(
            f"The 'settings' parameter of {_OWNER} must be a SimulationSettings. "
            f"Got {type(settings).__name__} instead."
        )
    if overrides:
        settings = settings.replace(**overrides)
    generator = check_rng(settings.seed if rng is None else rng, _OWNER)
    setup = _set_up(arm, controller, trajectory, settings)
    status, k_end, wall = _execute(setup, generator, progress, stop)
    s, every = settings, settings.record_every
    info: dict[str, JSONValue] = {
        "controller": controller.name,
        "sensor": s.sensor.describe(arm),
        "delay_s": s.delay.delay,
        "effective_delay_s": setup.channels.delay,
        "delay_method": s.delay.method if s.delay.delay > 0 else "none",
        "delay_reference": s.delay_reference,
        "shaper": None if s.shaper is None else type(s.shaper).__name__,
        "dt_s": s.dt,
        "substeps": s.substeps,
        "record_every": every,
        "record_signals": s.record_signals,
        "method": s.method,
        "feedforward": setup.feedforward,
        "gravity_compensation": setup.gravity_compensation,
        "smoothing_s": setup.smoothing,
        "reference_chosen_by": "user" if s.smoothing is not None else "controller",
        "duration_s": setup.loop.n_steps * s.dt,
        "n_links": arm.n_links,
        "n_modes": list(arm.n_modes),
        "flexible_joints": bool(arm.has_flexible_joints),
        "corner_times_s": [float(c) for c in trajectory.corner_times],
        "motion_end_s": float(trajectory.duration),
        "wall_time_s": wall,
        "controller_state": setup.loop.state.ctrl_state.tolist(),
    }
    # the last row written: the instant the run reached, or the last one recorded before
    last_row = (k_end + every - 1) // every if status == 0 else k_end // every
    out = setup.loop.out
    rows = setup.kept.shape[0]
    return assemble_result(
        arm,
        t=np.multiply(setup.kept, s.dt, dtype=np.float64),
        q=out.q,
        dq=out.dq,
        tau=out.tau,
        measurement=out.y if s.record_signals else np.empty((rows, 0)),
        reference=out.r if s.record_signals else np.empty((rows, 0)),
        desired=out.desired,
        tip=out.tip if out.tip.shape[0] else None,
        diverged=status != 0,
        last_row=min(last_row, setup.kept.shape[0] - 1),
        info=info,
    )


class _Setup(NamedTuple):
    """A run prepared: the compiled loop's inputs and what drives it from Python."""

    arm: Plant
    loop: Loop
    control: object  # the law's compiled function (CFunc)
    channels: Channels
    pipeline: ReferencePipeline
    stream: ReferenceStream | None
    whole: tuple[F64, F64] | None  # the whole reference (short runs, the SciPy loop)
    kept: NDArray[np.int64]  # the recorded instants
    feedforward: bool
    gravity_compensation: bool
    smoothing: float  # s, the smoothing of the path used (the settings' or the law's)
    method: str
    n_rows: int


def _set_up(
    arm: Plant, controller: Controller, trajectory: Trajectory, s: SimulationSettings
) -> _Setup:
    """Everything of a run that depends on the arm: checked, computed, allocated once."""
    use_ff = bool(controller.feedforward) if s.feedforward is None else s.feedforward
    use_gc = bool(controller.gravity_compensation)
    if s.gravity_compensation is not None:
        use_gc = s.gravity_compensation
    use_gc = use_gc and getattr(arm, "gravity", None) is not None  # (nothing to hold without)
    N, n = arm.n_links, arm.n_dof
    duration = float(trajectory.duration) if s.duration is None else s.duration
    n_steps = round(duration / s.dt)
    if n_steps < 1:
        raise InvalidValueError(
            f"The 'duration' parameter of {_OWNER} must cover at least one control period "
            f"({s.dt} s). Got {duration} instead."
        )
    n_rows = n_steps + 1
    check_budget(
        arm,
        s.sensor,
        s.delay,
        dt=s.dt,
        duration=duration,
        substeps=s.substeps,
        record_every=s.record_every,
        record_signals=s.record_signals,
    )

    # ------------------------------------------------------------ reference
    smoothing = s.smoothing
    if smoothing is None:  # what the law asks for
        smoothing = _law_smoothing(arm, controller, trajectory, s)
    link, distance, _ = s.sensor.resolve(arm)
    short_of_tip = link >= 0 and not (link == N - 1 and distance == arm.link_lengths[-1])
    pipeline = ReferencePipeline(
        arm,
        trajectory,
        s.dt,
        n_steps,
        shaper=s.shaper,
        delay=s.delay.delay if s.delay_reference else 0.0,
        point=(link, distance) if short_of_tip else None,
        elbow=s.elbow,
        feedforward=_rigid_dynamics(arm) if use_ff else None,
        smoothing=smoothing,
        owner=_OWNER,
    )
    whole: tuple[F64, F64] | None = None
    # a path of straight segments is computed in the loop, instant by instant, unless
    # the law's design reads the run's reference
    streams = s.method == "rk4" and not _designs_on_reference(controller)
    stream = pipeline.stream() if streams else None
    if stream is not None:
        design_reference = _first_row(stream, pipeline, s.dt)
    elif n_rows <= _WHOLE_REFERENCE_ROWS or s.method == "scipy":
        whole = pipeline.rows(0, n_rows)  # short runs: once, for the design and the loop
        design_reference = whole[0]
    else:  # long runs: block by block; a pass first checks the path and samples it
        design_reference = _sampled_reference(pipeline, n_rows)

    # ------------------------------------------------------------ initial state, limits
    if s.initial_state is None:
        x0 = np.zeros(2 * n)
        if pipeline.initial_angles is not None:
            x0[:N] = pipeline.initial_angles
            if arm.has_flexible_joints:
                x0[arm.motor_slice] = x0[:N]
    else:
        x0 = check_array(s.initial_state, "initial_state", _OWNER, shape=(2 * n,)).copy()
    limit = _torque_limit(s.torque_limit, N)
    if s.max_deflection is None:
        max_defl = np.array(arm.link_lengths, dtype=float)
    else:
        max_defl = np.full(N, s.max_deflection)

    # ------------------------------------------------------------ the loop's inputs
    channels = channel_arrays(arm, s.sensor, s.delay, s.dt / s.substeps)
    params = controller.design(arm, s.sensor, s.dt, design_reference)
    kept = recorded_instants(0, n_rows, n_steps, s.record_every)
    # the loop records the tip where the arm gives its basis (else the assembly computes it)
    basis = getattr(arm, "point_basis", None)
    record_tip = basis is not None and s.method == "rk4"
    recorded_reference = None
    if whole is not None:
        recorded_reference = tuple(a if s.record_every == 1 else a[kept] for a in whole)
    loop = loop_inputs(
        model=arm.arrays,
        params=np.asarray(params, dtype=float),
        sensor=channels.arrays,
        stream=no_stream() if stream is None else stream,
        dt=s.dt,
        substeps=s.substeps,
        n_steps=n_steps,
        every=s.record_every,
        torque_limit=limit,
        max_deflection=max_defl,
        q=x0[:n],
        dq=x0[n:],
        controller_state=np.asarray(controller.initial_state(arm), dtype=float),
        tip_phi=basis(N - 1, float(arm.link_lengths[-1])) if record_tip and basis else None,
        reference=recorded_reference,  # type: ignore[arg-type]
        recorded=kept.shape[0],
        record_signals=s.record_signals,
        gravity_compensation=use_gc,
    )
    if s.check_sampling and isinstance(arm, FlexibleArm):
        from ..control.sampling import check_sampling as check

        verdict = check(
            arm,
            controller,
            s.sensor,
            x0[:N],
            design_reference[0],
            loop.params,
            loop.state.ctrl_state.copy(),
            s.dt,
            gravity_compensation=use_gc,
        )
        if verdict.period_too_long:  # (a loop unstable in continuous time diverges anyway)
            raise InvalidValueError(verdict.message(_OWNER, _hubless_note(arm)))
    return _Setup(
        arm=arm,
        loop=loop,
        control=controller.cfunc,
        channels=channels,
        pipeline=pipeline,
        stream=stream,
        whole=whole,
        kept=kept,
        feedforward=use_ff,
        gravity_compensation=use_gc,
        smoothing=smoothing,
        method=s.method,
        n_rows=n_rows,
    )


def _execute(
    setup: _Setup, generator: np.random.Generator, progress: bool | None, stop: StopFlag | None
) -> tuple[int, int, float]:
    """Run the prepared loop: ``(status, last instant reached, wall time in s)``."""
    loop, pipeline, whole, stream = setup.loop, setup.pipeline, setup.whole, setup.stream
    n_rows, n_steps, every = setup.n_rows, loop.n_steps, loop.every
    n_ch, no_noise = setup.channels.n_ch, np.zeros((0, setup.channels.n_ch))
    start = time.perf_counter()
    if setup.method == "scipy":
        assert whole is not None
        status, k_end = run_scipy(setup.arm, loop, setup.control, whole[0])  # type: ignore[arg-type]
        return status, k_end, time.perf_counter() - start

    def chunk(k0: int, k1: int) -> tuple[int, int]:
        if stream is not None:
            reference = whole_or_empty  # not read: the loop computes it
        elif whole is not None:
            reference = whole[0][k0:k1]
        else:
            reference, desired = pipeline.rows(k0, k1)
            ks = recorded_instants(k0, k1, n_steps, every)
            rows = (ks + every - 1) // every
            loop.out.desired[rows] = desired[ks - k0]
            if loop.out.r.shape[0]:  # (no rows: the reference is not recorded)
                loop.out.r[rows] = reference[ks - k0]
        noise = no_noise
        if setup.channels.noisy:  # drawn block by block, in order: the same stream at once
            noise = generator.normal(size=(k1 - k0, n_ch))
        status, k = run(loop, setup.control, reference, noise, k0, k1)  # type: ignore[arg-type]
        if status == REFERENCE_FAILED:
            pipeline.raise_at(k)  # the pipeline's own message for that instant
        return int(status), int(k)

    whole_or_empty = np.zeros((0, pipeline.size))
    status, k_end = run_in_chunks(
        chunk,
        n_rows,
        n_rows * loop.substeps * loop.state.q.shape[0],
        progress,
        block=None if n_rows <= _WHOLE_REFERENCE_ROWS and stop is None else BLOCK,
        stop=stop,
    )
    return status, k_end, time.perf_counter() - start


_WHOLE_REFERENCE_ROWS = 4 * BLOCK
"""Runs with at most this many control instants compute their reference at once."""


def recorded_instants(k0: int, k1: int, n_steps: int, every: int) -> NDArray[np.int64]:
    """The instants ``k0 <= k < k1`` that a run of ``n_steps`` periods records with
    ``record_every = every``: the multiples of ``every``, and the last instant."""
    first = -(-k0 // every) * every
    kept = np.arange(first, k1, every, dtype=np.int64)
    if k0 <= n_steps < k1 and n_steps % every:
        kept = np.append(kept, np.int64(n_steps))
    return kept


_PATH_POINTS = 17
"""Evenly spaced instants (and the corners) at which a law is shown the path to choose
its reference (``Controller.reference_smoothing``)."""


def _law_smoothing(
    arm: Plant, controller: Controller, trajectory: Trajectory, s: SimulationSettings
) -> float:
    """The smoothing ``controller`` asks for (s), shown the path's end-effector points at
    :data:`_PATH_POINTS` evenly spaced instants and at the corners; checked."""
    if type(controller).reference_smoothing is Controller.reference_smoothing:
        return 0.0  # (the interface's own answer, without evaluating the path)
    duration = float(trajectory.duration)
    corners = [float(c) for c in trajectory.corner_times if 0.0 <= float(c) <= duration]
    times = np.union1d(np.linspace(0.0, duration, _PATH_POINTS), corners)
    path = np.asarray(trajectory.evaluate(times)[0], dtype=float).reshape(-1, 2)
    value = controller.reference_smoothing(arm, s.sensor, s.dt, path, s.elbow)
    if not isinstance(value, int | float) or not (np.isfinite(value) and value >= 0):
        raise InvalidValueError(
            f"The 'reference_smoothing' of {type(controller).__name__} must be a finite "
            f"number of seconds >= 0. Got {value!r} instead."
        )
    return float(value)


def _designs_on_reference(controller: Controller) -> bool:
    """Whether ``controller``'s design may read the run's reference (it overrides
    :meth:`~flexarm.control.controllers.Controller.design`)."""
    return type(controller).design is not Controller.design


def _first_row(stream: ReferenceStream, pipeline: ReferencePipeline, dt: float) -> F64:
    """The streamed reference's first row, shape (1, size) (or the pipeline's error)."""
    first, desired = np.zeros((1, pipeline.size)), np.empty((1, 2))
    status, k, _ = stream_rows(stream, np.zeros(1, dtype=np.int64), dt, first, desired)
    if status != OK:
        pipeline.raise_at(k)
    return first


def _sampled_reference(pipeline: ReferencePipeline, n_rows: int) -> F64:
    """The reference at evenly strided instants (at most :data:`_WHOLE_REFERENCE_ROWS`),
    from a pass over the whole path (which also checks it before the run starts)."""
    stride = -(-n_rows // _WHOLE_REFERENCE_ROWS)
    parts = []
    for k0 in range(0, n_rows, BLOCK):
        reference, _ = pipeline.rows(k0, min(k0 + BLOCK, n_rows))
        first = -(-k0 // stride) * stride
        parts.append(reference[first - k0 :: stride].copy())  # not a view: frees the block
    return np.concatenate(parts)


def check_budget(
    arm: Plant,
    sensor: Sensor | None = None,
    delay: DelayModel | None = None,
    *,
    dt: float,
    duration: float,
    substeps: int = 1,
    record_every: int = 1,
    record_signals: bool = True,
    runs: int = 1,
    workers: int = 1,
    owner: str = _OWNER,
    remedy: str | None = None,
) -> None:
    """Refuse runs that would need more memory or time than the limits allow.

    :func:`simulate` checks each run before allocating anything; a batch (e.g.
    ``flexarm reproduce``) checks all of its ``runs`` at once before the first, with
    ``min(runs, 2 workers)`` runs in memory at a time and ``runs / workers`` runs'
    time in all. Limits: ``flexarm._budget`` (``FLEXARM_MAX_MEMORY``,
    ``FLEXARM_MAX_TIME``).

    Parameters
    ----------
    arm : FlexibleArm
    sensor : Sensor, optional
        Default: the joint encoders.
    delay : DelayModel, optional
        Default: none.
    dt, duration : float
        Control period and simulated time, s.
    substeps, record_every : int
        As for :func:`simulate`.
    record_signals : bool
        As for :func:`simulate`: whether the measurement and the reference are
        recorded.
    runs, workers : int
        Runs of this size, and how many run at once.
    owner : str
        Named in the message.
    remedy : str, optional
        What to change, for the message (default: in :func:`simulate`'s terms).

    Raises
    ------
    InvalidValueError
        Naming what the runs would need, what to change and how to raise the limit.
    """
    sensor = check_sensor(sensor, owner)
    delay = DelayModel.none() if delay is None else delay
    N, n = arm.n_links, arm.n_dof
    n_steps = max(1, round(duration / dt))
    n_out = n_steps // record_every + 2
    n_y = measurement_size(N, sum(arm.n_modes))
    # per recorded row: t, q, dq, tau, measurement, reference, desired, tip, and the
    # assembly's temporaries (about as much again)
    signals = n_y + (6 + 4 * N) if record_signals else 0
    per_row = 8 * 2 * (1 + 2 * n + N + signals + 2 + 2)
    link = sensor.resolve(arm)[0]
    n_ch = 2 * N if link < 0 else 4
    h = dt / substeps
    ring = 0.0
    if delay.delay > 0 and delay.method == "exact":
        ring = 8.0 * n_ch * (delay.delay / h + 1)
    blocks = 8.0 * min(n_steps + 1, _WHOLE_REFERENCE_ROWS) * (6 + 4 * N + 2 + n_ch)
    at_once = min(runs, 2 * workers)
    what = f"{runs} runs of" if runs > 1 else "a run of"
    check_memory(
        (per_row * float(n_out) + ring + blocks) * at_once,
        f"{what} {n_steps + 1:.4g} control instants recording {n_out:.4g} rows"
        + (f" with a delay line of {delay.delay / h:.4g} substeps" if ring else "")
        + (f", {at_once} at a time" if runs > 1 else ""),
        owner,
        remedy
        or "Record fewer instants (record_every), shorten the duration, lengthen dt"
        + (" or shorten the delay" if ring else ""),
    )
    # about four dynamics calls per RK4 substep; a call grows with n_dof squared
    step = 4.0 * (60e-9 + 12e-9 * n * n) + 150e-9
    check_time(
        step * float(n_steps) * substeps * runs / max(1, min(workers, runs)),
        f"{what} {float(n_steps) * substeps:.4g} RK4 steps"
        + (f" on {min(workers, runs)} cores" if runs > 1 else ""),
        owner,
        remedy or "Shorten the duration, lengthen dt or use fewer substeps",
    )


def _torque_limit(torque_limit: float | tuple[float, ...] | None, n_links: int) -> F64:
    """Per-joint saturation (N m; the settings checked the values): infinite by
    default, one value broadcast, else one per joint."""
    if torque_limit is None:
        return np.full(n_links, np.inf)
    if isinstance(torque_limit, float):
        return np.full(n_links, torque_limit)
    limit = np.array(torque_limit, dtype=float)
    if limit.shape != (n_links,):
        raise InvalidValueError(
            f"The 'torque_limit' parameter of {_OWNER} must be a scalar or one per joint "
            f"({n_links}). Got {torque_limit!r} instead."
        )
    return limit


def _hubless_note(arm: FlexibleArm) -> str:
    """A clause for the sampled-data message when the arm has no hub inertia (the
    paper's idealisation: every loop closed on it is stiff)."""
    if arm.has_flexible_joints or any(link.hub_inertia > 0 for link in arm.links):
        return ""
    if any(jt.motor_inertia > 0 for jt in arm.joints or ()):  # rigid joints' rotors
        return ""
    return (
        " (the arm has no hub inertia, the paper's idealisation, which makes every loop "
        "closed on it stiff: on the paper's links the paper's PD has poles down to about "
        "-4,500 rad/s with one mode per link and -86,000 with three; hubs of 1 kg m^2 "
        "bring them to -450 to -1,200)"
    )


def _rigid_dynamics(arm: Plant) -> RigidDynamics:
    if not isinstance(arm, FlexibleArm) or arm.n_links != 2:
        raise InvalidValueError(
            f"The 'feedforward' parameter of {_OWNER} needs a two-link FlexibleArm (rigid "
            f"inverse dynamics of the joint references). Got {type(arm).__name__} with "
            f"{arm.n_links} links instead."
        )
    return RigidDynamics.of(arm)
