"""Compiled evaluation of piecewise straight paths (the square, polylines, waypoints).

:func:`piecewise_path` is the compiled twin of the NumPy evaluation
(:func:`flexarm.control._piecewise.piecewise_numpy`): the paths of
:mod:`flexarm.control.trajectories` call it on long time grids, where NumPy's
temporaries dominate the cost of a simulation's set-up. Both follow the same
formulas (the time scaling is one function, compiled here); the tests hold them
together.
"""

from __future__ import annotations

from collections.abc import Callable

import numba as nb
import numpy as np

from .._types import F64
from ._piecewise import quintic_scaling

__all__ = ["path_point", "piecewise_path"]


_quintic: Callable[[float], tuple[float, float, float]]
_quintic = nb.njit(cache=True, nogil=True, inline="always")(quintic_scaling)  # type: ignore[assignment]


@nb.njit(cache=True, nogil=True, inline="always")
def path_point(
    tj: float, knot_t: F64, knot_p: F64, quintic: bool
) -> tuple[float, float, float, float, float, float]:  # pragma: no cover - compiled
    """The path at one time ``tj`` (s): ``(x, y, vx, vy, ax, ay)`` in m, m/s, m/s**2
    (:func:`piecewise_path`'s formulas; the simulation loop streams it)."""
    k = knot_t.shape[0]
    i = int(np.searchsorted(knot_t, tj, side="right")) - 1
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
        s, ds, dds = _quintic(tau)
    else:
        s = tau
        ds = 1.0
        dds = 0.0
    moving = tj >= knot_t[0] and tj < knot_t[k - 1]
    dx = knot_p[i + 1, 0] - knot_p[i, 0]
    dy = knot_p[i + 1, 1] - knot_p[i, 1]
    x = knot_p[i, 0] + s * dx
    y = knot_p[i, 1] + s * dy
    if moving:
        return x, y, ds / span * dx, ds / span * dy, dds / span**2 * dx, dds / span**2 * dy
    return x, y, 0.0, 0.0, 0.0, 0.0


@nb.njit(cache=True, nogil=True)
def piecewise_path(
    t: F64, knot_t: F64, knot_p: F64, quintic: bool, pos: F64, vel: F64, acc: F64
) -> None:  # pragma: no cover - compiled
    """Straight segments between consecutive knots, written into ``pos, vel, acc``.

    ``t`` (m,) s, non-decreasing or not; ``knot_t`` (k,) strictly increasing, s
    (k >= 2); ``knot_p`` (k, 2), m; outputs (m, 2). Outside
    ``[knot_t[0], knot_t[-1])`` the path is at rest (velocity and acceleration 0).
    """
    for j in range(t.shape[0]):
        x, y, vx, vy, ax, ay = path_point(t[j], knot_t, knot_p, quintic)
        pos[j, 0], pos[j, 1] = x, y
        vel[j, 0], vel[j, 1] = vx, vy
        acc[j, 0], acc[j, 1] = ax, ay
