"""ARMA models from impulse responses: Prony's method, least-squares refinement, order by BIC.

The paper's linear subsystem is ARMA(l, l),
``Y_n = a1 Y_{n-1} + ... + al Y_{n-l} + b0 W_n + ... + bl W_{n-l}``
(:class:`~flexarm.ident.hammerstein.systems.ARMA`). :func:`arma_from_impulse_response`
fits it to an estimated impulse response ``lambda_0 .. lambda_{L-1}`` (as
:class:`~flexarm.ident.HammersteinIdentifier` produces), for each order
``l = 0 .. max_order``:

1. **Prony's start.** The AR part from ``h_k = a1 h_{k-1} + ... + al h_{k-l}``
   (``k > l``) by linear least squares; unstable roots reflected inside the
   unit circle (``r -> 0.999 / conj(r)``); the MA part from
   ``b_j = h_j - sum_i a_i h_{j-i}`` (``j <= l``).
2. **Refinement.** Nonlinear least squares on ``sum_k (h_k - h_k(a, b))**2``
   (Levenberg–Marquardt, SciPy), kept only if stable and better.
3. **Order.** The information criterion ``L ln(RSS / L) + penalty``, BIC
   ``(2 l + 1) ln L`` by default or AIC ``2 (2 l + 1)``, with ``RSS`` floored at
   ``1e-12 sum h**2``; ties go to the lower order.

SciPy is imported when a fit runs, not with this module.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...._types import F64
from ...._validation import check_array, check_int, check_option
from ....errors import InvalidValueError
from ...options import CRITERIA
from ..solution import ARMAFit
from ..systems import ARMA, spectral_radius

__all__ = ["arma_from_impulse_response"]


def _stabilise(a: F64) -> F64:
    """Reflect AR roots on or outside the unit circle to ``0.999 / conj(r)``."""
    if a.shape[0] == 0 or spectral_radius(a) < 1.0:
        return a
    roots = np.roots(np.r_[1.0, -a])
    big = np.abs(roots) >= 1.0
    roots[big] = 0.999 / np.conj(roots[big])
    out: F64 = -np.real(np.poly(roots))[1:]
    return out


def _impulse(a: F64, b: F64, n: int) -> F64:
    """The first ``n`` values of the impulse response of ``B(q) / A(q)`` (SciPy ``lfilter``)."""
    from scipy.signal import lfilter

    delta = np.zeros(n)
    delta[0] = 1.0
    out: F64 = np.asarray(lfilter(b, np.r_[1.0, -a], delta), dtype=np.float64)
    return out


def _fit_order(h: F64, order: int) -> tuple[F64, F64]:
    """ARMA(order, order) fitted to ``h`` (Prony start, nonlinear least-squares refinement)."""
    from scipy.optimize import least_squares

    L = h.shape[0]
    p = order
    if p == 0:
        return np.zeros(0), h[:1].copy()
    rows = np.array([h[k - p : k][::-1] for k in range(p + 1, L)])
    a = np.linalg.lstsq(rows, h[p + 1 : L], rcond=None)[0] if rows.size else np.zeros(p)
    a = _stabilise(np.asarray(a, dtype=np.float64))
    b = np.array([h[j] - sum(a[i - 1] * h[j - i] for i in range(1, j + 1)) for j in range(p + 1)])

    def resid(theta: F64) -> F64:
        return _impulse(theta[:p], theta[p:], L) - h

    try:
        sol = least_squares(resid, np.r_[a, b], method="lm", max_nfev=200 * (2 * p + 1))
        a2, b2 = sol.x[:p], sol.x[p:]
        if spectral_radius(a2) < 1.0 and np.sum(resid(sol.x) ** 2) <= np.sum(
            resid(np.r_[a, b]) ** 2
        ):
            a, b = a2, b2
    except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - keep the Prony start
        pass
    return np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)


def arma_from_impulse_response(
    h: ArrayLike, order: int | str = "bic", max_order: int = 4
) -> ARMAFit:
    """Fit the paper's ARMA(l, l) model to an impulse response ``h_0, …, h_{L-1}``.

    For each ``l`` the AR part comes from Prony's equations
    ``h_k = a1 h_{k-1} + ... + al h_{k-l}`` (``k > l``) by linear least squares,
    the MA part from ``b_j = h_j - sum_i a_i h_{j-i}`` (``j <= l``); both are
    then refined by nonlinear least squares on the impulse-response error
    (Levenberg–Marquardt), keeping the refinement only if it is stable and
    better. Unstable AR roots are reflected inside the unit circle.

    Parameters
    ----------
    h : array_like, shape (L,)
        Impulse response (``L >= 2 max_order + 2``).
    order : int or {"bic", "aic"}
        A fixed order ``l``, or the criterion that selects it:
        BIC ``L ln(RSS/L) + (2l+1) ln L`` or AIC ``L ln(RSS/L) + 2 (2l+1)``,
        with ``RSS`` floored at ``1e-12 sum h**2`` (ties go to the lower order).
    max_order : int
        Largest ``l`` tried by a criterion.

    Returns
    -------
    ARMAFit

    Examples
    --------
    >>> h = ARMA((0.5,), (1.0, 0.3)).impulse_response(30)
    >>> fit = arma_from_impulse_response(h)
    >>> fit.order, [round(v, 6) for v in fit.model.a + fit.model.b]
    (1, [0.5, 1.0, 0.3])
    """
    owner = "arma_from_impulse_response"
    ha = check_array(h, "h", owner, shape=(-1,))
    max_order = check_int(max_order, "max_order", owner, minimum=0)
    if isinstance(order, str):
        check_option(order, "order", owner, CRITERIA)
        orders = list(range(max_order + 1))
    else:
        orders = [check_int(order, "order", owner, minimum=0)]
    L = ha.shape[0]
    need = 2 * max(orders) + 2
    if need > L:
        raise InvalidValueError(
            f"The 'h' parameter of {owner} must hold >= {need} values for order "
            f"{max(orders)}. Got {L} instead."
        )
    if not np.any(ha != 0.0):
        raise InvalidValueError(
            f"The 'h' parameter of {owner} must not be all zero. Got zeros instead."
        )
    floor = 1e-12 * float(np.sum(ha**2))
    crit: dict[int, float] = {}
    rss: dict[int, float] = {}
    models: dict[int, ARMA] = {}
    for order_l in orders:
        a, b = _fit_order(ha, order_l)
        if not np.any(b != 0.0):
            continue
        r = float(np.sum((_impulse(a, b, L) - ha) ** 2))
        k = 2 * order_l + 1
        penalty = k * np.log(L) if order != "aic" else 2.0 * k
        crit[order_l] = float(L * np.log(max(r, floor) / L) + penalty)
        rss[order_l] = r
        models[order_l] = ARMA(tuple(a.tolist()), tuple(b.tolist()))
    best = min(crit, key=lambda o: (crit[o], o))
    return ARMAFit(models[best], best, crit, rss)
