"""Compiled dynamics of the flexible arm: plain arrays in, plain arrays out.

These Numba functions are what the simulator calls millions of times. They take
the packed model :class:`ArmArrays` (built once by
:attr:`flexarm.FlexibleArm.arrays`) and a :class:`Workspace` allocated once, so
a call allocates nothing. The readable NumPy implementation in
:mod:`flexarm.arm` is their reference; the tests hold the two together.

The model (see :mod:`flexarm.arm` for the derivation): the kinetic energy of
link ``i`` in its clamped frame is ``1/2 nu' Mb(delta) nu`` with body velocity
``nu = (u_x, u_y, alpha_dot, delta_dot) = Jb qdot``; ``M = sum Jb' Mb Jb`` and
the velocity terms ``h = C(q, qdot) qdot = sum Jb' beta`` with ``beta`` the
body-frame inertial force at ``qddot = 0``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple, TypeVar

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = [
    "RUNTIME_FREE",
    "ArmArrays",
    "Workspace",
    "forward_dynamics",
    "joint_forces",
    "make_workspace",
    "mass_and_bias",
    "njit_runtime_free",
    "point_kinematics",
]

F64 = NDArray[np.float64]


def _runtime_free_options() -> dict[str, bool]:
    """Numba options that compile a function without its reference-counting
    runtime (NRT), for hot functions that allocate nothing.

    Array arguments are then passed without atomic incref/decref calls, which
    cost the dynamics kernel ~40 % of its time. ``_nrt`` is a Numba target
    option of long standing but not a documented one, so it is used only where
    this Numba version lists it.
    """
    from numba.core import cpu

    return {"_nrt": False} if hasattr(cpu.CPUTargetOptions, "_nrt") else {}


RUNTIME_FREE = _runtime_free_options()


_Fn = TypeVar("_Fn", bound=Callable[..., Any])


def njit_runtime_free(**options: Any) -> Callable[[_Fn], _Fn]:
    """``numba.njit(**options)`` compiled without the refcount runtime where
    this Numba supports it (for hot functions that allocate nothing)."""
    decorator: Callable[[_Fn], _Fn] = nb.njit(**options, **RUNTIME_FREE)  # type: ignore[call-overload]
    return decorator


# Columns of ArmArrays.link
LEN, MASS, STATIC, INERTIA, HUB_MASS = 0, 1, 2, 3, 4
N_LINK_COLUMNS = 5
# Columns of ArmArrays.joint
J_A1, J_A2, J_KSW, J_ASW, J_INERTIA, J_DAMPING, J_COUPLED = 0, 1, 2, 3, 4, 5, 6
J_HAS_FRICTION, J_FRICTION_ON_MOTOR, J_G1 = 7, 8, 9
N_JOINT_COLUMNS = 15


class ArmArrays(NamedTuple):
    """The arm packed as plain arrays for the compiled kernels.

    Attributes
    ----------
    mode_start : int64 array, shape (n_links + 1,)
        Index in ``q`` of link ``i``'s first modal coordinate; link ``i`` owns
        ``q[mode_start[i]:mode_start[i + 1]]``.
    link : float array, shape (n_links, 5)
        Per link: length (m), mass ``rho L`` (kg), static moment ``rho L**2 / 2``
        (kg m), inertia about the joint ``rho L**3 / 3 + hub_inertia`` (kg m**2),
        hub mass at the joint (kg).
    mass_integral, moment_integral, tip_deflection, tip_slope : float arrays, shape (n_dof,)
        ``int rho phi``, ``int rho x phi``, ``phi(L)``, ``phi'(L)`` at each modal
        coordinate's index in ``q`` (zero at joint indices).
    modal_mass : float array, shape (n_dof, n_dof)
        ``int rho phi_j phi_k`` within each link's block, zero elsewhere.
    stiffness, damping : float arrays, shape (n_dof,)
        Diagonal of the stiffness (N m) and damping (N m s) matrices.
    payload : float array, shape (2,)
        Payload mass (kg) and rotary inertia (kg m**2) at the last link's tip.
    joint : float array, shape (n_joints, 15)
        Flexible joints (``n_joints`` is 0 for rigid joints or ``n_links``), one
        row each: ``a1, a2, ksw, asw`` of the spring law (a linear joint is
        ``k, 0, 0, 0``), reflected motor inertia ``J_m``, motor viscous damping,
        rotor coupling flag (1: the rotor turns with its carrier link), friction
        flag, friction side (0: link, 1: motor), Makkar ``g1..g6``. The motor
        angle of joint ``i`` is ``q[mode_start[-1] + i]``.
    """

    mode_start: NDArray[np.int64]
    link: F64
    mass_integral: F64
    moment_integral: F64
    tip_deflection: F64
    tip_slope: F64
    modal_mass: F64
    stiffness: F64
    damping: F64
    payload: F64
    joint: F64


class Workspace(NamedTuple):
    """Scratch arrays for one thread of kernel calls (``n = n_dof``)."""

    mass: F64  # (n, n)
    bias: F64  # (n,)
    jac: F64  # (2, n) base/tip velocity Jacobian, link frame
    angle: F64  # (n,) gradient of the link's absolute angle
    rhs: F64  # (n,)
    rows: F64  # (3, n) rows of the body inertia times the body Jacobian


def make_workspace(n_dof: int) -> Workspace:
    """Allocate the scratch arrays for an arm with ``n_dof`` coordinates."""
    return Workspace(
        np.zeros((n_dof, n_dof)),
        np.zeros(n_dof),
        np.zeros((2, n_dof)),
        np.zeros(n_dof),
        np.zeros(n_dof),
        np.zeros((3, n_dof)),
    )


@nb.njit(cache=True, nogil=True, inline="always")
def _add_rotor(M: F64, A: F64, joint: F64, i: int, m: int) -> None:  # pragma: no cover
    """Add rotor ``i``'s kinetic energy ``1/2 J_m (carrier rate + dq_m)**2`` to ``M``.

    ``A`` is the gradient of the carrier's absolute angle (constant in ``q``), so
    the term adds no velocity forces. Without coupling only ``J_m dq_m**2 / 2``.
    """
    jm = joint[i, J_INERTIA]
    M[m, m] += jm
    if joint[i, J_COUPLED] != 0.0:
        n = M.shape[0]
        for r in range(n):
            M[r, m] += jm * A[r]
            M[m, r] += jm * A[r]
            for c in range(n):
                M[r, c] += jm * A[r] * A[c]


@nb.njit(cache=True, nogil=True, inline="always")
def mass_and_bias(
    q: F64, dq: F64, model: ArmArrays, ws: Workspace
) -> None:  # pragma: no cover - compiled
    """Fill ``ws.mass`` with ``M(q)`` and ``ws.bias`` with ``C(q, dq) dq``.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        Coordinates (rad, modal units) and their rates.
    model : ArmArrays
    ws : Workspace
        Overwritten: ``mass`` (n, n) and ``bias`` (n,); ``jac`` and ``angle`` are scratch.
    """
    n = q.shape[0]
    M, h, U, A = ws.mass, ws.bias, ws.jac, ws.angle
    ms = model.mode_start
    lk = model.link
    v, w = model.mass_integral, model.moment_integral
    tdef, tslope, md = model.tip_deflection, model.tip_slope, model.modal_mass
    n_links = lk.shape[0]
    for r in range(n):
        h[r] = 0.0
        A[r] = 0.0
        U[0, r] = 0.0
        U[1, r] = 0.0
        for c in range(n):
            M[r, c] = 0.0
    bx = 0.0
    by = 0.0
    has_joints = model.joint.shape[0] > 0
    if has_joints:
        _add_rotor(M, A, model.joint, 0, int(ms[n_links]))  # first rotor: carrier is the base
    for i in range(n_links):
        if i > 0:
            # Frame change from the tip of link i-1 to link i: gamma = theta_i + tip slope.
            gamma = q[i]
            for r in range(ms[i - 1], ms[i]):
                gamma += tslope[r] * q[r]
            cg, sg = np.cos(gamma), np.sin(gamma)
            for r in range(n):
                ux, uy = U[0, r], U[1, r]
                U[0, r] = cg * ux + sg * uy
                U[1, r] = -sg * ux + cg * uy
            bx, by = cg * bx + sg * by, -sg * bx + cg * by
            for r in range(ms[i - 1], ms[i]):
                A[r] += tslope[r]
            # A is now the angle gradient of the carrier of joint i's rotor
            if has_joints:
                _add_rotor(M, A, model.joint, i, int(ms[n_links]) + i)
            # hub mass at the joint, carried by the previous link's tip
            mh = lk[i, HUB_MASS]
            if mh != 0.0:
                for r in range(n):
                    h[r] += mh * (U[0, r] * bx + U[1, r] * by)
                    for c in range(n):
                        M[r, c] += mh * (U[0, r] * U[0, c] + U[1, r] * U[1, c])
        A[i] += 1.0
        L, m, cx, ia = lk[i, LEN], lk[i, MASS], lk[i, STATIC], lk[i, INERTIA]
        a0, a1 = ms[i], ms[i + 1]
        ad = 0.0
        for r in range(n):
            ad += A[r] * dq[r]
        vd = 0.0  # v . delta
        vdd = 0.0  # v . delta_dot
        e = 0.0  # tip deflection
        ed = 0.0  # tip deflection rate
        dmd = 0.0  # delta' Md delta
        dmdd = 0.0  # delta' Md delta_dot
        for r in range(a0, a1):
            vd += v[r] * q[r]
            vdd += v[r] * dq[r]
            e += tdef[r] * q[r]
            ed += tdef[r] * dq[r]
            for c in range(a0, a1):
                dmd += q[r] * md[r, c] * q[c]
                dmdd += q[r] * md[r, c] * dq[c]
        ialpha = ia + dmd
        # The rows of P = Mb Jb for (u_x, u_y, alpha), then M += Jb' P row by row
        # (contiguous, so the compiler vectorises it); the modal rows of P last.
        P = ws.rows
        for c in range(n):
            P[0, c] = m * U[0, c] - vd * A[c]
            P[1, c] = m * U[1, c] + cx * A[c]
            P[2, c] = -vd * U[0, c] + cx * U[1, c] + ialpha * A[c]
        for c in range(a0, a1):
            P[1, c] += v[c]
            P[2, c] += w[c]
        for r in range(n):
            u0, u1, ar = U[0, r], U[1, r], A[r]
            for c in range(n):
                M[r, c] += u0 * P[0, c] + u1 * P[1, c] + ar * P[2, c]
        for r in range(a0, a1):
            vr, wr = v[r], w[r]
            for c in range(n):
                M[r, c] += vr * U[1, c] + wr * A[c]
            for c in range(a0, a1):
                M[r, c] += md[r, c]
        # Body-frame inertial force at qddot = 0.
        ad2 = ad * ad
        beta_ux = m * bx - ad2 * cx - 2.0 * ad * vdd
        beta_uy = m * by - ad2 * vd
        beta_al = -bx * vd + 2.0 * ad * dmdd + cx * by
        for r in range(n):
            h[r] += U[0, r] * beta_ux + U[1, r] * beta_uy + A[r] * beta_al
        for r in range(a0, a1):
            acc = v[r] * by
            for c in range(a0, a1):
                acc -= ad2 * md[r, c] * q[c]
            h[r] += acc
        # Tip of link i, still in link i's frame.
        for c in range(n):
            U[0, c] -= e * A[c]
            U[1, c] += L * A[c]
        for r in range(a0, a1):
            U[1, r] += tdef[r]
        bx += -ad2 * L - 2.0 * ad * ed
        by += -ad2 * e
    # Payload at the last tip: point mass, and rotary inertia turning with the tip slope.
    mp, jp = model.payload[0], model.payload[1]
    a0, a1 = ms[n_links - 1], ms[n_links]
    if mp != 0.0:
        for r in range(n):
            h[r] += mp * (U[0, r] * bx + U[1, r] * by)
            for c in range(n):
                M[r, c] += mp * (U[0, r] * U[0, c] + U[1, r] * U[1, c])
    if jp != 0.0:
        for r in range(a0, a1):
            A[r] += tslope[r]
        for r in range(n):
            for c in range(n):
                M[r, c] += jp * A[r] * A[c]


@nb.njit(cache=True, nogil=True, inline="always")
def _cholesky_solve(M: F64, b: F64, out: F64) -> None:  # pragma: no cover - compiled
    """Solve ``M out = b`` for symmetric positive definite ``M``.

    ``M``'s lower triangle is overwritten by the Cholesky factor and its
    diagonal by the factor's reciprocal diagonal (one division per row).
    """
    n = M.shape[0]
    for j in range(n):
        s = M[j, j]
        for k in range(j):
            s -= M[j, k] * M[j, k]
        inv = 1.0 / np.sqrt(s)
        M[j, j] = inv
        for i in range(j + 1, n):
            t = M[i, j]
            for k in range(j):
                t -= M[i, k] * M[j, k]
            M[i, j] = t * inv
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= M[i, k] * out[k]
        out[i] = t * M[i, i]
    for i in range(n - 1, -1, -1):
        t = out[i]
        for k in range(i + 1, n):
            t -= M[k, i] * out[k]
        out[i] = t * M[i, i]


@nb.njit(cache=True, nogil=True, inline="always")
def joint_forces(q: F64, dq: F64, tau: F64, model: ArmArrays, rhs: F64) -> None:  # pragma: no cover
    """Add the flexible joints' generalised forces to ``rhs``.

    Spring torque ``tau_s(q_m - q)`` on the link angle and its reaction on the
    motor, the input torque and motor damping on the motor, friction on the
    link (or motor) side.
    """
    jt = model.joint
    m0 = model.mode_start[model.mode_start.shape[0] - 1]
    for i in range(jt.shape[0]):
        m = m0 + i
        d = q[m] - q[i]
        ts = (jt[i, J_A1] + jt[i, J_A2] * d * d) * d
        if jt[i, J_KSW] != 0.0:
            ts -= jt[i, J_KSW] * np.exp(-jt[i, J_ASW] * d * d) * d
        rhs[i] += ts
        rhs[m] += tau[i] - ts - jt[i, J_DAMPING] * dq[m]
        if jt[i, J_HAS_FRICTION] != 0.0:
            on_motor = jt[i, J_FRICTION_ON_MOTOR] != 0.0
            k = m if on_motor else i
            v = dq[k]
            g = J_G1
            f = (
                jt[i, g] * (np.tanh(jt[i, g + 1] * v) - np.tanh(jt[i, g + 2] * v))
                + jt[i, g + 3] * np.tanh(jt[i, g + 4] * v)
                + jt[i, g + 5] * v
            )
            rhs[k] -= f


@nb.njit(cache=True, nogil=True, inline="always")
def forward_dynamics(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """``ddq = M(q)^-1 (B tau - C(q, dq) dq - K q - D dq + joint forces)``, into ``ddq``.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
    tau : ndarray, shape (n_links,)
        Joint torques in N m: on the joint angles for rigid joints, on the motor
        angles for flexible joints.
    model : ArmArrays
    ws : Workspace
        Scratch (overwritten).
    ddq : ndarray, shape (n_dof,)
        Output accelerations.
    """
    mass_and_bias(q, dq, model, ws)
    n = q.shape[0]
    rhs = ws.rhs
    for r in range(n):
        rhs[r] = -ws.bias[r] - model.stiffness[r] * q[r] - model.damping[r] * dq[r]
    if model.joint.shape[0] > 0:
        joint_forces(q, dq, tau, model, rhs)
    else:
        for r in range(tau.shape[0]):
            rhs[r] += tau[r]
    _cholesky_solve(ws.mass, rhs, ddq)


@njit_runtime_free(cache=True, nogil=True)
def point_kinematics(
    q: F64, dq: F64, model: ArmArrays, link: int, distance: float, phi: F64, out: F64
) -> None:  # pragma: no cover - compiled
    """Position and velocity of a point on a link, deflection included.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
    model : ArmArrays
    link : int
        0-based link index.
    distance : float
        Distance along the undeformed link from its joint, m.
    phi : ndarray, shape (n_modes of ``link``,)
        Mode shapes of ``link`` evaluated at ``distance``.
    out : ndarray, shape (4,)
        Written: ``x, y`` (m) and ``vx, vy`` (m/s) in the base frame.
    """
    ms = model.mode_start
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
        w = 0.0
        wd = 0.0
        if i < link:
            x = model.link[i, LEN]
            for r in range(a0, a1):
                w += model.tip_deflection[r] * q[r]
                wd += model.tip_deflection[r] * dq[r]
        else:
            x = distance
            for r in range(a0, a1):
                w += phi[r - a0] * q[r]
                wd += phi[r - a0] * dq[r]
        c, s = np.cos(alpha), np.sin(alpha)
        px += c * x - s * w
        py += s * x + c * w
        # d/dt R(alpha) [x, w] = alpha_dot R S [x, w] + R [0, wd],  S = [[0, -1], [1, 0]]
        vx += alpha_dot * (-c * w - s * x) - s * wd
        vy += alpha_dot * (-s * w + c * x) + c * wd
        if i < link:
            for r in range(a0, a1):
                alpha += model.tip_slope[r] * q[r]
                alpha_dot += model.tip_slope[r] * dq[r]
    out[0] = px
    out[1] = py
    out[2] = vx
    out[3] = vy
