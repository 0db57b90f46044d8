"""Hammerstein systems and their identification from input/output data, for any exciting input.

:class:`~flexarm.ident.hammerstein.identifier.HammersteinIdentifier` takes one
of two paths:

* :mod:`~flexarm.ident.hammerstein.white` — the paper's correlation approach
  for a white input (lag regressions, each a kernel regression of
  :mod:`flexarm.ident.regression`; the impulse response and ARMA model from them);
* :mod:`~flexarm.ident.hammerstein.correlated` — the ARX-Hammerstein structure
  fitted directly for a correlated input (piecewise-linear basis, rank-one
  separation, instrumental variables, held-out choice of order and knots).

Both produce one :class:`~flexarm.ident.hammerstein.solution.Solution`. Beside
them: the test systems (:mod:`~flexarm.ident.hammerstein.systems`), the
choice of path (:mod:`~flexarm.ident.hammerstein.whiteness`), the linear
baseline (:mod:`~flexarm.ident.hammerstein.linear`) and the comparison with the
best linear model on a validation part (:mod:`~flexarm.ident.hammerstein.comparison`),
predictions and scores
(:mod:`~flexarm.ident.hammerstein.prediction`), bootstrap bands
(:mod:`~flexarm.ident.hammerstein.bootstrap`) and the fit's report
(:mod:`~flexarm.ident.hammerstein.report`).

Names load on first use, as in :mod:`flexarm.ident`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .bootstrap import Bands as Bands
    from .comparison import Comparison as Comparison
    from .correlated.selection import Selection as Selection
    from .identifier import HammersteinIdentifier as HammersteinIdentifier
    from .linear import LinearARX as LinearARX
    from .prediction import fit_percent as fit_percent
    from .prediction import r2_score as r2_score
    from .report import IdentificationReport as IdentificationReport
    from .solution import ARMAFit as ARMAFit
    from .solution import two_point_normalisation as two_point_normalisation
    from .systems import ARMA as ARMA
    from .systems import EXAMPLE_ARMA as EXAMPLE_ARMA
    from .systems import Cubic as Cubic
    from .systems import DeadZone as DeadZone
    from .systems import HardLimiter as HardLimiter
    from .systems import PiecewiseLinear as PiecewiseLinear
    from .systems import Quantizer as Quantizer
    from .systems import Saturation as Saturation
    from .systems import Sign as Sign
    from .systems import simulate_hammerstein as simulate_hammerstein
    from .white.arma import arma_from_impulse_response as arma_from_impulse_response
    from .whiteness import IdentificationWarning as IdentificationWarning
    from .whiteness import WhitenessReport as WhitenessReport
    from .whiteness import whiteness_test as whiteness_test
