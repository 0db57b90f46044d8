"""The compiled loop of ARMA prediction from data (Numba): free run and k steps ahead.

:func:`~flexarm.ident.hammerstein.prediction.predict_output` is its checked face.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..._types import F64

__all__ = ["arma_predict"]


@nb.njit(cache=True)
def arma_predict(
    a: F64, b: F64, w: F64, d: F64, first: int, steps: int, out: F64
) -> None:  # pragma: no cover - compiled
    """Predict ``d_n = sum_i a_i d_{n-i} + sum_j b_j w_{n-j}`` into ``out`` (zero before n = 0).

    ``out[:first] = d[:first]`` (the initial conditions). For ``n >= first``:
    with ``steps <= 0`` the free run (every ``d_{n-i}`` with ``n - i >= first``
    predicted); with ``steps = k >= 1`` the ``k``-step-ahead prediction
    ``d_{n | n-k}`` (measured ``d`` up to ``n - k``, predicted after).
    """
    n_total = w.shape[0]
    p = a.shape[0]
    nb_ = b.shape[0]
    for n in range(min(first, n_total)):
        out[n] = d[n]
    if steps <= 0:
        for n in range(first, n_total):
            acc = 0.0
            for i in range(1, min(p, n) + 1):
                acc += a[i - 1] * out[n - i]
            for j in range(nb_):
                if n - j >= 0:
                    acc += b[j] * w[n - j]
            out[n] = acc
        return
    tmp = np.empty(steps)
    for n in range(first, n_total):
        lo = max(first, n - steps + 1)
        for s in range(lo, n + 1):
            acc = 0.0
            for i in range(1, min(p, s) + 1):
                t = s - i
                acc += a[i - 1] * (d[t] if t < lo else tmp[t - lo])
            for j in range(nb_):
                if s - j >= 0:
                    acc += b[j] * w[s - j]
            tmp[s - lo] = acc
        out[n] = tmp[n - lo]
