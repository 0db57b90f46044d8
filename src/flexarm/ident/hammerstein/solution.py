"""What either path of a Hammerstein identification produces: :class:`Solution`.

The white-input path (:mod:`~flexarm.ident.hammerstein.white`) and the
correlated-input path (:mod:`~flexarm.ident.hammerstein.correlated`) describe
the identified model in the same terms — the nonlinearity on a grid, the
impulse response, the ARMA model fitted to it (:class:`ARMAFit`) and the
output offset — normalised the same way: by two points where the
nonlinearity is known (the paper's two-point normalisation,
:func:`two_point_normalisation`), or else with the impulse response's entry
of largest magnitude ``+1``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..._types import F64
from ..._validation import check_real
from ...errors import InvalidValueError
from .systems import ARMA

__all__ = [
    "ARMAFit",
    "KnownPoints",
    "Solution",
    "check_known_points",
    "two_point_normalisation",
]

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
class ARMAFit:
    """An ARMA model fitted to an impulse response, with the order selection record.

    Attributes
    ----------
    model : ARMA
        The selected model.
    order : int
        Its order ``l`` (``ARMA(l, l)``).
    criterion : dict of int to float
        Information criterion of every order tried.
    rss : dict of int to float
        Residual sum of squares of the impulse response for every order tried.
    """

    model: ARMA
    order: int
    criterion: dict[int, float] = field(default_factory=dict)
    rss: dict[int, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Solution:
    """The identified model, as either path gives it.

    The white path derives it from the lag regressions
    (:func:`~flexarm.ident.hammerstein.white.correlation.solve`), the correlated path
    from the fitted ARX-Hammerstein structure
    (:func:`~flexarm.ident.hammerstein.correlated.solve.solve_correlated`).

    Attributes
    ----------
    lags : ndarray, shape (L,)
        ``lambda-tilde``, the unnormalised impulse response.
    shape : ndarray, shape (g,)
        The unnormalised nonlinearity ``psi`` on ``grid``.
    grid : ndarray, shape (g,)
        Where ``phi`` is estimated (units of the input): the grid points every lag
        regression reached, or the knots.
    weights : ndarray, shape (g,)
        Share of the inputs at each point of ``grid`` (kernel density weights, or the
        hat functions' shares; sum 1).
    impulse : ndarray, shape (L,)
        The normalised impulse response.
    nonlinearity : ndarray, shape (g,)
        The normalised ``phi`` on ``grid`` (units of ``W``).
    arma : ARMAFit
        The linear part fitted to ``impulse``.
    offset : float
        Output offset of the free-run prediction (units of the output).
    singular_values : ndarray
        Of the rank-one array: the density-weighted lag regressions, or the separated
        ``b c^T`` (rank one if Hammerstein).
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
