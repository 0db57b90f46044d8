"""Closed-loop simulation: :func:`simulate`.

The controller runs at its sample rate (period ``dt``) with zero-order hold;
the plant is integrated by fixed-step RK4 with ``substeps`` steps per period;
the whole loop is compiled (:mod:`flexarm.sim.loop`). ``method="scipy"`` runs
the same sampled-data loop with SciPy's adaptive ``solve_ivp`` (DOP853) between
control instants instead, as the accuracy reference for the fixed-step path.

Reference path: the trajectory gives the desired end-effector path; an input
shaper (:mod:`flexarm.control.shapers`) reshapes it; with ``delay_reference=True`` it is
also delayed by the sensor's transport delay (the paper's correction of the NMP
response, "time delays for command signals input to the control law"); inverse
kinematics (two-link arms) turns it into joint references. Tracking errors are
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

import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_int, check_option, check_real
from ..control.controllers import Controller, JacobianTransposePD
from ..control.signals import measurement_size, reference_size
from ..control.trajectories import Square
from ..errors import InvalidTypeError, InvalidValueError
from ..model import dynamics as kernels
from ..sensing.delays import DelayModel, discretize, pade_state_space
from ..sensing.sensors import Sensor, check_sensor
from . import loop as simloop
from .results import SimulationResult

__all__ = ["SimulationError", "simulate"]

_OWNER = "simulate"


class SimulationError(RuntimeError):
    """The simulated state diverged (non-finite, overflow or runaway deflection).

    Attributes
    ----------
    time : float
        Last control instant recorded, s.
    state : ndarray, shape (2 n_dof,)
        ``(q, dq)`` at that instant.
    result : SimulationResult
        The partial result up to ``time``.
    """

    def __init__(self, message: str, time: float, state: NDArray[np.float64], result: Any):
        super().__init__(message)
        self.time = time
        self.state = state
        self.result = result


def _joint_references(
    arm: Any, position: NDArray[np.float64], velocity: NDArray[np.float64], elbow: str
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Joint angles (inverse kinematics) and rates (``J dtheta = v``) of a path."""
    theta = arm.inverse_kinematics(position, elbow=elbow)
    l1, l2 = arm.links[0].length, arm.links[1].length
    phi1 = theta[:, 0]
    phi2 = phi1 + theta[:, 1]
    s1, c1, s2, c2 = np.sin(phi1), np.cos(phi1), np.sin(phi2), np.cos(phi2)
    a, b = -l1 * s1 - l2 * s2, -l2 * s2  # the rigid Jacobian [[a, b], [c, d]]
    c, d = l1 * c1 + l2 * c2, l2 * c2
    det = a * d - b * c
    scale = l1 * l2
    if np.any(np.abs(det) < 1e-6 * scale):
        k = int(np.argmin(np.abs(det)))
        raise InvalidValueError(
            "The trajectory passes through a kinematic singularity (elbow straight or "
            f"folded) at {position[k].tolist()} m: joint rates are unbounded there."
        )
    vx, vy = velocity[:, 0], velocity[:, 1]  # J dtheta = v, solved in closed form
    dtheta = np.stack([d * vx - b * vy, a * vy - c * vx], axis=1) / det[:, None]
    return theta, dtheta


