"""The settings of a closed-loop run: :class:`SimulationSettings`, validated once.

One frozen object carries everything that defines a run of :func:`flexarm.simulate`
besides the arm, the law and the path: what the law sees (sensor, delay), what it
is fed (shaper, smoothing, feedforward), the integration (period, substeps,
method) and what is recorded. It is validated when it is made, so that the
simulator, scenario files, sweeps and the command line share one set of checks;
:meth:`SimulationSettings.replace` makes a changed copy, validated again.
``simulate(arm, law, path, settings, dt=1e-4)`` is ``simulate(arm, law, path,
settings.replace(dt=1e-4))``.

What depends on the arm (a torque limit per joint, the initial state's length, a
feedforward that needs a two-link arm, a duration of at least one period) is
checked by the simulator.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Self, cast

import numpy as np

from .._validation import check_array, check_bool, check_int, check_option, check_real
from ..control.trajectories import ELBOWS
from ..errors import InvalidTypeError, InvalidValueError
from ..sensing.delays import DelayModel
from ..sensing.sensors import JointSensor, Sensor, check_sensor

if TYPE_CHECKING:
    from .references import PathShaper

__all__ = ["METHODS", "SimulationSettings"]

METHODS = ("rk4", "scipy")
"""Integrators: the compiled fixed-step loop, or SciPy's adaptive reference."""

_OWNER = "SimulationSettings"


