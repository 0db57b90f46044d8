"""The compiled (Numba) evaluation of a packed fuzzy system: the simulation loop's path.

Each public function checks its arguments when called from Python (a short
scratch buffer would be written past its end) and calls a private compiled
kernel; inside compiled code (a controller's loop) the same name is the kernel
itself.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .._compile import compiled_as
from ..errors import InvalidTypeError, InvalidValueError

__all__ = [
    "CompiledFuzzySystem",
    "evaluate",
    "evaluate_into",
    "evaluate_many",
    "pack_system",
    "unpack_system",
    "workspace_size",
]

FloatArray = NDArray[np.float64]


class CompiledFuzzySystem(NamedTuple):
    """A :class:`FuzzySystem` as plain arrays for :func:`evaluate`."""

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
def _workspace_size(system: CompiledFuzzySystem) -> int:
    """Length of the scratch buffer :func:`evaluate_into` needs for ``system``."""
    n_terms = system.term_type.shape[0]
    n_rules = system.rule_ante.shape[0]
    n_out = system.out_par.shape[0]
    cap = n_rules if system.ops[2] == 1 else n_out
    n1 = 2 + 6 * cap  # breakpoints of the implied sets
    n_cross = cap * (cap - 1) // 2 if system.ops[2] == 0 else 1  # crossings on one piece
    return int(n_terms + 7 * cap + n1 + n_cross + 2)


@nb.njit(cache=True, nogil=True)
def _evaluate(system: CompiledFuzzySystem, x: FloatArray) -> float:
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
        Allocates its scratch; inside a loop prefer :func:`evaluate_into`.
    """
    return _evaluate_into(system, x, np.empty(_workspace_size(system)))


@nb.njit(cache=True, nogil=True)
def _evaluate_into(system: CompiledFuzzySystem, x: FloatArray, buf: FloatArray) -> float:
    """:func:`evaluate` with caller-owned scratch ``buf`` of length
    :func:`workspace_size` (allocation-free: what a simulation loop calls)."""
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
def _evaluate_many(system: CompiledFuzzySystem, x: FloatArray) -> FloatArray:
    """:func:`evaluate` on each row of ``x`` (n, n_in); returns (n,)."""
    out = np.empty(x.shape[0])
    buf = np.empty(_workspace_size(system))
    for i in range(x.shape[0]):
        out[i] = _evaluate_into(system, x[i], buf)
    return out


def pack_system(c: CompiledFuzzySystem) -> FloatArray:
    """A compiled fuzzy system as one float vector (integer arrays bit-cast), to travel
    in a compiled controller's parameter vector; :func:`unpack_system` reads it back."""

    def ints(a: NDArray[np.int64]) -> FloatArray:
        return np.ascontiguousarray(a, dtype=np.int64).ravel().view(np.float64)

    sizes = np.array(
        [c.term_type.size, c.rule_ante.shape[0], c.rule_ante.shape[1], c.out_par.shape[0]],
        dtype=np.int64,
    )
    return np.concatenate(
        [
            ints(sizes),
            ints(c.term_type),
            c.term_par.ravel(),
            ints(c.term_input),
            c.input_bounds.ravel(),
            ints(c.rule_ante),
            ints(c.rule_cons),
            c.out_par.ravel(),
            ints(c.ops),
            c.out_range.ravel(),
        ]
    )


@nb.njit(cache=True, nogil=True)
def _unpack_system(p: FloatArray, o: int) -> CompiledFuzzySystem:  # pragma: no cover - compiled
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


# ------------------------------------------------------------------ checked public faces
def _check_system(system: object, owner: str) -> int:
    """The number of inputs of a consistent :class:`CompiledFuzzySystem`."""
    if not isinstance(system, CompiledFuzzySystem):
        raise InvalidTypeError(
            f"The 'system' parameter of {owner} must be a CompiledFuzzySystem "
            f"(FuzzySystem.compiled()). Got {type(system).__name__} instead."
        )
    arrays = {name: getattr(system, name) for name in CompiledFuzzySystem._fields}
    kinds = {"term_type": "i", "term_input": "i", "rule_ante": "i", "rule_cons": "i", "ops": "i"}
    for name, a in arrays.items():
        if not (isinstance(a, np.ndarray) and a.flags.c_contiguous):
            raise InvalidValueError(
                f"The 'system.{name}' parameter of {owner} must be a C-contiguous array."
            )
        want = np.int64 if kinds.get(name) == "i" else np.float64
        if a.dtype != want:
            raise InvalidValueError(
                f"The 'system.{name}' parameter of {owner} must be of dtype "
                f"{np.dtype(want).name}. Got {a.dtype} instead."
            )
    n_terms = arrays["term_type"].shape[0]
    n_in = arrays["input_bounds"].shape[0]
    n_rules = arrays["rule_ante"].shape[0]
    n_out = arrays["out_par"].shape[0]
    ok = (
        arrays["term_par"].shape == (n_terms, 4)
        and arrays["term_input"].shape == (n_terms,)
        and arrays["input_bounds"].shape == (n_in, 2)
        and arrays["rule_ante"].shape == (n_rules, n_in)
        and arrays["rule_cons"].shape == (n_rules,)
        and arrays["out_par"].shape == (n_out, 4)
        and arrays["ops"].shape == (3,)
        and arrays["out_range"].shape == (3,)
        and bool(np.all((arrays["term_input"] >= 0) & (arrays["term_input"] < n_in)))
        and bool(np.all((arrays["rule_ante"] >= -1) & (arrays["rule_ante"] < n_terms)))
        and bool(np.all((arrays["rule_cons"] >= 0) & (arrays["rule_cons"] < n_out)))
    )
    if not ok:
        raise InvalidValueError(
            f"The 'system' parameter of {owner} must be consistent (as FuzzySystem.compiled() "
            "builds it): its arrays' shapes and indices do not fit together."
        )
    return int(n_in)