def _point_references(
    arm: Any,
    theta: NDArray[np.float64],
    dtheta: NDArray[np.float64],
    link: int,
    distance: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Position and velocity of the point ``distance`` along ``link`` with rigid links
    at the joint angles ``theta`` (K, N) and rates ``dtheta`` (K, N)."""
    phi = np.cumsum(theta, axis=1)
    dphi = np.cumsum(dtheta, axis=1)
    lengths = [lk.length for lk in arm.links[:link]] + [distance]
    pos = np.zeros((theta.shape[0], 2))
    vel = np.zeros((theta.shape[0], 2))
    for i, length in enumerate(lengths):
        c, s = np.cos(phi[:, i]), np.sin(phi[:, i])
        pos += length * np.stack([c, s], axis=1)
        vel += length * dphi[:, i : i + 1] * np.stack([-s, c], axis=1)
    return pos, vel


def simulate(
    arm: Any,
    controller: Controller | None = None,
    trajectory: Any = None,
    *,
    sensor: Sensor | None = None,
    delay: DelayModel | None = None,
    delay_reference: bool = False,
    shaper: Any = None,
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
) -> SimulationResult:
    """Simulate ``arm`` under ``controller`` tracking ``trajectory``.

    Parameters
    ----------
    arm : FlexibleArm
        The plant (two links when the reference needs inverse kinematics).
    controller : Controller, optional
        Default: the paper's ``JacobianTransposePD.from_arm(arm)``.
    trajectory : trajectory object, optional
        Anything with ``evaluate(t) -> (position, velocity, acceleration)``
        (arrays (m, 2)), ``duration`` and ``corner_times``; default
        :class:`flexarm.control.trajectories.Square` ().
    sensor : JointSensor, PointSensor or TipSensor, optional
        Default :class:`JointSensor` (). With a point short of the end effector
        (two-link arms), the operational-space command ``r[0:4]`` is that
        point's desired position and velocity (rigid kinematics of the joint
        references), so that ``e = x_c - x`` compares like with like; the
        tracking errors are still those of the end effector.
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

    Returns
    -------
    SimulationResult

    Raises
    ------
    SimulationError
        If the state diverges; the partial result is attached.
    """
    controller = JacobianTransposePD.from_arm(arm) if controller is None else controller
    if not isinstance(controller, Controller):
        raise InvalidTypeError(
            f"The 'controller' parameter of {_OWNER} must be a flexarm Controller. "
            f"Got {type(controller).__name__} instead."
        )
    trajectory = Square() if trajectory is None else trajectory
    for attr in ("evaluate", "duration"):
        if not hasattr(trajectory, attr):
            raise InvalidTypeError(
                f"The 'trajectory' parameter of {_OWNER} must have '{attr}'. "
                f"Got {type(trajectory).__name__} instead."
            )
    sensor = check_sensor(sensor, _OWNER)
    delay = DelayModel.none() if delay is None else delay
    if not isinstance(delay, DelayModel):
        raise InvalidTypeError(
            f"The 'delay' parameter of {_OWNER} must be a DelayModel. "
            f"Got {type(delay).__name__} instead."
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
    if rng is None or isinstance(rng, int | np.integer):
        rng = np.random.default_rng(rng)
    elif not isinstance(rng, np.random.Generator):
        raise InvalidTypeError(
            f"The 'rng' parameter of {_OWNER} must be a numpy Generator or a seed. "
            f"Got {type(rng).__name__} instead."
        )
    N, n = arm.n_links, arm.n_dof
    n_steps = round(duration / dt)
    if n_steps < 1:
        raise InvalidValueError(
            f"The 'duration' parameter of {_OWNER} must cover at least one control period "
            f"({dt} s). Got {duration} instead."
        )
    t: NDArray[np.float64] = np.arange(n_steps + 1, dtype=np.float64) * dt

    # ------------------------------------------------------------ reference
    path: Callable[[NDArray[np.float64]], Any] = trajectory.evaluate
    if shaper is not None:
        path = shaper.apply_function(trajectory.evaluate)
    t_cmd = t - delay.delay if delay_reference else t
    pos, vel, acc = (np.asarray(a, dtype=float) for a in path(t_cmd))
    if shaper is None and not delay_reference:
        desired = pos
    else:
        desired = np.asarray(trajectory.evaluate(t)[0], dtype=float)
    reference = np.zeros((n_steps + 1, reference_size(N)))
    reference[:, 0:2], reference[:, 2:4], reference[:, 4:6] = pos, vel, acc
    if N == 2:
        theta_r, dtheta_r = _joint_references(arm, pos, vel, elbow)
        reference[:, 6 : 6 + N], reference[:, 6 + N :] = theta_r, dtheta_r
    link_s, distance_s, _ = sensor.resolve(arm)
    if link_s >= 0 and not (link_s == N - 1 and distance_s == arm.links[-1].length):
        # A point short of the end effector is commanded where the desired path puts
        # it: rigid kinematics of the joint references (paper.md §4: e = x_c - x with x
        # the sensed point). Errors are still measured at the end effector.
        if N != 2:
            raise InvalidValueError(
                f"The 'sensor' parameter of {_OWNER} may be a point short of the end "
                f"effector only on a two-link arm (its command needs inverse kinematics). "
                f"Got {sensor!r} on a {N}-link arm instead."
            )
        p_r, v_r = _point_references(arm, theta_r, dtheta_r, link_s, distance_s)
        reference[:, 0:2], reference[:, 2:4] = p_r, v_r
        reference[:, 4:6] = np.gradient(v_r, dt, axis=0) if n_steps > 1 else 0.0

    # ------------------------------------------------------------ initial state
    if initial_state is None:
        x0 = np.zeros(2 * n)
        if N == 2:
            x0[:N] = _joint_references(arm, desired[:1], np.zeros((1, 2)), elbow)[0][0]
            if arm.has_flexible_joints:
                x0[arm.motor_slice] = x0[:N]
    else:
        x0 = check_array(initial_state, "initial_state", _OWNER, shape=(2 * n,)).copy()

    # ------------------------------------------------------------ limits
    if torque_limit is None:
        limit = np.full(N, np.inf)
    else:
        limit = check_array(torque_limit, "torque_limit", _OWNER, finite=False)
        limit = np.broadcast_to(limit, (N,)).astype(float).copy() if limit.ndim == 0 else limit
        if limit.shape != (N,) or np.any(np.isnan(limit)) or np.any(limit <= 0):
            raise InvalidValueError(
                f"The 'torque_limit' parameter of {_OWNER} must be > 0, scalar or of shape "
                f"({N},). Got {torque_limit!r} instead."
            )
    lengths = np.array([lk.length for lk in arm.links])
    if max_deflection is None:
        max_defl = lengths.copy()
    else:
        max_defl = np.full(N, check_real(max_deflection, "max_deflection", _OWNER, positive=True))

    # ------------------------------------------------------------ sensor
    link, distance, phi = sensor.resolve(arm)
    n_ch = 2 * N if link < 0 else 4
    half = n_ch // 2
    noise_levels = np.r_[np.full(half, sensor.noise_std), np.full(half, sensor.rate_noise_std)]
    resolution = np.r_[np.full(half, sensor.quantization), np.full(half, sensor.rate_quantization)]
    noise = (
        rng.normal(size=(n_steps + 1, n_ch)) * noise_levels
        if np.any(noise_levels > 0)
        else np.zeros((0, n_ch))
    )
    h = dt / substeps
    delay_steps = 0
    order = 0
    ad, bd, cd, dd = np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(1)
    effective_delay = 0.0
    if delay.delay > 0:
        if delay.method == "exact":
            delay_steps = round(delay.delay / h)
            effective_delay = delay_steps * h
        else:
            A, B, C, D = pade_state_space(delay.delay, delay.order)
            Ad, Bd, Cd, Dd = discretize(A, B, C, D, h)
            order = Ad.shape[0]
            ad, bd, cd, dd = Ad, Bd[:, 0].copy(), Cd[0].copy(), Dd[0].copy()
            effective_delay = delay.delay
    sensor_arrays = simloop.SensorArrays(
        np.array([link], dtype=np.int64),
        np.array([distance]),
        np.ascontiguousarray(phi, dtype=float),
        np.array([delay_steps], dtype=np.int64),
        np.ascontiguousarray(ad),
        np.ascontiguousarray(bd),
        np.ascontiguousarray(cd),
        np.ascontiguousarray(dd),
        noise,
        resolution,
    )

    # ------------------------------------------------------------ run
    params = np.ascontiguousarray(controller.parameters_for(arm, sensor), dtype=float)
    ny = measurement_size(N, sum(arm.n_modes))
    out = {  # every row up to the last one reached is written; the rest become NaN below
        "q": np.empty((n_steps + 1, n)),
        "dq": np.empty((n_steps + 1, n)),
        "tau": np.empty((n_steps + 1, N)),
        "measurement": np.empty((n_steps + 1, ny)),
        "tip": np.full((n_steps + 1, 2), np.nan),
    }
    state = simloop.LoopState(
        x0[:n].copy(),
        x0[n:].copy(),
        np.zeros(N),
        np.ascontiguousarray(controller.initial_state(arm), dtype=float),
        np.zeros((delay_steps + 1, n_ch)),
        np.zeros(1, dtype=np.int64),
        np.zeros((n_ch, order)),
        np.zeros((6, n)),
        kernels.make_workspace(n),
        np.zeros(simloop.LoopState.signal_size(n_ch, ny, order)),
    )
    _prime_delay_line(arm, sensor_arrays, state)
    info = {
        "controller": getattr(controller, "name", type(controller).__name__),
        "sensor": sensor.describe(arm),
        "delay_s": delay.delay,
        "effective_delay_s": effective_delay,
        "delay_method": delay.method if delay.delay > 0 else "none",
        "delay_reference": delay_reference,
        "shaper": None if shaper is None else type(shaper).__name__,
        "dt_s": dt,
        "substeps": substeps,
        "method": method,
        "duration_s": n_steps * dt,
        "n_links": N,
        "n_modes": list(arm.n_modes),
        "flexible_joints": bool(arm.has_flexible_joints),
        "corner_times_s": [float(c) for c in getattr(trajectory, "corner_times", ())],
        "motion_end_s": float(trajectory.duration),
    }
    start = time.perf_counter()
    if method == "rk4":
        status, k_end = _run_chunks(
            arm,
            controller,
            params,
            sensor_arrays,
            reference,
            dt,
            substeps,
            limit,
            max_defl,
            state,
            out,
            progress,
        )
    else:
        status, k_end = _run_scipy(
            arm, controller, params, sensor_arrays, reference, dt, limit, max_defl, state, out
        )
    info["wall_time_s"] = time.perf_counter() - start
    info["controller_state"] = state.ctrl_state.tolist()
    for key in ("q", "dq", "tau", "measurement"):
        out[key][k_end + 1 :] = np.nan
    reached = out["q"][: k_end + 1]
    done = np.all(np.isfinite(reached), axis=1)
    out["tip"][: k_end + 1][done] = arm.tip_position(reached[done])
    info["status"] = "ok" if status == simloop.OK else "diverged"
    result = SimulationResult(
        t=t,
        q=out["q"],
        dq=out["dq"],
        tau=out["tau"],
        reference=reference,
        desired=desired,
        measurement=out["measurement"],
        tip=out["tip"],
        coordinate_names=arm.coordinate_names,
        tip_deflection_gains=np.asarray(arm.arrays.tip_deflection),
        mode_start=np.asarray(arm.arrays.mode_start),
        link_lengths=lengths,
        info=info,
    )
    if status != simloop.OK:
        tk = float(t[k_end])
        x = np.r_[out["q"][k_end], out["dq"][k_end]]
        raise SimulationError(
            f"the simulation diverged after t = {tk:.6g} s (state non-finite, overflowing "
            f"or a tip deflection beyond max_deflection); last state q, dq = "
            f"{np.array2string(x, precision=4, max_line_width=200)}",
            tk,
            x,
            result.truncated(k_end + 1),
        )
    return result


def _prime_delay_line(arm: Any, sensor: simloop.SensorArrays, state: simloop.LoopState) -> None:
    """Start the delay line at steady state on the initial sensed signal."""
    raw = np.zeros(state.buffer.shape[1])
    simloop.sense(state.q, state.dq, arm.arrays, sensor, raw)
    state.buffer[:] = raw
    order = sensor.pade_ad.shape[0]
    if order:
        # discrete steady state: x = (I - Ad)^-1 Bd u
        gain = np.linalg.solve(np.eye(order) - sensor.pade_ad, sensor.pade_bd)
        state.pade_x[:] = np.outer(raw, gain)


def _run_chunks(
    arm: Any,
    controller: Controller,
    params: NDArray[np.float64],
    sensor: simloop.SensorArrays,
    reference: NDArray[np.float64],
    dt: float,
    substeps: int,
    limit: NDArray[np.float64],
    max_defl: NDArray[np.float64],
    state: simloop.LoopState,
    out: dict[str, NDArray[np.float64]],
    progress: bool | None,
) -> tuple[int, int]:
    n_rows = reference.shape[0]
    work = n_rows * substeps * arm.n_dof
    show = sys.stderr.isatty() and work > 5e6 if progress is None else bool(progress)
    n_chunks = 50 if show else 1
    bounds = np.linspace(0, n_rows, n_chunks + 1).astype(int)
    status, k = simloop.OK, 0
    for c in range(n_chunks):
        k0, k1 = int(bounds[c]), int(bounds[c + 1])
        if k1 <= k0:
            continue
        status, k = simloop.run(
            arm.arrays,
            controller.cfunc,
            params,
            sensor,
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
        if show:
            _progress_bar((c + 1) / n_chunks)
        if status != simloop.OK:
            break
    if show:
        sys.stderr.write("\n")
    return int(status), min(int(k), n_rows - 1)


def _progress_bar(fraction: float) -> None:
    width = 40
    filled = round(width * fraction)
    sys.stderr.write(f"\rsimulating [{'#' * filled}{'.' * (width - filled)}] {fraction:5.1%}")
    sys.stderr.flush()


def _run_scipy(
    arm: Any,
    controller: Controller,
    params: NDArray[np.float64],
    sensor: simloop.SensorArrays,
    reference: NDArray[np.float64],
    dt: float,
    limit: NDArray[np.float64],
    max_defl: NDArray[np.float64],
    state: simloop.LoopState,
    out: dict[str, NDArray[np.float64]],
) -> tuple[int, int]:
    """The sampled-data loop with solve_ivp (DOP853, rtol 1e-10) between instants.

    Only undelayed, noise-free sensing is supported here: it is the accuracy
    reference for the integrator, not a second simulator.
    """
    from scipy.integrate import solve_ivp

    if sensor.delay_steps[0] or sensor.pade_ad.shape[0] or sensor.noise.shape[0]:
        raise InvalidValueError(
            "The 'method' parameter of simulate='scipy' supports undelayed, noise-free "
            "sensing only (it is the integrator's accuracy reference)."
        )
    n, N = arm.n_dof, arm.n_links
    q, dq = state.q.copy(), state.dq.copy()
    n_rows = reference.shape[0]
    # At each instant the compiled loop, run for that one row on a copy of the state,
    # forms the measurement and the torque exactly as the fixed-step path does (its
    # own RK4 step lands in the copy and is discarded); solve_ivp then integrates
    # the plant over the period under that held torque.
    for k in range(n_rows):
        st = state._replace(q=q.copy(), dq=dq.copy())
        last = k == n_rows - 1
        simloop.run(
            arm.arrays,
            controller.cfunc,
            params,
            sensor,
            reference[: k + 2] if not last else reference[: k + 1],
            dt,
            1,
            limit,
            max_defl,
            st,
            k,
            k + 1,
            out["q"],
            out["dq"],
            out["tau"],
            out["measurement"],
        )
        if last:
            return simloop.OK, k
        tau = out["tau"][k].copy()

        def rhs(_t: float, x: NDArray[np.float64], tau: NDArray[np.float64] = tau) -> Any:
            return np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], tau, backend="compiled")]

        sol = solve_ivp(rhs, (0.0, dt), np.r_[q, dq], method="DOP853", rtol=1e-10, atol=1e-12)
        x = sol.y[:, -1]
        q, dq = x[:n].copy(), x[n:].copy()
        if not np.all(np.isfinite(x)) or not sol.success:
            return simloop.DIVERGED, k
        e = np.array(
            [
                arm.arrays.tip_deflection[arm.modal_slice(i)] @ q[arm.modal_slice(i)]
                for i in range(N)
            ]
        )
        if np.any(np.abs(e) > max_defl):
            return simloop.DIVERGED, k
    return simloop.OK, n_rows - 1