@dataclass(frozen=True)
class SimulationSettings:
    """Everything that defines a closed-loop run besides the arm, the law and the path.

    Parameters
    ----------
    sensor : JointSensor, PointSensor or TipSensor
        What the law sees (default the joint encoders). With a point short of the
        end effector (two-link arms), the operational-space command is that
        point's desired position and velocity (rigid kinematics of the joint
        references), so that ``e = x_c - x`` compares like with like; the
        tracking errors are still those of the end effector.
    delay : DelayModel, optional
        Transport delay of the sensed signal (default, or None: none).
    delay_reference : bool
        Delay the reference fed to the law by the same amount.
    shaper : Shaper, optional
        Input shaper applied to the reference path.
    duration : float, optional
        Simulated time, s (> 0; None: the trajectory's duration).
    dt : float
        Control period, s (> 0; default 0.2 ms, 5 kHz: the paper's hubless arm
        needs it, see :mod:`flexarm.sim.closed_loop`).
    substeps : int
        RK4 steps per control period (>= 1).
    torque_limit : float or tuple of float, optional
        Symmetric saturation of each joint torque, N m (> 0; one value or one per
        joint; None: none).
    initial_state : tuple of float, optional
        ``(q, dq)`` at t = 0, length ``2 n_dof``. Default: at rest, undeflected,
        on the reference's first point (motor angles equal to joint angles).
    elbow : {"positive", "negative"}
        Inverse-kinematics branch of the reference.
    max_deflection : float, optional
        Tip deflection of any link (m) beyond which the run counts as diverged
        (> 0; None: that link's length).
    method : {"rk4", "scipy"}
        The compiled fixed-step loop, or the same sampled-data loop with SciPy's
        adaptive ``solve_ivp`` between control instants (the accuracy reference:
        noise-free sensing recorded at every instant only).
    seed : int, optional
        Seed of the sensor noise (>= 0; None: unseeded). ``simulate``'s ``rng``
        overrides it.
    feedforward : bool, optional
        Add the rigid inverse dynamics of the joint references to the law's
        torque (two-link arms). None: what the law asks for
        (``controller.feedforward``).
    gravity_compensation : bool, optional
        With an arm in a vertical plane (``FlexibleArm(gravity=...)``), add to the
        law's torque at every control instant the joint torques that hold the
        measured posture at rest, its links' sag included
        (:mod:`flexarm.control.gravity_compensation`), so that a law designed for
        the horizontal arm tracks as it does there. None: what the law asks for
        (``controller.gravity_compensation``: on for the built-in laws, off for
        your own). Nothing to add without gravity.
    smoothing : float, optional
        Standard deviation (s) of a zero-phase Gaussian smoothing of the path fed
        to the law (>= 0; 0: none, the raw path): the reference is known in
        advance, so a corner taken at constant speed is cut symmetrically with
        finite acceleration. Errors are still measured against the unsmoothed
        path. None (the default): what the law asks for
        (``controller.reference_smoothing``: none for the paper's laws, chosen
        from the closed loop by :class:`~flexarm.control.lqg.LQG` and
        :class:`~flexarm.control.reflected.ReflectedTipPD`); the result's
        ``info`` says which was used (``smoothing_s``, ``reference_chosen_by``).
    check_sampling : bool
        Before running, linearise the loop at the start and refuse a control period
        at which it is sampled-data unstable, with the pole and the period that
        would work. False runs it anyway (to watch it diverge).
    record_every : int
        Record every ``record_every``-th control instant and the last (>= 1). The
        run is the same; a long run then fits in bounded memory. The metrics are
        those of the recorded instants.
    record_signals : bool
        Record what the law saw and was given, the measurement and the reference
        (False: the result's ``measurement`` and ``reference`` have no columns, as
        an open-loop run's). The run and its metrics are the same; a run whose
        metrics alone are wanted then needs about a third of the memory (the paper's
        arm: 120 of 312 bytes per instant), which is also time, the kernel's, in
        a fresh process.

    Examples
    --------
    >>> s = SimulationSettings(dt=1e-4)
    >>> s.replace(substeps=2).substeps, s.dt
    (2, 0.0001)
    >>> SimulationSettings(dt=-1.0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    flexarm.errors.InvalidValueError: The 'dt' parameter of SimulationSettings must be > 0...
    """

    sensor: Sensor = field(default_factory=JointSensor)
    delay: DelayModel = field(default_factory=DelayModel.none)
    delay_reference: bool = False
    shaper: PathShaper | None = None
    duration: float | None = None
    dt: float = 2e-4
    substeps: int = 1
    torque_limit: float | tuple[float, ...] | None = None
    initial_state: tuple[float, ...] | None = None
    elbow: str = "positive"
    max_deflection: float | None = None
    method: str = "rk4"
    seed: int | None = None
    feedforward: bool | None = None
    gravity_compensation: bool | None = None
    smoothing: float | None = None
    check_sampling: bool = True
    record_every: int = 1
    record_signals: bool = True

    FILE_KEYS = (
        "duration",
        "dt",
        "substeps",
        "torque_limit",
        "seed",
        "elbow",
        "max_deflection",
        "smoothing",
        "feedforward",
        "gravity_compensation",
        "check_sampling",
        "record_every",
        "record_signals",
    )
    """The fields a scenario file's ``[simulation]`` section sets (the sensor, delay
    and shaper have sections of their own)."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "sensor", check_sensor(self.sensor, _OWNER))
        if cast(object, self.delay) is None:  # None reads as no delay
            set_(self, "delay", DelayModel.none())
        if not isinstance(self.delay, DelayModel):
            raise InvalidTypeError(
                f"The 'delay' parameter of {_OWNER} must be a DelayModel. "
                f"Got {type(self.delay).__name__} instead."
            )
        check_bool(self.delay_reference, "delay_reference", _OWNER)
        if self.shaper is not None and not callable(getattr(self.shaper, "apply_function", None)):
            raise InvalidTypeError(
                f"The 'shaper' parameter of {_OWNER} must be a Shaper (with apply_function). "
                f"Got {type(self.shaper).__name__} instead."
            )
        if self.duration is not None:
            set_(self, "duration", check_real(self.duration, "duration", _OWNER, positive=True))
        set_(self, "dt", check_real(self.dt, "dt", _OWNER, positive=True))
        set_(self, "substeps", check_int(self.substeps, "substeps", _OWNER, minimum=1))
        set_(self, "record_every", check_int(self.record_every, "record_every", _OWNER, minimum=1))
        if self.torque_limit is not None:
            limit = check_array(self.torque_limit, "torque_limit", _OWNER, finite=False)
            if limit.ndim > 1 or np.any(np.isnan(limit)) or not np.all(limit > 0):
                raise InvalidValueError(
                    f"The 'torque_limit' parameter of {_OWNER} must be > 0, a scalar or one per "
                    f"joint. Got {self.torque_limit!r} instead."
                )
            value = float(limit) if limit.ndim == 0 else tuple(float(x) for x in limit)
            set_(self, "torque_limit", value)
        if self.initial_state is not None:
            x0 = check_array(self.initial_state, "initial_state", _OWNER, shape=(-1,))
            set_(self, "initial_state", tuple(float(v) for v in x0))
        check_option(self.elbow, "elbow", _OWNER, ELBOWS)
        if self.max_deflection is not None:
            value = check_real(self.max_deflection, "max_deflection", _OWNER, positive=True)
            set_(self, "max_deflection", value)
        check_option(self.method, "method", _OWNER, METHODS)
        if self.seed is not None:
            set_(self, "seed", check_int(self.seed, "seed", _OWNER, minimum=0))
        check_bool(self.feedforward, "feedforward", _OWNER, optional=True)
        check_bool(self.gravity_compensation, "gravity_compensation", _OWNER, optional=True)
        if self.smoothing is not None:
            value = check_real(self.smoothing, "smoothing", _OWNER, nonnegative=True)
            set_(self, "smoothing", value)
        check_bool(self.check_sampling, "check_sampling", _OWNER)
        check_bool(self.record_signals, "record_signals", _OWNER)
        if self.method == "scipy" and (self.record_every != 1 or self._noisy()):
            raise InvalidValueError(
                f"The 'method' parameter of {_OWNER}='scipy' supports noise-free sensing "
                "recorded at every control instant only (it is the integrator's accuracy "
                "reference)."
            )

    def _noisy(self) -> bool:
        s = self.sensor
        return bool(s.noise_std > 0 or s.rate_noise_std > 0)

    def replace(self, **changes: Any) -> Self:
        """A copy with ``changes`` (field names), validated again.

        Raises
        ------
        InvalidTypeError
            For a name that is not a field.
        """
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise InvalidTypeError(
                f"{unknown[0]!r} is not a setting of a simulation (the settings: "
                f"{', '.join(sorted(names))})."
            )
        return dataclasses.replace(self, **changes)
