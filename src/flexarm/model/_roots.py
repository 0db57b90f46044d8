"""The clamped-mass frequency equation and its roots, found once per process.

Internal to :mod:`flexarm.model.beam`, which documents the equation and the numerics:
:func:`frequency_function` (public there), :func:`roots` of checked arguments and
:func:`cached_roots`, the same kept once per process for up to :data:`CACHED_UP_TO`
modes.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["CACHED_UP_TO", "cached_roots", "frequency_function", "frozen", "roots"]

_LINEAR_STEP = math.pi / 64.0
_LOG_POINTS_PER_DECADE = 64


def frequency_function(
    lam: ArrayLike, mass_ratio: float = 0.0, inertia_ratio: float = 0.0
) -> NDArray[np.float64]:
    """The clamped-mass frequency equation, scaled to stay O(1).

    Parameters
    ----------
    lam : array_like
        Dimensionless wavenumbers ``beta L`` (>= 0).
    mass_ratio, inertia_ratio : float
        ``mu = M / (rho L)`` and ``j = J / (rho L**3)``.

    Returns
    -------
    ndarray
        ``F(lam) / (cosh(lam) (1 + mu lam + j lam**3 + mu j lam**4))`` where
        ``F`` is the left side of the frequency equation in the module
        docstring. Same zeros as ``F``, no overflow for large ``lam``.
    """
    lam = np.asarray(lam, dtype=float)
    mu, jr = float(mass_ratio), float(inertia_ratio)
    e = np.exp(-lam)
    sech = 2.0 * e / (1.0 + e * e)
    tanh = (1.0 - e * e) / (1.0 + e * e)
    c, s = np.cos(lam), np.sin(lam)
    # cos*tanh - sin and sech - cos cancel to O(lam**3) and O(lam**4) at small lam
    # (heavy tips): there use the series of cos*sinh - sin*cosh and 1 - cos*cosh.
    small = lam < 1.0
    bending = np.where(small, _series_n(lam) * sech, c * tanh - s)
    clamped = np.where(small, _series_d(lam) * sech, sech - c)
    f = sech + c + mu * lam * bending - jr * lam**3 * (s + tanh * c) + mu * jr * lam**4 * clamped
    out: NDArray[np.float64] = f / (1.0 + mu * lam + jr * lam**3 + mu * jr * lam**4)
    return out


# cos(x) cosh(x) = sum_k (-4)**k x**(4k) / (4k)!; below x = 1 twelve terms are exact.
_SERIES_K = np.arange(1, 13)
_SERIES_COEF = (-4.0) ** _SERIES_K


def _series_d(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``1 - cos(x) cosh(x)`` without cancellation for ``|x| < 1``."""
    terms = _SERIES_COEF / np.array([math.factorial(4 * k) for k in _SERIES_K], dtype=float)
    xx = np.minimum(np.abs(x), 1.0)[..., None]
    out: NDArray[np.float64] = -np.sum(terms * xx ** (4 * _SERIES_K), axis=-1)
    return out


def _series_n(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``cos(x) sinh(x) - sin(x) cosh(x)`` (the derivative of ``cos cosh``) for ``|x| < 1``."""
    terms = _SERIES_COEF / np.array([math.factorial(4 * k - 1) for k in _SERIES_K], dtype=float)
    xx = np.minimum(np.abs(x), 1.0)[..., None]
    out: NDArray[np.float64] = np.sum(terms * xx ** (4 * _SERIES_K - 1), axis=-1)
    return out


CACHED_UP_TO = 64
"""Root and quadrature arrays of up to this many modes are kept once per process (a few
kB each; larger ones are computed each time rather than held)."""


@functools.lru_cache(maxsize=64)
def cached_roots(n: int, mu: float, jr: float) -> NDArray[np.float64]:
    """:func:`roots`, once per process for each argument (read-only)."""
    return frozen(roots(n, mu, jr))


def roots(n: int, mu: float, jr: float) -> NDArray[np.float64]:
    """:func:`flexarm.model.beam.clamped_mass_roots` of checked arguments."""
    if n == 0:
        return np.zeros(0)

    # Lowest possible root: a rigid tip body on a massless beam bounds it from below.
    small = min(1.0, (3.0 / max(mu, 1e-300)) ** 0.25, (1.0 / max(jr, 1e-300)) ** 0.25)
    lo = 0.1 * small
    decades = max(1.0, math.log10(1.0 / lo))
    log_grid = np.logspace(math.log10(lo), 0.0, int(decades * _LOG_POINTS_PER_DECADE) + 1)
    found: list[float] = []
    _collect_roots(log_grid, mu, jr, found, n)
    upper = 1.0
    while len(found) < n:
        # Roots are about pi apart for large lam: extend in blocks that hold the rest.
        span = (n - len(found) + 2) * math.pi
        steps = np.arange(int(span / _LINEAR_STEP) + 2, dtype=np.float64)
        grid: NDArray[np.float64] = upper + _LINEAR_STEP * steps
        _collect_roots(grid, mu, jr, found, n)
        upper = float(grid[-1])
    return np.asarray(found[:n])


def _collect_roots(
    grid: NDArray[np.float64], mu: float, jr: float, roots: list[float], n: int
) -> None:
    """Append the roots bracketed by sign changes of the scaled equation on ``grid``."""
    from scipy.optimize import brentq  # loaded on first use: import flexarm stays light

    def g(x: float) -> float:
        return float(frequency_function(x, mu, jr))

    values = frequency_function(grid, mu, jr)
    for k in range(grid.size - 1):
        if len(roots) >= n:
            return
        a, b = float(grid[k]), float(grid[k + 1])
        fa, fb = float(values[k]), float(values[k + 1])
        if fb == 0.0:
            roots.append(b)
        elif fa * fb < 0.0:
            roots.append(brentq(g, a, b, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=200))


def frozen(a: NDArray[Any]) -> NDArray[Any]:
    a = np.asarray(a)
    a.flags.writeable = False
    return a
