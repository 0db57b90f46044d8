"""Units a record's columns may be given in, and their factors to SI.

A column of a record names its unit (``unit = "deg"``); the calibration works in
SI (rad, rad/s, m, s, N m, A). :func:`to_si` converts; an unknown unit is one
clear error naming it and the units known.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["QUANTITIES", "UNITS", "to_si", "unit_quantity"]

UNITS: dict[str, tuple[str, float]] = {
    # angle
    "rad": ("angle", 1.0),
    "mrad": ("angle", 1e-3),
    "deg": ("angle", math.pi / 180.0),
    "rev": ("angle", 2.0 * math.pi),
    # angular rate
    "rad/s": ("rate", 1.0),
    "deg/s": ("rate", math.pi / 180.0),
    "rpm": ("rate", 2.0 * math.pi / 60.0),
    # length
    "m": ("length", 1.0),
    "mm": ("length", 1e-3),
    "um": ("length", 1e-6),
    "in": ("length", 0.0254),
    # strain
    "1": ("strain", 1.0),
    "strain": ("strain", 1.0),
    "microstrain": ("strain", 1e-6),
    # time
    "s": ("time", 1.0),
    "ms": ("time", 1e-3),
    "us": ("time", 1e-6),
    # current
    "A": ("current", 1.0),
    "mA": ("current", 1e-3),
    # torque
    "N m": ("torque", 1.0),
    "N mm": ("torque", 1e-3),
    "mN m": ("torque", 1e-3),
}
"""Unit name -> (quantity, factor to SI)."""

QUANTITIES = tuple(sorted({q for q, _ in UNITS.values()}))
"""The quantities a unit may measure."""


def unit_quantity(unit: str) -> str | None:
    """The quantity ``unit`` measures (``"angle"``, ``"current"``, ...), or None if unknown."""
    entry = UNITS.get(unit)
    return None if entry is None else entry[0]


def to_si(values: NDArray[np.float64], unit: str) -> NDArray[np.float64]:
    """``values`` given in ``unit`` converted to SI (a new array)."""
    return np.asarray(values, dtype=np.float64) * UNITS[unit][1]
