"""Position and velocity of a point of the arm, compiled: :func:`point_state`.

Internal: the bare kernels behind :func:`flexarm.model.dynamics.point_kinematics`, which
the simulator's sensors call at every control step; the NumPy reference is
:func:`flexarm.model.kinematics.deflected_point`.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ..._compile import njit_runtime_free
from ..arrays import LEN, ArmArrays

__all__ = ["point_kinematics", "point_state"]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True, inline="always")
def point_state(
    q: F64, dq: F64, arrays: ArmArrays, link: int, distance: float, phi: F64
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """Position and velocity of a point on a link, deflection included: ``x, y`` (m)
    and ``vx, vy`` (m/s) in the base frame. The parameters are those of
    :func:`flexarm.model.dynamics.point_kinematics` (``arrays`` its ``model``)."""
    ms = arrays.mode_start
    shortening = arrays.shortening_quartic.shape[1] > 0
    alpha = 0.0
    alpha_dot = 0.0
    px = 0.0
    py = 0.0
    vx = 0.0
    vy = 0.0
    for i in range(link + 1):
        alpha += q[i]
        alpha_dot += dq[i]
        a0, a1 = ms[i], ms[i + 1]
        nm = a1 - a0
        w = 0.0
        wd = 0.0
        u = 0.0  # foreshortening of the point
        ud = 0.0
        if i < link:
            x = arrays.link[i, LEN]
            for r in range(a0, a1):
                w += arrays.tip_deflection[r] * q[r]
                wd += arrays.tip_deflection[r] * dq[r]
            if shortening:
                for r in range(a0, a1):
                    sr = 0.0
                    for c in range(a0, a1):
                        sr += arrays.shortening_tip[r, c] * q[c]
                    u += 0.5 * q[r] * sr
                    ud += sr * dq[r]
        else:
            x = distance
            for r in range(a0, a1):
                w += phi[r - a0] * q[r]
                wd += phi[r - a0] * dq[r]
            if shortening and phi.shape[0] >= nm + nm * nm:
                for j in range(nm):
                    sr = 0.0
                    for c in range(nm):
                        sr += phi[nm + j * nm + c] * q[a0 + c]
                    u += 0.5 * q[a0 + j] * sr
                    ud += sr * dq[a0 + j]
        c, s = np.cos(alpha), np.sin(alpha)
        if shortening:
            x -= u
        px += c * x - s * w
        py += s * x + c * w
        # d/dt R(alpha) [x, w] = alpha_dot R S [x, w] + R [-ud, wd],  S = [[0, -1], [1, 0]]
        vx += alpha_dot * (-c * w - s * x) - s * wd
        vy += alpha_dot * (-s * w + c * x) + c * wd
        if shortening:
            vx -= c * ud
            vy -= s * ud
        if i < link:
            for r in range(a0, a1):
                alpha += arrays.tip_slope[r] * q[r]
                alpha_dot += arrays.tip_slope[r] * dq[r]
    return px, py, vx, vy


@njit_runtime_free(cache=True, nogil=True)
def point_kinematics(
    q: F64, dq: F64, arrays: ArmArrays, link: int, distance: float, phi: F64, out: F64
) -> None:  # pragma: no cover - compiled
    """:func:`point_state` into ``out`` (shape (4,)): ``x, y`` (m), ``vx, vy`` (m/s)."""
    out[0], out[1], out[2], out[3] = point_state(q, dq, arrays, link, distance, phi)
