"""The paper's experiments in one call: :func:`~flexarm.studies.reproduction.study.reproduce`.

The matrix {nonadaptive PD, fuzzy adaptive} x {joint sensor, end-effector
sensor, sensor 0.5 m from the elbow} on the default square (paper.md §4), a
sensitivity study (the same matrix under each delay model; the fuzzy law over
a range of ``ks`` and both adaptation laws), and a verdict on each of the
paper's claims with the numbers behind it.

What "tracks well" means is stated, not tuned: a run tracks well when it
completes without diverging and its RMS end-effector error is at most
``tolerance`` times the square's side (default 5 %: 0.2 m on the 4 m square).
The paper gives no figure; the tolerance is a parameter and the report prints
every error beside the verdict, so a reader can apply their own.

Every run is one :func:`flexarm.simulate` call built from a
:class:`flexarm.sim.scenario.Scenario`, so each case can be rerun with
``flexarm simulate --scenario`` (the report lists the settings). A run that
diverges is reported as such, with the time, and its partial result is kept
for the figures.

Modules, in the order they build on each other:

* :mod:`~flexarm.studies.reproduction.cases` — one run (:class:`Case`), its
  outcome (:class:`CaseResult`), the study's choices and defaults (light: the
  command line reads them without loading the simulator);
* :mod:`~flexarm.studies.reproduction.verdicts` — the claims and their verdicts,
  pure functions of case results;
* :mod:`~flexarm.studies.reproduction.experiment` — the run matrix
  (:class:`RunMatrix`) and running it;
* :mod:`~flexarm.studies.reproduction.report` — :class:`Reproduction`: summary,
  table, figures, HTML;
* :mod:`~flexarm.studies.reproduction.study` — :func:`reproduce`, all of the above.

Names are imported on first use, so importing this package loads no Numba.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

_SUBMODULES = ("cases", "experiment", "report", "study", "verdicts")

__getattr__, __dir__, __all__ = attach(__name__, _SUBMODULES)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .cases import ADAPTATION_LAWS as ADAPTATION_LAWS
    from .cases import CONTROLLER_KINDS as CONTROLLER_KINDS
    from .cases import DEFAULT_KS_RANGE as DEFAULT_KS_RANGE
    from .cases import DELAY_CASES as DELAY_CASES
    from .cases import SENSOR_CASES as SENSOR_CASES
    from .cases import Case as Case
    from .cases import CaseResult as CaseResult
    from .experiment import RunMatrix as RunMatrix
    from .report import OUTPUT_FILES as OUTPUT_FILES
    from .report import Reproduction as Reproduction
    from .study import reproduce as reproduce
    from .verdicts import Claim as Claim
