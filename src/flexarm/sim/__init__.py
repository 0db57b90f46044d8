"""The simulator: closed loop and open loop, results, metrics, scenario files.

* :func:`simulate` — a controller tracking a trajectory through a sensor
  (:mod:`~flexarm.sim.closed_loop`; the reference pipeline in
  :mod:`~flexarm.sim.references`, the compiled loop in :mod:`~flexarm.sim.loop`);
* :func:`simulate_many` — many runs at once on every core (:mod:`~flexarm.sim.batch`);
* :class:`SimulationSettings` — what defines a run besides the arm, the law and the
  path (:mod:`~flexarm.sim.settings`);
* :func:`simulate_open_loop` — the plant driven by joint torques
  (:mod:`~flexarm.sim.open_loop`);
* :func:`simulate_prescribed` — the plant with its joint motion prescribed
  (:mod:`~flexarm.sim.prescribed`);
* :class:`SimulationResult` — time series, metrics, plots, files (:mod:`~flexarm.sim.results`);
* :mod:`~flexarm.sim.scenario` — runs described by TOML files.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

_SUBMODULES = (
    "batch",
    "chunks",
    "closed_loop",
    "integrator",
    "loop",
    "metrics",
    "open_loop",
    "prescribed",
    "references",
    "results",
    "scenario",
    "scipy_loop",
    "settings",
)
_NAMES = {
    "Scenario": "scenario",
    "SimulationError": "results",
    "SimulationResult": "results",
    "joint_reference": "references",
    "load_scenario": "scenario",
    "iter_simulations": "batch",
    "simulate": "closed_loop",
    "simulate_many": "batch",
    "simulate_open_loop": "open_loop",
    "simulate_prescribed": "prescribed",
    "SimulationSettings": "settings",
}

__getattr__, __dir__, __all__ = attach(__name__, _SUBMODULES, _NAMES)

if TYPE_CHECKING:  # what type checkers see; nothing is imported at run time
    from .batch import iter_simulations as iter_simulations
    from .batch import simulate_many as simulate_many
    from .closed_loop import simulate as simulate
    from .open_loop import simulate_open_loop as simulate_open_loop
    from .prescribed import simulate_prescribed as simulate_prescribed
    from .references import joint_reference as joint_reference
    from .results import SimulationError as SimulationError
    from .results import SimulationResult as SimulationResult
    from .scenario import Scenario as Scenario
    from .scenario import load_scenario as load_scenario
    from .settings import SimulationSettings as SimulationSettings
