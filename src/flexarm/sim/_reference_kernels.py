"""Compiled kernels of the reference pipeline: the rigid two-link joint path,
and the reference streamed instant by instant inside the simulation loop.

:func:`joint_path_rows` is the compiled twin of
:func:`flexarm.sim.references.joint_path` (inverse kinematics, then the joint
rates and accelerations from the rigid Jacobian in closed form), row by row
without temporaries (:func:`joint_row`); the pipeline calls it on every block of
a run's control instants. The NumPy function stays the public, documented
reference; the tests hold the two together.

:func:`stream_row` is the whole pipeline at one instant for a path of straight
segments (the square, lines, waypoints) without shaping or smoothing: the
same path and joint-row kernels in the same order, so the loop computes the
same numbers the pipeline would have precomputed, without the arrays.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ..control._path_kernels import path_point

__all__ = [
    "OK",
    "SINGULAR",
    "UNREACHABLE",
    "ReferenceStream",
    "joint_path_rows",
    "joint_row",
    "no_stream",
    "reference_stream",
    "stream_row",
    "stream_rows",
]

F64 = NDArray[np.float64]
OK, UNREACHABLE, SINGULAR = 0, 1, 2


@nb.njit(cache=True, nogil=True, inline="always")
def joint_row(
    l1: float,
    l2: float,
    sign: float,
    singularity_tol: float,
    x: float,
    y: float,
    vx: float,
    vy: float,
    ax_: float,
    ay_: float,
) -> tuple[int, float, float, float, float, float, float, float]:  # pragma: no cover
    """:func:`joint_path_rows` at one point of the path: ``(code, value, theta1,
    theta2, dtheta1, dtheta2, ddtheta1, ddtheta2)`` (``value`` as there)."""
    r2 = x**2 + y**2
    c2 = (r2 - l1**2 - l2**2) / (2 * l1 * l2)
    if not (c2 <= 1.0 + 1e-12 and c2 >= -1.0 - 1e-12):
        return UNREACHABLE, math.sqrt(r2), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
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
    t2 = math.atan2(s2, c2)
    cs2 = cs1 * c2 - sn1 * s2  # the second link's absolute angle
    sn2 = sn1 * c2 + cs1 * s2
    a = -l1 * sn1 - l2 * sn2  # the rigid Jacobian [[a, b], [c, d]]
    b = -l2 * sn2
    c = l1 * cs1 + l2 * cs2
    d = l2 * cs2
    det = a * d - b * c
    near = abs(det) / (l1 * l2)
    if near < singularity_tol:
        return SINGULAR, near, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    w1 = (d * vx - b * vy) / det
    w2 = (a * vy - c * vx) / det
    g1 = l1 * w1**2
    g2 = l2 * (w1 + w2) ** 2
    ax = ax_ + (g1 * cs1 + g2 * cs2)  # a - Jdot dtheta
    ay = ay_ + (g1 * sn1 + g2 * sn2)
    return OK, 0.0, t1, t2, w1, w2, (d * ax - b * ay) / det, (a * ay - c * ax) / det


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
        code, value, t1, t2, w1, w2, e1, e2 = joint_row(
            l1,
            l2,
            sign,
            singularity_tol,
            pos[k, 0],
            pos[k, 1],
            vel[k, 0],
            vel[k, 1],
            acc[k, 0],
            acc[k, 1],
        )
        if code != OK:
            return code, k, value
        theta[k, 0], theta[k, 1] = t1, t2
        dtheta[k, 0], dtheta[k, 1] = w1, w2
        ddtheta[k, 0], ddtheta[k, 1] = e1, e2
    return OK, -1, 0.0


class ReferenceStream(NamedTuple):
    """A run's reference computed in the loop, instant by instant (build with
    :func:`reference_stream`): a path of straight segments between knots
    (:func:`flexarm.control._path_kernels.path_point`), delayed by ``spec[1]``
    for the law, through the rigid two-link inverse kinematics.

    knot_t : (k,) knot times, s; knot_p : (k, 2) knot points, m;
    spec : (7,) ``(on, quintic, delay s, l1 m, l2 m, elbow sign, singularity_tol)``;
    ``on = 0``: off (the loop reads precomputed rows instead).
    """

    knot_t: F64
    knot_p: F64
    spec: F64


def reference_stream(
    knot_t: F64,
    knot_p: F64,
    *,
    quintic: bool,
    delay: float,
    lengths: tuple[float, float],
    sign: float,
    singularity_tol: float,
) -> ReferenceStream:
    """The one way to build a :class:`ReferenceStream` that is on."""
    spec = np.array([1.0, float(quintic), delay, *lengths, sign, singularity_tol])
    return ReferenceStream(
        knot_t=np.ascontiguousarray(knot_t, dtype=np.float64),
        knot_p=np.ascontiguousarray(knot_p, dtype=np.float64),
        spec=spec,
    )


def no_stream() -> ReferenceStream:
    """A :class:`ReferenceStream` that is off."""
    return ReferenceStream(knot_t=np.zeros(2), knot_p=np.zeros((2, 2)), spec=np.zeros(7))


@nb.njit(cache=True, nogil=True, inline="always")
def stream_row(stream: ReferenceStream, t: float, r: F64, desired: F64) -> tuple[int, float]:
    """The reference vector ``r`` (layout of :mod:`flexarm.control.signals`, two
    links, feedforward columns left as they are) and the desired point (m) at
    time ``t`` (s). Returns ``(code, value)`` as :func:`joint_row`."""
    spec = stream.spec
    quintic = spec[1] != 0.0
    delay = spec[2]
    x, y, vx, vy, ax, ay = path_point(t - delay, stream.knot_t, stream.knot_p, quintic)
    if delay != 0.0:
        dx, dy, _, _, _, _ = path_point(t, stream.knot_t, stream.knot_p, quintic)
        desired[0], desired[1] = dx, dy
    else:
        desired[0], desired[1] = x, y
    code, value, t1, t2, w1, w2, e1, e2 = joint_row(
        spec[3], spec[4], spec[5], spec[6], x, y, vx, vy, ax, ay
    )
    r[0], r[1], r[2], r[3], r[4], r[5] = x, y, vx, vy, ax, ay
    r[6], r[7], r[8], r[9], r[10], r[11] = t1, t2, w1, w2, e1, e2
    return code, value


@nb.njit(cache=True, nogil=True)
def stream_rows(
    stream: ReferenceStream, instants: NDArray[np.int64], dt: float, r: F64, desired: F64
) -> tuple[int, int, float]:  # pragma: no cover - compiled
    """:func:`stream_row` at times ``t = k dt`` for ``k`` in ``instants``, into rows of
    ``r`` (m, 14) and ``desired`` (m, 2); ``(code, k, value)`` at the first instant
    that fails, else ``(OK, -1, 0)``."""
    for j in range(instants.shape[0]):
        k = instants[j]
        code, value = stream_row(stream, k * dt, r[j], desired[j])
        if code != OK:
            return code, k, value
    return OK, -1, 0.0
