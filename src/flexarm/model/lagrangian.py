"""The NumPy reference of the arm's Lagrangian: one body at a time.

Every body (link, hub, rotor, payload) contributes ``T = 1/2 (Jb dq)' Mb (Jb dq)``
with its body Jacobian ``Jb(q)`` and body inertia ``Mb(q)``; then
``M = sum Jb' Mb Jb`` and, by d'Alembert, the velocity terms are
``C(q, dq) dq = sum Jb' beta`` with ``beta`` the body-frame inertial force at
``qddot = 0``. The kinematic map is in :mod:`flexarm.model.arm`, the
foreshortening terms are derived in ``_link_body``; the compiled
kernels of :mod:`flexarm.model.dynamics` compute the same sums and the tests
hold the two together (and both against an independent SymPy derivation).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from .arrays import HUB_MASS, TIP_INERTIA, ArmArrays
from .packing import ArmParameters

__all__ = [
    "Body",
    "LagrangianArm",
    "body_terms",
    "christoffel_matrix",
    "mass_matrix_derivatives",
]

Body = tuple[NDArray[Any], NDArray[Any], NDArray[Any] | None]
"""``(Jb, Mb, beta)``: body Jacobian (k, n_dof), body inertia (k, k), inertial
force at ``qddot = 0`` (k,) or None."""


class LagrangianArm(ArmParameters, Protocol):
    """What :func:`body_terms` reads of an arm (:class:`flexarm.FlexibleArm`)."""

    @property
    def arrays(self) -> ArmArrays: ...
    @property
    def motor_slice(self) -> slice: ...

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
    zero = np.zeros(1)
    for i in range(N):
        s = arm.modal_slice(i)
        if i > 0:
            prev = arm.modal_slice(i - 1)
            gamma = q[i] + a.tip_slope[prev] @ q[prev]
            Rt = np.array([[np.cos(gamma), np.sin(gamma)], [-np.sin(gamma), np.cos(gamma)]])
            U, b = Rt @ U, Rt @ b
            A = A.copy()
            A[prev] += a.tip_slope[prev]
            # the tip body of link i-1 turns with its tip (its mass is at the joint, below)
            jt_tip = a.link[i - 1, TIP_INERTIA]
            bodies.append((A[None, :].copy(), np.array([[jt_tip]]), None if dq is None else zero))
        if arm.joints is not None:
            # rotor i spins at N_i (carrier angle rate / N_i + dq_i), dq_i its motor angle
            # (flexible joints) or joint angle (rigid), link side:
            # T = 1/2 J_m (carrier rate / N_i + dq_i)**2; A is the carrier's gradient
            jt = arm.joints[i]
            row = A / jt.gear_ratio if arm.rotor_coupling else np.zeros(n)
            row[arm.motor_slice.start + i if arm.has_flexible_joints else i] += 1.0
            jm = jt.motor_inertia
            bodies.append((row[None, :], np.array([[jm]]), None if dq is None else zero))
        if i > 0:  # the hub at joint i and the tip body of link i-1
            mh = a.link[i, HUB_MASS]
            bodies.append((U.copy(), mh * np.eye(2), None if dq is None else mh * b))
        A = A.copy()
        A[i] += 1.0
        L, m, cx, ia = a.link[i, :HUB_MASS]
        delta = q[s]
        nm = delta.shape[0]
        D = np.zeros((nm, n))
        D[:, s] = np.eye(nm)
        Jb = np.vstack([U, A[None, :], D])
        dd = None if dq is None else dq[s]
        ad = 0.0 if dq is None else A @ dq
        Mb, beta = _link_body(a, s, L, m, cx, ia, delta, dd, ad, b)
        bodies.append((Jb, Mb, beta))
        # the tip, in link i's frame: (L - u(L), w(L)), with u(L) = 1/2 delta' S(L) delta
        e = a.tip_deflection[s] @ delta
        sl = a.shortening_tip[s, s] @ delta
        ul = 0.5 * (delta @ sl)
        if dd is not None:
            ed = a.tip_deflection[s] @ dd
            b = b + np.array(
                [
                    -(ad**2) * (L - ul) - 2 * ad * ed - dd @ a.shortening_tip[s, s] @ dd,
                    -(ad**2) * e - 2 * ad * (sl @ dd),
                ]
            )
        U = U + np.vstack([-e * A, (L - ul) * A])
        U[0, s] -= sl
        U[1, s] += a.tip_deflection[s]
    s = arm.modal_slice(N - 1)
    Ap = A.copy()
    Ap[s] += a.tip_slope[s]
    mp, jp = a.payload[0], a.payload[1]  # with the last link's tip body
    bodies.append((U.copy(), mp * np.eye(2), None if dq is None else mp * b))
    bodies.append((Ap[None, :], np.array([[jp]]), None if dq is None else np.zeros(1)))
    return bodies


def _link_body(
    a: ArmArrays,
    s: slice,
    L: float,
    m: float,
    cx: float,
    ia: float,
    delta: NDArray[Any],
    dd: NDArray[Any] | None,
    ad: Any,
    b: NDArray[Any],
) -> tuple[NDArray[Any], NDArray[Any] | None]:
    """Body inertia ``Mb`` and inertial force ``beta`` of one link.

    The link's points are at ``(x - u(x), w(x))`` in its clamped frame, whose
    origin moves with velocity ``(u_x, u_y)`` (frame components) and
    acceleration ``b`` at ``qddot = 0``, and which turns at ``ad``. With
    ``P(x) = [[1, 0, -w, -(S(x) delta)'], [0, 1, x - u, phi']]`` the point's
    velocity is ``P nu``, ``nu = (u_x, u_y, alpha_dot, delta_dot)``, so
    ``Mb = int rho P' P dx`` and ``beta = int rho P' a0 dx`` with ``a0`` the
    point's acceleration at ``qddot = 0``::

        a0 = b + (-ad**2 (x - u) - 2 ad w_dot - delta_dot' S(x) delta_dot,
                  -ad**2 w + 2 ad (-u_dot))

    Without geometric stiffening ``u = 0`` and only the first terms remain.
    """
    v, w, md = a.mass_integral[s], a.moment_integral[s], a.modal_mass[s, s]
    nm = delta.shape[0]
    vd, dmd = v @ delta, delta @ md @ delta
    Mb = np.zeros((3 + nm, 3 + nm), dtype=np.result_type(delta, float))
    Mb[0, 0] = Mb[1, 1] = m
    Mb[0, 2] = -vd
    Mb[1, 2] = cx
    Mb[1, 3:] = v
    Mb[2, 2] = ia + dmd
    Mb[2, 3:] = w
    Mb[3:, 3:] = md
    beta = None
    if dd is not None:
        vdd = v @ dd
        beta = np.concatenate(
            [
                [m * b[0] - ad**2 * cx - 2 * ad * vdd],
                [m * b[1] - ad**2 * vd],
                [-b[0] * vd + 2 * ad * (delta @ md @ dd) + cx * b[1]],
                v * b[1] - ad**2 * (md @ delta),
            ]
        )
    if a.shortening_quartic.shape[1] and nm:
        # foreshortening: y = int rho S delta, p = delta' y = 2 int rho u,
        # R[a, b] = int rho phi_a (S delta)_b, Q[b, d] = int rho (S delta)_b (S delta)_d
        Sm, X = a.shortening_mass[s, s], a.shortening_moment[s, s]
        T3 = a.shortening_cubic[s, :nm, :nm]
        T4 = a.shortening_quartic[s, :nm, :nm, :nm]
        y = Sm @ delta
        p = delta @ y
        R = T3 @ delta
        Q = np.einsum("badc,a,c->bd", T4, delta, delta)
        Mb[0, 3:] = Mb[3:, 0] = -y
        Mb[1, 2] = cx - 0.5 * p
        Mb[2, 2] += -(delta @ X @ delta) + 0.25 * (delta @ Q @ delta)
        Mb[2, 3:] += R.T @ delta - 0.5 * (R @ delta)
        Mb[3:, 3:] += Q
        if beta is not None and dd is not None:
            Rd = T3 @ dd
            Qd = np.einsum("badc,a,c->bd", T4, delta, dd)
            beta[0] += 0.5 * ad**2 * p - dd @ Sm @ dd
            beta[1] += -2 * ad * (y @ dd)
            beta[2] += (
                -0.5 * b[1] * p
                + delta @ Rd @ dd
                - 2 * ad * (delta @ X @ dd - 0.5 * (delta @ Q @ dd))
            )
            beta[3:] += (
                -2 * ad * (R @ dd)
                - b[0] * y
                + ad**2 * (X @ delta - 0.5 * (Q @ delta))
                + 2 * ad * (R.T @ dd)
                + Qd @ dd
            )
    Mb[2:, 1] = Mb[1, 2:]
    Mb[3:, 2] = Mb[2, 3:]
    Mb[2, 0] = Mb[0, 2]
    return Mb, beta


# ---------------------------------------------------------------- dynamics


def mass_matrix_derivatives(
    mass_matrix: Callable[[NDArray[Any]], NDArray[Any]], q: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``dM/dq_k`` for every ``k``, shape ``(n, n, n)`` (k first), by complex-step
    differentiation of ``mass_matrix`` (exact to rounding) at ``q`` (shape (n,))."""
    n = q.shape[0]
    step = 1e-30
    out = np.empty((n, n, n))
    for k in range(n):
        qc = q.astype(complex)
        qc[k] += 1j * step
        out[k] = mass_matrix(qc).imag / step
    return out


def christoffel_matrix(dM: NDArray[np.float64], dq: NDArray[Any]) -> NDArray[np.float64]:
    """The Coriolis matrix from Christoffel symbols of the first kind,
    ``C_kj = sum_i 1/2 (dM_kj/dq_i + dM_ki/dq_j - dM_ij/dq_k) dq_i``, with
    ``dM[i, k, j] = dM_kj / dq_i`` (:func:`mass_matrix_derivatives`)."""
    t1 = np.einsum("ikj,i->kj", dM, dq)
    t2 = np.einsum("jki,i->kj", dM, dq)
    t3 = np.einsum("kij,i->kj", dM, dq)
    out: NDArray[np.float64] = 0.5 * (t1 + t2 - t3)
    return out
