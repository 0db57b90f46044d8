"""The joint study's settings: the drive's static map, the excitation, the sensors' noise.

Frozen, validated dataclasses (NumPy only: reading them loads no simulator).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64
from ..._validation import validate_real_fields
from ...errors import InvalidTypeError, InvalidValueError

__all__ = ["DriveNonlinearity", "JointExcitation", "JointSensors", "check_types"]


def check_types(owner: str, *checks: tuple[str, object, type]) -> None:
    """Raise the :class:`~flexarm.errors.InvalidTypeError` of the first
    ``(name, value, kind)`` whose ``value`` is not a ``kind``."""
    for name, value, kind in checks:
        if not isinstance(value, kind):
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must be a {kind.__name__}. "
                f"Got {type(value).__name__} instead."
            )


@dataclass(frozen=True)
class DriveNonlinearity:
    """The motor drive's static map from commanded to applied torque (N m to N m).

    ``phi(u) = clip(sign(u) max(|u| - dead_band, 0), -limit, limit)``: a dead
    band (static friction of the gear, amplifier offset) and current limiting.

    Parameters
    ----------
    dead_band : float
        Half-width of the dead band, N m (>= 0).
    limit : float
        Saturation level, N m (> 0).

    Examples
    --------
    >>> DriveNonlinearity(2.0, 40.0)([-50.0, 1.0, 10.0])
    array([-40.,   0.,   8.])
    """

    dead_band: float = 2.0
    limit: float = 40.0

    def __post_init__(self) -> None:
        validate_real_fields(
            self, "DriveNonlinearity", positive=("limit",), nonnegative=("dead_band",)
        )

    def __call__(self, u: ArrayLike) -> F64:
        """Applied torque, N m, for the commands ``u`` (N m, any shape)."""
        v = np.asarray(u, dtype=np.float64)
        out: F64 = np.clip(
            np.sign(v) * np.maximum(np.abs(v) - self.dead_band, 0.0), -self.limit, self.limit
        )
        return out


@dataclass(frozen=True)
class JointExcitation:
    """The random-torque experiment.

    The commands are i.i.d.: each is drawn, with probability
    ``dead_band_fraction``, from ``U(-dead_band_span, dead_band_span)`` (to
    resolve the drive's dead band, :mod:`~flexarm.studies.joint_identification.design`),
    and otherwise from ``U(-amplitude, amplitude)``.

    Parameters
    ----------
    duration : float
        Length of the record, s (> 0).
    dt : float
        Simulation and sampling period, s (default 0.2 ms).
    hold : float
        Hold time of each random command, s; also the Hammerstein sample
        period. Rounded to a whole number of ``dt``.
    amplitude : float
        Half-range of the wide commands, N m.
    drive : DriveNonlinearity
        The drive's static map (the Hammerstein part's true ``phi``).
    dead_band_fraction : float
        Share of the commands drawn near the dead band, in [0, 1) (0: all wide,
        the default experiment).
    dead_band_span : float
        Half-range of those commands, N m (> 0; at most ``amplitude``).
    """

    duration: float = 60.0
    dt: float = 2e-4
    hold: float = 0.01
    amplitude: float = 60.0
    drive: DriveNonlinearity = field(default_factory=DriveNonlinearity)
    dead_band_fraction: float = 0.0
    dead_band_span: float = 6.0

    def __post_init__(self) -> None:
        validate_real_fields(
            self,
            "JointExcitation",
            positive=("duration", "dt", "hold", "amplitude", "dead_band_span"),
            nonnegative=("dead_band_fraction",),
        )
        if not self.dead_band_fraction < 1.0:
            raise InvalidValueError(
                "The 'dead_band_fraction' parameter of JointExcitation must be < 1. "
                f"Got {self.dead_band_fraction} instead."
            )
        if self.dead_band_span > self.amplitude:
            raise InvalidValueError(
                "The 'dead_band_span' parameter of JointExcitation must be <= amplitude = "
                f"{self.amplitude}. Got {self.dead_band_span} instead."
            )
        if not isinstance(self.drive, DriveNonlinearity):
            raise InvalidTypeError(
                "The 'drive' parameter of JointExcitation must be a DriveNonlinearity. "
                f"Got {type(self.drive).__name__} instead."
            )
        if self.hold < self.dt:
            raise InvalidValueError(
                f"The 'hold' parameter of JointExcitation must be >= dt = {self.dt}. "
                f"Got {self.hold} instead."
            )

    @property
    def hold_steps(self) -> int:
        """Samples per held command."""
        return max(1, round(self.hold / self.dt))

    @property
    def n_steps(self) -> int:
        """Sample periods in the record (``duration / dt``, rounded)."""
        return round(self.duration / self.dt)

    @property
    def n_holds(self) -> int:
        """Whole holds in the record."""
        return self.n_steps // self.hold_steps

    def commands(self, n: int, rng: np.random.Generator) -> F64:
        """``n`` commands (N m) drawn from ``rng`` (class docstring).

        With ``dead_band_fraction = 0`` exactly the draws of the uniform
        experiment, ``rng.uniform(-amplitude, amplitude, n)``.
        """
        wide = rng.uniform(-self.amplitude, self.amplitude, n)
        if self.dead_band_fraction == 0.0:
            return wide
        near = rng.uniform(-self.dead_band_span, self.dead_band_span, n)
        out: F64 = np.where(rng.uniform(size=n) < self.dead_band_fraction, near, wide)
        return out


@dataclass(frozen=True)
class JointSensors:
    """Noise levels (standard deviations) of the measured signals.

    Parameters
    ----------
    angle_noise : float
        Motor and link encoders, rad.
    rate_noise : float
        Motor and link rates, rad/s.
    torque_noise : float
        Applied torque from the motor current, N m.
    torque_sensor_noise : float
        Joint torque sensor (``torque_measurement="sensor"``), N m.
    acceleration_noise : float
        Link accelerometer (after its hold-period filter), rad/s**2.
    """

    angle_noise: float = 1e-6
    rate_noise: float = 1e-4
    torque_noise: float = 0.05
    torque_sensor_noise: float = 0.1
    acceleration_noise: float = 0.01

    def __post_init__(self) -> None:
        validate_real_fields(
            self,
            "JointSensors",
            nonnegative=(
                "angle_noise",
                "rate_noise",
                "torque_noise",
                "torque_sensor_noise",
                "acceleration_noise",
            ),
        )
