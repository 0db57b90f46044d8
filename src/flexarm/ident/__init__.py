"""Nonparametric identification (paper §5): kernel regression and Hammerstein systems.

* :mod:`~flexarm.ident.regression` — the estimators of ``E[Y | X = x]`` (eq. 14),
  their streaming state in :mod:`~flexarm.ident.accumulators` (one per mode);
* :mod:`~flexarm.ident.bandwidth` — the default-bandwidth rule (Silverman's);
* :mod:`~flexarm.ident.hammerstein` — Hammerstein identification for any
  exciting input: the paper's correlation approach for a white input
  (:mod:`~flexarm.ident.correlation`, :mod:`~flexarm.ident.lags`, ARMA fitting
  in :mod:`~flexarm.ident.arma`), the ARX-Hammerstein path for a correlated one
  (:mod:`~flexarm.ident.correlated`: :mod:`~flexarm.ident.hatbasis`,
  :mod:`~flexarm.ident.arx`, :mod:`~flexarm.ident.selection`), the choice by
  :mod:`~flexarm.ident.whiteness`, the linear baseline
  :mod:`~flexarm.ident.linear`, predictions and scores in
  :mod:`~flexarm.ident.prediction`, bootstrap bands in
  :mod:`~flexarm.ident.bootstrap`, the fit's :mod:`~flexarm.ident.report`;
  test systems in :mod:`~flexarm.ident.systems`;
* :mod:`~flexarm.ident.convergence` — the Monte Carlo rate study;
* :mod:`~flexarm.ident.data` — reading columns of data files;
* :mod:`~flexarm.ident.fits` — one-call fits from data, with plots and files.

Names load on first use (PEP 562): ``import flexarm.ident`` imports neither
Numba nor SciPy; ``flexarm.ident.KERNELS`` and the data readers stay light,
an estimator brings in its compiled loops.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

_SUBMODULES = (
    "accumulators",
    "arma",
    "arx",
    "bandwidth",
    "binning",
    "bootstrap",
    "convergence",
    "correlated",
    "correlation",
    "data",
    "fits",
    "hammerstein",
    "hatbasis",
    "kernels",
    "lags",
    "linear",
    "options",
    "prediction",
    "regression",
    "report",
    "selection",
    "systems",
    "whiteness",
)
_NAMES = {
    "KERNELS": "options",
    "BANDWIDTH_RULES": "options",
    "Silverman": "bandwidth",
    "silverman_bandwidth": "bandwidth",
    "evaluate_kernel": "kernels",
    "NadarayaWatson": "regression",
    "NotFittedError": "regression",
    "RecursiveKernelRegression": "regression",
    "SemiRecursiveKernelRegression": "regression",
    # Hammerstein systems and their identification (issue 7)
    "ARMA": "systems",
    "EXAMPLE_ARMA": "systems",
    "Cubic": "systems",
    "DeadZone": "systems",
    "HardLimiter": "systems",
    "PiecewiseLinear": "systems",
    "Quantizer": "systems",
    "Saturation": "systems",
    "Sign": "systems",
    "fit_percent": "systems",
    "simulate_hammerstein": "systems",
    "ARMAFit": "arma",
    "arma_from_impulse_response": "arma",
    "two_point_normalisation": "correlation",
    "HammersteinIdentifier": "hammerstein",
    # any exciting input (issue 17)
    "Bands": "bootstrap",
    "IdentificationReport": "report",
    "IdentificationWarning": "whiteness",
    "LinearARX": "linear",
    "Selection": "selection",
    "WhitenessReport": "whiteness",
    "r2_score": "prediction",
    "whiteness_test": "whiteness",
    # Monte Carlo rate study (issue 6)
    "ConvergenceResult": "convergence",
    "convergence_study": "convergence",
    # data files and one-call fits
    "DataError": "data",
    "load_columns": "data",
    "read_xy": "data",
    "HammersteinFit": "fits",
    "RegressionFit": "fits",
    "fit_hammerstein": "fits",
    "fit_regression": "fits",
}

__getattr__, __dir__, __all__ = attach(__name__, _SUBMODULES, _NAMES)

if TYPE_CHECKING:  # what type checkers and IDEs see; nothing is imported at run time
    from .arma import ARMAFit as ARMAFit
    from .arma import arma_from_impulse_response as arma_from_impulse_response
    from .bandwidth import Silverman as Silverman
    from .bandwidth import silverman_bandwidth as silverman_bandwidth
    from .bootstrap import Bands as Bands
    from .convergence import ConvergenceResult as ConvergenceResult
    from .convergence import convergence_study as convergence_study
    from .correlation import two_point_normalisation as two_point_normalisation
    from .data import DataError as DataError
    from .data import load_columns as load_columns
    from .data import read_xy as read_xy
    from .fits import HammersteinFit as HammersteinFit
    from .fits import RegressionFit as RegressionFit
    from .fits import fit_hammerstein as fit_hammerstein
    from .fits import fit_regression as fit_regression
    from .hammerstein import HammersteinIdentifier as HammersteinIdentifier
    from .kernels import evaluate_kernel as evaluate_kernel
    from .linear import LinearARX as LinearARX
    from .options import BANDWIDTH_RULES as BANDWIDTH_RULES
    from .options import KERNELS as KERNELS
    from .prediction import r2_score as r2_score
    from .regression import NadarayaWatson as NadarayaWatson
    from .regression import NotFittedError as NotFittedError
    from .regression import RecursiveKernelRegression as RecursiveKernelRegression
    from .regression import SemiRecursiveKernelRegression as SemiRecursiveKernelRegression
    from .report import IdentificationReport as IdentificationReport
    from .selection import Selection as Selection
    from .systems import ARMA as ARMA
    from .systems import EXAMPLE_ARMA as EXAMPLE_ARMA
    from .systems import Cubic as Cubic
    from .systems import DeadZone as DeadZone
    from .systems import HardLimiter as HardLimiter
    from .systems import PiecewiseLinear as PiecewiseLinear
    from .systems import Quantizer as Quantizer
    from .systems import Saturation as Saturation
    from .systems import Sign as Sign
    from .systems import fit_percent as fit_percent
    from .systems import simulate_hammerstein as simulate_hammerstein
    from .whiteness import IdentificationWarning as IdentificationWarning
    from .whiteness import WhitenessReport as WhitenessReport
    from .whiteness import whiteness_test as whiteness_test
