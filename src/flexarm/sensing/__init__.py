"""What a controller can see: sensors and transport delays.

* :mod:`~flexarm.sensing.sensors` — joint encoders, a point on a link, the tip;
* :mod:`~flexarm.sensing.delays` — transport delays (exact, Padé) and bending-wave speeds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

_SUBMODULES = ("delays", "sensors")

__getattr__, __dir__, __all__ = attach(__name__, _SUBMODULES)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .delays import DelayModel as DelayModel
    from .sensors import JointSensor as JointSensor
    from .sensors import PointSensor as PointSensor
    from .sensors import Sensor as Sensor
    from .sensors import TipSensor as TipSensor
