"""Tracking metrics of a simulation, as functions of plain arrays.

All errors are end-effector position errors in metres against the desired
(unshaped, undelayed) path; times in seconds.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "control_effort",
    "corner_errors",
    "max_error",
    "residual_vibration",
    "rms_error",
    "settling_time",
]

F64 = NDArray[np.float64]


def rms_error(error: F64) -> float:
    """Root-mean-square of ``error`` (m), NaN samples ignored."""
    e = error[np.isfinite(error)]
    return float(np.sqrt(np.mean(e**2))) if e.size else float("nan")


def max_error(error: F64) -> float:
    """Largest ``error`` (m), NaN samples ignored."""
    e = error[np.isfinite(error)]
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
    for i, tc in enumerate(corner_times):
        sel = (t >= tc) & (t <= tc + window) & np.isfinite(error)
        if np.any(sel):
            out[i] = error[sel].max()
    return out


def residual_vibration(t: F64, deflection: F64, start: float) -> float:
    """RMS elastic deflection of the end effector (m) after ``start``.

    ``deflection`` is the distance between the end effector and where the rigid
    kinematics of the joint angles puts it. If ``start`` is at or after the end
    of the run, the last 10 % of the run is used.
    """
    if start >= t[-1]:
        start = t[-1] - 0.1 * (t[-1] - t[0])
    sel = (t >= start) & np.isfinite(deflection)
    return float(np.sqrt(np.mean(deflection[sel] ** 2))) if np.any(sel) else float("nan")


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
    ok = np.all(np.isfinite(tau), axis=1)
    kept = np.count_nonzero(ok)
    if kept < 2:
        return float("nan")
    if kept < ok.shape[0]:  # (a diverged run's last rows; else no copies)
        tau, t = tau[ok], t[ok]
    return float(np.trapezoid(np.einsum("ij,ij->i", tau, tau), t))
