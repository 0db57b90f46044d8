"""The bare compiled kernels of the fuzzy evaluation, and the packed system they read.

The kernels check nothing: :mod:`flexarm.fuzzy.compiled` holds their checked public
faces (``evaluate`` calls :func:`evaluate_kernel` once its arguments have passed),
and flexarm's own compiled code (the controllers' laws) calls these kernels directly.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CompiledFuzzySystem",
    "evaluate_into_kernel",
    "evaluate_kernel",
    "evaluate_many_kernel",
    "unpack_system_kernel",
    "workspace_size_kernel",
]

FloatArray = NDArray[np.float64]


class CompiledFuzzySystem(NamedTuple):
    """A :class:`~flexarm.fuzzy.system.FuzzySystem` as plain arrays for the compiled
    evaluation (:func:`~flexarm.fuzzy.compiled.evaluate`)."""

    term_type: NDArray[np.int64]  # (T,) 0 trapezoid (a, b, c, d), 1 Gaussian (mean, sigma)
    term_par: FloatArray  # (T, 4)
    term_input: NDArray[np.int64]  # (T,) input index of each term
    input_bounds: FloatArray  # (n_in, 2) input universes
    rule_ante: NDArray[np.int64]  # (R, n_in) global term index, -1 for "don't care"
    rule_cons: NDArray[np.int64]  # (R,) output term index
    out_par: FloatArray  # (K, 4) output trapezoids (a, b, c, d)
    ops: NDArray[np.int64]  # (3,) AND (0 min, 1 product), implication, aggregation (0 max)
    out_range: FloatArray  # (3,) lo, hi, default


# ------------------------------------------------------------ compiled kernels


@nb.njit(cache=True, nogil=True)
def _trap1(a: float, b: float, c: float, d: float, x: float) -> float:
    if x >= b and x <= c:
        return 1.0
    if x <= a or x >= d:
        return 0.0
    if x < b:
        return (x - a) / (b - a)
    return (d - x) / (d - c)


@nb.njit(cache=True, nogil=True)
def _imp1(sp: Any, sw: Any, i: int, imp: int, x: float) -> float:
    mu = _trap1(sp[i, 0], sp[i, 1], sp[i, 2], sp[i, 3], x)
    v: float = min(mu, sw[i]) if imp == 0 else mu * sw[i]
    return v


@nb.njit(cache=True, nogil=True)
def _linear_aggregate(left: Any, right: Any, m: int, agg: int, u: float) -> float:
    """Max (agg 0) or bounded sum (agg 1) of ``m`` linear functions at ``u`` in [0, 1]."""
    acc = 0.0
    for i in range(m):
        v = left[i] + u * (right[i] - left[i])
        if agg == 0:
            acc = max(acc, v)
        else:
            acc += v
    return acc if agg == 0 else min(acc, 1.0)


@nb.njit(cache=True, nogil=True)
def _insertion_sort(v: Any, start: int, stop: int) -> None:
    """Sort ``v[:stop]`` in place, given ``v[:start]`` already sorted."""
    for i in range(max(start, 1), stop):
        key = v[i]
        k = i - 1
        while k >= 0 and v[k] > key:
            v[k + 1] = v[k]
            k -= 1
        v[k + 1] = key


@nb.njit(cache=True, nogil=True)
def workspace_size_kernel(system: CompiledFuzzySystem) -> int:
    """Length of the scratch buffer :func:`evaluate_into_kernel` needs for ``system``."""
    n_terms = system.term_type.shape[0]
    n_rules = system.rule_ante.shape[0]
    n_out = system.out_par.shape[0]
    cap = n_rules if system.ops[2] == 1 else n_out
    n1 = 2 + 6 * cap  # breakpoints of the implied sets
    n_cross = cap * (cap - 1) // 2 if system.ops[2] == 0 else 1  # crossings on one piece
    return int(n_terms + 7 * cap + n1 + n_cross + 2)


@nb.njit(cache=True, nogil=True)
def evaluate_kernel(system: CompiledFuzzySystem, x: FloatArray) -> float:
    """Compiled centroid output of a packed system at one input vector.

    Parameters
    ----------
    system : CompiledFuzzySystem
        From :meth:`FuzzySystem.compiled`.
    x : ndarray, shape (n_in,)
        The inputs, each in its variable's unit.

    Returns
    -------
    float
        Equal (to rounding) to :meth:`FuzzySystem.__call__` at ``x``; the
        system's default when no rule fires, NaN for non-finite inputs.
        Allocates its scratch; inside a loop prefer :func:`evaluate_into_kernel`.
    """
    return evaluate_into_kernel(system, x, np.empty(workspace_size_kernel(system)))


@nb.njit(cache=True, nogil=True)
def evaluate_into_kernel(system: CompiledFuzzySystem, x: FloatArray, buf: FloatArray) -> float:
    """:func:`evaluate_kernel` with caller-owned scratch ``buf`` of length
    :func:`workspace_size_kernel` (allocation-free: what a simulation loop calls)."""
    and_op = system.ops[0]
    imp = system.ops[1]
    agg = system.ops[2]
    lo = system.out_range[0]
    hi = system.out_range[1]
    default: float = system.out_range[2]
    n_in = system.rule_ante.shape[1]
    for j in range(n_in):
        if not np.isfinite(x[j]):
            return np.nan
    n_terms = system.term_type.shape[0]
    n_rules = system.rule_ante.shape[0]
    n_out = system.out_par.shape[0]
    cap = n_rules if agg == 1 else n_out
    # One workspace: input memberships, implied sets (params, levels), breakpoints.
    mu_in = buf[:n_terms]
    sp = buf[n_terms : n_terms + 4 * cap].reshape((cap, 4))
    sw = buf[n_terms + 4 * cap : n_terms + 5 * cap]
    v1 = buf[n_terms + 5 * cap : n_terms + 6 * cap]
    v2 = buf[n_terms + 6 * cap : n_terms + 7 * cap]
    pts = buf[n_terms + 7 * cap :]
    for t in range(n_terms):
        j = system.term_input[t]
        xj = min(max(x[j], system.input_bounds[j, 0]), system.input_bounds[j, 1])
        pa = system.term_par[t]
        if system.term_type[t] == 0:
            mu_in[t] = _trap1(pa[0], pa[1], pa[2], pa[3], xj)
        else:
            z = (xj - pa[0]) / pa[1]
            mu_in[t] = math.exp(-0.5 * z * z)
    if agg == 0:
        for k in range(n_out):
            sw[k] = 0.0
    m = 0
    for r in range(n_rules):
        s = 1.0
        for j in range(n_in):
            t = system.rule_ante[r, j]
            if t >= 0:
                s = min(s, mu_in[t]) if and_op == 0 else s * mu_in[t]
        if agg == 0:
            k = system.rule_cons[r]
            sw[k] = max(sw[k], s)
        elif s > 0.0:
            sp[m, :] = system.out_par[system.rule_cons[r]]
            sw[m] = s
            m += 1
    if agg == 0:
        for k in range(n_out):
            if sw[k] > 0.0:
                sp[m, :] = system.out_par[k]
                sw[m] = sw[k]
                m += 1
    if m == 0:
        return default
    # Breakpoints of the implied sets.
    pts[0] = lo
    pts[1] = hi
    n = 2
    for i in range(m):
        for q in range(4):
            v = sp[i, q]
            if q > 0 and v == sp[i, q - 1]:
                continue
            if np.isfinite(v) and v > lo and v < hi:
                pts[n] = v
                n += 1
        if imp == 0 and sw[i] < 1.0:
            a, b, c, d = sp[i, 0], sp[i, 1], sp[i, 2], sp[i, 3]
            if a < b and np.isfinite(a):
                pts[n] = min(max(a + sw[i] * (b - a), lo), hi)
                n += 1
            if c < d and np.isfinite(d):
                pts[n] = min(max(d - sw[i] * (d - c), lo), hi)
                n += 1
    _insertion_sort(pts, 0, n)
    # On each piece between breakpoints every implied set is linear, so the
    # aggregate is the max (or the bounded sum) of linear functions: linear
    # between the crossings of any two of them (max) or of the sum with 1
    # (bounded sum). Integrate it exactly, piece by piece, from the end values.
    us = pts[n:]
    area = 0.0
    moment = 0.0
    for s in range(n - 1):
        p0 = pts[s]
        h = pts[s + 1] - p0
        if h <= 0.0:
            continue
        x1 = p0 + h / 3.0
        x2 = p0 + 2.0 * h / 3.0
        for i in range(m):  # end values of set i on this piece (extrapolated from thirds)
            f1 = _imp1(sp, sw, i, imp, x1)
            f2 = _imp1(sp, sw, i, imp, x2)
            v1[i] = 2.0 * f1 - f2
            v2[i] = 2.0 * f2 - f1
        us[0] = 0.0
        k_u = 1
        if agg == 0:
            for i in range(m):
                for k in range(i + 1, m):
                    dl = v1[i] - v1[k]
                    dr = v2[i] - v2[k]
                    if dl * dr < 0.0:
                        us[k_u] = dl / (dl - dr)
                        k_u += 1
        else:
            sl = -1.0
            sr = -1.0
            for i in range(m):
                sl += v1[i]
                sr += v2[i]
            if sl * sr < 0.0:
                us[k_u] = sl / (sl - sr)
                k_u += 1
        us[k_u] = 1.0
        k_u += 1
        _insertion_sort(us, 1, k_u - 1)
        f_prev = _linear_aggregate(v1, v2, m, agg, 0.0)
        for q in range(1, k_u):
            u0 = us[q - 1]
            u1 = us[q]
            f_next = _linear_aggregate(v1, v2, m, agg, u1)
            if u1 > u0:
                a = p0 + h * u0
                b = p0 + h * u1
                w = b - a
                ml = max(f_prev, 0.0)
                mr = max(f_next, 0.0)
                area += w * (ml + mr) / 2.0
                moment += w / 6.0 * (a * (2.0 * ml + mr) + b * (ml + 2.0 * mr))
            f_prev = f_next
    if not area > 0.0:
        return default
    return moment / area


@nb.njit(cache=True, nogil=True)
def evaluate_many_kernel(system: CompiledFuzzySystem, x: FloatArray) -> FloatArray:
    """:func:`evaluate_kernel` on each row of ``x`` (n, n_in); returns (n,)."""
    out = np.empty(x.shape[0])
    buf = np.empty(workspace_size_kernel(system))
    for i in range(x.shape[0]):
        out[i] = evaluate_into_kernel(system, x[i], buf)
    return out


@nb.njit(cache=True, nogil=True)
def unpack_system_kernel(
    p: FloatArray, o: int
) -> CompiledFuzzySystem:  # pragma: no cover - compiled
    """Views of ``p[o:]`` as a :class:`CompiledFuzzySystem` (no copy, no allocation)."""
    sizes = p[o : o + 4].view(np.int64)
    nt, nr, ni, nk = sizes[0], sizes[1], sizes[2], sizes[3]
    o += 4
    term_type = p[o : o + nt].view(np.int64)
    o += nt
    term_par = p[o : o + 4 * nt].reshape((nt, 4))
    o += 4 * nt
    term_input = p[o : o + nt].view(np.int64)
    o += nt
    input_bounds = p[o : o + 2 * ni].reshape((ni, 2))
    o += 2 * ni
    rule_ante = p[o : o + nr * ni].view(np.int64).reshape((nr, ni))
    o += nr * ni
    rule_cons = p[o : o + nr].view(np.int64)
    o += nr
    out_par = p[o : o + 4 * nk].reshape((nk, 4))
    o += 4 * nk
    ops = p[o : o + 3].view(np.int64)
    o += 3
    out_range = p[o : o + 3]
    return CompiledFuzzySystem(
        term_type=term_type,
        term_par=term_par,
        term_input=term_input,
        input_bounds=input_bounds,
        rule_ante=rule_ante,
        rule_cons=rule_cons,
        out_par=out_par,
        ops=ops,
        out_range=out_range,
    )
