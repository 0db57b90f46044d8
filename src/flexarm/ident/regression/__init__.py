"""Kernel regression estimates of ``E[Y | X = x]`` (the paper's eq. 14), and their study.

* :mod:`~flexarm.ident.regression.estimators` — the semi-recursive, fully
  recursive and Nadaraya–Watson estimators (one implementation), in exact,
  grid, binned and series modes;
* :mod:`~flexarm.ident.regression.accumulators` — their streaming state, one
  accumulator per mode, summed in the blocked order of
  :mod:`~flexarm.ident.regression.accumulators.blocks`;
* :mod:`~flexarm.ident.regression.kernels` — the kernels and the Gaussian
  series; :mod:`~flexarm.ident.regression.bandwidth` — Silverman's rule;
  :mod:`~flexarm.ident.regression.binning` — linear binning and its error
  bound; :mod:`~flexarm.ident.regression.chunked` — fits from chunks and
  Dask arrays;
* :mod:`~flexarm.ident.regression.convergence` — the Monte Carlo study of the
  estimate's rate (the paper's Theorem 1).

Names load on first use, as in :mod:`flexarm.ident`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .bandwidth import Silverman as Silverman
    from .bandwidth import silverman_bandwidth as silverman_bandwidth
    from .convergence import ConvergenceResult as ConvergenceResult
    from .convergence import convergence_study as convergence_study
    from .estimators import NadarayaWatson as NadarayaWatson
    from .estimators import RecursiveKernelRegression as RecursiveKernelRegression
    from .estimators import SemiRecursiveKernelRegression as SemiRecursiveKernelRegression
    from .kernels import evaluate_kernel as evaluate_kernel
