r"""Compiled loops of the ARX-Hammerstein regression (Numba).

Regression row ``n`` of the over-parameterised ARX-Hammerstein model
(:mod:`flexarm.ident.hammerstein.correlated.arx`) of order ``(p, q)`` with ``K`` knots is

.. math:: \phi_n = (y_{n-1}, \dots, y_{n-p},\;
          g_k(u_{n-j}),\ j = 0..q,\ k \ne r),

the hat functions ``g_k`` of the knots (:mod:`flexarm.ident.hammerstein.correlated.hatbasis`) at the
lagged inputs, without the reference knot ``r`` (the hats sum to one, so one
of them is redundant beside the centring). Column of ``y_{n-i}``: ``i - 1``;
column of ``g_k(u_{n-j})``: ``p + j (K - 1) + k'`` with ``k' = k - [k > r]``.
At most two hats are non-zero per lag, so a row has ``p + 2 (q + 1)``
non-zero entries and the sums below cost that number squared per row,
whatever ``K``. The rows are those of the ``segments`` ``[a, b)`` (an array of
shape ``(m, 2)``) whose lags stay inside the segment, from ``a + max(p, q)``
to ``b`` by ``stride``.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ...._types import F64, I64

__all__ = ["hammerstein_gram", "instrument_cross", "locate_sorted"]


@nb.njit(cache=True)
def _row(
    y: F64, seg: I64, pos: F64, p: int, q: int, k: int, ref: int, n: int, cols: I64, vals: F64
) -> int:  # pragma: no cover - compiled
    """Non-zero entries of row ``n`` into ``cols``/``vals``; returns their count."""
    m = 0
    for i in range(1, p + 1):
        cols[m] = i - 1
        vals[m] = y[n - i]
        m += 1
    for j in range(q + 1):
        s = seg[n - j]
        w = pos[n - j]
        base = p + j * (k - 1)
        if s != ref:
            cols[m] = base + (s if s < ref else s - 1)
            vals[m] = 1.0 - w
            m += 1
        if s + 1 != ref:
            cols[m] = base + (s + 1 if s + 1 < ref else s)
            vals[m] = w
            m += 1
    return m


@nb.njit(cache=True)
def hammerstein_gram(
    y: F64,
    seg: I64,
    pos: F64,
    p: int,
    q: int,
    k: int,
    ref: int,
    segments: I64,
    stride: int,
    gram: F64,
    sums: F64,
    cross: F64,
) -> tuple[int, float]:  # pragma: no cover - compiled
    """Add ``sum phi phi^T`` to ``gram`` (its upper triangle only: a row's columns
    come in increasing order), ``sum phi`` to ``sums``, ``sum phi y_n`` to ``cross``.

    Returns the number of rows and ``sum y_n`` over them.
    """
    cols = np.empty(p + 2 * (q + 1), np.int64)
    vals = np.empty(p + 2 * (q + 1))
    count = 0
    total = 0.0
    lag = max(p, q)
    for g in range(segments.shape[0]):
        for n in range(segments[g, 0] + lag, segments[g, 1], stride):
            m = _row(y, seg, pos, p, q, k, ref, n, cols, vals)
            target = y[n]
            for a in range(m):
                ca = cols[a]
                va = vals[a]
                sums[ca] += va
                cross[ca] += va * target
                for b in range(a, m):
                    gram[ca, cols[b]] += va * vals[b]
            count += 1
            total += target
    return count, total


@nb.njit(cache=True)
def instrument_cross(
    x: F64,
    y: F64,
    seg: I64,
    pos: F64,
    p: int,
    q: int,
    k: int,
    ref: int,
    segments: I64,
    stride: int,
    block: F64,
    sums: F64,
    cross: F64,
) -> None:  # pragma: no cover - compiled
    """The instruments' rows: ``sum x_{n-i} phi_n^T`` into ``block`` (``p`` rows),
    ``sum x_{n-i}`` into ``sums`` and ``sum x_{n-i} y_n`` into ``cross`` (``i = 1..p``)."""
    cols = np.empty(p + 2 * (q + 1), np.int64)
    vals = np.empty(p + 2 * (q + 1))
    lag = max(p, q)
    for g in range(segments.shape[0]):
        for n in range(segments[g, 0] + lag, segments[g, 1], stride):
            m = _row(y, seg, pos, p, q, k, ref, n, cols, vals)
            target = y[n]
            for i in range(1, p + 1):
                z = x[n - i]
                sums[i - 1] += z
                cross[i - 1] += z * target
                for b in range(m):
                    block[i - 1, cols[b]] += z * vals[b]


@nb.njit(cache=True)
def locate_sorted(u: F64, knots: F64, seg: I64, pos: F64) -> None:  # pragma: no cover - compiled
    """:func:`~flexarm.ident.hammerstein.correlated.hatbasis.locate` by bisection, one pass,
    into ``seg`` and ``pos``."""
    k = knots.shape[0]
    for n in range(u.shape[0]):
        x = u[n]
        lo, hi = 0, k - 2
        while lo < hi:  # the last segment i with knots[i] <= x (0 if x < knots[0])
            mid = (lo + hi + 1) // 2
            if knots[mid] <= x:
                lo = mid
            else:
                hi = mid - 1
        left = knots[lo]
        seg[n] = lo
        pos[n] = (x - left) / (knots[lo + 1] - left)
