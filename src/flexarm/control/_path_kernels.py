"""Compiled evaluation of piecewise straight paths (the square, polylines, waypoints).

:func:`piecewise_path` is the compiled twin of the NumPy evaluation in
:mod:`flexarm.control.trajectories` (which calls it for long time grids, where
NumPy's temporaries dominate the cost of a simulation's set-up). Both follow
the same formulas; the tests hold them together.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = ["piecewise_path"]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True)
def piecewise_path(
    t: F64, knot_t: F64, knot_p: F64, quintic: bool, pos: F64, vel: F64, acc: F64
) -> None:  # pragma: no cover - compiled
    """Straight segments between consecutive knots, written into ``pos, vel, acc``.

    ``t`` (m,) s, non-decreasing or not; ``knot_t`` (k,) strictly increasing, s
    (k >= 2); ``knot_p`` (k, 2), m; outputs (m, 2). Outside
    ``[knot_t[0], knot_t[-1])`` the path is at rest (velocity and acceleration 0).
    """
    k = knot_t.shape[0]
    first = knot_t[0]
    last = knot_t[k - 1]
    for j in range(t.shape[0]):
        tj = t[j]
        i = np.searchsorted(knot_t, tj, side="right") - 1
        if i < 0:
            i = 0
        elif i > k - 2:
            i = k - 2
        t0 = knot_t[i]
        span = knot_t[i + 1] - t0
        tau = (tj - t0) / span
        if tau < 0.0:
            tau = 0.0
        elif tau > 1.0:
            tau = 1.0
        if quintic:
            s = tau**3 * (10.0 + tau * (-15.0 + 6.0 * tau))
            ds = 30.0 * tau**2 * (1.0 - tau) ** 2
            dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau)
        else:
            s = tau
            ds = 1.0
            dds = 0.0
        moving = tj >= first and tj < last
        for c in range(2):
            delta = knot_p[i + 1, c] - knot_p[i, c]
            pos[j, c] = knot_p[i, c] + s * delta
            if moving:
                vel[j, c] = ds / span * delta
                acc[j, c] = dds / span**2 * delta
            else:
                vel[j, c] = 0.0
                acc[j, c] = 0.0
