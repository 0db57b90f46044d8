"""Nonparametric identification (paper §5): kernel regression estimates of ``E[Y | X = x]``.

See :mod:`flexarm.ident.regression` for the estimators and their streaming
state, and :mod:`flexarm.ident.kernels` for the kernels.
"""

from __future__ import annotations

from .convergence import ConvergenceResult, convergence_study
from .hammerstein import (
    ARMAFit,
    HammersteinIdentifier,
    arma_from_impulse_response,
    fit_percent,
    two_point_normalisation,
)
from .kernels import KERNELS, evaluate_kernel
from .regression import (
    NadarayaWatson,
    NotFittedError,
    RecursiveKernelRegression,
    SemiRecursiveKernelRegression,
)
from .systems import (
    ARMA,
    EXAMPLE_ARMA,
    Cubic,
    DeadZone,
    HardLimiter,
    PiecewiseLinear,
    Quantizer,
    Saturation,
    Sign,
    simulate_hammerstein,
)

__all__ = [
    "KERNELS",
    "NadarayaWatson",
    "NotFittedError",
    "RecursiveKernelRegression",
    "SemiRecursiveKernelRegression",
    "evaluate_kernel",
]
__all__ += [  # Hammerstein systems and their identification (issue 7)
    "ARMA",
    "EXAMPLE_ARMA",
    "ARMAFit",
    "Cubic",
    "DeadZone",
    "HammersteinIdentifier",
    "HardLimiter",
    "PiecewiseLinear",
    "Quantizer",
    "Saturation",
    "Sign",
    "arma_from_impulse_response",
    "fit_percent",
    "simulate_hammerstein",
    "two_point_normalisation",
]
__all__ += ["ConvergenceResult", "convergence_study"]  # Monte Carlo rate study (issue 6)
