"""Nonparametric identification (paper §5): kernel regression and Hammerstein systems.

Two estimator families, each a subpackage:

* :mod:`~flexarm.ident.regression` — the kernel regression estimates of
  ``E[Y | X = x]`` (the paper's eq. 14): the estimators
  (:mod:`~flexarm.ident.regression.estimators`), their streaming state
  (:mod:`~flexarm.ident.regression.accumulators`, one per mode), the kernels,
  the default-bandwidth rule (:mod:`~flexarm.ident.regression.bandwidth`,
  Silverman's), linear binning and the Monte Carlo rate study
  (:mod:`~flexarm.ident.regression.convergence`);
* :mod:`~flexarm.ident.hammerstein` — Hammerstein identification for any
  exciting input (:class:`~flexarm.ident.hammerstein.identifier.HammersteinIdentifier`):
  the paper's correlation approach for a white input
  (:mod:`~flexarm.ident.hammerstein.white`), the ARX-Hammerstein path for a
  correlated one (:mod:`~flexarm.ident.hammerstein.correlated`), the choice by
  :mod:`~flexarm.ident.hammerstein.whiteness`, the linear baseline and the
  comparison with the best linear model, predictions and scores, bootstrap
  bands, the fit's report, and the test systems
  (:mod:`~flexarm.ident.hammerstein.systems`).

What serves both stays here: the names of the choices
(:mod:`~flexarm.ident.options`), reading columns of data files
(:mod:`~flexarm.ident.data`) and the one-call fits with plots and files
(:mod:`~flexarm.ident.fits`).

Names load on first use (PEP 562): ``import flexarm.ident`` imports neither
Numba nor SciPy; ``flexarm.ident.KERNELS`` and the data readers stay light,
an estimator brings in its compiled loops.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from ._estimator import NotFittedError as NotFittedError
    from .data import DataError as DataError
    from .data import load_columns as load_columns
    from .data import read_xy as read_xy
    from .fits import HammersteinFit as HammersteinFit
    from .fits import RegressionFit as RegressionFit
    from .fits import fit_hammerstein as fit_hammerstein
    from .fits import fit_regression as fit_regression
    from .hammerstein.bootstrap import Bands as Bands
    from .hammerstein.comparison import Comparison as Comparison
    from .hammerstein.correlated.selection import Selection as Selection
    from .hammerstein.identifier import HammersteinIdentifier as HammersteinIdentifier
    from .hammerstein.linear import LinearARX as LinearARX
    from .hammerstein.prediction import fit_percent as fit_percent
    from .hammerstein.prediction import r2_score as r2_score
    from .hammerstein.report import IdentificationReport as IdentificationReport
    from .hammerstein.solution import ARMAFit as ARMAFit
    from .hammerstein.solution import two_point_normalisation as two_point_normalisation
    from .hammerstein.systems import ARMA as ARMA
    from .hammerstein.systems import EXAMPLE_ARMA as EXAMPLE_ARMA
    from .hammerstein.systems import Cubic as Cubic
    from .hammerstein.systems import DeadZone as DeadZone
    from .hammerstein.systems import HardLimiter as HardLimiter
    from .hammerstein.systems import PiecewiseLinear as PiecewiseLinear
    from .hammerstein.systems import Quantizer as Quantizer
    from .hammerstein.systems import Saturation as Saturation
    from .hammerstein.systems import Sign as Sign
    from .hammerstein.systems import simulate_hammerstein as simulate_hammerstein
    from .hammerstein.white.arma import arma_from_impulse_response as arma_from_impulse_response
    from .hammerstein.whiteness import IdentificationWarning as IdentificationWarning
    from .hammerstein.whiteness import WhitenessReport as WhitenessReport
    from .hammerstein.whiteness import whiteness_test as whiteness_test
    from .options import BANDWIDTH_RULES as BANDWIDTH_RULES
    from .options import KERNELS as KERNELS
    from .regression.bandwidth import Silverman as Silverman
    from .regression.bandwidth import silverman_bandwidth as silverman_bandwidth
    from .regression.convergence import ConvergenceResult as ConvergenceResult
    from .regression.convergence import convergence_study as convergence_study
    from .regression.estimators import NadarayaWatson as NadarayaWatson
    from .regression.estimators import RecursiveKernelRegression as RecursiveKernelRegression
    from .regression.estimators import (
        SemiRecursiveKernelRegression as SemiRecursiveKernelRegression,
    )
    from .regression.kernels import evaluate_kernel as evaluate_kernel
