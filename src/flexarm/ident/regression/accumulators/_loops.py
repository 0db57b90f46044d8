"""Compiled loops shared by the accumulators (Numba, ``cache=True``).

Every weight is ``scale_i * prod_j k((x_j - X_ij) / h_ij)`` computed with the
floating-point operations of :func:`flexarm.ident.regression.kernels.kernel_weight` (or
its scalar ``d = 1`` specialisation), and every sum runs over the samples in
arrival order, one addition per sample: that is what makes the modes agree
bit for bit (see :mod:`flexarm.ident.regression.accumulators`).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ...._types import F64, I64
from ..kernels import kernel_weight

__all__ = [
    "GAUSS_ZERO",
    "LOCATE_STEPS",
    "accumulate_rows",
    "add_totals",
    "band_update_1d",
    "exact_predict",
    "exact_sums_1d",
    "grid_update",
    "grid_update_1d",
    "locate",
    "ratio",
    "sample_bandwidths",
    "search_table",
]


#: ``exp(-u**2 / 2) == 0.0`` exactly in float64 for ``|u| > 38.61`` (``u**2/2 > 745.2``).
GAUSS_ZERO = 38.61


@nb.njit(cache=True, nogil=True)
def sample_bandwidths(
    bw: F64, decay: float, start: int, n: int, recursive: bool
) -> tuple[F64, F64]:  # pragma: no cover - compiled
    """``h[k] = bw * i**(-decay)`` with ``i = start + k + 1``; scale ``prod(h)**-1`` or 1.

    ``decay = 0`` takes ``i**(-0.0) = 1`` without calling ``pow`` (which returns
    exactly 1 for a zero exponent).
    """
    d = bw.shape[0]
    h = np.empty((n, d))
    scale = np.ones(n)
    fixed = decay == 0.0
    for k in range(n):
        f = 1.0 if fixed else float(start + k + 1) ** (-decay)
        p = 1.0
        for j in range(d):
            h[k, j] = bw[j] * f
            p *= h[k, j]
        if recursive:
            scale[k] = 1.0 / p
    return h, scale


#: Linear steps from a table's guess before :func:`locate` falls back to a binary search.
LOCATE_STEPS = 8


@nb.njit(cache=True, nogil=True)
def search_table(gs: F64) -> tuple[F64, I64]:  # pragma: no cover - compiled
    """Guesses for :func:`locate` on the sorted points ``gs``: ``2 g`` buckets over their span.

    Returns ``floats = [g0, inv]`` (the first point, buckets per unit of the
    points) and ``table[b] = #{gs < g0 + b / inv}``, ``b = 0 .. 2 g``. No
    buckets (``inv = 0``) when the span is 0 or too small for them.
    """
    g = gs.shape[0]
    if g == 0:
        return np.zeros(2), np.zeros(1, np.int64)
    span = gs[g - 1] - gs[0]
    nb_ = 2 * g
    inv = nb_ / span if span > 0.0 else 0.0
    if not (0.0 < inv < 1e300):
        inv = 0.0
        nb_ = 0
    table = np.empty(nb_ + 1, np.int64)
    for b in range(nb_ + 1):
        table[b] = np.searchsorted(gs, gs[0] + b / inv if b > 0 else gs[0], side="left")
    floats = np.array([gs[0], inv])
    return floats, table


@nb.njit(cache=True, nogil=True, inline="always")
def locate(gs: F64, v: float, right: bool, floats: F64, table: I64) -> int:  # pragma: no cover
    """``np.searchsorted(gs, v, side)`` (``side = "right"`` if ``right``), exactly.

    Starts from the bucket table of :func:`search_table` and walks at most
    :data:`LOCATE_STEPS` points each way; beyond that (or without a table), a
    binary search. The walk stops only where the answer's defining inequalities
    hold, so the result is ``searchsorted``'s whatever the guess.
    """
    g = gs.shape[0]
    nb_ = table.shape[0] - 1
    f = (v - floats[0]) * floats[1]
    if not (f > 0.0):
        k = 0
    elif f >= nb_:
        k = table[nb_]
    else:
        k = table[int(f)]
    for _ in range(LOCATE_STEPS):
        if k < g and (gs[k] <= v if right else gs[k] < v):
            k += 1
        elif k > 0 and (gs[k - 1] > v if right else gs[k - 1] >= v):
            k -= 1
        else:
            return k
    if right:
        return int(np.searchsorted(gs, v, side="right"))
    return int(np.searchsorted(gs, v, side="left"))


@nb.njit(cache=True, nogil=True)
def grid_update_1d(
    code: int, gs: F64, x: F64, y: F64, h: F64, scale: F64, num: F64, den: F64, radius: float
) -> None:  # pragma: no cover - compiled
    """``d = 1``: ``gs`` is the sorted grid and ``num``/``den`` follow its order.

    Each sample visits only the grid points in its window (``|u| <= 1``, or
    ``38.61`` for the Gaussian, where its float64 value becomes exactly 0; the
    caller passes this ``radius``, smaller in binned mode), found by binary
    search (:func:`locate`; padded, the kernel itself decides the edge). The weight is
    ``scale * k(u)``, the same floating-point operations as ``kernel_weight``
    (adding a zero weight, which that path skips, changes no sum).
    """
    floats, table = search_table(gs)
    for i in range(x.shape[0]):
        xi = x[i]
        hi = h[i]
        si = scale[i]
        yi = y[i]
        r = radius * hi * (1.0 + 1e-9) + 1e-12 * abs(xi)
        lo = locate(gs, xi - r, False, floats, table)
        up = locate(gs, xi + r, True, floats, table)
        if code == 0:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * math.exp(-0.5 * u * u)
                num[k] += w * yi
                den[k] += w
        elif code == 1:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * (0.75 * (1.0 - u * u)) if abs(u) <= 1.0 else 0.0
                num[k] += w * yi
                den[k] += w
        elif code == 2:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * 0.5 if abs(u) <= 1.0 else 0.0
                num[k] += w * yi
                den[k] += w
        else:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * (1.0 - abs(u)) if abs(u) <= 1.0 else 0.0
                num[k] += w * yi
                den[k] += w


@nb.njit(cache=True, nogil=True)
def grid_update(
    code: int, grid: F64, X: F64, y: F64, h: F64, scale: F64, num: F64, den: F64
) -> None:  # pragma: no cover - compiled
    """Add samples to the running sums at every grid point, in sample order (any ``d``)."""
    g = grid.shape[0]
    for i in range(X.shape[0]):
        xi = X[i]
        hi = h[i]
        for j in range(g):
            w = kernel_weight(code, grid[j], xi, hi, scale[i])
            if w != 0.0:
                num[j] += w * y[i]
                den[j] += w


@nb.njit(cache=True, nogil=True)
def exact_predict(
    code: int, Q: F64, X: F64, y: F64, h: F64, scale: F64, block: int
) -> F64:  # pragma: no cover - compiled
    """Eq. 14 at the rows of ``Q`` from the stored samples (NaN where no weight).

    Sums in the blocked order of :mod:`~flexarm.ident.regression.accumulators.blocks`:
    per block from 0 in sample order, complete blocks added in order, the open
    block's partial last — as grid mode does, so the two agree bit for bit.
    """
    out = np.empty(Q.shape[0])
    n = X.shape[0]
    for q in range(Q.shape[0]):
        num = 0.0
        den = 0.0
        for a in range(0, n, block):  # each block's partial sums, added in order
            pn = 0.0
            pd = 0.0
            for i in range(a, min(n, a + block)):
                w = kernel_weight(code, Q[q], X[i], h[i], scale[i])
                if w != 0.0:
                    pn += w * y[i]
                    pd += w
            num += pn
            den += pd
        out[q] = num / den if den != 0.0 else np.nan
    return out


@nb.njit(cache=True, nogil=True)
def exact_sums_1d(
    code: int, qs: F64, x: F64, y: F64, h: F64, scale: F64, block: int, radius: float
) -> tuple[F64, F64]:  # pragma: no cover - compiled
    """``d = 1``: the sums of :func:`exact_predict` at the sorted points ``qs``, windowed.

    Each block's partial sums are accumulated sample by sample onto the points
    of each sample's window (:func:`grid_update_1d`, ``radius`` as there), then
    added in block order. Every point receives the same weights, computed by
    the same operations and added in the same order as :func:`exact_predict`
    adds them (the zero weights it skips change no sum), so the sums are the
    same bit for bit; the work is the window's points, not every point.
    """
    g = qs.shape[0]
    n = x.shape[0]
    num = np.zeros(g)
    den = np.zeros(g)
    pn = np.empty(g)
    pd = np.empty(g)
    for a in range(0, n, block):
        b = min(n, a + block)
        pn[:] = 0.0
        pd[:] = 0.0
        grid_update_1d(code, qs, x[a:b], y[a:b], h[a:b], scale[a:b], pn, pd, radius)
        for k in range(g):
            num[k] += pn[k]
            den[k] += pd[k]
    return num, den


@nb.njit(cache=True, nogil=True)
def band_update_1d(
    gs: F64, x: F64, y: F64, h: F64, scale: F64, num: F64, den: F64, inner: float
) -> None:  # pragma: no cover - compiled
    """The Gaussian terms of :func:`grid_update_1d` with ``|u| >= inner`` only.

    Each sample adds, at the grid points ``inner h_i`` or farther from it (and
    within the Gaussian's window, found exactly as :func:`grid_update_1d`
    finds it), the same weight with the same operations. At a grid point with
    no sample within ``inner h``, these sums are therefore the direct sums bit
    for bit (series mode's fallback far from the data).
    """
    g0 = gs[0]
    g1 = gs[gs.shape[0] - 1]
    floats, table = search_table(gs)
    for i in range(x.shape[0]):
        xi = x[i]
        hi = h[i]
        if xi - inner * hi < g0 and g1 < xi + inner * hi:
            continue  # the whole grid is nearer than inner h: no band point
        si = scale[i]
        yi = y[i]
        r = GAUSS_ZERO * hi * (1.0 + 1e-9) + 1e-12 * abs(xi)
        lo = locate(gs, xi - r, False, floats, table)
        up = locate(gs, xi + r, True, floats, table)
        mid_lo = locate(gs, xi - inner * hi, True, floats, table)
        mid_up = locate(gs, xi + inner * hi, False, floats, table)
        for k in range(lo, min(up, mid_lo)):
            u = (gs[k] - xi) / hi
            w = si * math.exp(-0.5 * u * u)
            num[k] += w * yi
            den[k] += w
        for k in range(max(lo, mid_up, mid_lo), up):
            u = (gs[k] - xi) / hi
            w = si * math.exp(-0.5 * u * u)
            num[k] += w * yi
            den[k] += w


@nb.njit(cache=True, nogil=True)
def accumulate_rows(W: F64, y: F64, num: F64, den: F64) -> None:  # pragma: no cover
    """``num += sum_i W[i] y[i]``, ``den += sum_i W[i]`` row by row (callable kernels)."""
    for i in range(W.shape[0]):
        for j in range(W.shape[1]):
            w = W[i, j]
            if w != 0.0:
                num[j] += w * y[i]
                den[j] += w


@nb.njit(cache=True, nogil=True)
def add_totals(scale: F64, y: F64, totals: F64) -> None:  # pragma: no cover - compiled
    """``totals += (sum scale_i, sum scale_i |y_i|)``, one sample at a time, in order."""
    for i in range(y.shape[0]):
        totals[0] += scale[i]
        totals[1] += scale[i] * abs(y[i])


@nb.njit(cache=True, nogil=True)
def ratio(num: F64, den: F64) -> F64:  # pragma: no cover - compiled
    """``num / den`` elementwise, NaN where ``den == 0``."""
    out = np.empty(num.shape[0])
    for j in range(num.shape[0]):
        out[j] = num[j] / den[j] if den[j] != 0.0 else np.nan
    return out
