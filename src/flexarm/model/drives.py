"""Drives: a motor behind a gear, as a data sheet gives it.

A joint of a real arm is driven by a motor through a gear: the controller sets a
current (through an amplifier), the motor makes a torque ``K_t i`` on its shaft,
the gear multiplies it by its ratio ``N`` and passes a fraction ``eta`` of it (its
efficiency), and the rotor's inertia ``J_r`` is felt at the joint as ``N**2 J_r``
(the rotor turns ``N`` times as fast as the joint). :class:`Drive` holds these
numbers and converts an input to the joint torque; the rotor's reflected inertia
belongs on the motor side of the joint, once (:attr:`Drive.reflected_inertia`).

Examples
--------
>>> d = Drive(torque_constant=0.119, gear_ratio=100, efficiency=0.75, current_limit=1.0)
>>> round(float(d.joint_torque(current=0.5)), 6)   # 0.75 x 0.119 x 100 x 0.5
4.4625
>>> round(float(d.joint_torque(current=3.0)), 6)   # at the amplifier's limit, 1 A
8.925
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_real
from ..errors import InvalidTypeError, InvalidValueError
from .joints import check_gear_ratio

__all__ = ["Drive", "check_drives", "drive_torques"]

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Drive:
    """A motor behind a gear, as a data sheet gives it.

    Parameters
    ----------
    torque_constant : float
        ``K_t``, N m/A at the motor shaft (> 0; for a DC motor, numerically its
        back-EMF constant in V s/rad).
    gear_ratio : float
        ``N``, motor turns per joint turn (>= 1).
    efficiency : float
        ``eta``, the fraction of the motor's torque the gear passes (0 < eta <= 1).
    current_limit : float
        The amplifier's limit, A (> 0; inf: none): a larger current is clipped.
    rotor_inertia : float
        ``J_r``, the rotor's inertia about its own axis, kg m**2 (>= 0).
    current_offset : float
        ``i_0``, A: what the current reading shows at zero current (a measured
        current ``i`` drives ``i - i_0``); default 0.
    """

    torque_constant: float = 1.0
    gear_ratio: float = 1.0
    efficiency: float = 1.0
    current_limit: float = math.inf
    rotor_inertia: float = 0.0
    current_offset: float = 0.0

    def __post_init__(self) -> None:
        owner = "Drive"
        set_ = object.__setattr__
        set_(
            self,
            "torque_constant",
            check_real(self.torque_constant, "torque_constant", owner, positive=True),
        )
        set_(self, "gear_ratio", check_gear_ratio(self.gear_ratio, owner))
        eta = check_real(self.efficiency, "efficiency", owner, positive=True)
        if eta > 1.0:
            raise InvalidValueError(
                f"The 'efficiency' parameter of {owner} must be in (0, 1]. Got {eta} instead."
            )
        set_(self, "efficiency", eta)
        limit = (
            float(self.current_limit)
            if isinstance(self.current_limit, int | float)
            else self.current_limit
        )
        if not (isinstance(limit, float) and limit > 0) or math.isnan(limit):
            raise InvalidValueError(
                f"The 'current_limit' parameter of {owner} must be > 0 (inf: none). "
                f"Got {self.current_limit!r} instead."
            )
        set_(self, "current_limit", limit)
        set_(
            self,
            "rotor_inertia",
            check_real(self.rotor_inertia, "rotor_inertia", owner, nonnegative=True),
        )
        set_(self, "current_offset", check_real(self.current_offset, "current_offset", owner))

    @property
    def torque_gain(self) -> float:
        """Joint torque per ampere, ``eta K_t N`` (N m/A)."""
        return self.efficiency * self.torque_constant * self.gear_ratio

    @property
    def reflected_inertia(self) -> float:
        """The rotor's inertia felt at the joint, ``N**2 J_r`` (kg m**2)."""
        return self.gear_ratio**2 * self.rotor_inertia

    @property
    def torque_limit(self) -> float:
        """The joint torque at the current limit, N m."""
        return self.torque_gain * self.current_limit

    def joint_torque(
        self, *, current: ArrayLike | None = None, motor_torque: ArrayLike | None = None
    ) -> F64:
        """The torque at the joint (N m) for a measured motor ``current`` (A: less the
        reading's offset, clipped to the limit) or a torque on the motor shaft
        ``motor_torque`` (N m); one of them."""
        if (current is None) == (motor_torque is None):  # neither or both
            raise InvalidValueError(
                "Drive.joint_torque takes a 'current' or a 'motor_torque', one of them."
            )
        if motor_torque is None:
            i = check_array(cast(ArrayLike, current), "current", "Drive.joint_torque")
            return np.asarray(
                self.torque_gain
                * np.clip(i - self.current_offset, -self.current_limit, self.current_limit)
            )
        tm = check_array(motor_torque, "motor_torque", "Drive.joint_torque")
        return np.asarray(self.efficiency * self.gear_ratio * tm)


def check_drives(drives: object, n_links: int, owner: str) -> tuple[Drive | None, ...]:
    """``drives`` checked: a sequence of one :class:`Drive` (or None) per joint."""
    if not isinstance(drives, Sequence) or isinstance(drives, str):
        raise InvalidTypeError(
            f"The 'drives' parameter of {owner} must be a sequence of Drive or None, "
            f"one per joint. Got {type(drives).__name__} instead."
        )
    checked = tuple(drives)
    for k, d in enumerate(checked):
        if d is not None and not isinstance(d, Drive):
            raise InvalidTypeError(
                f"The 'drives' parameter of {owner} must hold Drive objects or None. "
                f"Got {type(d).__name__} at position {k} instead."
            )
    if len(checked) != n_links:
        raise InvalidValueError(
            f"The 'drives' parameter of {owner} must hold one Drive (or None) per joint "
            f"({n_links}). Got {len(checked)} instead."
        )
    return checked


def drive_torques(
    drives: Sequence[Drive | None] | None, inputs: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Joint torques (N m) of joint inputs, shape (..., n_joints): a current (A) where
    ``drives`` has a :class:`Drive` (:meth:`Drive.joint_torque`), a torque elsewhere."""
    out = np.array(inputs, dtype=float)
    for j, d in enumerate(drives or ()):
        if d is not None:
            out[..., j] = d.joint_torque(current=inputs[..., j])
    return out
