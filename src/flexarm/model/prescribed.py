r"""Prescribed joint motion: the arm's response when its actuated angles follow a law.

A perfect servo — infinitely stiff and fast — makes the actuated coordinates
(the joint angles with rigid joints, the motor angles with flexible joints)
follow a prescribed motion ``theta(t)`` exactly, whatever the links do. The rest
of the coordinates (modal coordinates, and the link angles behind flexible
joints) then obey the equations of motion partitioned into actuated ``a`` and
free ``f`` coordinates,

.. math:: M_{ff} \ddot q_f = Q_f - h_f - M_{fa} \ddot\theta, \qquad
          \tau = M_{aa} \ddot\theta + M_{af} \ddot q_f + h_a - Q_a,

where ``Q`` are the generalised forces other than inertia and the joint
torques (modal stiffness and damping, joint springs and friction, gravity) and ``h``
the velocity terms; ``tau`` is the torque the servo must deliver. This is the
constraint ``q_a = theta(t)`` imposed exactly (a Lagrange multiplier per joint,
which is ``tau``), not a stiff servo approximating it.

:func:`prescribed_dynamics` is the compiled kernel; :func:`prescribed_accelerations`
its NumPy reference (``FlexibleArm`` methods). The actuated coordinates are
contiguous in ``q`` and so are the free ones (:func:`free_range`).
"""

from __future__ import annotations

from typing import Any, Protocol

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .arrays import ArmArrays, Workspace
from .dynamics import joint_forces, mass_and_bias
from .dynamics._dense import ldlt_solve, rigid_joint_friction
from .dynamics._gravity import gravity_forces

__all__ = ["free_range", "prescribed_accelerations", "prescribed_dynamics"]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True, inline="always")
def free_range(model: ArmArrays, n_dof: int) -> tuple[int, int]:  # pragma: no cover - compiled
    """``(f0, f1)``: the free coordinates are ``q[f0:f1]``; the actuated ones the
    joint angles ``q[:n_links]`` (rigid joints, ``f0 = n_links, f1 = n_dof``)
    or the motor angles ``q[f1:]`` (flexible joints, ``f0 = 0``)."""
    n_links = model.link.shape[0]
    if model.joint.shape[0] > 0:
        return 0, int(model.mode_start[n_links])
    return n_links, n_dof


@nb.njit(cache=True, nogil=True)
def prescribed_dynamics(
    q: F64, dq: F64, acc: F64, model: ArmArrays, ws: Workspace, ddq: F64, tau: F64
) -> None:  # pragma: no cover - compiled
    """Accelerations and servo torques under prescribed actuated accelerations.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        The state; its actuated entries are the prescribed angles (rad) and
        rates (rad/s) at this instant.
    acc : ndarray, shape (n_links,)
        Prescribed accelerations of the actuated coordinates, rad/s**2.
    model : ArmArrays
    ws : Workspace
        Scratch (overwritten).
    ddq : ndarray, shape (n_dof,)
        Written: every coordinate's acceleration (``acc`` at the actuated ones).
    tau : ndarray, shape (n_links,)
        Written: the joint (motor) torques that produce the motion, N m.
    """
    n = q.shape[0]
    n_links = model.link.shape[0]
    mass_and_bias(q, dq, model, ws)
    M, rhs = ws.mass, ws.rhs
    for r in range(n):
        rhs[r] = -model.stiffness[r] * q[r] - model.damping[r] * dq[r] - ws.bias[r]
    if model.joint.shape[0] > 0:
        for i in range(n_links):
            tau[i] = 0.0
        joint_forces(q, dq, tau, model, rhs)
    else:
        rigid_joint_friction(dq, model, rhs)
    gravity_forces(q, model, rhs)
    f0, f1 = free_range(model, n)
    a0 = f1 if f0 == 0 else 0  # first actuated coordinate
    nf = f1 - f0
    L, b = ws.lmass, ws.lbias
    for r in range(nf):
        t = rhs[f0 + r]
        for i in range(n_links):
            t -= M[f0 + r, a0 + i] * acc[i]
        b[r] = t
        for c in range(r + 1):
            L[r, c] = M[f0 + r, f0 + c]
    if nf > 0:
        ldlt_solve(L[:nf, :nf], b[:nf], ws.inv_diag[:nf])
    for r in range(nf):
        ddq[f0 + r] = b[r]
    for i in range(n_links):
        ddq[a0 + i] = acc[i]
    for i in range(n_links):
        t = -rhs[a0 + i]
        for c in range(n):
            t += M[a0 + i, c] * ddq[c]
        tau[i] = t


class _Arm(Protocol):
    @property
    def n_links(self) -> int: ...
    @property
    def n_dof(self) -> int: ...
    @property
    def actuated_slice(self) -> slice: ...
    def mass_matrix(self, q: Any, *, backend: str = ...) -> NDArray[Any]: ...
    def velocity_terms(self, q: Any, dq: Any) -> NDArray[Any]: ...
    def generalized_forces(self, q: Any, dq: Any, tau: Any) -> NDArray[Any]: ...


def prescribed_accelerations(arm: _Arm, q: F64, dq: F64, acc: F64) -> tuple[F64, F64]:
    """NumPy reference of :func:`prescribed_dynamics`: ``(ddq, tau)`` for ``arm``
    (a :class:`flexarm.FlexibleArm`) at ``q, dq`` (shape (n_dof,)) with the
    actuated coordinates accelerating at ``acc`` (shape (n_links,), rad/s**2)."""
    M = np.asarray(arm.mass_matrix(q, backend="numpy"), dtype=float)
    rhs = arm.generalized_forces(q, dq, np.zeros(arm.n_links)) - arm.velocity_terms(q, dq)
    act = np.zeros(arm.n_dof, dtype=bool)
    act[arm.actuated_slice] = True
    ddq = np.zeros(arm.n_dof)
    ddq[act] = acc
    free = ~act
    ddq[free] = np.linalg.solve(M[np.ix_(free, free)], rhs[free] - M[np.ix_(free, act)] @ acc)
    tau = M[act] @ ddq - rhs[act]
    return ddq, np.asarray(tau, dtype=float)
