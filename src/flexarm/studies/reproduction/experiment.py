"""The run matrix of the reproduction, and running it.

:class:`RunMatrix` lists the runs: the paper's matrix {nonadaptive PD, fuzzy
adaptive} x {joint sensor, end-effector sensor, sensor 0.5 m from the elbow}
under each sensor model — the paper's (rigid kinematics of the joint angles
through the seed's transport delay, 2nd-order Padé, reference delayed: the
paper's experiment) and the physical one (the deflected point, no added delay)
— with the default fuzzy settings, and the sensitivity study (the paper's
model under each delay model; the fuzzy law over ``ks`` and the adaptation
laws under each sensor model).
Runs that two lists share (and nonadaptive runs that differ only in the fuzzy
settings, which they ignore) are run once.

Every run is one :func:`flexarm.simulate` call built from a
:class:`flexarm.sim.scenario.Scenario`, so each case can be rerun with
``flexarm simulate --scenario``. A run that diverges is a result: its status,
the time and the partial series are kept (:func:`run_case`).
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ...control.linearize import closed_loop_poles
from ...control.trajectories import Square
from ...sim.batch import Outcome, iter_simulations
from ...sim.closed_loop import check_budget
from ...sim.results import SimulationError
from ...sim.scenario import Scenario
from .cases import (
    CONTROLLER_KINDS,
    PAPER_DELAY,
    SENSOR_CASES,
    SENSOR_MODELS,
    Case,
    CaseResult,
    Metrics,
)

__all__ = ["Progress", "RunMatrix", "case_result", "progress_printer", "run_case", "square_side"]

Progress = Callable[[int, int, Case], None]
"""Called after each finished run with ``(done, total, case)``."""

_SOURCE = "reproduce"
_MODEL_DELAY = {"paper": PAPER_DELAY, "physical": "none"}


@dataclass(frozen=True)
class RunMatrix:
    """The runs of the study, in report order.

    Attributes
    ----------
    matrix : tuple of Case
        The paper's matrix, model-major then controller-major (the default fuzzy
        settings).
    delay_study : tuple of Case
        The paper's model under each delay model (delay-major).
    ks_study : tuple of Case
        The fuzzy law over ``ks`` and the adaptation laws (model-major, law, ``ks``).
    """

    matrix: tuple[Case, ...]
    delay_study: tuple[Case, ...] = ()
    ks_study: tuple[Case, ...] = ()
    converged: tuple[Case, ...] = ()
    converged_dt: float | None = None

    @classmethod
    def build(
        cls,
        *,
        ks: float,
        law: str,
        ks_range: Sequence[float] = (),
        laws: Sequence[str] = (),
        delays: Sequence[str] = (),
        converged_dt: float | None = None,
    ) -> RunMatrix:
        """The matrix with the fuzzy law ``(ks, law)``, and the sensitivity study.

        Parameters
        ----------
        ks : float
            Membership-width gain of the matrix's fuzzy runs, dimensionless.
        law : {"scaled", "damping"}
            Adaptation law of the matrix's fuzzy runs.
        ks_range, laws : sequences
            The ``ks`` study: every law at every ``ks`` (empty: none).
        delays : sequence of {"none", "seed", "dispersive"}
            The delay study: the matrix under each delay model (empty: none).
        converged_dt : float, optional
            Also the matrix on the converged arm, at this control period (s;
            None: not).
        """
        matrix = tuple(
            Case(c, s, _MODEL_DELAY[m], ks, law, m)
            for m in SENSOR_MODELS
            for c in CONTROLLER_KINDS
            for s in SENSOR_CASES
        )
        delay_study = tuple(
            Case(c, s, d, ks, law, "paper")
            for d in delays
            for c in CONTROLLER_KINDS
            for s in SENSOR_CASES
        )
        ks_study = tuple(
            Case("fuzzy", s, _MODEL_DELAY[m], k, lw, m)
            for m in SENSOR_MODELS
            for lw in laws
            for k in ks_range
            for s in SENSOR_CASES
        )
        converged = (
            tuple(dataclasses.replace(c, arm="converged") for c in matrix)
            if converged_dt is not None
            else ()
        )
        return cls(matrix, delay_study, ks_study, converged, converged_dt)

    def unique(self) -> dict[tuple[str | float, ...], Case]:
        """The distinct runs by :meth:`Case.key`, first occurrence first."""
        unique: dict[tuple[str | float, ...], Case] = {}
        for c in (*self.matrix, *self.delay_study, *self.ks_study, *self.converged):
            unique.setdefault(c.key(), c)
        return unique

    def period(self, case: Case, dt: float) -> float:
        """The control period of ``case``: ``dt``, or the converged arm's own."""
        if case.arm == "converged" and self.converged_dt is not None:
            return self.converged_dt
        return dt

    def validate(self, duration: float | None, dt: float, workers: int = 1) -> None:
        """Build every run's scenario and check what the runs need (memory, time), so
        that bad settings fail before the first run."""
        unique = self.unique().values()
        for c in unique:
            sc = Scenario.from_dict(c.scenario_dict(duration, self.period(c, dt)), source=_SOURCE)
            check_budget(
                sc.arm,
                sc.sensor,
                sc.delay,
                dt=sc.simulation.dt,
                duration=float(sc.simulation.duration or sc.trajectory.duration),
                substeps=sc.simulation.substeps,
                record_every=sc.simulation.record_every,
                runs=len(unique),
                workers=workers,
                owner="reproduce",
                remedy="Shorten the duration or lengthen dt",
            )

    def run(
        self,
        duration: float | None,
        dt: float,
        *,
        workers: int = 1,
        progress: Progress | None = None,
    ) -> tuple[list[CaseResult], list[CaseResult], list[CaseResult], list[CaseResult]]:
        """Run every distinct case once, on ``workers`` cores
        (:func:`flexarm.sim.batch.iter_simulations`).

        Parameters
        ----------
        duration : float or None
            Simulated time per run, s (None: the whole square).
        dt : float
            Control period, s.
        workers : int
            Runs in parallel.
        progress : callable, optional
            Called with ``(done, total, case)`` after each run.

        Returns
        -------
        matrix, delay_study, ks_study, converged : list of CaseResult
            In the order of the attributes; a run shared by several cases is
            the same result, relabelled with each case.
        """
        unique = list(self.unique().items())
        scenarios = [
            Scenario.from_dict(case.scenario_dict(duration, self.period(case, dt)), source=_SOURCE)
            for _, case in unique
        ]
        runs = [{"arm": sc.arm, **sc.simulate_kwargs(), "progress": False} for sc in scenarios]
        results: dict[tuple[str | float, ...], CaseResult] = {}
        outcomes = iter_simulations(runs, workers=workers, errors="return", progress=False)
        for done, (i, outcome) in enumerate(outcomes, start=1):
            key, case = unique[i]
            results[key] = case_result(case, scenarios[i], outcome)
            if progress is not None:
                progress(done, len(unique), case)

        def pick(cases: tuple[Case, ...]) -> list[CaseResult]:
            out = []
            for c in cases:
                r = results[c.key()]
                if r.case != c:  # the same run under another name (pd ignores ks and law)
                    r = dataclasses.replace(r, case=c)
                out.append(r)
            return out

        return (
            pick(self.matrix),
            pick(self.delay_study),
            pick(self.ks_study),
            pick(self.converged),
        )


