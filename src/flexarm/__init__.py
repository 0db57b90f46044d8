"""flexarm: model, simulate, control and identify flexible robot manipulators."""

from __future__ import annotations

from .arm import FlexibleArm
from .joints import LinearJoint, MakkarFriction, NonlinearJoint
from .link import Link
from .modes import BeamModes

__all__ = [
    "BeamModes",
    "FlexibleArm",
    "LinearJoint",
    "Link",
    "MakkarFriction",
    "NonlinearJoint",
    "__version__",
]

__version__ = "0.1.0"
