"""The path a sagging arm must be commanded so that its tip follows the desired one.

An arm in a vertical plane (``FlexibleArm(gravity=...)``) held at joint angles
``theta`` comes to rest with its links sagging (:meth:`FlexibleArm.equilibrium`):
its tip stands at ``p_eq(theta)``, off the rigid kinematics ``p_rigid(theta)`` by
the sag (up to about 1 m on the paper's 4.5 m links, stretched out sideways under
9.81 m/s**2). A law that places the joints, or the rigid kinematics of the
encoders, on the inverse kinematics of the desired point ``p`` leaves the tip
that far from it. :func:`sag_corrected_angles` finds instead the joint angles
whose *static* tip is on ``p``, ``p_eq(theta*) = p``, by Newton's method with the
rigid Jacobian (the sag's own slope is small beside it), and
:class:`SagCorrectedPath` turns a path into the one to command:

.. math:: p_c(t) = p(t) + f\\,\\bigl(p_{rigid}(\\theta^*(p(t))) - p(t)\\bigr),

``f = 1`` for a law whose reference is the rigid kinematics of the joints (a
joint PD, the Jacobian-transpose PD on the encoders, the LQG, whose design
model carries the sag as an offset of its output), ``f = 1 - alpha`` for the
reflected output ``p_rigid + alpha (p_sensed - p_rigid)``. The correction is
computed at knots (every ``spacing`` s and at the corners) and interpolated
linearly between them; its slope is added to the velocity. Without gravity the
commanded path is the path.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._types import F64
from .._validation import check_array, check_int, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm
from ..model.kinematics import rigid_jacobian, rigid_point
from .gravity_compensation import holding_torques, scratch_size
from .trajectories import ELBOWS, Trajectory, check_trajectory, evaluation_times

__all__ = ["SagCorrectedPath", "rest_tips", "sag_corrected_angles"]

_OWNER = "sag_corrected_angles"


def rest_tips(arm: FlexibleArm, theta: ArrayLike) -> tuple[F64, F64]:
    """Where the tip of ``arm`` held at rest at joint angles ``theta`` stands, and the
    torques that hold it there: the static sag by the compiled fixed point of
    :mod:`flexarm.control.gravity_compensation` (that of
    :meth:`FlexibleArm.equilibrium`; rigid joints), warm-started from posture to
    posture.

    Parameters
    ----------
    arm : FlexibleArm
    theta : array_like, shape (m, n_links)
        Joint angles, rad.

    Returns
    -------
    tips : ndarray, shape (m, 2)
        m.
    torques : ndarray, shape (m, n_links)
        N m.
    """
    angles = check_array(theta, "theta", "rest_tips", shape=(-1, arm.n_links))
    n = arm.n_dof
    scratch = np.zeros(scratch_size(n, arm.n_links))
    tips, torques = np.zeros((angles.shape[0], 2)), np.zeros((angles.shape[0], arm.n_links))
    for k, th in enumerate(angles):
        holding_torques(np.ascontiguousarray(th), arm.arrays, scratch, torques[k])
        tips[k] = np.asarray(arm.tip_position(scratch[:n]), dtype=float)
    return tips, torques


def sag_corrected_angles(
    arm: FlexibleArm,
    points: ArrayLike,
    *,
    elbow: str = "positive",
    tol: float = 1e-9,
    max_iter: int = 30,
) -> F64:
    """The joint angles at which ``arm``, held at rest, has its deflected tip on ``points``.

    Parameters
    ----------
    arm : FlexibleArm
        A two-link arm (with gravity; without, the rigid inverse kinematics).
    points : array_like, shape (m, 2) or (2,)
        Desired tip positions, m.
    elbow : {"positive", "negative"}
        Inverse-kinematics branch of the starting guess.
    tol : float
        Stop when the static tip is within ``tol`` m of the point.
    max_iter : int
        Newton steps at the most per point.

    Returns
    -------
    ndarray, shape (m, 2) or (2,)
        ``theta*``, rad: ``arm.equilibrium(theta*).tip`` is the point (the sag by
        the fixed point of :mod:`flexarm.control.gravity_compensation`, the same
        static sag; rigid joints).

    Raises
    ------
    InvalidValueError
        If a point is out of reach or Newton's method does not converge.
    """
    if not isinstance(arm, FlexibleArm) or arm.n_links != 2:
        raise InvalidTypeError(
            f"The 'arm' parameter of {_OWNER} must be a two-link FlexibleArm. "
            f"Got {type(arm).__name__} instead."
        )
    pts = check_array(points, "points", _OWNER)
    single = pts.ndim == 1
    pts = np.atleast_2d(pts)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise InvalidValueError(
            f"The 'points' parameter of {_OWNER} must have shape (m, 2) or (2,). "
            f"Got shape {np.shape(points)} instead."
        )
    check_option(elbow, "elbow", _OWNER, ELBOWS)
    tol = check_real(tol, "tol", _OWNER, positive=True)
    max_iter = check_int(max_iter, "max_iter", _OWNER, minimum=1)
    theta = np.asarray(arm.inverse_kinematics(pts, elbow=elbow), dtype=float).reshape(-1, 2)
    if arm.gravity is None:
        return theta[0] if single else theta
    lengths = np.asarray(arm.link_lengths, dtype=float)
    for k in range(theta.shape[0]):
        for _ in range(max_iter):
            miss = pts[k] - rest_tips(arm, theta[k : k + 1])[0][0]
            if float(np.linalg.norm(miss)) <= tol:
                break
            theta[k] += np.linalg.solve(rigid_jacobian(lengths, theta[k]), miss)
        else:
            raise InvalidValueError(
                f"The 'points' parameter of {_OWNER} has a point, {pts[k].tolist()} m, whose "
                f"sag-corrected joint angles Newton's method does not find in {max_iter} steps."
            )
    return theta[0] if single else theta


@dataclass(frozen=True)
class SagCorrectedPath:
    """The path to command so that the sagging tip follows ``path`` (module docstring).

    Parameters
    ----------
    arm : FlexibleArm
        The arm (two links; its gravity and links give the sag).
    path : Trajectory
        The desired tip path.
    fraction : float
        ``f`` of the module docstring, in [0, 1] (1: the rigid kinematics of the
        sag-corrected joint angles; 0: the path itself).
    spacing : float
        Knot spacing of the correction, s (> 0; the corners are knots too).
    elbow : {"positive", "negative"}
        Inverse-kinematics branch.

    Attributes
    ----------
    knot_times : ndarray, shape (k,)
        s.
    angles : ndarray, shape (k, 2)
        ``theta*`` at the knots, rad.
    correction : ndarray, shape (k, 2)
        ``p_c - p`` at the knots, m.
    """

    arm: FlexibleArm
    path: Trajectory
    fraction: float = 1.0
    spacing: float = 0.1
    elbow: str = "positive"
    knot_times: F64 = field(init=False, repr=False, compare=False)
    angles: F64 = field(init=False, repr=False, compare=False)
    correction: F64 = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        owner = "SagCorrectedPath"
        check_trajectory(self.path, owner)
        f = check_real(self.fraction, "fraction", owner)
        if not 0.0 <= f <= 1.0:
            raise InvalidValueError(
                f"The 'fraction' parameter of {owner} must lie in [0, 1]. Got {f!r} instead."
            )
        spacing = check_real(self.spacing, "spacing", owner, positive=True)
        duration = float(self.path.duration)
        n = max(2, int(np.ceil(duration / spacing)) + 1)
        corners = [c for c in self.path.corner_times if 0.0 <= c <= duration]
        t = np.union1d(np.linspace(0.0, duration, n), corners)
        p = np.asarray(self.path.evaluate(t)[0], dtype=float)
        theta = sag_corrected_angles(self.arm, p, elbow=self.elbow)
        rigid = rigid_point(np.asarray(self.arm.link_lengths, dtype=float), theta)[0]
        for name, value in (
            ("fraction", f),
            ("knot_times", t),
            ("angles", theta),
            ("correction", f * (rigid - p)),
        ):
            object.__setattr__(self, name, value)

    @property
    def duration(self) -> float:
        """Total time, s (the path's)."""
        return float(self.path.duration)

    @property
    def corner_times(self) -> tuple[float, ...]:
        """The path's corner times, s."""
        return tuple(self.path.corner_times)

    def evaluate(self, t: ArrayLike) -> tuple[F64, F64, F64]:
        """Commanded position (m), velocity (m/s) and acceleration (m/s**2) at ``t`` (s):
        the path's plus the interpolated correction and its slope."""
        tt, scalar = evaluation_times(t, "SagCorrectedPath.evaluate")
        p, v, a = (np.asarray(x, dtype=float).reshape(-1, 2) for x in self.path.evaluate(tt))
        kt, c = self.knot_times, self.correction
        tc = np.clip(tt, kt[0], kt[-1])  # held at the ends outside the path's time
        i = np.clip(np.searchsorted(kt, tc, side="right") - 1, 0, kt.shape[0] - 2)
        slope = (c[i + 1] - c[i]) / (kt[i + 1] - kt[i])[:, None]
        offset = c[i] + slope * (tc - kt[i])[:, None]
        inside = ((tt >= kt[0]) & (tt <= kt[-1]))[:, None]
        out = (p + offset, v + np.where(inside, slope, 0.0), a)
        if scalar:
            return out[0][0], out[1][0], out[2][0]
        return out
