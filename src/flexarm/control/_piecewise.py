"""The straight-segment paths evaluated in NumPy, and the time scaling they share.

:func:`piecewise_numpy` evaluates the paths made of straight segments (the square,
lines, waypoints) on short time grids, where compiling or loading the compiled twin
(:mod:`flexarm.control._path_kernels`, which takes :func:`quintic_scaling` from here)
costs more than it saves; :data:`COMPILED_FROM` is where the twin takes over.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np

from .._types import F64

__all__ = ["COMPILED_FROM", "piecewise_numpy", "quintic_scaling"]

_T = TypeVar("_T", float, F64)

COMPILED_FROM = 4096
"""Time grids at least this long are evaluated by the compiled kernel."""


def quintic_scaling(tau: _T) -> tuple[_T, _T, _T]:
    """The rest-to-rest time scaling ``s = 10 tau**3 - 15 tau**4 + 6 tau**5`` and its
    first two derivatives in ``tau`` (a float, or an array), for ``tau`` in [0, 1]."""
    s = tau**3 * (10.0 + tau * (-15.0 + 6.0 * tau))
    ds = 30.0 * tau**2 * (1.0 - tau) ** 2
    dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau)
    return s, ds, dds


def piecewise_numpy(t: F64, knot_t: F64, knot_p: F64, quintic: bool) -> tuple[F64, F64, F64]:
    """Straight segments between consecutive knots, each with its own time scaling.

    ``t`` (m,) s; ``knot_t`` (k,) strictly increasing, s (k >= 2); ``knot_p`` (k, 2),
    m; a repeated point is a dwell. Returns the position, velocity and acceleration,
    each (m, 2), in m, m/s and m/s**2. Outside ``[knot_t[0], knot_t[-1])`` the path is
    at rest (velocity and acceleration 0). The compiled kernels' reference.
    """
    k = knot_t.shape[0]
    i = np.clip(np.searchsorted(knot_t, t, side="right") - 1, 0, k - 2)
    t0 = knot_t[i]
    span = knot_t[i + 1] - t0
    tau = np.clip((t - t0) / span, 0.0, 1.0)
    moving = ((t >= knot_t[0]) & (t < knot_t[-1]))[:, None]
    delta = knot_p[i + 1] - knot_p[i]
    if quintic:
        s, ds, dds = quintic_scaling(tau)
    else:
        s = tau
        ds = np.ones_like(tau)
        dds = np.zeros_like(tau)
    pos = knot_p[i] + s[:, None] * delta
    vel = np.where(moving, (ds / span)[:, None] * delta, 0.0)
    with np.errstate(over="ignore"):  # a side of ~1e154 s or more: no acceleration, as compiled
        acc = np.where(moving, (dds / span**2)[:, None] * delta, 0.0)
    return pos, vel, acc
