"""Output redefinition: the "reflected tip" law and its stability limit.

A distant sensor's output is non-minimum phase; the joint angles' rigid
kinematics is not, but it ignores the deflection. The reflected output mixes
them (Wang & Vidyasagar, 1992):

.. math:: y_\\alpha = p_{rigid}(\\theta) + \\alpha\\,(p_{sensed} - p_{rigid}(\\theta)),

``alpha = 0`` the collocated output, ``alpha = 1`` the sensed point itself.
:class:`ReflectedTipPD` is the paper's Jacobian-transpose PD on ``y_alpha``
(and its rate), with the Jacobian of the sensed point's rigid kinematics.
Below a limit ``alpha*`` the loop is stable; :func:`reflection_limit` finds it
from the loop linearised at rest through the compiled law
(:func:`flexarm.control.linearize.closed_loop_matrix`), as the smallest ``alpha``
at which an eigenvalue crosses into the right half plane, over a set of
configurations (the reference's).

The reference it asks for (:meth:`ReflectedTipPD.reference_smoothing`, what
:func:`flexarm.simulate` uses unless told otherwise). The law has no feedforward:
it follows the path by feedback alone, through its slowest ringing mode (on the
paper's arm along the square: 5.1-6.3 rad/s, damping ratios 0.06-0.23, with the
tip; 1.3-1.9 rad/s, 0.08-0.10, with the point 0.5 m from the elbow). A raw corner
asks it for content far above that; smoothing a lot would cut the corners
instead. The law asks for the Gaussian that halves the reference's content at
the slowest of those frequencies ``omega_r``, ``sigma = sqrt(2 ln 2) / omega_r``
(0.23 s on the paper's arm with the tip, 0.89 s with the point).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numba as nb
import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import ArrayLike

from .._types import F64
from .._validation import check_real
from ..errors import InvalidValueError
from ..model.arm import FlexibleArm
from ..model.plant import Plant
from ..sensing.sensors import Sensor
from .controllers import (
    Controller,
    JacobianTransposePD,
    gaussian_smoothing,
    jacobian_transpose_law,
    ringing_frequency,
    wrap_control_function,
)
from .linearize import closed_loop_matrix, closed_loop_poles
from .signals import y_angles, y_point, y_point_rate, y_rates

__all__ = ["ReflectedTipPD", "reflection_limit"]

_OWNER = "ReflectedTipPD"


@nb.njit(cache=True, nogil=True)
def _reflected(t: float, y: F64, r: F64, p: F64, s: F64, tau: F64) -> None:  # pragma: no cover
    """``p``: the Jacobian-transpose layout (Kp, Kd, lever lengths), then alpha. ``s``:
    scratch of the measurement's length."""
    n = tau.shape[0]
    alpha = p[8 + n]
    for k in range(y.shape[0]):
        s[k] = y[k]
    ya, yr, yp, yv = y_angles(n), y_rates(n), y_point(n), y_point_rate(n)
    px = py = vx = vy = 0.0
    phi = phid = 0.0
    for i in range(n):
        phi += y[ya + i]
        phid += y[yr + i]
        lever = p[8 + i]
        px += lever * math.cos(phi)
        py += lever * math.sin(phi)
        vx -= lever * math.sin(phi) * phid
        vy += lever * math.cos(phi) * phid
    s[yp] = px + alpha * (y[yp] - px)
    s[yp + 1] = py + alpha * (y[yp + 1] - py)
    s[yv] = vx + alpha * (y[yv] - vx)
    s[yv + 1] = vy + alpha * (y[yv + 1] - vy)
    jacobian_transpose_law(s, r, p, 1.0, 1.0, tau)


reflected_cfunc = wrap_control_function(_reflected, cache=True)


