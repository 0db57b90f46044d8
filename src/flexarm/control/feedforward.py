"""Feedforward from the reference: the rigid inverse dynamics of a two-link arm.

With the links held straight (modal coordinates zero) and the motors locked to
the link angles, a planar two-link arm is a rigid chain whose joint torques are

.. math:: \\tau = M(\\theta_2) \\ddot\\theta + h(\\theta_2, \\dot\\theta),\\quad
          M = \\begin{pmatrix} \\alpha + 2\\beta\\cos\\theta_2 &
          \\delta_{12} + \\beta\\cos\\theta_2 \\\\
          \\delta_{12} + \\beta\\cos\\theta_2 & \\delta \\end{pmatrix},\\quad
          h = \\beta\\sin\\theta_2 \\begin{pmatrix} -\\dot\\theta_2 (2\\dot\\theta_1
          + \\dot\\theta_2) \\\\ \\dot\\theta_1^2 \\end{pmatrix}.

The constants come from the arm's own mass matrix (:meth:`FlexibleArm.mass_matrix`
restricted to rigid motion, at ``theta_2 = 0`` and ``pi / 2``), so links, hubs, rotors
and the payload are all in them. ``delta_12 = delta`` but for a geared rotor carried by
link 1, whose cross term is ``J_m / N`` where its own term in ``delta`` is ``J_m``.
:func:`flexarm.simulate` adds these torques to any law's output when asked
(``feedforward=True``): the reference pipeline puts them in the reference vector
(:func:`flexarm.control.signals.r_feedforward`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._types import F64
from ..errors import InvalidValueError
from ..model.arm import FlexibleArm

__all__ = ["RigidDynamics", "rigid_projection"]


def rigid_projection(arm: FlexibleArm) -> F64:
    """``P``, shape (n_dof, n_links): ``q = P theta`` is rigid motion (joint angles and
    motor angles equal to ``theta``, modal coordinates zero)."""
    p = np.zeros((arm.n_dof, arm.n_links))
    p[: arm.n_links] = np.eye(arm.n_links)
    if arm.has_flexible_joints:
        p[arm.motor_slice] = np.eye(arm.n_links)
    return p


@dataclass(frozen=True)
class RigidDynamics:
    """The rigid two-link dynamics constants ``alpha, beta, delta`` and ``delta12``
    (kg m**2; ``delta12`` None: equal to ``delta``).

    Build with :meth:`of` from an arm. Call to get the torques.

    Examples
    --------
    >>> rd = RigidDynamics.of(FlexibleArm.paper())
    >>> tau = rd([0.0, 0.5], [0.0, 0.0], [1.0, 0.0])   # N m, shape (2,)
    """

    alpha: float
    beta: float
    delta: float
    delta12: float | None = None

    @property
    def _d12(self) -> float:
        return self.delta if self.delta12 is None else self.delta12

    @classmethod
    def of(cls, arm: FlexibleArm) -> RigidDynamics:
        """The constants of ``arm`` (two links) from its mass matrix at ``theta_2 = 0``
        and ``pi / 2``."""
        if arm.n_links != 2:
            raise InvalidValueError(
                "The 'arm' parameter of RigidDynamics.of must have two links. "
                f"Got {arm.n_links} links instead."
            )
        p = rigid_projection(arm)

        def rigid_mass(theta2: float) -> F64:
            q = p @ np.array([0.0, theta2])
            return np.asarray(p.T @ np.asarray(arm.mass_matrix(q).real) @ p)

        m, m90 = rigid_mass(0.0), rigid_mass(0.5 * np.pi)
        delta = float(m[1, 1])
        beta = 0.5 * (float(m[0, 0]) - float(m90[0, 0]))  # M11 = alpha + 2 beta cos
        delta12 = float(m[0, 1]) - beta
        if abs(delta12 - delta) <= 1e-12 * float(m[0, 0]):  # no geared rotor on link 1
            beta = float(m[0, 1]) - delta
            return cls(alpha=float(m[0, 0]) - 2.0 * beta, beta=beta, delta=delta)
        return cls(float(m90[0, 0]), beta, delta, delta12)

    def mass_matrix(self, theta2: ArrayLike) -> F64:
        """``M(theta_2)``, shape (..., 2, 2), kg m**2."""
        c = np.cos(np.asarray(theta2, dtype=float))
        m12 = self._d12 + self.beta * c
        return np.stack(
            [
                np.stack([self.alpha + 2 * self.beta * c, m12], -1),
                np.stack([m12, np.full_like(c, self.delta)], -1),
            ],
            -2,
        )

    def __call__(self, theta: ArrayLike, dtheta: ArrayLike, ddtheta: ArrayLike) -> F64:
        """Joint torques ``M(theta_2) ddtheta + h(theta_2, dtheta)``, N m.

        Parameters
        ----------
        theta, dtheta, ddtheta : array_like, shape (..., 2)
            Joint angles (rad), rates (rad/s) and accelerations (rad/s**2).

        Returns
        -------
        ndarray, shape (..., 2)
        """
        th = np.asarray(theta, dtype=float)
        w = np.asarray(dtheta, dtype=float)
        a = np.asarray(ddtheta, dtype=float)
        c, s = np.cos(th[..., 1]), np.sin(th[..., 1])
        m11 = self.alpha + 2 * self.beta * c
        m12 = self._d12 + self.beta * c
        h1 = -self.beta * s * w[..., 1] * (2 * w[..., 0] + w[..., 1])
        h2 = self.beta * s * w[..., 0] ** 2
        return np.stack(
            [m11 * a[..., 0] + m12 * a[..., 1] + h1, m12 * a[..., 0] + self.delta * a[..., 1] + h2],
            axis=-1,
        )
