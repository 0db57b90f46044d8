"""Nonparametric identification (paper §5): kernel regression estimates of ``E[Y | X = x]``.

See :mod:`flexarm.ident.regression` for the estimators and their streaming
state, and :mod:`flexarm.ident.kernels` for the kernels.
"""

from __future__ import annotations

from .kernels import KERNELS, evaluate_kernel
from .regression import (
    NadarayaWatson,
    NotFittedError,
    RecursiveKernelRegression,
    SemiRecursiveKernelRegression,
)

__all__ = [
    "KERNELS",
    "NadarayaWatson",
    "NotFittedError",
    "RecursiveKernelRegression",
    "SemiRecursiveKernelRegression",
    "evaluate_kernel",
]
