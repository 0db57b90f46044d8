"""The paper's experiments in one call: :func:`reproduce` (experiment, verdicts, report)."""

from __future__ import annotations

import time
from collections.abc import Sequence

from ..._validation import check_bool, check_int, check_option, check_real
from ...errors import InvalidValueError
from ...sim.batch import default_workers
from .beyond import run_beyond
from .cases import (
    ADAPTATION_LAWS,
    DEFAULT_DT,
    DEFAULT_KS,
    DEFAULT_KS_RANGE,
    DEFAULT_LAW,
    DEFAULT_TOLERANCE,
    DELAY_CASES,
)
from .converged import Converged, converged_period, verdict_changes
from .experiment import Progress, RunMatrix, progress_printer, square_side
from .report import Reproduction, Settings
from .verdicts import claims

__all__ = ["reproduce"]

_OWNER = "reproduce"


def reproduce(
    *,
    duration: float | None = None,
    dt: float = DEFAULT_DT,
    ks: float = DEFAULT_KS,
    law: str = DEFAULT_LAW,
    ks_range: Sequence[float] = DEFAULT_KS_RANGE,
    laws: Sequence[str] = ADAPTATION_LAWS,
    delays: Sequence[str] = DELAY_CASES,
    sensitivity: bool = True,
    beyond: bool = True,
    converged: bool = True,
    tolerance: float = DEFAULT_TOLERANCE,
    workers: int | None = None,
    progress: Progress | bool | None = None,
) -> Reproduction:
    """Run the paper's experiments (:mod:`flexarm.studies.reproduction`).

    Parameters
    ----------
    duration : float, optional
        Simulated time per run, s (default: the whole square, 20 s).
    dt : float
        Control period, s (2e-4: the hubless paper arm under the paper's gains
        is sampled-data unstable at 1 ms).
    ks, law
        The fuzzy law of the paper's matrix (:class:`flexarm.control.adaptive.FuzzyAdaptiveJTPD`):
        membership-width gain (dimensionless, >= 0) and adaptation law.
    ks_range : sequence of float
        The ``ks`` values of the sensitivity study (each >= 0).
    laws : sequence of {"scaled", "damping"}
        The adaptation laws of the sensitivity study.
    delays : sequence of {"none", "seed", "dispersive"}
        The delay models of the sensitivity study.
    sensitivity : bool
        Run the sensitivity study (else only the matrix).
    beyond : bool
        Run the study beyond the paper: flexarm's controllers on the physical
        distant sensors and their robustness rows
        (:mod:`~flexarm.studies.reproduction.beyond`).
    converged : bool
        Rerun the matrix on a converged arm (three clamped-mass modes per link,
        geometric stiffening) and judge the claims there too
        (:mod:`~flexarm.studies.reproduction.converged`).
    tolerance : float
        "Tracks well" means RMS error <= ``tolerance`` x the square's side
        (:mod:`~flexarm.studies.reproduction.verdicts`).
    workers : int, optional
        Runs in parallel (:func:`flexarm.simulate_many`: threads, the compiled loop
        releases the GIL). Default: every core this process may use.
    progress : bool or callable, optional
        ``True`` prints one line per finished run on stderr; a callable gets
        ``(done, total, case)``. Default: on when stderr is a terminal.

    Returns
    -------
    Reproduction
    """
    if duration is not None:
        duration = check_real(duration, "duration", _OWNER, positive=True)
    dt = check_real(dt, "dt", _OWNER, positive=True)
    ks = check_real(ks, "ks", _OWNER, nonnegative=True)
    check_option(law, "law", _OWNER, ADAPTATION_LAWS)
    ks_values = tuple(check_real(k, "ks_range", _OWNER, nonnegative=True) for k in ks_range)
    law_values = tuple(check_option(x, "laws", _OWNER, ADAPTATION_LAWS) for x in laws)
    delay_values = tuple(check_option(x, "delays", _OWNER, DELAY_CASES) for x in delays)
    if sensitivity and not (ks_values and law_values and delay_values):
        raise InvalidValueError(
            f"The 'ks_range', 'laws' and 'delays' parameters of {_OWNER} must be non-empty "
            "when sensitivity is on. Got an empty one instead."
        )
    tolerance = check_real(tolerance, "tolerance", _OWNER, positive=True)
    workers = default_workers() if workers is None else workers
    workers = check_int(workers, "workers", _OWNER, minimum=1)

    for name, flag in (("sensitivity", sensitivity), ("beyond", beyond), ("converged", converged)):
        check_bool(flag, name, _OWNER)
    converged_dt = converged_period(dt) if converged else None
    if sensitivity:
        runs = RunMatrix.build(
            ks=ks,
            law=law,
            ks_range=ks_values,
            laws=law_values,
            delays=delay_values,
            converged_dt=converged_dt,
        )
    else:
        runs = RunMatrix.build(ks=ks, law=law, converged_dt=converged_dt)
    runs.validate(duration, dt, workers)  # bad settings fail before the first run

    start = time.perf_counter()
    cases, delay_study, ks_study, converged_cases = runs.run(
        duration, dt, workers=workers, progress=progress_printer(progress)
    )
    extra = run_beyond(duration, dt, workers=workers) if beyond else None
    wall = time.perf_counter() - start

    side = square_side()
    settings = Settings(
        duration_s=duration,
        dt_s=dt,
        ks=ks,
        law=law,
        ks_range=list(ks_values),
        laws=list(law_values),
        delays=list(delay_values),
        sensitivity=sensitivity,
        beyond=beyond,
        tolerance=tolerance,
        square_side_m=side,
        tolerance_m=tolerance * side,
        runs=len(runs.unique()),
        wall_time_s=wall,
    )
    verdicts = claims(cases, ks_study, tolerance * side)
    on_converged = None
    if converged_dt is not None:
        converged_claims = claims(converged_cases, [], tolerance * side)
        on_converged = Converged(
            converged_dt,
            converged_cases,
            converged_claims,
            verdict_changes(verdicts, converged_claims),  # claim 4 needs a ks study: not here
        )
    return Reproduction(cases, delay_study, ks_study, verdicts, settings, extra, on_converged)
