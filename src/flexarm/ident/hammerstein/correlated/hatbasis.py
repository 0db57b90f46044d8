r"""Piecewise-linear functions on knots at the input's quantiles (the hat basis).

The correlated-input path of Hammerstein identification
(:mod:`flexarm.ident.hammerstein.correlated.arx`) represents the nonlinearity by its values
``c_k`` at knots ``t_0 < ... < t_{K-1}``:

.. math:: \varphi(x) = \sum_k c_k\, g_k(x),

with ``g_k`` the hat functions (linear B-splines): between ``t_i`` and
``t_{i+1}``, ``phi(x) = (1 - w) c_i + w c_{i+1}`` with ``w = (x - t_i) /
(t_{i+1} - t_i)``. Beyond the end knots the end segments continue (``w < 0``
or ``w > 1``), so two knots give a linear map and a linear map stays linear.
No polynomial form is assumed: dead zones, saturations and jumps are
followed to the knot spacing, and the number of knots is chosen from the data
(:mod:`flexarm.ident.hammerstein.correlated.selection`).

Knots sit at the quantiles ``k / (K - 1)`` of the inputs (ties merged): every
hat function then carries about ``n / (K - 1)`` samples, so no basis function
lives on a rarely visited input range — the failure of equispaced knots at
the edges of a Gaussian or a swept input.
"""

from __future__ import annotations

import numpy as np

from ...._types import F64, I64

__all__ = ["evaluate", "locate", "quantile_knots"]


def quantile_knots(u_sorted: F64, n_knots: int) -> F64:
    """Knots at the quantiles ``k / (n_knots - 1)`` of sorted inputs, ties merged.

    Parameters
    ----------
    u_sorted : ndarray, shape (n,)
        The inputs, sorted ascending (units of ``u``), ``n >= 1``.
    n_knots : int
        Knots wanted (>= 2); fewer come back when the inputs take fewer values.

    Returns
    -------
    ndarray, shape (K,)
        Strictly increasing knots (units of ``u``), from ``min u`` to ``max u``;
        ``K = 1`` only for a constant input.

    Examples
    --------
    >>> quantile_knots(np.arange(11.0), 3)
    array([ 0.,  5., 10.])
    """
    n = u_sorted.shape[0]
    pos = np.linspace(0.0, n - 1.0, n_knots)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, n - 1)
    frac = pos - lo
    t = u_sorted[lo] + frac * (u_sorted[hi] - u_sorted[lo])
    out: F64 = np.unique(t)
    return out


def locate(u: F64, knots: F64) -> tuple[I64, F64]:
    """Segment and position of each input: ``u`` lies at ``w`` along ``[t_i, t_{i+1}]``.

    Parameters
    ----------
    u : ndarray, shape (n,)
        Inputs (units of ``u``).
    knots : ndarray, shape (K,)
        Strictly increasing knots, ``K >= 2``.

    Returns
    -------
    segment : ndarray of int64, shape (n,)
        ``i`` in ``0 .. K - 2`` (the end segments for inputs beyond the knots).
    position : ndarray, shape (n,)
        ``w = (u - t_i) / (t_{i+1} - t_i)``; outside ``[0, 1]`` beyond the end knots.
    """
    from ._loops import locate_sorted

    seg = np.empty(u.shape[0], dtype=np.int64)
    pos = np.empty(u.shape[0])
    locate_sorted(np.ascontiguousarray(u, dtype=np.float64), knots, seg, pos)
    return seg, pos


def evaluate(segment: I64, position: F64, values: F64) -> F64:
    """The piecewise-linear function with knot values ``values`` at located inputs.

    Parameters
    ----------
    segment, position : ndarray, shape (n,)
        From :func:`locate`.
    values : ndarray, shape (K,)
        Values at the knots.

    Returns
    -------
    ndarray, shape (n,)
        ``(1 - w) c_i + w c_{i+1}`` (linear beyond the end knots).

    Examples
    --------
    >>> t = np.array([0.0, 1.0, 3.0])
    >>> evaluate(*locate(np.array([-1.0, 0.5, 2.0, 4.0]), t), np.array([0.0, 2.0, 2.0]))
    array([-2.,  1.,  2.,  2.])
    """
    out: F64 = values[segment] + position * (values[segment + 1] - values[segment])
    return out
