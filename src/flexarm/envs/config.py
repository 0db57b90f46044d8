"""The configuration of the flexible-arm environment: :class:`EnvConfig`.

One frozen, validated dataclass holds everything that defines an episode: the
plant, the reference, the sensor and its transport delay, the control period,
the torque limits, the reward's weights and the divergence rule. The
environments (:mod:`flexarm.envs.env`, :mod:`flexarm.envs.vector`) read it;
this module needs no Gymnasium and no compiled code.

Defaults
--------
* the paper's arm (:meth:`flexarm.FlexibleArm.paper`) tracking the default square
  (:class:`flexarm.control.trajectories.Square`: 20 s) read by joint encoders;
* a control period of 10 ms (100 Hz, a usual rate for learned policies) with 10
  RK4 substeps of 1 ms: the open-loop paper arm's fastest pole is about 99 rad/s,
  so ``h |lambda|`` is 0.1, well inside RK4's stability bound (2.8) and accurate;
* torque limits of 100 N m per joint: the paper's Jacobian-transpose PD
  peaks at 80 N m on the default square (at its corners), 36 N m at the 99th
  percentile, so the box holds what a good law needs with some margin;
* a joint-rate limit of 20 rad/s (the square needs about 0.5 rad/s): beyond it
  the arm counts as diverged;
* no gravity (a horizontal plane), unless the arm has it or ``gravity`` gives it,
  and no gravity compensation: the action is the whole joint torque.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .._types import F64
from .._validation import check_array, check_bool, check_int, check_option, check_real
from ..control.trajectories import Square, Trajectory, check_trajectory
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm
from ..model.gravity import check_gravity
from ..model.plant import Plant, check_plant
from ..sensing.delays import DelayModel
from ..sensing.sensors import JointSensor, Sensor, check_sensor

__all__ = ["DEFAULT_TORQUE_LIMIT", "EnvConfig"]

_OWNER = "EnvConfig"

DEFAULT_TORQUE_LIMIT = 100.0
"""Default torque limit per joint, N m (module docstring)."""


@dataclass(frozen=True)
class EnvConfig:
    """What defines an episode of :class:`flexarm.envs.FlexibleArmEnv`.

    Parameters
    ----------
    arm : FlexibleArm
        The plant (default :meth:`FlexibleArm.paper`).
    trajectory : Trajectory
        The end-effector reference (default :class:`Square` ()); its position and
        velocity at the current instant are part of the observation.
    sensor : JointSensor, PointSensor or TipSensor
        What the observation holds (default joint encoders): the joint angles
        (rad, wrapped to [-pi, pi)) and rates (rad/s), or the sensed point's
        position (m) and velocity (m/s), with the sensor's noise and
        quantisation (``model="paper"`` for the paper's sensor model).
    delay : DelayModel
        Transport delay of the sensed signal, at substep resolution as in
        :func:`flexarm.simulate` (default none).
    dt : float
        Control period, s: one step holds the action over ``dt`` (default 0.01).
    substeps : int
        RK4 steps per period (default 10).
    duration : float, optional
        Episode length, s (default: the trajectory's duration); the episode is
        truncated after ``round(duration / dt)`` steps.
    torque_limit : float or tuple of float
        Bounds of the action, N m: a scalar for every joint, or one per joint
        (default 100).
    tracking_weight : float
        Weight of the squared end-effector tracking error in the reward, 1/m**2
        (default 1).
    effort_weight : float
        Weight of the squared torques relative to their limits,
        ``sum_i (tau_i / limit_i)**2`` (dimensionless; default 0.01).
    divergence_penalty : float
        The reward of the step on which the episode terminates by divergence
        (its negative; default 100).
    max_rate : float
        Joint rate (rad/s) beyond which the arm counts as diverged (default 20).
    max_deflection : float, optional
        Tip deflection of any link (m) beyond which the arm counts as diverged
        (default: that link's length, as in :func:`flexarm.simulate`).
    initial_state : tuple of float, optional
        ``(q, dq)`` at the start, shape (2 n_dof,). Default: at rest,
        undeflected, the end effector on the reference's first point (inverse
        kinematics on the ``elbow`` branch; two-link arms).
    initial_angle_std : float
        Standard deviation of a Gaussian perturbation of the initial joint
        angles (and motor angles with them), rad, drawn at each reset from the
        environment's generator (default 0: every episode starts alike).
    elbow : {"positive", "negative"}
        Inverse-kinematics branch of the initial configuration.
    gravity : (float, float), optional
        Gravity in the plane of motion ``(g_x, g_y)``, m/s**2 in the base frame
        (``(0, -9.81)``: a vertical plane with ``y`` up): the episode's arm is
        ``arm`` with it (``dataclasses.replace(arm, gravity=gravity)``, a
        :class:`FlexibleArm`; :mod:`flexarm.model.gravity`), integrated by the
        same compiled dynamics as :func:`flexarm.simulate`. None (default): the
        arm's own (none for the default arm: a horizontal plane).
    gravity_compensation : bool
        Add to the action, at every step, the joint torques that hold the
        measured posture at rest against gravity, its links' sag included, as
        :func:`flexarm.simulate` adds them to a law's torque
        (:mod:`flexarm.control.gravity_compensation`; the measured angles: the
        sensor's delayed, noisy encoder angles, or the collocated angles for a
        point or tip sensor), before the torque limits clip the sum; the
        action is then a correction about the posture's holding torques.
        Default False: the action is the whole joint torque (an arm with
        gravity falls under a zero action). Nothing to add without gravity.

    Notes
    -----
    The reward of a step that applies torques ``tau`` over ``[t_k, t_k + dt)``
    is ``-(tracking_weight e**2 + effort_weight sum_i (tau_i / limit_i)**2)``
    with ``e`` (m) the distance between the deflected end effector and the
    reference at ``t_k + dt``; ``-divergence_penalty`` on a diverging step.
    ``tau`` is the torque applied: the action clipped to the limits, or with
    ``gravity_compensation`` the action plus the holding torques, clipped.
    """

    arm: Plant = field(default_factory=FlexibleArm.paper)
    trajectory: Trajectory = field(default_factory=Square)
    sensor: Sensor = field(default_factory=JointSensor)
    delay: DelayModel = field(default_factory=DelayModel.none)
    dt: float = 0.01
    substeps: int = 10
    duration: float | None = None
    torque_limit: float | tuple[float, ...] = DEFAULT_TORQUE_LIMIT
    tracking_weight: float = 1.0
    effort_weight: float = 0.01
    divergence_penalty: float = 100.0
    max_rate: float = 20.0
    max_deflection: float | None = None
    initial_state: tuple[float, ...] | None = None
    initial_angle_std: float = 0.0
    elbow: str = "positive"
    gravity: tuple[float, float] | None = None
    gravity_compensation: bool = False

    def __post_init__(self) -> None:
        arm = check_plant(self.arm, _OWNER)
        if self.gravity is not None:
            g = check_gravity(self.gravity, _OWNER)
            if not isinstance(arm, FlexibleArm):
                raise InvalidTypeError(
                    f"The 'gravity' parameter of {_OWNER} needs a FlexibleArm 'arm' (to build "
                    f"it with gravity). Got {type(arm).__name__} instead; build the plant "
                    "with its gravity and leave 'gravity' None."
                )
            if arm.gravity != g:
                arm = dataclasses.replace(arm, gravity=g)
                object.__setattr__(self, "arm", arm)
            object.__setattr__(self, "gravity", g)
        check_bool(self.gravity_compensation, "gravity_compensation", _OWNER)
        check_trajectory(self.trajectory, _OWNER)
        sensor = check_sensor(self.sensor, _OWNER)
        sensor.resolve(arm)  # the sensed point exists on this arm
        if not isinstance(self.delay, DelayModel):
            raise InvalidTypeError(
                f"The 'delay' parameter of {_OWNER} must be a DelayModel. "
                f"Got {type(self.delay).__name__} instead."
            )
        check_real(self.dt, "dt", _OWNER, positive=True)
        check_int(self.substeps, "substeps", _OWNER, minimum=1)
        if self.duration is not None:
            check_real(self.duration, "duration", _OWNER, positive=True)
        for name in ("tracking_weight", "effort_weight", "divergence_penalty"):
            check_real(getattr(self, name), name, _OWNER, nonnegative=True)
        for name in ("max_rate", "max_deflection"):
            value = getattr(self, name)
            if value is not None:
                check_real(value, name, _OWNER, positive=True)
        check_real(self.initial_angle_std, "initial_angle_std", _OWNER, nonnegative=True)
        check_option(self.elbow, "elbow", _OWNER, ("positive", "negative"))
        limit = check_array(self.torque_limit, "torque_limit", _OWNER)
        if limit.ndim == 0:
            limit = np.full(arm.n_links, float(limit))
        if limit.shape != (arm.n_links,) or not np.all(limit > 0):
            raise InvalidValueError(
                f"The 'torque_limit' parameter of {_OWNER} must be > 0, scalar or of shape "
                f"({arm.n_links},) (N m). Got {self.torque_limit!r} instead."
            )
        object.__setattr__(self, "torque_limit", tuple(float(x) for x in limit))
        if self.initial_state is not None:
            x0 = check_array(self.initial_state, "initial_state", _OWNER, shape=(2 * arm.n_dof,))
            object.__setattr__(self, "initial_state", tuple(float(x) for x in x0))
        if self.n_steps < 1:
            raise InvalidValueError(
                f"The 'duration' parameter of {_OWNER} must cover at least one control "
                f"period ({self.dt} s). Got {self.episode_duration} instead."
            )

    # ------------------------------------------------------------ derived
    @property
    def episode_duration(self) -> float:
        """The episode's length, s (``duration`` or the trajectory's)."""
        return float(self.trajectory.duration if self.duration is None else self.duration)

    @property
    def n_steps(self) -> int:
        """Steps per episode: ``round(episode_duration / dt)``."""
        return round(self.episode_duration / self.dt)

    @property
    def compensates_gravity(self) -> bool:
        """Whether a step adds the holding torques (``gravity_compensation`` and an arm
        with gravity)."""
        return bool(self.gravity_compensation) and getattr(self.arm, "gravity", None) is not None

    @property
    def limits(self) -> F64:
        """Torque limits, N m, shape (n_links,)."""
        return np.array(self.torque_limit, dtype=float)

    @property
    def deflection_limits(self) -> F64:
        """Tip deflection per link beyond which the arm diverges, m, shape (n_links,)."""
        if self.max_deflection is None:
            return np.array(self.arm.link_lengths, dtype=float)
        return np.full(self.arm.n_links, float(self.max_deflection))

    @property
    def reach(self) -> float:
        """Bound on the distance of any point from the base, m: every link's length
        and its largest tip deflection at right angles."""
        lengths = np.asarray(self.arm.link_lengths, dtype=float)
        return float(np.sum(np.hypot(lengths, self.deflection_limits)))

    def initial_rest_state(self) -> F64:
        """``(q, dq)`` at the start of an episode, before any perturbation, shape (2 n_dof,)."""
        arm = self.arm
        if self.initial_state is not None:
            return np.array(self.initial_state, dtype=float)
        if arm.n_links != 2:
            raise InvalidValueError(
                f"The 'initial_state' parameter of {_OWNER} is needed for an arm of "
                f"{arm.n_links} links (the default start is inverse kinematics of two links)."
            )
        p0 = np.asarray(self.trajectory.evaluate(0.0)[0], dtype=float)
        theta = np.asarray(arm.inverse_kinematics(p0, self.elbow), dtype=float)
        x0 = np.zeros(2 * arm.n_dof)
        x0[:2] = theta
        if arm.has_flexible_joints:
            x0[arm.motor_slice] = theta
        return x0
