"""Compiled kernels of the reference pipeline: the rigid two-link joint path.

:func:`joint_path_rows` is the compiled twin of
:func:`flexarm.sim.references.joint_path` (inverse kinematics, then the joint
rates and accelerations from the rigid Jacobian in closed form), row by row
without temporaries; the pipeline calls it on every block of a run's control
instants. The NumPy function stays the public, documented reference; the tests
hold the two together.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = ["OK", "SINGULAR", "UNREACHABLE", "joint_path_rows"]

F64 = NDArray[np.float64]
OK, UNREACHABLE, SINGULAR = 0, 1, 2


@nb.njit(cache=True, nogil=True)
def joint_path_rows(
    l1: float,
    l2: float,
    sign: float,
    singularity_tol: float,
    pos: F64,
    vel: F64,
    acc: F64,
    theta: F64,
    dtheta: F64,
    ddtheta: F64,
) -> tuple[int, int, float]:  # pragma: no cover - compiled
    """Joint angles, rates and accelerations of a rigid two-link arm on a path.

    Parameters
    ----------
    l1, l2 : float
        Link lengths, m.
    sign : float
        +1 or -1: the elbow branch (sign of ``theta_2``).
    singularity_tol : float
        Smallest allowed ``|det J| / (l1 l2)``.
    pos, vel, acc : ndarray, shape (m, 2)
        The path, m, m/s, m/s**2.
    theta, dtheta, ddtheta : ndarray, shape (m, 2)
        Written: rad, rad/s, rad/s**2 (``theta_1`` wrapped to ``[-pi, pi)``).

    Returns
    -------
    (code, row, value)
        ``(OK, -1, 0)``; or ``(UNREACHABLE, row, distance from the base)`` at the
        first unreachable row; or ``(SINGULAR, row, |det J| / (l1 l2))`` at the
        first row too close to a singularity.
    """
    for k in range(pos.shape[0]):
        x = pos[k, 0]
        y = pos[k, 1]
        r2 = x**2 + y**2
        c2 = (r2 - l1**2 - l2**2) / (2 * l1 * l2)
        if not (c2 <= 1.0 + 1e-12 and c2 >= -1.0 - 1e-12):
            return UNREACHABLE, k, math.sqrt(r2)
        c2 = min(max(c2, -1.0), 1.0)
        s2 = math.sqrt(1.0 - c2**2) * sign
        # theta_1 = alpha - beta, alpha the target's bearing, beta the elbow's offset:
        # their sines and cosines come from the geometry, with no trigonometric call
        r = math.sqrt(r2)
        ca, sa = (x / r, y / r) if r > 0.0 else (1.0, 0.0)
        bx, by = l1 + l2 * c2, l2 * s2
        rho = math.sqrt(bx**2 + by**2)
        cb, sb = (bx / rho, by / rho) if rho > 0.0 else (1.0, 0.0)
        cs1 = ca * cb + sa * sb
        sn1 = sa * cb - ca * sb
        t1 = math.atan2(sn1, cs1)
        if t1 >= math.pi:  # [-pi, pi)
            t1 -= 2.0 * math.pi
        theta[k, 0] = t1
        theta[k, 1] = math.atan2(s2, c2)
        cs2 = cs1 * c2 - sn1 * s2  # the second link's absolute angle
        sn2 = sn1 * c2 + cs1 * s2
        a = -l1 * sn1 - l2 * sn2  # the rigid Jacobian [[a, b], [c, d]]
        b = -l2 * sn2
        c = l1 * cs1 + l2 * cs2
        d = l2 * cs2
        det = a * d - b * c
        near = abs(det) / (l1 * l2)
        if near < singularity_tol:
            return SINGULAR, k, near
        w1 = (d * vel[k, 0] - b * vel[k, 1]) / det
        w2 = (a * vel[k, 1] - c * vel[k, 0]) / det
        dtheta[k, 0] = w1
        dtheta[k, 1] = w2
        g1 = l1 * w1**2
        g2 = l2 * (w1 + w2) ** 2
        ax = acc[k, 0] + (g1 * cs1 + g2 * cs2)  # a - Jdot dtheta
        ay = acc[k, 1] + (g1 * sn1 + g2 * sn2)
        ddtheta[k, 0] = (d * ax - b * ay) / det
        ddtheta[k, 1] = (a * ay - c * ax) / det
    return OK, -1, 0.0
