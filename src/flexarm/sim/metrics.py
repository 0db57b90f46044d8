"""Tracking metrics of a simulation, as functions of plain arrays.

All errors are end-effector position errors in metres against the desired
(unshaped, undelayed) path; times in seconds, increasing (the control instants).
Each metric is computed with as few passes and temporaries over the series as it
needs (a long run has millions of rows, and fresh memory is slow to come by), the
same arithmetic in the same order as the plain NumPy expressions in the
docstrings; the series of one number per row (:func:`row_distances`,
:func:`elastic_deflection`) are computed :data:`BLOCK` rows at a time in small
buffers, each row's number the same as over the whole.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "BLOCK",
    "control_effort",
    "corner_errors",
    "elastic_deflection",
    "max_error",
    "residual_start",
    "residual_vibration",
    "rms_error",
    "row_distances",
    "settling_time",
]

F64 = NDArray[np.float64]

BLOCK = 1 << 15
"""Rows per block of the per-row series (their buffers stay in the cache)."""


def row_distances(a: F64, b: F64) -> F64:
    """``|a_k - b_k|`` of each row of two (K, 2) arrays, m: ``sqrt(einsum("ij,ij->i",
    d, d))`` of ``d = a - b``, shape (K,)."""
    n = a.shape[0]
    out = np.empty(n)
    d = np.empty((min(n, BLOCK), a.shape[1]))
    for k0 in range(0, n, BLOCK):
        k1 = min(k0 + BLOCK, n)
        part = np.subtract(a[k0:k1], b[k0:k1], out=d[: k1 - k0])
        np.einsum("ij,ij->i", part, part, out=out[k0:k1])
    return np.sqrt(out, out=out)


def elastic_deflection(angles: F64, lengths: F64, tip: F64) -> F64:
    """The distance (m) between the end effector ``tip`` (K, 2) and where the rigid
    kinematics of the joint ``angles`` (K, N; rad) with links of ``lengths`` (N,; m)
    puts it, shape (K,): with ``phi`` the absolute angles (a cumulative sum by
    column), ``|tip - (cos(phi) @ lengths, sin(phi) @ lengths)|`` row by row."""
    n, n_links = angles.shape
    out = np.empty(n)
    rows = min(n, BLOCK)
    phi, trig = np.empty((rows, n_links)), np.empty((rows, n_links))
    x, y, d = np.empty(rows), np.empty(rows), np.empty((rows, 2))
    for k0 in range(0, n, BLOCK):
        m = min(k0 + BLOCK, n) - k0
        p = phi[:m]
        np.copyto(p, angles[k0 : k0 + m])
        for i in range(1, n_links):
            p[:, i] += p[:, i - 1]
        np.matmul(np.cos(p, out=trig[:m]), lengths, out=x[:m])
        np.matmul(np.sin(p, out=trig[:m]), lengths, out=y[:m])
        np.subtract(tip[k0 : k0 + m, 0], x[:m], out=d[:m, 0])
        np.subtract(tip[k0 : k0 + m, 1], y[:m], out=d[:m, 1])
        np.einsum("ij,ij->i", d[:m], d[:m], out=out[k0 : k0 + m])
    return np.sqrt(out, out=out)


def _finite(x: F64) -> F64:
    """``x[np.isfinite(x)]``, and ``x`` itself (no copy) when every sample is finite."""
    finite = np.isfinite(x)
    return x if finite.all() else x[finite]


def _rms(x: F64) -> float:
    """``sqrt(mean(x**2))`` of the finite samples of ``x`` (NaN if none)."""
    e = _finite(x)
    if not e.size:
        return float("nan")
    squares = np.square(e)  # (e**2: the same numbers)
    return float(np.sqrt(np.mean(squares)))


def rms_error(error: F64) -> float:
    """Root-mean-square of ``error`` (m), NaN samples ignored."""
    return _rms(error)


def max_error(error: F64) -> float:
    """Largest ``error`` (m), NaN samples ignored."""
    e = _finite(error)
    return float(e.max()) if e.size else float("nan")


def corner_errors(
    t: F64, error: F64, corner_times: Sequence[float], window: float = 1.0
) -> NDArray[np.float64]:
    """Largest error in ``[t_c, t_c + window]`` after each corner time ``t_c``.

    Returns
    -------
    ndarray, shape (len(corner_times),)
        NaN for corners outside the simulated time.
    """
    out = np.full(len(corner_times), np.nan)
    for i, tc in enumerate(corner_times):  # the rows t_c <= t <= t_c + window
        a = int(np.searchsorted(t, tc, side="left"))
        b = int(np.searchsorted(t, tc + window, side="right"))
        e = _finite(error[a:b])
        if e.size:
            out[i] = e.max()
    return out


def residual_start(t: F64, start: float) -> int:
    """The first row of :func:`residual_vibration`'s window: the first ``t >= start``,
    or of the last 10 % of the run if ``start`` is at or after its end."""
    if start >= t[-1]:
        start = t[-1] - 0.1 * (t[-1] - t[0])
    return int(np.searchsorted(t, start, side="left"))


def residual_vibration(t: F64, deflection: F64, start: float) -> float:
    """RMS elastic deflection of the end effector (m) after ``start``.

    ``deflection`` is the distance between the end effector and where the rigid
    kinematics of the joint angles puts it. If ``start`` is at or after the end
    of the run, the last 10 % of the run is used (:func:`residual_start`). Only
    those rows are read: ``deflection`` may hold just them (shape
    ``(len(t) - residual_start(t, start),)``) instead of every row.
    """
    k = residual_start(t, start)
    window = deflection[k:] if deflection.shape[0] == t.shape[0] else deflection
    return _rms(window)


def settling_time(t: F64, error: F64, start: float, tolerance: float) -> float:
    """Time after ``start`` from which the error stays within ``tolerance`` (m).

    NaN if it never settles within the run (or ``start`` is past the end).
    """
    sel = t >= start
    if not np.any(sel):
        return float("nan")
    ts, es = t[sel], error[sel]
    outside = np.flatnonzero(~(es <= tolerance))
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    if last == es.size - 1:
        return float("nan")
    return float(ts[last + 1] - start)


def control_effort(t: F64, tau: F64) -> float:
    """``int sum_i tau_i**2 dt`` in N**2 m**2 s (trapezoid rule, NaN rows dropped)."""
    if not np.isfinite(tau).all():  # (a diverged run's last rows; else no copies)
        ok = np.all(np.isfinite(tau), axis=1)
        tau, t = tau[ok], t[ok]
    if tau.shape[0] < 2:
        return float("nan")
    # np.trapezoid(y, t), y = sum_i tau_i**2, by blocks of intervals:
    # sum(diff(t) * (y[1:] + y[:-1]) / 2)
    n = tau.shape[0] - 1  # intervals
    pairs = np.empty(n)
    y, dt = np.empty(min(n, BLOCK) + 1), np.empty(min(n, BLOCK))
    for k0 in range(0, n, BLOCK):
        k1 = min(k0 + BLOCK, n)
        rows = tau[k0 : k1 + 1]
        power = np.einsum("ij,ij->i", rows, rows, out=y[: k1 - k0 + 1])
        part = np.add(power[1:], power[:-1], out=pairs[k0:k1])
        part *= np.subtract(t[k0 + 1 : k1 + 1], t[k0:k1], out=dt[: k1 - k0])
        part /= 2.0
    return float(np.add.reduce(pairs))
