"""Sensors: collocated (joint encoders) and noncollocated (a point on a link).

A sensor decides what the controller sees as the position and velocity of the
end effector (layout in :mod:`flexarm.control.signals`):

* :class:`JointSensor` — collocated: the joint angles and rates (the motor
  angles for flexible joints); position and velocity follow from the rigid
  kinematics of those angles. Noise and quantisation act on the angles.
* :class:`PointSensor` — noncollocated: the Cartesian position and velocity of
  the point ``distance`` metres along link ``link`` (0-based). ``PointSensor(1,
  0.5)`` is the paper's sensor 0.5 m from the elbow. Noise and quantisation act
  on the Cartesian signals.
* :class:`TipSensor` — the end effector (the last link's tip).

Two models of a sensed point (``model=``), named for what they are:

``"physical"`` (default)
    The deflected point itself (:meth:`flexarm.FlexibleArm.point_position`):
    what a camera, a laser tracker or an accelerometer-based estimate at that
    point would give on a real arm.
``"paper"``
    What Sasiadek et al. (2014, Sec. V) simulated: the rigid direct kinematics
    (their eqs. 9–10) of the measured joint angles and rates, with the sensor's
    distance along its link in place of that link's length — the deflection is
    not in it. Its transport delay (``delay=`` of the simulation) stands for the
    wave travel, as in the paper. The encoders read the motor angles with
    flexible joints.

For the joint encoders the two coincide (:class:`JointSensor` has
``model="physical"``). Both point models are commanded alike: the operational-
space reference is the sensed point's position on the rigid arm following the
joint references, and the law's Jacobian is that point's
(:func:`flexarm.control.controllers.operational_lengths`).

Noise is Gaussian, drawn from the simulation's ``rng`` (seeded runs are
reproducible); quantisation rounds to a multiple of the resolution. A transport
delay (:mod:`flexarm.sensing.delays`) acts on the sensed signal before noise and
quantisation. With a noncollocated sensor the encoder angles that feed the
Jacobian are taken as exact and undelayed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .._validation import check_int, check_option, check_real, validate_real_fields
from ..errors import InvalidTypeError, InvalidValueError
from ..model.plant import Plant

__all__ = [
    "SENSOR_MODELS",
    "JointSensor",
    "PointSensor",
    "Sensor",
    "TipSensor",
    "check_sensor",
    "parse_sensor",
]

_NOISE_FIELDS = ("noise_std", "rate_noise_std", "quantization", "rate_quantization")
SENSOR_MODELS = ("physical", "paper")
"""Models of a sensed point: the deflected point, or the paper's rigid kinematics."""


def _check_fields(sensor: object, owner: str, *nonnegative: str) -> None:
    """Check a sensor's noise and quantisation fields (and ``nonnegative`` others,
    stored as floats) and its ``model``."""
    validate_real_fields(sensor, owner, nonnegative=(*nonnegative, *_NOISE_FIELDS))
    check_option(getattr(sensor, "model", None), "model", owner, SENSOR_MODELS)


@dataclass(frozen=True)
class _Channels:
    """The fields of a sensor that is no more than its noise, quantisation and model
    (:class:`JointSensor`, :class:`TipSensor`), checked alike."""

    noise_std: float = 0.0
    rate_noise_std: float = 0.0
    quantization: float = 0.0
    rate_quantization: float = 0.0
    model: str = "physical"

    def __post_init__(self) -> None:
        _check_fields(self, type(self).__name__)


@dataclass(frozen=True)
class JointSensor(_Channels):
    """Joint encoders (collocated).

    Parameters
    ----------
    noise_std : float
        Standard deviation of the angle noise, rad.
    rate_noise_std : float
        Standard deviation of the rate noise, rad/s.
    quantization : float
        Encoder resolution, rad (0: none).
    rate_quantization : float
        Rate resolution, rad/s (0: none).
    model : {"physical", "paper"}
        Accepted for symmetry with the point sensors; the two models of the
        encoders are the same (the paper's joint sensor is the rigid kinematics
        of the joint angles, which is what the law reads from encoders anyway).
    """

    name = "joint"

    def resolve(self, arm: Plant) -> tuple[int, float, NDArray[np.float64]]:
        """``(link, distance, mode shapes at the point)``; link -1 means collocated."""
        return -1, 0.0, np.zeros(0)

    def describe(self, arm: Plant) -> str:
        return "joint"


