"""flexarm: model, simulate, control and identify flexible robot manipulators."""

from __future__ import annotations

from .model.arm import FlexibleArm
from .model.joints import LinearJoint, MakkarFriction, NonlinearJoint
from .model.link import Link
from .model.modes import BeamModes

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
