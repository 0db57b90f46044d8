"""The NumPy reference of the arm's Lagrangian: one body at a time.

Every body (link, hub, rotor, payload) contributes ``T = 1/2 (Jb dq)' Mb (Jb dq)``
with its body Jacobian ``Jb(q)`` and body inertia ``Mb(q)``; then
``M = sum Jb' Mb Jb`` and, by d'Alembert, the velocity terms are
``C(q, dq) dq = sum Jb' beta`` with ``beta`` the body-frame inertial force at
``qddot = 0``. The derivation is in :mod:`flexarm.model.arm`; the compiled
kernels of :mod:`flexarm.model.dynamics` compute the same sums and the tests
hold the two together (and both against an independent SymPy derivation).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from .arrays import ArmArrays

__all__ = ["Body", "LagrangianArm", "body_terms"]

Body = tuple[NDArray[Any], NDArray[Any], NDArray[Any] | None]
"""``(Jb, Mb, beta)``: body Jacobian (k, n_dof), body inertia (k, k), inertial
force at ``qddot = 0`` (k,) or None."""


class _Joint(Protocol):
    @property
    def motor_inertia(self) -> float: ...


class _Link(Protocol):
    @property
    def hub_mass(self) -> float: ...


class LagrangianArm(Protocol):
    """What :func:`body_terms` reads of an arm (:class:`flexarm.FlexibleArm`)."""

    @property
    def n_dof(self) -> int: ...
    @property
    def n_links(self) -> int: ...
    @property
    def arrays(self) -> ArmArrays: ...
    @property
    def links(self) -> Sequence[_Link]: ...
    @property
    def joints(self) -> Sequence[_Joint] | None: ...
    @property
    def rotor_coupling(self) -> bool: ...
    @property
    def motor_slice(self) -> slice: ...
    @property
    def payload_mass(self) -> float: ...
    @property
    def payload_inertia(self) -> float: ...

    def modal_slice(self, link: int) -> slice: ...


def body_terms(arm: LagrangianArm, q: NDArray[Any], dq: NDArray[Any] | None) -> list[Body]:
    """Per body: (Jb, Mb, beta) with ``T = 1/2 (Jb dq)' Mb (Jb dq)`` and the
    inertial force ``Jb' beta`` at ``qddot = 0`` (``beta`` is None when
    ``dq`` is None). Works for real and complex ``q`` (complex step)."""
    n, N = arm.n_dof, arm.n_links
    dtype = np.result_type(q, float)
    a = arm.arrays
    U = np.zeros((2, n), dtype=dtype)  # velocity Jacobian of the current joint, link frame
    A = np.zeros(n)  # gradient of the link's absolute angle (constant)
    b = np.zeros(2, dtype=dtype)  # inertial acceleration of the joint at qddot = 0
    bodies: list[tuple[Any, ...]] = []
    ad = 0.0
    for i in range(N):
        s = arm.modal_slice(i)
        if i > 0:
            prev = arm.modal_slice(i - 1)
            gamma = q[i] + a.tip_slope[prev] @ q[prev]
            Rt = np.array([[np.cos(gamma), np.sin(gamma)], [-np.sin(gamma), np.cos(gamma)]])
            U, b = Rt @ U, Rt @ b
            A = A.copy()
            A[prev] += a.tip_slope[prev]
        if arm.joints is not None:
            # rotor i spins at (carrier angle rate + dq_mi); A is the carrier's gradient
            row = A.copy() if arm.rotor_coupling else np.zeros(n)
            row[arm.motor_slice.start + i] += 1.0
            jm = arm.joints[i].motor_inertia
            bodies.append((row[None, :], np.array([[jm]]), None if dq is None else np.zeros(1)))
        if i > 0:
            mh = arm.links[i].hub_mass
            bodies.append((U.copy(), mh * np.eye(2), None if dq is None else mh * b))
        A = A.copy()
        A[i] += 1.0
        L, m, cx, ia, _ = a.link[i]
        delta = q[s]
        v, w, mdelta = a.mass_integral[s], a.moment_integral[s], a.modal_mass[s, s]
        nm = delta.shape[0]
        D = np.zeros((nm, n))
        D[:, s] = np.eye(nm)
        Jb = np.vstack([U, A[None, :], D])
        Mb = np.zeros((3 + nm, 3 + nm), dtype=dtype)
        Mb[0, 0] = Mb[1, 1] = m
        Mb[0, 2] = Mb[2, 0] = -(v @ delta)
        Mb[1, 2] = Mb[2, 1] = cx
        Mb[1, 3:] = Mb[3:, 1] = v
        Mb[2, 2] = ia + delta @ mdelta @ delta
        Mb[2, 3:] = Mb[3:, 2] = w
        Mb[3:, 3:] = mdelta
        beta = None
        e = a.tip_deflection[s] @ delta
        if dq is not None:
            ad = A @ dq
            dd = dq[s]
            beta = np.concatenate(
                [
                    [m * b[0] - ad**2 * cx - 2 * ad * (v @ dd)],
                    [m * b[1] - ad**2 * (v @ delta)],
                    [-b[0] * (v @ delta) + 2 * ad * (delta @ mdelta @ dd) + cx * b[1]],
                    v * b[1] - ad**2 * (mdelta @ delta),
                ]
            )
            ed = a.tip_deflection[s] @ dd
            b = b + np.array([-(ad**2) * L - 2 * ad * ed, -(ad**2) * e])
        bodies.append((Jb, Mb, beta))
        U = U + np.vstack([-e * A, L * A])
        U[1, s] += a.tip_deflection[s]
    s = arm.modal_slice(N - 1)
    Ap = A.copy()
    Ap[s] += a.tip_slope[s]
    mp, jp = arm.payload_mass, arm.payload_inertia
    bodies.append((U.copy(), mp * np.eye(2), None if dq is None else mp * b))
    bodies.append((Ap[None, :], np.array([[jp]]), None if dq is None else np.zeros(1)))
    return bodies


# ---------------------------------------------------------------- dynamics
