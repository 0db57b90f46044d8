"""The instruments a laboratory rig has, as functions of a recorded run.

Where :mod:`flexarm.sensing.sensors` says what a controller sees inside the loop,
an instrument says what a rig's logger recorded: a channel computed from the
states of a run (``q`` of shape (K, n_dof), at times ``t``), with its own pure
delay (a logger's channels are often not aligned) and its own quantum. The
calibration (:mod:`flexarm.calibration`) compares these with measured channels.

* :class:`Encoder` — a joint's encoder: the motor angle with flexible joints,
  else the joint angle (rad), rounded to its quantum (``2 pi / counts``).
* :class:`JointDeflection` — the link's angle relative to its motor across a
  flexible joint, ``q - q_m`` (rad): a drive or a link modelled as a torsional
  spring.
* :class:`StrainGauge` — the bending strain at a point of a flexible link,
  ``eps = (T / 2) w''(x)`` (dimensionless) for a strip of thickness ``T``, or its
  "tip angle" form ``eps 2 L / (3 T)`` (rad): the angle of the tip seen from the
  root under the static shape of a cantilever loaded at its tip (``w(L) =
  w''(0) L**2 / 3``), as laboratory strain-gauge amplifiers are calibrated.
* :class:`TipAngle` — the geometric angle of a link's tip seen from its root,
  ``w(L) / L`` (rad).

Each is a frozen dataclass with ``measure(arm, t, q) -> ndarray (K,)``, the delay
applied (the channel at ``t`` is the undelayed one at ``t - delay``, held at its
first value before the record starts); :func:`measure` applies many at once.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np

from .._types import F64
from .._validation import check_array, check_int, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm

__all__ = [
    "GAUGE_FORMS",
    "Encoder",
    "Instrument",
    "JointDeflection",
    "StrainGauge",
    "TipAngle",
    "delayed",
    "measure",
]

GAUGE_FORMS = ("strain", "tip_angle")
"""What a strain gauge reports: the strain, or the vendor's tip-angle form of it."""


class Instrument(Protocol):
    """What :func:`measure` needs of an instrument."""

    @property
    def delay(self) -> float: ...

    def raw(self, arm: FlexibleArm, q: F64) -> F64: ...

    def measure(self, arm: FlexibleArm, t: F64, q: F64) -> F64: ...


def delayed(t: F64, signal: F64, delay: float) -> F64:
    """``signal`` (sampled at ``t``, s) delayed by ``delay`` (s, >= 0): its value at
    ``t - delay``, linearly interpolated, held at its first value before ``t[0]``."""
    if delay == 0.0:
        return signal
    return np.asarray(np.interp(t - delay, t, signal, left=signal[0]), dtype=np.float64)


class _Channel:
    """The shared part: the joint or link read (the field :attr:`_index` names), the
    delay and the quantum, their checks."""

    _index: ClassVar[str]  # "joint" or "link"
    delay: float
    quantum: float

    def __post_init__(self) -> None:
        owner, index, set_ = type(self).__name__, self._index, object.__setattr__
        set_(self, index, check_int(getattr(self, index), index, owner, minimum=0))
        set_(self, "delay", check_real(self.delay, "delay", owner, nonnegative=True))
        set_(self, "quantum", check_real(self.quantum, "quantum", owner, nonnegative=True))

    def _index_in(self, arm: FlexibleArm) -> int:
        """The joint or link read, checked against ``arm``."""
        index: int = getattr(self, self._index)
        if index >= arm.n_links:
            raise InvalidValueError(
                f"The '{self._index}' parameter of {type(self).__name__} must be a "
                f"{self._index} of the arm (< {arm.n_links}). Got {index} instead."
            )
        return index

    def raw(self, arm: FlexibleArm, q: F64) -> F64:  # pragma: no cover - interface
        raise NotImplementedError

    def measure(self, arm: FlexibleArm, t: F64, q: F64) -> F64:
        """The channel at the times ``t`` (s, shape (K,)) of the states ``q`` (shape
        (K, n_dof)): delayed, then rounded to the quantum (0: not rounded)."""
        if not isinstance(arm, FlexibleArm):
            raise InvalidTypeError(
                f"The 'arm' parameter of {type(self).__name__}.measure must be a "
                f"FlexibleArm. Got {type(arm).__name__} instead."
            )
        t = check_array(t, "t", type(self).__name__, shape=(-1,))
        q = check_array(q, "q", type(self).__name__, shape=(t.shape[0], arm.n_dof))
        value = delayed(t, self.raw(arm, q), self.delay)
        if self.quantum > 0:
            value = np.round(value / self.quantum) * self.quantum
        return value


@dataclass(frozen=True)
class _JointChannel(_Channel):
    """A channel of one joint (:class:`Encoder`, :class:`JointDeflection`)."""

    _index = "joint"
    joint: int
    quantum: float = 0.0
    delay: float = 0.0


