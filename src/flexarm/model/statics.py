r"""The arm at rest under gravity: :func:`~flexarm.model.statics.equilibrium` and its
:class:`~flexarm.model.statics.Equilibrium`.

Holding joint angles ``theta`` (the link-side angles) against gravity
(:mod:`flexarm.model.gravity`), the arm comes to rest where every generalised
force other than inertia vanishes, ``Q(q, 0, tau) = 0``:

* the modal coordinates carry the links' static deflection (their sag),
  ``K delta = -dV/d delta``, solved by Newton's method from straight links (one
  step without geometric stiffening, where ``V`` is linear in ``delta``);
* the joint torques hold the weight, ``tau = dV/d theta`` at that sag; with
  flexible joints each spring carries it at a deflection ``tau_s(Delta) = tau``
  and the motor stands at ``theta + Delta``.

The tangent stiffness there, ``K_T = K + d2V/dq2`` (joint springs at their
static deflection), with the mass matrix gives the small vibrations about the
posture. A standing link (gravity pointing from its tip to its joint) is
softened by its weight and beyond its buckling load (Greenhill's
``(rho g L**3)_cr = 7.837 EI`` for a uniform column under its own weight; less
with a tip mass) the straight link is no equilibrium one can hold:
``K_T`` with the actuated coordinates held is then not positive definite.
:func:`equilibrium` raises :class:`UnstableEquilibriumError` there (or, with
``require_stable=False``, returns the result flagged ``stable=False``), so a
simulation or a linearisation is never started about it unknowingly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_int, check_real
from ..errors import InvalidValueError
from .gravity import gravity_stiffness

__all__ = ["Equilibrium", "UnstableEquilibriumError", "equilibrium"]

F64 = NDArray[np.float64]

_OWNER = "FlexibleArm.equilibrium"


@dataclass(frozen=True)
class Equilibrium:
    """The arm at rest holding joint angles against gravity (module docstring).

    Attributes
    ----------
    q : ndarray, shape (n_dof,)
        The configuration: the held joint angles (rad), each link's static
        modal deflections, and with flexible joints the motor angles.
    deflections : tuple of ndarray
        Link by link, its modal coordinates (``q[arm.modal_slice(i)]``).
    torques : ndarray, shape (n_links,)
        The joint (motor) torques that hold the posture, N m: the operating
        input of a linearisation about it.
    stiffness : ndarray, shape (n_dof, n_dof)
        The tangent stiffness ``K + d2V/dq2``, joint springs at their static
        deflection (N m/rad; modal units).
    eigenvalues : ndarray
        Increasing squared natural frequencies (1/s**2) of the arm about the
        posture with the actuated coordinates held (joint angles, or motor
        angles with flexible joints); a negative one is a buckled direction.
    stable : bool
        Whether all ``eigenvalues`` are positive: the held posture is stable.
    tip : ndarray, shape (2,)
        The deflected tip, m, base frame.
    residual : float
        Largest generalised force left at ``q`` (N m; modal units).
    """

    q: F64
    deflections: tuple[F64, ...]
    torques: F64
    stiffness: F64
    eigenvalues: F64
    stable: bool
    tip: F64
    residual: float

    @property
    def frequencies(self) -> F64:
        """Natural frequencies about the posture, actuated coordinates held, rad/s
        (increasing; NaN where the posture is unstable)."""
        lam = self.eigenvalues
        out: F64 = np.sqrt(np.where(lam >= 0.0, lam, np.nan))
        return out


class UnstableEquilibriumError(InvalidValueError):
    """The held posture is not stable: a link beyond its buckling load
    (:func:`equilibrium`). ``equilibrium`` holds the flagged result."""

    def __init__(self, message: str, equilibrium: Equilibrium) -> None:
        super().__init__(message)
        self.equilibrium = equilibrium


def equilibrium(
    arm: Any,
    q_joints: ArrayLike,
    *,
    require_stable: bool = True,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> Equilibrium:
    """The static equilibrium of ``arm`` holding the joint angles ``q_joints``.

    Parameters
    ----------
    arm : FlexibleArm
        Any arm; without gravity the links stay straight and the torques are zero.
    q_joints : array_like, shape (n_links,)
        The held (link-side) joint angles, rad.
    require_stable : bool
        Raise :class:`UnstableEquilibriumError` if the held posture is unstable
        (default); False returns it flagged ``stable=False``.
    tol : float
        Newton's method stops when a step changes no modal coordinate by more
        than ``tol`` times (1 + the largest of them), or when the forces left
        are below ``tol`` times the elastic and gravity forces that balance.
    max_iter : int
        Newton steps at the most.

    Returns
    -------
    Equilibrium

    Raises
    ------
    UnstableEquilibriumError
        With ``require_stable``, if the tangent stiffness with the actuated
        coordinates held is not positive definite (a standing link beyond its
        buckling load).
    InvalidValueError
        If Newton's method does not converge in ``max_iter`` steps.
    """
    theta = check_array(q_joints, "q_joints", _OWNER, shape=(arm.n_links,), real=True)
    tol = check_real(tol, "tol", _OWNER, positive=True)
    max_iter = check_int(max_iter, "max_iter", _OWNER, minimum=1)
    n, n_links = arm.n_dof, arm.n_links
    q = np.zeros(n)
    q[:n_links] = theta
    if arm.joints is not None:
        q[arm.motor_slice] = theta
    modal = np.zeros(n, dtype=bool)
    modal[n_links : int(arm.arrays.mode_start[-1])] = True
    zero_rate, zero_tau = np.zeros(n), np.zeros(n_links)
    k_modal = np.diag(arm.arrays.stiffness)[np.ix_(modal, modal)]
    k_diag = np.diag(k_modal)
    for it in range(max_iter if modal.any() else 0):
        r = arm.generalized_forces(q, zero_rate, zero_tau)[modal]
        elastic = k_diag * q[modal]
        load = np.max(np.abs(elastic)) + np.max(np.abs(r + elastic))  # the forces that balance
        if it > 0 and np.max(np.abs(r)) <= tol * load:
            break  # converged in force (also where the stiffness is nearly singular)
        jac = k_modal + gravity_stiffness(arm, q)[np.ix_(modal, modal)]
        step = np.linalg.solve(jac, r)
        q[modal] += step
        if np.max(np.abs(step)) <= tol * (1.0 + np.max(np.abs(q[modal]))):
            break
    else:
        if modal.any():
            raise InvalidValueError(
                f"The 'q_joints' parameter of {_OWNER} has no static equilibrium that "
                f"Newton's method finds in {max_iter} steps (links too flexible for their "
                f"weight: a sag beyond the model's small deflections?). Got {theta.tolist()} rad."
            )
    torques = -arm.generalized_forces(q, zero_rate, zero_tau)[:n_links]
    k_t = np.diag(np.asarray(arm.arrays.stiffness, dtype=float))
    if arm.joints is not None:
        m0 = arm.motor_slice.start
        for i, jt in enumerate(arm.joints):
            d = _spring_deflection(jt, float(torques[i]))
            q[m0 + i] = theta[i] + d
            k = float(jt.tangent_stiffness(d))
            k_t[i, i] += k
            k_t[m0 + i, m0 + i] += k
            k_t[i, m0 + i] -= k
            k_t[m0 + i, i] -= k
    k_t = k_t + gravity_stiffness(arm, q)
    residual = arm.generalized_forces(q, zero_rate, torques)
    keep = np.ones(n, dtype=bool)
    keep[arm.actuated_slice] = False
    lam = np.zeros(0)
    if keep.any():
        import scipy.linalg  # loaded on first use: import flexarm stays light

        mass = np.asarray(arm.mass_matrix(q), dtype=float)[np.ix_(keep, keep)]
        lam = scipy.linalg.eigh(k_t[np.ix_(keep, keep)], mass, eigvals_only=True)
    stable = bool(np.all(lam > 0.0))
    result = Equilibrium(
        q=q,
        deflections=tuple(q[arm.modal_slice(i)].copy() for i in range(n_links)),
        torques=torques,
        stiffness=k_t,
        eigenvalues=lam,
        stable=stable,
        tip=np.asarray(arm.tip_position(q), dtype=float),
        residual=float(np.max(np.abs(residual))) if n else 0.0,
    )
    if require_stable and not stable:
        raise UnstableEquilibriumError(
            f"The 'q_joints' parameter of {_OWNER} gives a posture that is not stable: "
            f"its tangent stiffness with the joints held has a negative eigenvalue "
            f"({lam[0]:.4g} 1/s**2), as a link standing beyond its buckling load "
            f"(Euler/Greenhill) has. Got {theta.tolist()} rad.",
            result,
        )
    return result


def _spring_deflection(joint: Any, torque: float, max_iter: int = 50) -> float:
    """The deflection ``Delta`` (rad) at which ``joint``'s spring carries ``torque``
    (N m): Newton's method from the linearised spring."""
    k0 = float(joint.tangent_stiffness(0.0))
    d = torque / k0
    for _ in range(max_iter):
        step = (float(joint.torque(d)) - torque) / float(joint.tangent_stiffness(d))
        d -= step
        if abs(step) <= 1e-14 * (1.0 + abs(d)):
            return d
    raise InvalidValueError(
        f"The 'q_joints' parameter of {_OWNER} needs a joint torque of {torque:.6g} N m "
        "that the joint spring cannot carry (its law has no deflection for it)."
    )
