"""One run of a sweep, done: build its scenario, simulate, keep the metrics only.

:func:`run_scenario` is the whole of a run (:meth:`Scenario.from_dict` then
:func:`flexarm.simulate`); :func:`record_of` turns what it gave (a result, or
the exception it raised) into a :class:`Record`, a small JSON-ready mapping:
the journal's line and a row of the table. The time series are dropped as soon
as the metrics are computed.

A run that diverges (:class:`~flexarm.sim.results.SimulationError`) is
``"diverged"`` at the time it stopped; a scenario that cannot be built (a bad
combination of parameters) or any other exception is ``"error"`` with its
message. Neither stops the sweep.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, TypedDict

from .._version import __version__
from .reader import Value
from .spec import METRICS

if TYPE_CHECKING:
    from ..sim.results import SimulationResult

__all__ = ["RUN_SOURCE", "STATUSES", "Record", "record_of", "run_scenario"]

STATUSES = ("ok", "diverged", "error")
"""A run's status: it ran to the end; it diverged; it could not run."""

RUN_SOURCE = "run"
"""The source named by a run's scenario errors (stripped from the table's message)."""


class Record(TypedDict):
    """A finished run: one line of the journal, one row of the table.

    ``metrics`` holds :data:`~flexarm.sweeps.spec.METRICS` for an ``"ok"`` run
    and is empty otherwise; times are in s (NaN where undefined).
    """

    run_id: str
    status: str
    message: str
    sim_time_s: float
    wall_time_s: float
    metrics: dict[str, float | list[float]]
    flexarm: str


def run_scenario(scenario: Mapping[str, Value]) -> SimulationResult:
    """Build ``scenario`` (:meth:`~flexarm.sim.scenario.Scenario.from_dict`) and simulate it.

    Raises
    ------
    ScenarioError
        If the scenario cannot be built.
    SimulationError
        If the run diverges.
    """
    from ..sim.scenario import Scenario

    sc = Scenario.from_dict(scenario, source=RUN_SOURCE)
    # the record keeps the metrics only: the measurement and the reference are not recorded
    # (the same run and metrics, a third of the memory)
    return sc.simulate(progress=False, record_signals=False)


def record_of(run_id: str, outcome: SimulationResult | BaseException) -> Record:
    """The record of a run given its result or the exception it raised.

    Parameters
    ----------
    run_id : str
        The run's id (:func:`flexarm.sweeps.keys.run_id`).
    outcome : SimulationResult or Exception
        What :func:`run_scenario` returned or raised.
    """
    from ..sim.results import SimulationError

    nan = math.nan
    if isinstance(outcome, SimulationError):
        wall = outcome.result.info.get("wall_time_s")
        return _record(run_id, "diverged", _message(outcome), outcome.time, _float(wall), {})
    if isinstance(outcome, BaseException):
        return _record(run_id, "error", _message(outcome), nan, nan, {})
    m = outcome.metrics()
    metrics = {name: m[name] for name in METRICS}
    return _record(run_id, "ok", "", _float(m["sim_time_s"]), _float(m["wall_time_s"]), metrics)


def _record(
    run_id: str,
    status: str,
    message: str,
    sim_time: float,
    wall_time: float,
    metrics: dict[str, float | list[float]],
) -> Record:
    return Record(
        run_id=run_id,
        status=status,
        message=message,
        sim_time_s=float(sim_time),
        wall_time_s=wall_time,
        metrics=metrics,
        flexarm=__version__,
    )


def _float(value: object) -> float:
    return float(value) if isinstance(value, int | float) else math.nan


def _message(exc: BaseException) -> str:
    """One line: the scenario error without its source, others with their type."""
    from ..errors import FlexarmError, ScenarioError

    text = str(exc)
    if isinstance(exc, ScenarioError) and text.startswith(f"{exc.source}: "):
        text = text[len(exc.source) + 2 :]
    elif not isinstance(exc, FlexarmError):
        text = f"{type(exc).__name__}: {text}"
    return " ".join(text.split())