@dataclass(frozen=True)
class Encoder(_JointChannel):
    """A joint's encoder: the motor angle with flexible joints, else the joint angle.

    Parameters
    ----------
    joint : int
        The joint (0-based).
    quantum : float
        Resolution, rad (>= 0; e.g. ``2 pi / (4096 x 100)`` for 1024 lines in
        quadrature behind a 100:1 gear); 0: not rounded.
    delay : float
        Pure delay of the channel, s (>= 0).
    """

    def raw(self, arm: FlexibleArm, q: F64) -> F64:
        """The encoder angle of every row of ``q`` (rad), undelayed and unrounded."""
        j = self._index_in(arm)
        if arm.has_flexible_joints:
            return np.ascontiguousarray(q[:, arm.motor_slice][:, j])
        return np.ascontiguousarray(q[:, j])


@dataclass(frozen=True)
class JointDeflection(_JointChannel):
    """The link's angle relative to its motor across a flexible joint, ``q - q_m``.

    Parameters
    ----------
    joint : int
        The joint (0-based); the arm must have flexible joints.
    quantum, delay : float
        As for :class:`Encoder` (rad, s).
    """

    def raw(self, arm: FlexibleArm, q: F64) -> F64:
        """``q - q_m`` of the joint for every row of ``q`` (rad)."""
        j = self._index_in(arm)
        if not arm.has_flexible_joints:
            raise InvalidValueError(
                "The 'arm' parameter of JointDeflection must have flexible joints (a rigid "
                "joint does not deflect)."
            )
        return np.ascontiguousarray(q[:, j] - q[:, arm.motor_slice][:, j])


@dataclass(frozen=True)
class StrainGauge(_Channel):
    """The bending strain at a point of a flexible link, or its tip-angle form.

    Parameters
    ----------
    link : int
        The link (0-based).
    position : float
        Distance of the gauge from the link's root, m (0 to the link's length).
    thickness : float
        Thickness of the strip in the plane of bending, m (> 0): the surface strain
        is ``(thickness / 2) w''``.
    form : {"strain", "tip_angle"}
        ``"strain"``: the strain (dimensionless); ``"tip_angle"``: ``strain x 2 L /
        (3 thickness)`` in rad, the angle of the tip seen from the root under the
        static shape of a cantilever loaded at its tip (the vendor's calibration of
        a root gauge).
    quantum, delay : float
        As for :class:`Encoder` (in the unit of ``form``; s).
    """

    _index = "link"
    link: int
    position: float = 0.0
    thickness: float = 1e-3
    form: str = "strain"
    quantum: float = 0.0
    delay: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        owner, set_ = "StrainGauge", object.__setattr__
        set_(self, "position", check_real(self.position, "position", owner, nonnegative=True))
        set_(self, "thickness", check_real(self.thickness, "thickness", owner, positive=True))
        check_option(self.form, "form", owner, GAUGE_FORMS)

    def gain(self, arm: FlexibleArm) -> F64:
        """The channel per modal coordinate of the link, shape (n_modes of the link,):
        ``(T / 2) phi_j''(x)``, times ``2 L / (3 T)`` in the tip-angle form."""
        link = self._index_in(arm)
        length = float(arm.link_lengths[link])
        if self.position > length:
            raise InvalidValueError(
                f"The 'position' parameter of StrainGauge must be within link {link} "
                f"(<= {length} m). Got {self.position} instead."
            )
        if arm.n_modes[link] == 0:
            return np.zeros(0)
        curvature = arm.modes[link].curvature(np.array([self.position]))[:, 0]
        strain = 0.5 * self.thickness * curvature
        if self.form == "tip_angle":
            return strain * (2.0 * length / (3.0 * self.thickness))
        return strain

    def raw(self, arm: FlexibleArm, q: F64) -> F64:
        """The channel for every row of ``q``, undelayed and unrounded."""
        gain = self.gain(arm)
        return np.ascontiguousarray(q[:, arm.modal_slice(self.link)] @ gain)


@dataclass(frozen=True)
class TipAngle(_Channel):
    """The geometric angle of a link's tip seen from its root, ``w(L) / L`` (rad).

    Parameters
    ----------
    link : int
        The link (0-based).
    quantum, delay : float
        As for :class:`Encoder` (rad, s).
    """

    _index = "link"
    link: int
    quantum: float = 0.0
    delay: float = 0.0

    def raw(self, arm: FlexibleArm, q: F64) -> F64:
        """``w(L) / L`` of the link for every row of ``q`` (rad)."""
        link = self._index_in(arm)
        if arm.n_modes[link] == 0:
            return np.zeros(q.shape[0])
        length = float(arm.link_lengths[link])
        tip = arm.modes[link].shape(np.array([length]))[:, 0] / length
        return np.ascontiguousarray(q[:, arm.modal_slice(link)] @ tip)


def measure(
    arm: FlexibleArm, t: F64, q: F64, instruments: Mapping[str, Instrument] | Sequence[Instrument]
) -> dict[str, F64] | list[F64]:
    """Every instrument's channel for a run: a dict for a mapping of named
    instruments, a list for a sequence (each shape (K,))."""
    if isinstance(instruments, Mapping):
        return {name: inst.measure(arm, t, q) for name, inst in instruments.items()}
    return [inst.measure(arm, t, q) for inst in instruments]
