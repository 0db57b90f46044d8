"""The correlation approach: a Hammerstein system's parts from its lag regressions.

Given the grid-mode sums of the lag regressions ``m_k(x) = E[Y_{n+k} | X_n = x]``,
``k = 0 .. L-1`` (:class:`~flexarm.ident.HammersteinIdentifier` keeps them),
:func:`solve` computes the impulse response (the instrument's covariances),
the nonlinearity (the least-squares combination of the centred regressions,
normalised by two known points or by the largest impulse-response entry) and
the ARMA model (:func:`~flexarm.ident.arma.arma_from_impulse_response`). See
:mod:`flexarm.ident.hammerstein` for the method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._validation import check_real
from ..errors import InvalidValueError
from .arma import ARMAFit, arma_from_impulse_response

__all__ = [
    "KnownPoints",
    "Solution",
    "check_known_points",
    "solve",
    "two_point_normalisation",
]

F64 = NDArray[np.float64]
#: Two points where the nonlinearity is known: ``((x1, phi1), (x2, phi2))``.
KnownPoints = tuple[tuple[float, float], tuple[float, float]]


def two_point_normalisation(m1: float, m2: float, phi1: float, phi2: float) -> tuple[float, float]:
    """The paper's two-point normalisation: ``(d1, alpha)`` with ``phi = (m - alpha) / d1``.

    ``d1 = (m1 - m2) / (phi1 - phi2)`` and ``alpha = m1 - d1 phi1``, where
    ``m1, m2`` are the (unnormalised) estimates at two points where ``phi`` is
    known to be ``phi1 != phi2``.

    Examples
    --------
    >>> two_point_normalisation(3.0, 1.0, 1.0, 0.0)
    (2.0, 1.0)
    """
    owner = "two_point_normalisation"
    m1, m2 = check_real(m1, "m1", owner), check_real(m2, "m2", owner)
    phi1, phi2 = check_real(phi1, "phi1", owner), check_real(phi2, "phi2", owner)
    if phi1 == phi2:
        raise InvalidValueError(
            f"The 'phi2' parameter of {owner} must differ from phi1. Got {phi2}."
        )
    d1 = (m1 - m2) / (phi1 - phi2)
    if d1 == 0.0:
        raise InvalidValueError(
            f"The 'm2' parameter of {owner} must differ from m1 (the estimate must separate "
            f"the two points). Got {m2} instead."
        )
    return d1, m1 - d1 * phi1


def check_known_points(value: object, owner: str) -> KnownPoints | None:
    """``known_points`` checked: ``None``, or two points with ``x1 != x2`` and ``phi1 != phi2``."""
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = np.zeros(0)
    if arr.shape != (2, 2) or not np.all(np.isfinite(arr)):
        raise InvalidValueError(
            f"The 'known_points' parameter of {owner} must be ((x1, phi(x1)), (x2, phi(x2))), "
            f"four finite numbers. Got {value!r} instead."
        )
    (x1, f1), (x2, f2) = arr.tolist()
    if x1 == x2 or f1 == f2:
        raise InvalidValueError(
            f"The 'known_points' parameter of {owner} must have x1 != x2 and "
            f"phi(x1) != phi(x2). Got {value!r} instead."
        )
    return (x1, f1), (x2, f2)


@dataclass(frozen=True)
class Solution:
    """What :func:`solve` derives from the lag regressions.

    Attributes
    ----------
    lags : ndarray, shape (L,)
        ``lambda-tilde``, the unnormalised impulse response.
    shape : ndarray, shape (g,)
        The unnormalised nonlinearity ``psi`` on ``grid``.
    grid : ndarray, shape (g,)
        The grid points every regression reached (units of the input).
    weights : ndarray, shape (g,)
        Kernel density weights of the input on ``grid`` (sum 1).
    impulse : ndarray, shape (L,)
        The normalised impulse response.
    nonlinearity : ndarray, shape (g,)
        The normalised ``phi`` on ``grid`` (units of ``W``).
    arma : ARMAFit
        The linear part fitted to ``impulse``.
    offset : float
        Output offset of the free-run prediction (units of the output).
    singular_values : ndarray
        Of the density-weighted lag-regression array (rank one if Hammerstein).
    """

    lags: F64
    shape: F64
    grid: F64
    weights: F64
    impulse: F64
    nonlinearity: F64
    arma: ARMAFit
    offset: float
    singular_values: F64


def solve(
    num: F64,
    den: F64,
    grid: F64,
    *,
    instrument: str,
    known_points: KnownPoints | None,
    order: int | str,
    max_order: int,
    mean_y: float,
    owner: str,
) -> Solution:
    """Impulse response, nonlinearity and ARMA model from the lag regressions' sums.

    Parameters
    ----------
    num, den : ndarray, shape (L, g)
        Grid-mode sums ``sum Y_{i+k} w_i(x)`` and ``sum w_i(x)`` of lag ``k``.
    grid : ndarray, shape (g,)
        The grid (units of the input).
    instrument : {"auto", "regression", "input"}
        The correlation approach's instrument.
    known_points : ((x1, phi1), (x2, phi2)) or None
        Two-point normalisation, or ``None`` (largest impulse-response entry ``+1``).
    order : int or {"bic", "aic"}
        ARMA order or criterion; ``max_order`` the largest tried.
    mean_y : float
        Mean of the output (units of the output).
    owner : str
        Named in the error messages.
    """
    valid = np.all(den > 0.0, axis=0)
    if np.count_nonzero(valid) < 2:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must spread over the grid. Got samples "
            "reaching fewer than 2 grid points instead."
        )
    grid = grid[valid]
    m = num[:, valid] / den[:, valid]
    w = den[0, valid] / np.sum(den[0, valid])
    centred = m - (m @ w)[:, None]
    sq = np.sqrt(w)
    svals = np.linalg.svd(centred * sq[None, :], compute_uv=False)
    if instrument == "auto":
        left, s, _ = np.linalg.svd(centred * sq[None, :], full_matrices=False)
        psi = (left[:, 0] @ centred) / s[0] if s[0] > 0 else np.zeros(grid.shape[0])
    elif instrument == "regression":
        psi = centred[0]
    else:
        psi = grid - grid @ w
    lags = centred @ (w * psi)
    energy = float(lags @ lags)
    if not energy > 0.0 or not np.isfinite(energy):
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must depend on u through the chosen instrument "
            f"({instrument!r}). Got no correlation instead (try instrument='auto')."
        )
    shape = (lags @ centred) / energy
    if known_points is None:
        k = int(np.argmax(np.abs(lags)))
        scale = float(lags[k])
        impulse = lags / scale
        phi = shape * scale
    else:
        (x1, f1), (x2, f2) = known_points
        for x in (x1, x2):
            if not grid[0] <= x <= grid[-1]:
                raise InvalidValueError(
                    f"The 'known_points' parameter of {owner} must lie within the input's "
                    f"range [{grid[0]:.6g}, {grid[-1]:.6g}]. Got x = {x} instead."
                )
        s1, s2 = np.interp([x1, x2], grid, shape)
        if s1 == s2:
            raise InvalidValueError(
                f"The 'known_points' parameter of {owner} must name points where the "
                f"estimate differs. Got equal estimates at x1 = {x1} and x2 = {x2} instead."
            )
        d1, alpha = two_point_normalisation(float(s1), float(s2), f1, f2)
        phi = (shape - alpha) / d1
        impulse = lags * d1
    arma = arma_from_impulse_response(impulse, order=order, max_order=max_order)
    offset = mean_y - arma.model.dc_gain * float(phi @ w)
    return Solution(lags, shape, grid, w, impulse, phi, arma, offset, svals)