@dataclass(frozen=True)
class PointSensor:
    """A point ``distance`` m along link ``link`` (0-based), deflection included.

    Parameters
    ----------
    link : int
        0-based link index.
    distance : float
        Distance from the link's joint along the undeformed link, m.
    noise_std, rate_noise_std : float
        Noise standard deviations of the position (m) and velocity (m/s).
    quantization, rate_quantization : float
        Resolutions of the position (m) and velocity (m/s); 0 for none.
    model : {"physical", "paper"}
        The deflected point, or the paper's rigid kinematics of the measured
        joint angles at that point (module docstring).
    """

    link: int
    distance: float
    noise_std: float = 0.0
    rate_noise_std: float = 0.0
    quantization: float = 0.0
    rate_quantization: float = 0.0
    model: str = "physical"
    name = "point"

    def __post_init__(self) -> None:
        object.__setattr__(self, "link", check_int(self.link, "link", "PointSensor", minimum=0))
        _check_fields(self, "PointSensor", "distance")

    def resolve(self, arm: Plant) -> tuple[int, float, NDArray[np.float64]]:
        if self.link >= arm.n_links:
            raise InvalidValueError(
                f"The 'link' parameter of PointSensor must be < {arm.n_links} (0-based). "
                f"Got {self.link} instead."
            )
        length = float(arm.link_lengths[self.link])
        if self.distance > length:
            raise InvalidValueError(
                f"The 'distance' parameter of PointSensor must be <= {length} m (link "
                f"{self.link}'s length). Got {self.distance} instead."
            )
        basis = getattr(arm, "point_basis", None)  # shapes, and S(distance) with stiffening
        if basis is not None:
            phi = np.ascontiguousarray(basis(self.link, self.distance), dtype=np.float64)
        else:
            phi = np.ascontiguousarray(arm.modes[self.link].shape(self.distance)[:, 0])
        return self.link, self.distance, phi

    def describe(self, arm: Plant) -> str:
        spec = f"point:{self.link}:{self.distance:g}"
        return spec if self.model == "physical" else f"{spec} (paper model)"


@dataclass(frozen=True)
class TipSensor(_Channels):
    """The end effector: the last link's tip (same parameters as
    :class:`PointSensor`; ``model="paper"`` is the paper's end-effector sensor,
    the rigid kinematics of the measured joint angles)."""

    name = "tip"

    def at(self, arm: Plant) -> PointSensor:
        last = arm.n_links - 1
        return PointSensor(
            last,
            float(arm.link_lengths[last]),
            self.noise_std,
            self.rate_noise_std,
            self.quantization,
            self.rate_quantization,
            self.model,
        )

    def resolve(self, arm: Plant) -> tuple[int, float, NDArray[np.float64]]:
        return self.at(arm).resolve(arm)

    def describe(self, arm: Plant) -> str:
        return "tip" if self.model == "physical" else "tip (paper model)"


@runtime_checkable
class Sensor(Protocol):
    """What the simulator and the linear analysis need of a sensor.

    ``resolve(arm)`` gives ``(link, distance, phi)``: the sensed point's link
    (-1 for the joint encoders), its distance along the link (m) and the link's
    mode shapes there; the noise and quantisation fields act on the sensed
    channels (positions in rad or m, rates in rad/s or m/s).
    """

    @property
    def name(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def noise_std(self) -> float: ...
    @property
    def rate_noise_std(self) -> float: ...
    @property
    def quantization(self) -> float: ...
    @property
    def rate_quantization(self) -> float: ...

    def resolve(self, arm: Plant) -> tuple[int, float, NDArray[np.float64]]: ...
    def describe(self, arm: Plant) -> str: ...


def check_sensor(sensor: object, owner: str) -> Sensor:
    """``sensor``, or :class:`JointSensor` () for ``None``; a TypeError naming ``owner`` else."""
    if sensor is None:
        return JointSensor()
    if not isinstance(sensor, Sensor):
        raise InvalidTypeError(
            f"The 'sensor' parameter of {owner} must be a sensor (JointSensor, PointSensor, "
            f"TipSensor or alike). Got {type(sensor).__name__} instead."
        )
    return sensor


_POINT = re.compile(r"^point:(?P<link>[^:]+):(?P<distance>[^:]+)$")


def parse_sensor(spec: str, model: str = "physical", **noise: float) -> Sensor:
    """A sensor from its command-line form: ``joint``, ``tip`` or ``point:LINK:DISTANCE``
    (link 0-based, distance in m: ``point:1:0.5`` is 0.5 m from the elbow), with
    the point ``model`` (``"physical"`` or ``"paper"``; the encoders have one)."""
    if not isinstance(spec, str):
        raise InvalidTypeError(
            f"The 'sensor' parameter must be a str. Got {type(spec).__name__} instead."
        )
    if spec == "joint":
        return JointSensor(**noise, model=model)
    if spec == "tip":
        return TipSensor(**noise, model=model)
    m = _POINT.match(spec)
    if m is None:
        raise InvalidValueError(
            "The 'sensor' parameter must be 'joint', 'tip' or 'point:LINK:DISTANCE'. "
            f"Got {spec!r} instead."
        )
    try:
        link = int(m["link"])
        distance = float(m["distance"])
    except ValueError:
        raise InvalidValueError(
            f"The 'sensor' parameter 'point:LINK:DISTANCE' needs an integer link and a "
            f"distance in m. Got {spec!r} instead."
        ) from None
    check_real(distance, "distance", "PointSensor", nonnegative=True)
    return PointSensor(link, distance, **noise, model=model)
