"""Closed-loop simulation: :func:`simulate`.

The controller runs at its sample rate (period ``dt``) with zero-order hold;
the plant is integrated by fixed-step RK4 with ``substeps`` steps per period;
the whole loop is compiled (:mod:`flexarm.sim.loop`). ``method="scipy"`` runs
the same sampled-data loop with SciPy's adaptive ``solve_ivp`` (DOP853) between
control instants instead, as the accuracy reference for the fixed-step path.

:func:`simulate` is three steps: the reference pipeline
(:class:`flexarm.sim.references.ReferencePipeline`: trajectory, shaper, delay,
joint references), the loop driver (:mod:`flexarm.sim.driver`), and the result
assembly (:func:`flexarm.sim.results.assemble_result`). A path of straight
segments (the square, lines, waypoints) without shaping, smoothing, feedforward or
a sensed point short of the end effector is not precomputed: the compiled loop
computes its reference at each instant with the pipeline's own kernels (the same
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

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._budget import check_memory, check_time
from .._io import JSONValue
from .._validation import check_array, check_int, check_option, check_real, check_rng
from ..control.controllers import Controller, JacobianTransposePD
from ..control.feedforward import RigidDynamics
from ..control.signals import measurement_size
from ..control.trajectories import Square, Trajectory, check_trajectory
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm
from ..model.kinematics import lever_lengths
from ..model.plant import Plant, check_plant
from ..sensing.delays import DelayModel, discretize, pade_state_space
from ..sensing.sensors import Sensor, check_sensor
from ._reference_kernels import OK, ReferenceStream, no_stream, stream_rows
from .driver import LoopOutputs, StopFlag, run_in_chunks, run_scipy
from .loop import (
    REFERENCE_FAILED,
    SensorArrays,
    loop_state,
    prime_delay_line,
    run,
    sensor_arrays,
)
from .references import BLOCK, PathShaper, ReferencePipeline
from .results import SimulationError, SimulationResult, assemble_result

__all__ = ["SimulationError", "check_budget", "recorded_instants", "simulate"]

F64 = NDArray[np.float64]
_OWNER = "simulate"


def simulate(
    arm: Plant,
    controller: Controller | None = None,
    trajectory: Trajectory | None = None,
    *,
    sensor: Sensor | None = None,
    delay: DelayModel | None = None,
    delay_reference: bool = False,
    shaper: PathShaper | None = None,
    duration: float | None = None,
    dt: float = 2e-4,
    substeps: int = 1,
    torque_limit: float | ArrayLike | None = None,
    initial_state: ArrayLike | None = None,
    elbow: str = "positive",
    max_deflection: float | None = None,
    method: str = "rk4",
    rng: np.random.Generator | int | None = None,
    progress: bool | None = None,
    feedforward: bool | None = None,
    smoothing: float = 0.0,
    check_sampling: bool = True,
    record_every: int = 1,
    stop: StopFlag | None = None,
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
    sensor : JointSensor, PointSensor or TipSensor, optional
        Default :class:`JointSensor` (). With a point short of the end effector
        (two-link arms), the operational-space command is that point's desired
        position and velocity (rigid kinematics of the joint references), so
        that ``e = x_c - x`` compares like with like; the tracking errors are
        still those of the end effector.
    delay : DelayModel, optional
        Transport delay of the sensed signal (default none).
    delay_reference : bool
        Delay the reference fed to the control law by the same amount.
    shaper : Shaper, optional
        Input shaper applied to the reference path.
    duration : float, optional
        Simulated time in s (default: the trajectory's duration).
    dt : float
        Control period, s (default 0.2 ms: see the module docstring).
    substeps : int
        RK4 steps per control period (>= 1).
    torque_limit : float or array_like, shape (n_links,), optional
        Symmetric saturation of each joint torque, N m (default none).
    initial_state : array_like, shape (2 n_dof,), optional
        ``(q, dq)`` at t = 0. Default: at rest, undeflected, on the reference's
        first point (motor angles equal to joint angles).
    elbow : {"positive", "negative"}
        Inverse-kinematics branch of the reference.
    max_deflection : float, optional
        Tip deflection of any link (m) beyond which the run counts as diverged
        (default: that link's length).
    method : {"rk4", "scipy"}
        Compiled fixed-step loop, or the SciPy adaptive reference (slow).
    rng : numpy.random.Generator or int, optional
        Source of sensor noise (seeded runs are reproducible).
    progress : bool, optional
        Show a progress bar on stderr (default: when stderr is a terminal and
        the run is long).
    feedforward : bool, optional
        Add the rigid inverse dynamics of the joint references
        (:class:`flexarm.control.feedforward.RigidDynamics`) to the law's torque
        (two-link arms). Default: what the controller asks for
        (``controller.feedforward``; the observer-based law does).
    smoothing : float
        Standard deviation (s) of a zero-phase Gaussian smoothing of the path fed
        to the law (0: none): the reference is known in advance, so a corner
        taken at constant speed is cut symmetrically with finite acceleration
        (:func:`flexarm.sim.references.smoothed_path`). Errors are still measured
        against the unsmoothed path.
    check_sampling : bool
        Before running, linearise the loop at the start and refuse a control
        period ``dt`` at which it is sampled-data unstable, with the pole and the
        period that would work (:mod:`flexarm.control.sampling`; undelayed,
        noise-free). False runs it anyway (to watch it diverge).
    record_every : int
        Record every ``record_every``-th control instant, and the last one (>= 1;
        default every instant). The run itself is the same; a long run then fits
        in bounded memory (the reference is computed as the run goes).
        The metrics are those of the recorded instants.
    stop : threading.Event or alike, optional
        Checked between chunks of the run (about every 2**15 control instants):
        once set, the run ends with :class:`~flexarm.errors.Cancelled` (how an
        interrupted batch stops its runs promptly).

    Returns
    -------
    SimulationResult

    Raises
    ------
    SimulationError
        If the state diverges; the partial result is attached.
    Cancelled
        If ``stop`` was set before the run's end.
    InvalidValueError
        For a bad parameter, a path out of the arm's workspace, a control period
        at which the loop is sampled-data unstable, or a run that would need
        more memory or time than the limits allow (``flexarm._budget``:
        ``FLEXARM_MAX_MEMORY``, ``FLEXARM_MAX_TIME``), which is refused before
        anything is allocated.
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
    sensor = check_sensor(sensor, _OWNER)
    delay = DelayModel.none() if delay is None else delay
    if not isinstance(delay, DelayModel):
        raise InvalidTypeError(
            f"The 'delay' parameter of {_OWNER} must be a DelayModel. "
            f"Got {type(delay).__name__} instead."
        )
    if shaper is not None and not callable(getattr(shaper, "apply_function", None)):
        raise InvalidTypeError(
            f"The 'shaper' parameter of {_OWNER} must be a Shaper (with apply_function). "
            f"Got {type(shaper).__name__} instead."
        )
    dt = check_real(dt, "dt", _OWNER, positive=True)
    substeps = check_int(substeps, "substeps", _OWNER, minimum=1)
    duration = float(trajectory.duration) if duration is None else duration
    duration = check_real(duration, "duration", _OWNER, positive=True)
    check_option(method, "method", _OWNER, ("rk4", "scipy"))
    check_option(elbow, "elbow", _OWNER, ("positive", "negative"))
    if not isinstance(delay_reference, bool):
        raise InvalidTypeError(
            f"The 'delay_reference' parameter of {_OWNER} must be a bool. "
            f"Got {delay_reference!r} instead."
        )
    generator = check_rng(rng, _OWNER)
    for name, flag in (("feedforward", feedforward), ("check_sampling", check_sampling)):
        if not isinstance(flag, bool) and not (name == "feedforward" and flag is None):
            raise InvalidTypeError(
                f"The '{name}' parameter of {_OWNER} must be a bool. Got {flag!r} instead."
            )
    use_ff = bool(controller.feedforward) if feedforward is None else feedforward
    every = check_int(record_every, "record_every", _OWNER, minimum=1)
    N, n = arm.n_links, arm.n_dof
    n_steps = round(duration / dt)
    if n_steps < 1:
        raise InvalidValueError(
            f"The 'duration' parameter of {_OWNER} must cover at least one control period "
            f"({dt} s). Got {duration} instead."
        )
    n_rows = n_steps + 1
    ny = measurement_size(N, sum(arm.n_modes))
    check_budget(
        arm, sensor, delay, dt=dt, duration=duration, substeps=substeps, record_every=every
    )

    # ------------------------------------------------------------ reference
    link, distance, _ = sensor.resolve(arm)
    short_of_tip = link >= 0 and not (link == N - 1 and distance == arm.link_lengths[-1])
    pipeline = ReferencePipeline(
        arm,
        trajectory,
        dt,
        n_steps,
        shaper=shaper,
        delay=delay.delay if delay_reference else 0.0,
        point=(link, distance) if short_of_tip else None,
        elbow=elbow,
        feedforward=_rigid_dynamics(arm) if use_ff else None,
        smoothing=check_real(smoothing, "smoothing", _OWNER, nonnegative=True),
        owner=_OWNER,
    )
    whole: tuple[F64, F64] | None = None
    # a path of straight segments is computed in the loop, instant by instant, unless
    # the law's design reads the run's reference
    streams = method == "rk4" and not _designs_on_reference(controller)
    stream = pipeline.stream() if streams else None
    if stream is not None:
        design_reference = _first_row(stream, pipeline, dt)
    elif n_rows <= _WHOLE_REFERENCE_ROWS or method == "scipy":
        whole = pipeline.rows(0, n_rows)  # short runs: once, for the design and the loop
        design_reference = whole[0]
    else:  # long runs: block by block; a pass first checks the path and samples it
        design_reference = _sampled_reference(pipeline, n_rows)

    # ------------------------------------------------------------ initial state, limits
    if initial_state is None:
        x0 = np.zeros(2 * n)
        if pipeline.initial_angles is not None:
            x0[:N] = pipeline.initial_angles
            if arm.has_flexible_joints:
                x0[arm.motor_slice] = x0[:N]
    else:
        x0 = check_array(initial_state, "initial_state", _OWNER, shape=(2 * n,)).copy()
    limit = _torque_limit(torque_limit, N)
    if max_deflection is None:
        max_defl = np.array(arm.link_lengths, dtype=float)
    else:
        max_defl = np.full(N, check_real(max_deflection, "max_deflection", _OWNER, positive=True))

    # ------------------------------------------------------------ sensor, state
    h = dt / substeps
    sensed, levels, effective_delay = _sensor_arrays(arm, sensor, delay, h)
    params = np.ascontiguousarray(controller.design(arm, sensor, dt, design_reference), dtype=float)
    state = loop_state(
        q=x0[:n],
        dq=x0[n:],
        n_links=N,
        controller_state=np.asarray(controller.initial_state(arm), dtype=float),
        sensor=sensed,
        n_y=ny,
    )
    prime_delay_line(arm.arrays, sensed, state)
    if check_sampling and isinstance(arm, FlexibleArm):
        from ..control.sampling import check_sampling as check

        verdict = check(
            arm,
            controller,
            sensor,
            x0[:N],
            design_reference[0],
            params,
            state.ctrl_state.copy(),
            dt,
        )
        if verdict.period_too_long:  # (a loop unstable in continuous time diverges anyway)
            raise InvalidValueError(verdict.message(_OWNER, _hubless_note(arm)))
    kept = recorded_instants(0, n_rows, n_steps, every)
    n_out = kept.shape[0]
    out: LoopOutputs = {  # every row up to the last one reached is written
        "q": np.empty((n_out, n)),
        "dq": np.empty((n_out, n)),
        "tau": np.empty((n_out, N)),
        "measurement": np.empty((n_out, ny)),
    }
    # the loop records the tip where the arm gives its basis (else the assembly computes it)
    basis = getattr(arm, "point_basis", None)
    tip_phi = np.zeros(0) if basis is None else basis(N - 1, float(arm.link_lengths[-1]))
    out["tip"] = np.empty((n_out if basis is not None and method == "rk4" else 0, 2))
    if whole is not None:
        out["reference"], out["desired"] = (a if every == 1 else a[kept] for a in whole)
    else:
        out["reference"], out["desired"] = np.empty((n_out, pipeline.size)), np.empty((n_out, 2))

    # ------------------------------------------------------------ run
    start = time.perf_counter()
    if method == "rk4":

        def chunk(k0: int, k1: int) -> tuple[int, int]:
            if stream is not None:
                reference = design_reference[:0]  # not read: the loop computes it
            elif whole is not None:
                reference = whole[0][k0:k1]
            else:
                reference, desired = pipeline.rows(k0, k1)
                ks = recorded_instants(k0, k1, n_steps, every)
                rows = (ks + every - 1) // every
                out["reference"][rows], out["desired"][rows] = reference[ks - k0], desired[ks - k0]
            noise = sensed.noise
            if np.any(levels > 0):  # drawn block by block, in order: the same stream at once
                noise = generator.normal(size=(k1 - k0, levels.shape[0])) * levels
            first = (k0 + every - 1) // every
            status, k = run(
                arm.arrays,
                controller.cfunc,
                params,
                sensed._replace(noise=noise),
                reference,
                no_stream() if stream is None else stream,
                dt,
                substeps,
                limit,
                max_defl,
                state,
                k0,
                k1,
                n_steps,
                every,
                out["q"][first:],
                out["dq"][first:],
                out["tau"][first:],
                out["measurement"][first:],
                out["reference"][first:],
                out["desired"][first:],
                tip_phi,
                out["tip"][first:],
            )
            if status == REFERENCE_FAILED:
                pipeline.raise_at(k)  # the pipeline's own message for that instant
            return int(status), int(k)

        status, k_end = run_in_chunks(
            chunk,
            n_rows,
            n_rows * substeps * n,
            progress,
            block=None if n_rows <= _WHOLE_REFERENCE_ROWS and stop is None else BLOCK,
            stop=stop,
        )
    else:
        assert whole is not None
        if every != 1 or np.any(levels > 0):
            raise InvalidValueError(
                f"The 'method' parameter of {_OWNER}='scipy' supports noise-free sensing "
                "recorded at every control instant only (it is the integrator's accuracy "
                "reference)."
            )
        status, k_end = run_scipy(
            arm, controller.cfunc, params, sensed, whole[0], dt, limit, max_defl, state, out
        )
    info: dict[str, JSONValue] = {
        "controller": controller.name,
        "sensor": sensor.describe(arm),
        "delay_s": delay.delay,
        "effective_delay_s": effective_delay,
        "delay_method": delay.method if delay.delay > 0 else "none",
        "delay_reference": delay_reference,
        "shaper": None if shaper is None else type(shaper).__name__,
        "dt_s": dt,
        "substeps": substeps,
        "record_every": every,
        "method": method,
        "feedforward": use_ff,
        "smoothing_s": smoothing,
        "duration_s": n_steps * dt,
        "n_links": N,
        "n_modes": list(arm.n_modes),
        "flexible_joints": bool(arm.has_flexible_joints),
        "corner_times_s": [float(c) for c in trajectory.corner_times],
        "motion_end_s": float(trajectory.duration),
        "wall_time_s": time.perf_counter() - start,
        "controller_state": state.ctrl_state.tolist(),
    }
    # the last row written: the instant the run reached, or the last one recorded before
    last_row = (k_end + every - 1) // every if status == 0 else k_end // every
    return assemble_result(
        arm,
        t=np.multiply(kept, dt, dtype=np.float64),
        q=out["q"],
        dq=out["dq"],
        tau=out["tau"],
        measurement=out["measurement"],
        reference=out["reference"],
        desired=out["desired"],
        tip=out["tip"] if out["tip"].shape[0] else None,
        diverged=status != 0,
        last_row=min(last_row, n_out - 1),
        info=info,
    )


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
    per_row = 8 * 2 * (1 + 2 * n + N + n_y + (6 + 4 * N) + 2 + 2)
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


def _torque_limit(torque_limit: float | ArrayLike | None, n_links: int) -> F64:
    """Per-joint saturation (N m): infinite by default; scalar broadcast; > 0."""
    if torque_limit is None:
        return np.full(n_links, np.inf)
    limit = check_array(torque_limit, "torque_limit", _OWNER, finite=False)
    if limit.ndim == 0:
        limit = np.broadcast_to(limit, (n_links,)).astype(float).copy()
    if limit.shape != (n_links,) or np.any(np.isnan(limit)) or np.any(limit <= 0):
        raise InvalidValueError(
            f"The 'torque_limit' parameter of {_OWNER} must be > 0, scalar or of shape "
            f"({n_links},). Got {torque_limit!r} instead."
        )
    return np.asarray(limit, dtype=float)


def _sensor_arrays(
    arm: Plant, sensor: Sensor, delay: DelayModel, h: float
) -> tuple[SensorArrays, F64, float]:
    """The sensor and its delay (at substep resolution ``h``) as plain arrays (no
    noise rows yet), the noise levels of its channels, and the delay actually
    realised (s)."""
    link, distance, phi = sensor.resolve(arm)
    n_links = arm.n_links
    n_ch = 2 * n_links if link < 0 else 4
    half = n_ch // 2
    levels = np.r_[np.full(half, sensor.noise_std), np.full(half, sensor.rate_noise_std)]
    resolution = np.r_[np.full(half, sensor.quantization), np.full(half, sensor.rate_quantization)]
    delay_steps, pade, effective = 0, None, 0.0
    if delay.delay > 0:
        if delay.method == "exact":
            delay_steps = round(delay.delay / h)
            effective = delay_steps * h
        else:
            ad, bd, cd, dd = discretize(*pade_state_space(delay.delay, delay.order), h)
            pade = (ad, bd[:, 0], cd[0], dd[0])
            effective = delay.delay
    rigid = link >= 0 and sensor.model == "paper"
    lengths = np.asarray(arm.link_lengths, dtype=float)
    arrays = sensor_arrays(
        link=link,
        rigid=rigid,
        distance=distance,
        phi=phi,
        levers=lever_lengths(lengths, link, distance) if rigid else lengths,
        delay_steps=delay_steps,
        pade=pade,
        noise=np.zeros((0, n_ch)),  # drawn block by block as the run goes
        resolution=resolution,
    )
    return arrays, levels, effective


def _hubless_note(arm: FlexibleArm) -> str:
    """A clause for the sampled-data message when the arm has no hub inertia (the
    paper's idealisation: every loop closed on it is stiff)."""
    if arm.has_flexible_joints or any(link.hub_inertia > 0 for link in arm.links):
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
