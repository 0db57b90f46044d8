"""flexarm: model, simulate, control and identify flexible robot manipulators.

The package is layered as the data flows (parameters -> model -> simulator <-
controllers, sensors, references -> results; data -> estimators):

* :mod:`flexarm.model` — beam modes, links, joints, the arm and its compiled dynamics;
* :mod:`flexarm.sensing` — sensors and transport delays;
* :mod:`flexarm.control` — trajectories, input shapers, control laws, linear analysis;
* :mod:`flexarm.sim` — the simulator, its results and metrics, scenario files;
* :mod:`flexarm.fuzzy` — Mamdani fuzzy inference (the paper's adaptive law);
* :mod:`flexarm.ident` — kernel regression and Hammerstein identification;
* :mod:`flexarm.calibration` — an arm's parameters fitted to measured runs
  (``flexarm.calibrate``);
* :mod:`flexarm.sweeps` — grid and Monte Carlo sweeps over scenario parameters
  (``flexarm.sweep``), on every core or a Dask cluster;
* :mod:`flexarm.studies` — the paper's reproduction and the robot-joint study;
* :mod:`flexarm.envs` — Gymnasium environments (the ``rl`` extra);
* :mod:`flexarm.figures` — figure files (PNG, PDF, SVG) and the plots' style;
* :mod:`flexarm.cli` — the ``flexarm`` command.

Everything is imported on first use: ``import flexarm`` is cheap (no Numba, no
Matplotlib), and ``flexarm.ident.SemiRecursiveKernelRegression`` works without
importing :mod:`flexarm.ident` first.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._lazy import attach
from ._version import __version__

_SUBPACKAGES = (
    "calibration",
    "cli",
    "control",
    "envs",
    "figures",
    "fuzzy",
    "ident",
    "model",
    "modes",
    "sensing",
    "sim",
    "studies",
    "sweeps",
)
_NAMES = {
    "BeamModes": "model.beam",
    "Drive": "model.drives",
    "FlexibleArm": "model.arm",
    "LinearJoint": "model.joints",
    "Link": "model.link",
    "MakkarFriction": "model.joints",
    "NonlinearJoint": "model.joints",
    "RigidJoint": "model.joints",
    "RigidLink": "model.link",
    "SimulationError": "sim.results",
    "SimulationResult": "sim.results",
    "simulate": "sim.closed_loop",
    "simulate_many": "sim.batch",
    "simulate_open_loop": "sim.open_loop",
    "simulate_prescribed": "sim.prescribed",
    "SimulationSettings": "sim.settings",
    "sweep": "sweeps.driver",
    "calibrate": "calibration.result",
}

__getattr__, __dir__, __all__ = attach(__name__, _SUBPACKAGES, _NAMES)
__all__ += ["__version__"]

if TYPE_CHECKING:  # what type checkers and IDEs see; nothing is imported at run time
    from .calibration.result import calibrate as calibrate
    from .model.arm import FlexibleArm as FlexibleArm
    from .model.beam import BeamModes as BeamModes
    from .model.drives import Drive as Drive
    from .model.joints import (
        LinearJoint as LinearJoint,
    )
    from .model.joints import (
        MakkarFriction as MakkarFriction,
    )
    from .model.joints import (
        NonlinearJoint as NonlinearJoint,
    )
    from .model.joints import RigidJoint as RigidJoint
    from .model.link import Link as Link
    from .model.link import RigidLink as RigidLink
    from .sim.batch import simulate_many as simulate_many
    from .sim.closed_loop import simulate as simulate
    from .sim.open_loop import simulate_open_loop as simulate_open_loop
    from .sim.prescribed import simulate_prescribed as simulate_prescribed
    from .sim.results import SimulationError as SimulationError
    from .sim.results import SimulationResult as SimulationResult
    from .sim.settings import SimulationSettings as SimulationSettings
    from .sweeps.driver import sweep as sweep
