"""Closed-loop simulation: :func:`simulate`.

The controller runs at its sample rate (period ``dt``) with zero-order hold;
the plant is integrated by fixed-step RK4 with ``substeps`` steps per period;
the whole loop is compiled (:mod:`flexarm.sim.loop`). ``method="scipy"`` runs
the same sampled-data loop with SciPy's adaptive ``solve_ivp`` (DOP853) between
control instants instead, as the accuracy reference for the fixed-step path.

:func:`simulate` is three steps: the reference pipeline
(:func:`flexarm.sim.references.reference_signals`: trajectory, shaper, delay,
joint references), the loop driver (:mod:`flexarm.sim.driver`), and the result
assembly (:func:`flexarm.sim.results.assemble_result`). Tracking errors are
always measured against the desired, unshaped, undelayed path.

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
from .driver import LoopOutputs, run_in_chunks, run_scipy
from .loop import LoopState, SensorArrays, loop_state, prime_delay_line, run, sensor_arrays
from .references import PathShaper, reference_signals
from .results import SimulationError, SimulationResult, assemble_result

__all__ = ["SimulationError", "simulate"]

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

    Returns
    -------
    SimulationResult

    Raises
    ------
    SimulationError
        If the state diverges; the partial result is attached.
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
    N, n = arm.n_links, arm.n_dof
    n_steps = round(duration / dt)
    if n_steps < 1:
        raise InvalidValueError(
            f"The 'duration' parameter of {_OWNER} must cover at least one control period "
            f"({dt} s). Got {duration} instead."
        )
    t: F64 = np.arange(n_steps + 1, dtype=np.float64) * dt

    # ------------------------------------------------------------ reference
    link, distance, _ = sensor.resolve(arm)
    short_of_tip = link >= 0 and not (link == N - 1 and distance == arm.link_lengths[-1])
    refs = reference_signals(
        arm,
        trajectory,
        t,
        shaper=shaper,
        delay=delay.delay if delay_reference else 0.0,
        point=(link, distance) if short_of_tip else None,
        elbow=elbow,
        feedforward=_rigid_dynamics(arm) if use_ff else None,
        smoothing=check_real(smoothing, "smoothing", _OWNER, nonnegative=True),
        owner=_OWNER,
    )

    # ------------------------------------------------------------ initial state, limits
    if initial_state is None:
        x0 = np.zeros(2 * n)
        if refs.initial_angles is not None:
            x0[:N] = refs.initial_angles
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
    sensed, effective_delay = _sensor_arrays(arm, sensor, delay, h, n_steps + 1, generator)
    params = np.ascontiguousarray(controller.design(arm, sensor, dt, refs.reference), dtype=float)
    ny = measurement_size(N, sum(arm.n_modes))
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
            arm, controller, sensor, x0[:N], refs.reference[0], params, state.ctrl_state.copy(), dt
        )
        if verdict.period_too_long:  # (a loop unstable in continuous time diverges anyway)
            raise InvalidValueError(verdict.message(_OWNER))
    out: LoopOutputs = {  # every row up to the last one reached is written
        "q": np.empty((n_steps + 1, n)),
        "dq": np.empty((n_steps + 1, n)),
        "tau": np.empty((n_steps + 1, N)),
        "measurement": np.empty((n_steps + 1, ny)),
    }

    # ------------------------------------------------------------ run
    start = time.perf_counter()
    if method == "rk4":

        def chunk(k0: int, k1: int) -> tuple[int, int]:
            return _run(
                arm,
                controller,
                params,
                sensed,
                refs.reference,
                dt,
                substeps,
                limit,
                max_defl,
                state,
                k0,
                k1,
                out,
            )

        status, k_end = run_in_chunks(chunk, n_steps + 1, (n_steps + 1) * substeps * n, progress)
    else:
        status, k_end = run_scipy(
            arm, controller.cfunc, params, sensed, refs.reference, dt, limit, max_defl, state, out
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
    return assemble_result(
        arm,
        t=t,
        q=out["q"],
        dq=out["dq"],
        tau=out["tau"],
        measurement=out["measurement"],
        reference=refs.reference,
        desired=refs.desired,
        diverged=status != 0,
        last_row=k_end,
        info=info,
    )


def _run(
    arm: Plant,
    controller: Controller,
    params: F64,
    sensed: SensorArrays,
    reference: F64,
    dt: float,
    substeps: int,
    limit: F64,
    max_defl: F64,
    state: LoopState,
    k0: int,
    k1: int,
    out: LoopOutputs,
) -> tuple[int, int]:
    status, k = run(
        arm.arrays,
        controller.cfunc,
        params,
        sensed,
        reference,
        dt,
        substeps,
        limit,
        max_defl,
        state,
        k0,
        k1,
        out["q"],
        out["dq"],
        out["tau"],
        out["measurement"],
    )
    return int(status), int(k)


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
    arm: Plant, sensor: Sensor, delay: DelayModel, h: float, n_rows: int, rng: np.random.Generator
) -> tuple[SensorArrays, float]:
    """The sensor, its delay (at substep resolution ``h``) and its noise as plain
    arrays, and the delay actually realised (s)."""
    link, distance, phi = sensor.resolve(arm)
    n_links = arm.n_links
    n_ch = 2 * n_links if link < 0 else 4
    half = n_ch // 2
    levels = np.r_[np.full(half, sensor.noise_std), np.full(half, sensor.rate_noise_std)]
    resolution = np.r_[np.full(half, sensor.quantization), np.full(half, sensor.rate_quantization)]
    noise = np.zeros((0, n_ch))  # no noise: no draws (the rng is left untouched)
    if np.any(levels > 0):
        noise = rng.normal(size=(n_rows, n_ch)) * levels
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
        noise=noise,
        resolution=resolution,
    )
    return arrays, effective


def _rigid_dynamics(arm: Plant) -> RigidDynamics:
    if not isinstance(arm, FlexibleArm) or arm.n_links != 2:
        raise InvalidValueError(
            f"The 'feedforward' parameter of {_OWNER} needs a two-link FlexibleArm (rigid "
            f"inverse dynamics of the joint references). Got {type(arm).__name__} with "
            f"{arm.n_links} links instead."
        )
    return RigidDynamics.of(arm)