@dataclass(frozen=True)
class ReflectedTipPD(Controller):
    """Jacobian-transpose PD on the reflected output ``y_alpha`` (module docstring).

    Parameters
    ----------
    alpha : float
        The reflection, in ``[-1, 1]`` (0: collocated, 1: the sensed point).
        Stable below :func:`reflection_limit`.
    kp, kd : float or array_like, shape (2,) or (2, 2)
        The PD gains, N/m and N s/m (default: the paper's).

    Needs a point sensor (tip or a point of a link) and reads the encoders too.
    """

    alpha: float = 0.5
    kp: ArrayLike = 150.79
    kd: ArrayLike = 17.364
    name = "reflected"

    def __post_init__(self) -> None:
        a = check_real(self.alpha, "alpha", _OWNER)
        if not -1.0 <= a <= 1.0:
            raise InvalidValueError(
                f"The 'alpha' parameter of {_OWNER} must lie in [-1, 1]. Got {a!r} instead."
            )
        object.__setattr__(self, "alpha", a)

    @classmethod
    def from_arm(cls, arm: Plant, alpha: float = 0.5, zeta: float = 0.707) -> ReflectedTipPD:
        """The paper's gains (as :meth:`JacobianTransposePD.from_arm`) on ``y_alpha``."""
        base = JacobianTransposePD.from_arm(arm, zeta)
        return cls(alpha=alpha, kp=base.kp, kd=base.kd)

    @property
    def cfunc(self) -> CFunc:
        return reflected_cfunc

    def parameters(self, arm: Plant) -> F64:
        raise InvalidValueError(f"{_OWNER} needs the sensor it reflects: use parameters_for.")

    def parameters_for(self, arm: Plant, sensor: Sensor | None) -> F64:
        if sensor is None or sensor.resolve(arm)[0] < 0:
            raise InvalidValueError(
                f"The 'sensor' parameter of {_OWNER} must be a point sensor (tip or a point "
                "of a link): the law reflects the sensed point. Got the joint encoders instead."
            )
        base = JacobianTransposePD(kp=self.kp, kd=self.kd).parameters_for(arm, sensor)
        return np.concatenate([base, [self.alpha]])

    def initial_state(self, arm: Plant) -> F64:
        return np.zeros(2 * arm.n_links + 4 + sum(arm.n_modes))  # scratch for y_alpha

    def reference_smoothing(
        self,
        arm: Plant,
        sensor: Sensor | None,
        dt: float,
        path: F64,
        elbow: str = "positive",
    ) -> float:
        """The smoothing of the path this law asks for, s (module docstring):
        ``sqrt(2 ln 2) / omega_r``, half the content at ``omega_r``, the slowest
        ringing frequency (:func:`~flexarm.control.controllers.ringing_frequency`:
        damping ratio below 0.5) of the loop linearised at rest
        (:func:`~flexarm.control.linearize.closed_loop_poles`) at each point of
        ``path`` (end-effector points, shape (P, 2), m). 0 where the loop cannot be
        linearised so (not a two-link FlexibleArm, joint encoders, a point out of
        reach: the run then says what is wrong).
        """
        if not isinstance(arm, FlexibleArm) or arm.n_links != 2:
            return 0.0
        if sensor is None or sensor.resolve(arm)[0] < 0:
            return 0.0
        try:
            poles = [closed_loop_poles(arm, self, p, sensor, elbow=elbow) for p in path]
        except ValueError:
            return 0.0
        return gaussian_smoothing(ringing_frequency(np.concatenate(poles)), 2.0)


def reflection_limit(
    arm: FlexibleArm,
    sensor: Sensor,
    positions: Sequence[ArrayLike],
    *,
    kp: ArrayLike = 150.79,
    kd: ArrayLike = 17.364,
    elbow: str = "positive",
    tolerance: float = 1e-3,
) -> float:
    """The largest ``alpha`` in ``[0, 1]`` at which :class:`ReflectedTipPD` is stable at
    every rest point in ``positions`` (end-effector points, m), by bisection on
    the largest real part of the linearised loop's eigenvalues.

    Returns 1.0 if the loop is stable up to ``alpha = 1``; raises if it is
    unstable already at ``alpha = 0``.
    """
    tol = check_real(tolerance, "tolerance", "reflection_limit", positive=True)
    points = [np.asarray(pt, dtype=float) for pt in positions]
    if not points:
        raise InvalidValueError("The 'positions' parameter of reflection_limit must be non-empty.")

    def growth(alpha: float) -> float:
        law = ReflectedTipPD(alpha=alpha, kp=kp, kd=kd)
        return max(
            float(
                np.max(
                    np.linalg.eigvals(closed_loop_matrix(arm, law, pt, sensor, elbow=elbow)).real
                )
            )
            for pt in points
        )

    if growth(0.0) >= 0.0:
        raise InvalidValueError(
            "The 'kp' parameter of reflection_limit gives a loop that is unstable even on the "
            "collocated output (alpha = 0)."
        )
    if growth(1.0) < 0.0:
        return 1.0
    lo, hi = 0.0, 1.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if growth(mid) < 0.0 else (lo, mid)
    return lo
