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
from numpy.typing import ArrayLike, NDArray

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

F64 = NDArray[np.float64]

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
    for i in range(x.shape[0]):
        f = (x[i] - origin) / w
        if not (f >= 0.0 and f < nk):  # outside the clusters (also keeps int() in range)
            continue
        k = int(f)
        b = (x[i] - (origin + (k + 0.5) * w)) / h
        e = scale * math.exp(-0.5 * b * b)
        ey = e * y[i]
        for j in range(p):
            md[k, j] += e
            mn[k, j] += ey
            e *= b
            ey *= b


@nb.njit(cache=True, nogil=True)
def gauss_series_eval(
    q: F64, origin: float, h: float, mn: F64, md: F64
) -> tuple[F64, F64, F64]:  # pragma: no cover - compiled
    """The sums ``N(x)``, ``D(x)`` at the points ``q`` from the moments (see above), scaled.

    Returns ``num``, ``den`` and ``shift`` with ``N = num exp(-shift)``,
    ``D = den exp(-shift)``: ``shift = t**2/2`` of the nearest non-empty
    cluster, so that far from the data the weights do not fall into the
    subnormal range (where direct summation loses its precision) before the
    ratio ``N / D = num / den`` is taken. ``den = 0`` exactly when no
    non-empty cluster lies within ``SERIES_REACH`` (no sample within 38.61 h).
    """
    w = SERIES_WIDTH * h
    nk = mn.shape[0]
    p = mn.shape[1]
    inv = np.empty(p)
    inv[0] = 1.0
    for j in range(1, p):
        inv[j] = inv[j - 1] / j
    num = np.zeros(q.shape[0])
    den = np.zeros(q.shape[0])
    shift = np.zeros(q.shape[0])
    for m in range(q.shape[0]):
        x = q[m]
        flo = max(0.0, min(float(nk), (x - SERIES_REACH * h - origin) / w))
        fhi = max(-1.0, min(nk - 1.0, (x + SERIES_REACH * h - origin) / w + 1.0))
        klo = int(flo)
        khi = int(fhi)
        s0 = np.inf
        for k in range(klo, khi + 1):
            if md[k, 0] != 0.0:
                t = (x - (origin + (k + 0.5) * w)) / h
                if abs(t) <= SERIES_REACH:
                    s0 = min(s0, 0.5 * t * t)
        if s0 == np.inf:
            continue
        shift[m] = s0
        sn = 0.0
        sd = 0.0
        for k in range(klo, khi + 1):
            if md[k, 0] == 0.0:
                continue
            t = (x - (origin + (k + 0.5) * w)) / h
            if abs(t) > SERIES_REACH:
                continue
            g = math.exp(s0 - 0.5 * t * t)
            if g == 0.0:
                continue
            an = mn[k, p - 1] * inv[p - 1]
            ad = md[k, p - 1] * inv[p - 1]
            for j in range(p - 2, -1, -1):
                an = an * t + mn[k, j] * inv[j]
                ad = ad * t + md[k, j] * inv[j]
            sn += g * an
            sd += g * ad
        num[m] = sn
        den[m] = sd
    return num, den, shift