def run_case(case: Case, duration: float | None, dt: float) -> CaseResult:
    """Run one case; a divergence is a result (status ``"diverged"``, partial series).

    Parameters
    ----------
    case : Case
    duration : float or None
        Simulated time, s (None: the whole square).
    dt : float
        Control period, s.
    """
    scenario = Scenario.from_dict(case.scenario_dict(duration, dt), source=_SOURCE)
    try:
        outcome: Outcome = scenario.simulate(progress=False)
    except SimulationError as exc:
        outcome = exc
    return case_result(case, scenario, outcome)


def case_result(case: Case, scenario: Scenario, outcome: Outcome) -> CaseResult:
    """The :class:`CaseResult` of ``case`` run as ``scenario`` from the run's outcome
    (a result, or the :class:`SimulationError` of a run that diverged; any other
    exception is raised)."""
    delay_s = scenario.delay.delay
    start = np.asarray(scenario.trajectory.evaluate(np.zeros(1))[0][0], dtype=float)
    poles = closed_loop_poles(scenario.arm, scenario.controller, start, scenario.sensor)
    pole = float(poles[0].real)
    if isinstance(outcome, SimulationError):
        partial = outcome.result
        wall = partial.info.get("wall_time_s")
        metrics: Metrics = {
            "sim_time_s": float(outcome.time),
            "wall_time_s": float(wall) if isinstance(wall, int | float) else None,
        }
        return CaseResult(case, "diverged", float(outcome.time), metrics, delay_s, pole, partial)
    if isinstance(outcome, Exception):
        raise outcome
    return CaseResult(case, "ok", None, outcome.metrics(), delay_s, pole, outcome)


def square_side() -> float:
    """Side of the default square the study tracks, m."""
    trajectory = Scenario.from_dict({}, source=_SOURCE).trajectory
    assert isinstance(trajectory, Square)
    return float(trajectory.side)


def progress_printer(progress: Progress | bool | None) -> Progress | None:
    """A callable as it is; ``True``: one line per run on stderr; None: that if stderr is a tty."""
    if callable(progress):
        return progress
    show = sys.stderr.isatty() if progress is None else bool(progress)
    if not show:
        return None

    def report(done: int, total: int, case: Case) -> None:
        print(f"[{done}/{total}] {case.label}", file=sys.stderr, flush=True)

    return report
