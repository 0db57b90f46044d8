"""Smoothing kernels for the kernel regression estimators.

In ``d`` dimensions every named kernel is a **product kernel**,
``K(u) = k(u_1) k(u_2) ... k(u_d)`` with ``k`` the one-dimensional profile
below. The product form (rather than the radial ``k(|u|)``) is chosen because

* the Gaussian is naturally a product (``exp(-|u|^2/2)``), so all kernels
  behave alike;
* it matches a bandwidth given per input dimension (each coordinate is scaled
  by its own ``h``);
* the support of a compact kernel is the box ``|u_j| <= 1``, so the grid points
  a sample touches are found coordinate by coordinate (a binary search for
  ``d = 1`` on a sorted grid).

============== =================================== =========
name           profile ``k(u)``                    support
============== =================================== =========
gaussian       ``exp(-u**2 / 2)``                  all ``u``
epanechnikov   ``3/4 (1 - u**2)``                  ``|u|<=1``
uniform        ``1/2``                             ``|u|<=1``
triangular     ``1 - |u|``                         ``|u|<=1``
============== =================================== =========

Constant factors cancel in the ratio estimates (eq. 14 of the paper), so the
Gaussian is left unnormalised as the specification writes it. A user callable
``K(u)`` taking ``u`` of shape ``(m, d)`` and returning shape ``(m,)`` is also
accepted by the estimators; it is evaluated with NumPy, not compiled.

:func:`evaluate_kernel` is the readable NumPy reference; :func:`kernel_weight`
is the compiled scalar version used by the estimators' inner loops. The tests
hold the two together.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba as nb
import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64
from ..._validation import check_array, check_option
from ...errors import InvalidValueError
from ..options import KERNELS

__all__ = [
    "KERNELS",
    "SERIES_REACH",
    "SERIES_TERMS",
    "SERIES_TRUNCATION",
    "SERIES_WIDTH",
    "KernelFunction",
    "evaluate_kernel",
    "gauss_series_eval",
    "gauss_series_moments",
    "kernel_code",
    "kernel_profile",
    "kernel_weight",
    "support_radius",
]


#: A user kernel: ``u`` of shape ``(m, d)`` in, weights of shape ``(m,)`` out.
KernelFunction = Callable[[F64], ArrayLike]


def kernel_code(name: str, owner: str = "kernel_code") -> int:
    """Return the integer code of a named kernel (its index in :data:`KERNELS`)."""
    return KERNELS.index(check_option(name, "kernel", owner, KERNELS))


def support_radius(name: str) -> float:
    """Return ``r`` such that the profile vanishes for ``|u| > r`` (``inf`` for the Gaussian).

    >>> support_radius("epanechnikov"), support_radius("gaussian")
    (1.0, inf)
    """
    return math.inf if kernel_code(name, "support_radius") == 0 else 1.0


def _profile(code: int, u: F64) -> F64:
    a = np.abs(u)
    if code == 0:
        return np.exp(-0.5 * u * u)
    inside = a <= 1.0
    if code == 1:
        return np.where(inside, 0.75 * (1.0 - u * u), 0.0)
    if code == 2:
        return np.where(inside, 0.5, 0.0)
    return np.where(inside, 1.0 - a, 0.0)


def evaluate_kernel(name: str, u: ArrayLike) -> F64:
    """Evaluate a named product kernel with NumPy (the reference implementation).

    Parameters
    ----------
    name : str
        One of :data:`KERNELS`.
    u : array_like, shape (m, d) or (m,)
        Scaled offsets ``(x - X_i) / h_i`` (dimensionless); shape ``(m,)`` means ``d = 1``.

    Returns
    -------
    ndarray, shape (m,)
        ``K(u) = prod_j k(u_j)``.

    Examples
    --------
    >>> evaluate_kernel("triangular", [[0.5, 0.5], [2.0, 0.0]])
    array([0.25, 0.  ])
    """
    code = kernel_code(name, "evaluate_kernel")
    arr = check_array(u, "u", "evaluate_kernel")
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise InvalidValueError(
            "The 'u' parameter of evaluate_kernel must be of shape (m, d) or (m,). "
            f"Got shape {arr.shape} instead."
        )
    out: F64 = np.prod(_profile(code, arr), axis=1)
    return out


@nb.njit(cache=True)
def kernel_profile(code: int, u: float) -> float:  # pragma: no cover - compiled
    """Compiled one-dimensional profile ``k(u)`` of the kernel with code ``code``."""
    if code == 0:
        return math.exp(-0.5 * u * u)
    a = abs(u)
    if a > 1.0:
        return 0.0
    if code == 1:
        return 0.75 * (1.0 - u * u)
    if code == 2:
        return 0.5
    return 1.0 - a


@nb.njit(cache=True)
def kernel_weight(
    code: int, x: F64, xi: F64, hi: F64, scale: float
) -> float:  # pragma: no cover - compiled
    """Compiled ``scale * prod_j k((x_j - xi_j) / hi_j)``; stops at the first zero factor.

    ``x``, ``xi``, ``hi`` have shape ``(d,)``. Every estimator computes its
    weights through this one function, so exact and grid modes agree bit for bit.
    """
    w = scale
    for j in range(x.shape[0]):
        w *= kernel_profile(code, (x[j] - xi[j]) / hi[j])
        if w == 0.0:
            return 0.0
    return w


# --------------------------------------------------------------------------- Gaussian series

#: Terms kept of the Taylor series in :func:`gauss_series_moments` (see its docstring).
SERIES_TERMS = 28
#: Cluster width of the series, in units of ``h`` (so ``|b| <= 1/16``).
SERIES_WIDTH = 0.125
#: Bound on the *relative* truncation error of one Gaussian weight in the series:
#: ``exp(2 |t b|) |t b|**28 / 28!`` at ``|t| = SERIES_REACH``, ``|b| = 1/16``.
SERIES_TRUNCATION = 2.7e-17
#: A cluster centre farther than this many ``h`` from ``x`` is skipped: every sample
#: in it is beyond 38.61 h, where ``exp(-u**2/2)`` underflows to exactly 0 in float64.
SERIES_REACH = 38.61 + 0.0625


@nb.njit(cache=True, nogil=True)
def gauss_series_moments(
    x: F64, y: F64, scale: float, origin: float, h: float, mn: F64, md: F64
) -> None:  # pragma: no cover - compiled
    """Add samples to the cluster moments of the Gaussian series (one bandwidth ``h``).

    Clusters are ``w = h/8`` wide, centre ``c_k = origin + (k + 1/2) w``; with
    ``b = (X_i - c_k)/h`` (``|b| <= 1/16``) and ``t = (x - c_k)/h``,

    ``exp(-(x - X_i)**2 / (2 h**2)) = exp(-t**2/2) exp(-b**2/2) sum_j t**j b**j / j!``

    so ``sum_i Y_i K = sum_k exp(-t_k**2/2) sum_j t_k**j / j! mn[k, j]`` with
    ``mn[k, j] = sum_{i in k} s Y_i exp(-b_i**2/2) b_i**j`` (``md`` likewise
    without ``Y_i``). Truncating after ``p = SERIES_TERMS`` terms errs, relative
    to the weight itself, by at most ``exp(2 |t b|) |t b|**p / p!`` (Lagrange
    remainder of ``exp(t b)``, divided by ``exp(t b) >= exp(-|t b|)``): below
    :data:`SERIES_TRUNCATION` for every ``|t| <= SERIES_REACH`` and below
    ``1e-37`` within ``8 h``. The alternating terms lose at most a factor
    ``exp(2 |t b|) <= 130`` of relative precision to cancellation. So each
    weight is as accurate, relatively, as the directly computed
    ``exp(-u**2/2)``, to about ``1e-13`` at worst. Samples outside the clusters
    are skipped (the caller makes the clusters cover every sample with a
    nonzero weight at the points it will evaluate).
    """
    w = SERIES_WIDTH * h
    nk = mn.shape[0]
    p = mn.shape[1]
    # Four samples at a time, their power series interleaved (four independent chains of
    # products instead of one); each moment still receives its terms in sample order.
    ks = np.empty(4, np.int64)
    bs = np.empty(4)
    es = np.empty(4)
    eys = np.empty(4)
    i = 0
    while i < x.shape[0]:
        c = 0
        while c < 4 and i < x.shape[0]:
            f = (x[i] - origin) / w
            if f >= 0.0 and f < nk:  # inside the clusters (also keeps int() in range)
                k = int(f)
                b = (x[i] - (origin + (k + 0.5) * w)) / h
                e = scale * math.exp(-0.5 * b * b)
                ks[c], bs[c], es[c], eys[c] = k, b, e, e * y[i]
                c += 1
            i += 1
        if c == 4:
            k0, k1, k2, k3 = ks[0], ks[1], ks[2], ks[3]
            b0, b1, b2, b3 = bs[0], bs[1], bs[2], bs[3]
            e0, e1, e2, e3 = es[0], es[1], es[2], es[3]
            f0, f1, f2, f3 = eys[0], eys[1], eys[2], eys[3]
            for j in range(p):
                md[k0, j] += e0
                mn[k0, j] += f0
                md[k1, j] += e1
                mn[k1, j] += f1
                md[k2, j] += e2
                mn[k2, j] += f2
                md[k3, j] += e3
                mn[k3, j] += f3
                e0 *= b0
                f0 *= b0
                e1 *= b1
                f1 *= b1
                e2 *= b2
                f2 *= b2
                e3 *= b3
                f3 *= b3
            continue
        for t in range(c):  # the last few samples, one at a time
            k, b, e, ey = ks[t], bs[t], es[t], eys[t]
            for j in range(p):
                md[k, j] += e
                mn[k, j] += ey
                e *= b
                ey *= b


@nb.njit(cache=True, nogil=True)
def _horner(
    q: F64, ck: float, h: float, cn: F64, cd: F64, m0: int, m1: int, ts: F64, an: F64, ad: F64
) -> None:  # pragma: no cover - compiled
    """``t = (q[m] - ck) / h`` and the two series in ``t`` (coefficients ``cn``, ``cd``) by
    Horner's rule, for the points ``m0 .. m1 - 1`` at once, into ``ts``, ``an``, ``ad[:m1-m0]``
    (a loop over the points innermost, which the compiler vectorises)."""
    p = cn.shape[0]
    for r in range(m1 - m0):
        ts[r] = (q[m0 + r] - ck) / h
        an[r] = cn[p - 1]
        ad[r] = cd[p - 1]
    for j in range(p - 2, -1, -1):
        cj = cn[j]
        dj = cd[j]
        for r in range(m1 - m0):
            an[r] = an[r] * ts[r] + cj
            ad[r] = ad[r] * ts[r] + dj


@nb.njit(cache=True, nogil=True)
def gauss_series_eval(
    q: F64, origin: float, h: float, mn: F64, md: F64
) -> tuple[F64, F64, F64]:  # pragma: no cover - compiled
    """The sums ``N(x)``, ``D(x)`` at the sorted points ``q`` from the moments (see above), scaled.

    Returns ``num``, ``den`` and ``shift`` with ``N = num exp(-shift)``,
    ``D = den exp(-shift)``: ``shift = t**2/2`` of the nearest non-empty
    cluster, so that far from the data the weights do not fall into the
    subnormal range (where direct summation loses its precision) before the
    ratio ``N / D = num / den`` is taken. ``den = 0`` exactly when no
    non-empty cluster lies within ``SERIES_REACH`` (no sample within 38.61 h).

    ``q`` must be sorted (ascending): the loops run over the clusters, each over
    the run of points in its reach (Horner's rule for all of them at once); every
    point receives the clusters' terms in cluster order, so the result is that of
    the loop over the points, each over its clusters, bit for bit.
    """
    w = SERIES_WIDTH * h
    nk = mn.shape[0]
    p = mn.shape[1]
    g = q.shape[0]
    inv = np.empty(p)
    inv[0] = 1.0
    for j in range(1, p):
        inv[j] = inv[j - 1] / j
    klo = np.empty(g, np.int64)  # the clusters a point looks at: klo .. khi, both
    khi = np.empty(g, np.int64)  # nondecreasing in the point, as q is sorted
    for m in range(g):
        x = q[m]
        klo[m] = int(max(0.0, min(float(nk), (x - SERIES_REACH * h - origin) / w)))
        khi[m] = int(max(-1.0, min(nk - 1.0, (x + SERIES_REACH * h - origin) / w + 1.0)))
    first = np.empty(nk, np.int64)  # cluster k reaches the points first[k] .. stop[k] - 1
    stop = np.empty(nk, np.int64)
    m0 = m1 = 0
    for k in range(nk):
        while m1 < g and klo[m1] <= k:
            m1 += 1
        while m0 < m1 and khi[m0] < k:
            m0 += 1
        first[k], stop[k] = m0, m1
    s0 = np.full(g, np.inf)  # t**2/2 of each point's nearest non-empty cluster in reach
    for k in range(nk):
        m0, m1 = first[k], stop[k]
        if md[k, 0] == 0.0:
            continue
        ck = origin + (k + 0.5) * w
        for m in range(m0, m1):
            t = (q[m] - ck) / h
            if abs(t) <= SERIES_REACH:
                s0[m] = min(s0[m], 0.5 * t * t)
    num = np.zeros(g)
    den = np.zeros(g)
    cn = np.empty(p)
    cd = np.empty(p)
    ts = np.empty(g)
    an = np.empty(g)
    ad = np.empty(g)
    for k in range(nk):
        m0, m1 = first[k], stop[k]
        if md[k, 0] == 0.0 or m0 == m1:
            continue
        ck = origin + (k + 0.5) * w
        for j in range(p):
            cn[j] = mn[k, j] * inv[j]
            cd[j] = md[k, j] * inv[j]
        _horner(q, ck, h, cn, cd, m0, m1, ts, an, ad)
        for r in range(m1 - m0):
            t = ts[r]
            if abs(t) <= SERIES_REACH:
                gm = math.exp(s0[m0 + r] - 0.5 * t * t)
                if gm != 0.0:
                    num[m0 + r] += gm * an[r]
                    den[m0 + r] += gm * ad[r]
    shift = np.where(s0 == np.inf, 0.0, s0)
    return num, den, shift
