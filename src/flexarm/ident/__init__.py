"""Nonparametric identification (paper §5): kernel regression and Hammerstein systems.

* :mod:`~flexarm.ident.regression` — the estimators of ``E[Y | X = x]`` (eq. 14),
  their streaming state in :mod:`~flexarm.ident.accumulators` (one per mode);
* :mod:`~flexarm.ident.bandwidth` — the default-bandwidth rule (Silverman's);
* :mod:`~flexarm.ident.hammerstein` — Hammerstein identification by the
  correlation approach (:mod:`~flexarm.ident.correlation`,
  :mod:`~flexarm.ident.lags`), ARMA fitting in :mod:`~flexarm.ident.arma`,
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
    "bandwidth",
    "binning",
    "convergence",
    "correlation",
    "data",
    "fits",
    "hammerstein",
    "kernels",
    "lags",
    "options",
    "regression",
    "systems",
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
    from .options import BANDWIDTH_RULES as BANDWIDTH_RULES
    from .options import KERNELS as KERNELS
    from .regression import NadarayaWatson as NadarayaWatson
    from .regression import NotFittedError as NotFittedError
    from .regression import RecursiveKernelRegression as RecursiveKernelRegression
    from .regression import SemiRecursiveKernelRegression as SemiRecursiveKernelRegression
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
