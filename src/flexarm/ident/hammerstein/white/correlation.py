"""The correlation approach: a Hammerstein system's parts from its lag regressions.

For every lag ``k = 0 .. L-1`` the lag regression ``m_k(x) = E[Y_{n+k} | X_n = x]``
of a white input is ``lambda_k phi(x) + c_k``, so the centred regressions form a
rank-one array. Given their grid-mode sums (:mod:`~flexarm.ident.hammerstein.white.lags`
keeps them), :func:`solve` computes the impulse response — the covariance with
an instrument (``"auto"``: the leading singular pair, which also serves an even
``phi`` and a delayed linear part; ``"regression"``: ``m_0``, the paper's;
``"input"``: ``x``) —, the shape of ``phi`` — their least-squares combination —,
normalised by two known points (the paper's ``d1``, ``alpha``) or else with the
impulse response's largest entry ``+1`` and ``phi`` of mean zero, and the ARMA
model of the impulse response
(:func:`~flexarm.ident.hammerstein.white.arma.arma_from_impulse_response`, order
by BIC).
"""

from __future__ import annotations

import numpy as np

from ...._types import F64
from ....errors import InvalidValueError
from ..solution import KnownPoints, Solution, two_point_normalisation
from .arma import arma_from_impulse_response

__all__ = ["solve"]


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
