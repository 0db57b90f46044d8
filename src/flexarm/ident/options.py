"""Names of the choices the identification functions accept (no Numba, no SciPy).

The command line builds its ``choices`` from these tuples without importing
the compiled estimators, so ``flexarm --help`` stays quick. The modules that
implement the choices import them from here: one spelling everywhere.
"""

from __future__ import annotations

__all__ = [
    "BANDWIDTH_RULES",
    "BINNABLE",
    "CRITERIA",
    "DISTRIBUTIONS",
    "INSTRUMENTS",
    "KERNELS",
    "METHODS",
    "ORDER_RULES",
    "REGRESSION_FUNCTIONS",
]

#: Names of the built-in kernels, in the order of their compiled codes
#: (:mod:`flexarm.ident.regression.kernels`).
KERNELS: tuple[str, ...] = ("gaussian", "epanechnikov", "uniform", "triangular")

#: Kernels that binned mode accepts: the continuous ones (:mod:`flexarm.ident.regression.binning`).
BINNABLE: tuple[str, ...] = ("gaussian", "epanechnikov", "triangular")

#: Named bandwidth rules (:mod:`flexarm.ident.regression.bandwidth`).
BANDWIDTH_RULES: tuple[str, ...] = ("silverman",)

#: Information criteria that choose an ARMA order (:mod:`flexarm.ident.hammerstein.white.arma`).
CRITERIA: tuple[str, ...] = ("bic", "aic")

#: Order rules of :class:`~flexarm.ident.HammersteinIdentifier`: "auto" (BIC on the white
#: path, held-out validation on the correlated path) or an information criterion.
ORDER_RULES: tuple[str, ...] = ("auto", *CRITERIA)

#: Identification paths of :class:`~flexarm.ident.HammersteinIdentifier`.
METHODS: tuple[str, ...] = ("auto", "white", "correlated")

#: Instruments of the Hammerstein correlation approach
#: (:mod:`flexarm.ident.hammerstein.white.correlation`).
INSTRUMENTS: tuple[str, ...] = ("auto", "regression", "input")

#: Named regression functions of the convergence study
#: (:mod:`flexarm.ident.regression.convergence`).
REGRESSION_FUNCTIONS: tuple[str, ...] = ("smooth", "deadzone", "saturation", "quantizer")

#: Input distributions of the convergence study.
DISTRIBUTIONS: tuple[str, ...] = ("uniform", "normal")
