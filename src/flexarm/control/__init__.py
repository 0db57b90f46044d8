"""References and control: trajectories, input shapers, control laws, linear analysis.

* :mod:`~flexarm.control.trajectories` — end-effector paths (the paper's square, ...);
* :mod:`~flexarm.control.shapers` — ZV, ZVD and EI input shapers;
* :mod:`~flexarm.control.signals` — the layout of what a controller reads;
* :mod:`~flexarm.control.controllers` — joint PD, Jacobian-transpose PD, your own law;
* :mod:`~flexarm.control.adaptive` — the paper's fuzzy adaptive law;
* :mod:`~flexarm.control.linearize` — linearised closed loops.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

_SUBMODULES = ("adaptive", "controllers", "linearize", "shapers", "signals", "trajectories")

__getattr__, __dir__, __all__ = attach(__name__, _SUBMODULES)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .adaptive import FuzzyAdaptiveJTPD as FuzzyAdaptiveJTPD
    from .controllers import CompiledController as CompiledController
    from .controllers import Controller as Controller
    from .controllers import JacobianTransposePD as JacobianTransposePD
    from .controllers import JointPD as JointPD
    from .linearize import closed_loop_poles as closed_loop_poles
    from .shapers import Shaper as Shaper
    from .trajectories import Circle as Circle
    from .trajectories import Line as Line
    from .trajectories import PointToPoint as PointToPoint
    from .trajectories import Square as Square
    from .trajectories import Trajectory as Trajectory
    from .trajectories import Waypoints as Waypoints