def _check_inputs(x: object, n_in: int, owner: str, batch: bool) -> None:
    shape = f"(m, {n_in})" if batch else f"({n_in},)"
    if not (isinstance(x, np.ndarray) and x.dtype == np.float64 and x.flags.c_contiguous):
        raise InvalidValueError(
            f"The 'x' parameter of {owner} must be a C-contiguous float64 array of shape "
            f"{shape}. Got {type(x).__name__} instead."
        )
    if (x.ndim, x.shape[-1] if x.ndim else -1) != ((2 if batch else 1), n_in):
        raise InvalidValueError(
            f"The 'x' parameter of {owner} must be of shape {shape}. Got shape {x.shape} instead."
        )


def workspace_size(system: CompiledFuzzySystem) -> int:
    """Length of the scratch buffer :func:`evaluate_into` needs for ``system``."""
    _check_system(system, "workspace_size")
    return int(_workspace_size(system))


def evaluate(system: CompiledFuzzySystem, x: FloatArray) -> float:
    """Compiled centroid output of a packed system at one input vector ``x`` (shape
    (n_in,)); checked (``_evaluate``)."""
    n_in = _check_system(system, "evaluate")
    _check_inputs(x, n_in, "evaluate", batch=False)
    return float(_evaluate(system, x))


def evaluate_into(system: CompiledFuzzySystem, x: FloatArray, buf: FloatArray) -> float:
    """:func:`evaluate` with caller-owned scratch ``buf`` of at least
    :func:`workspace_size` entries; checked (``_evaluate_into``)."""
    owner = "evaluate_into"
    n_in = _check_system(system, owner)
    _check_inputs(x, n_in, owner, batch=False)
    need = int(_workspace_size(system))
    if not (
        isinstance(buf, np.ndarray)
        and buf.dtype == np.float64
        and buf.ndim == 1
        and buf.flags.c_contiguous
        and buf.flags.writeable
        and buf.shape[0] >= need
    ):
        raise InvalidValueError(
            f"The 'buf' parameter of {owner} must be a writable, C-contiguous float64 array "
            f"of at least {need} entries (workspace_size(system)). Got "
            f"{getattr(buf, 'shape', type(buf).__name__)} instead."
        )
    return float(_evaluate_into(system, x, buf))


def evaluate_many(system: CompiledFuzzySystem, x: FloatArray) -> FloatArray:
    """:func:`evaluate` on each row of ``x`` (shape (m, n_in)); returns (m,); checked."""
    n_in = _check_system(system, "evaluate_many")
    _check_inputs(x, n_in, "evaluate_many", batch=True)
    out: FloatArray = _evaluate_many(system, x)
    return out


def unpack_system(p: FloatArray, o: int) -> CompiledFuzzySystem:
    """Views of ``p[o:]`` (:func:`pack_system`'s vector) as a system; checked."""
    if not (isinstance(p, np.ndarray) and p.dtype == np.float64 and p.ndim == 1):
        raise InvalidValueError(
            "The 'p' parameter of unpack_system must be a float64 vector (pack_system)."
        )
    if not (int(o) >= 0 and int(o) + 4 <= p.shape[0]):
        raise InvalidValueError(
            f"The 'o' parameter of unpack_system must be in [0, {p.shape[0] - 4}]."
        )
    nt, nr, ni, nk = (int(v) for v in p[int(o) : int(o) + 4].view(np.int64))
    need = 4 + nt + 4 * nt + nt + 2 * ni + nr * ni + nr + 4 * nk + 3 + 3
    if min(nt, nr, ni, nk) < 0 or int(o) + need > p.shape[0]:
        raise InvalidValueError(
            "The 'p' parameter of unpack_system must hold a packed system at 'o'. Got a "
            "vector too short for the sizes it states instead."
        )
    system: CompiledFuzzySystem = _unpack_system(p, int(o))
    _check_system(system, "unpack_system")
    return system


@compiled_as(workspace_size)
def _workspace_size_compiled(system):  # type: ignore[no-untyped-def]
    return lambda system: _workspace_size(system)


@compiled_as(evaluate)
def _evaluate_compiled(system, x):  # type: ignore[no-untyped-def]
    return lambda system, x: _evaluate(system, x)


@compiled_as(evaluate_into)
def _evaluate_into_compiled(system, x, buf):  # type: ignore[no-untyped-def]
    return lambda system, x, buf: _evaluate_into(system, x, buf)


@compiled_as(evaluate_many)
def _evaluate_many_compiled(system, x):  # type: ignore[no-untyped-def]
    return lambda system, x: _evaluate_many(system, x)


@compiled_as(unpack_system)
def _unpack_system_compiled(p, o):  # type: ignore[no-untyped-def]
    return lambda p, o: _unpack_system(p, o)
