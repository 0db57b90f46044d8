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

from .._validation import check_array, check_option

__all__ = [
    "KERNELS",
    "KernelFunction",
    "evaluate_kernel",
    "kernel_code",
    "kernel_profile",
    "kernel_weight",
    "support_radius",
]

F64 = NDArray[np.float64]

#: Names of the built-in kernels, in the order of their compiled codes.
KERNELS: tuple[str, ...] = ("gaussian", "epanechnikov", "uniform", "triangular")

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
        raise ValueError(
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
