"""The dense kernel: the mass matrix of the arm, its factorisation and solve.

Internal: the bare kernels behind :func:`flexarm.model.dynamics.forward_dynamics_dense`,
:func:`flexarm.model.dynamics.mass_and_bias` and
:func:`flexarm.model.dynamics.joint_forces` (that module describes the algorithms).

The coordinates are taken in the link-major order of
:func:`flexarm.model.dynamics.local_order` (joint 1, link 1's modes, joint 2, ...), in
which each link's body Jacobian is zero beyond a prefix: :func:`assemble_local`
forms only the lower triangle of ``M`` and :func:`ldlt_solve` solves with an
``L D L'`` factorisation.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .. import arrays as layout
from ..arrays import (
    HUB_MASS,
    INERTIA,
    LEN,
    MASS,
    ROTOR_COUPLING,
    ROTOR_FRICTION,
    ROTOR_G1,
    ROTOR_INERTIA,
    STATIC,
    TIP_INERTIA,
    ArmArrays,
    Workspace,
)
from ._gravity import gravity_forces
from ._link_terms import link_foreshortening, link_sums

__all__ = [
    "assemble_local",
    "forward_dynamics_dense",
    "generalized_forces",
    "joint_forces",
    "ldlt_factor",
    "ldlt_solve",
    "mass_and_bias",
    "rigid_joint_friction",
]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True, inline="always")
def joint_forces(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, rhs: F64
) -> None:  # pragma: no cover
    """Add the flexible joints' generalised forces to ``rhs``.

    Spring torque ``tau_s(q_m - q)`` and the damper across it,
    ``c (dq_m - dq)``, on the link angle and their reaction on the motor, the input
    torque and motor damping on the motor, friction on each joint's side (link or
    motor).
    """
    jt = arrays.joint
    m0 = arrays.mode_start[arrays.mode_start.shape[0] - 1]
    for i in range(jt.shape[0]):
        m = m0 + i
        d = q[m] - q[i]
        ts = (jt[i, layout.J_A1] + jt[i, layout.J_A2] * d * d) * d
        if jt[i, layout.J_KSW] != 0.0:
            ts -= jt[i, layout.J_KSW] * np.exp(-jt[i, layout.J_ASW] * d * d) * d
        if jt[i, layout.J_SPRING_DAMPING] != 0.0:  # the damper across the spring
            ts += jt[i, layout.J_SPRING_DAMPING] * (dq[m] - dq[i])
        rhs[i] += ts
        rhs[m] += tau[i] - ts - jt[i, layout.J_DAMPING] * dq[m]
        if jt[i, layout.J_HAS_FRICTION] != 0.0:
            on_motor = jt[i, layout.J_FRICTION_ON_MOTOR] != 0.0
            k = m if on_motor else i
            rhs[k] -= _makkar(jt[i], layout.J_G1, dq[k])


@nb.njit(cache=True, nogil=True, inline="always")
def _makkar(row: F64, g: int, v: float) -> float:  # pragma: no cover - compiled
    """Makkar's friction law with ``g1..g6`` at ``row[g:g + 6]``, at the rate ``v``."""
    f: float = (
        row[g] * (np.tanh(row[g + 1] * v) - np.tanh(row[g + 2] * v))
        + row[g + 3] * np.tanh(row[g + 4] * v)
        + row[g + 5] * v
    )
    return f


@nb.njit(cache=True, nogil=True, inline="always")
def rigid_joint_friction(dq: F64, arrays: ArmArrays, rhs: F64) -> None:  # pragma: no cover
    """Subtract the rigid joints' friction (:class:`flexarm.model.joints.RigidJoint`,
    on the joint rates) from ``rhs``; their viscous damping is in ``arrays.damping``."""
    lk = arrays.link
    for i in range(lk.shape[0]):
        if lk[i, ROTOR_FRICTION] != 0.0:
            rhs[i] -= _makkar(lk[i], ROTOR_G1, dq[i])


@nb.njit(cache=True, nogil=True, inline="always")
def _add_rotor(
    inertia: float, coupling: float, k: int, rows: int, A: F64, M: F64
) -> None:  # pragma: no cover - compiled
    """A rotor of ``inertia`` (kg m**2) on coordinate ``k``, turning at ``coupling``
    (1 / N) times its carrier's angular rate, whose gradient is ``A[:rows]``, plus
    ``dq_k``: its terms added to the lower triangle of ``M`` (row ``k`` and the
    carrier's block)."""
    M[k, k] += inertia
    if coupling != 0.0:
        for r in range(rows):
            ar = inertia * coupling * A[r]
            M[k, r] += ar
            for c in range(r + 1):
                M[r, c] += ar * coupling * A[c]


@nb.njit(cache=True, nogil=True, inline="always")
def _add_point_mass(
    mass: float, rows: int, U: F64, bx: float, by: float, M: F64, h: F64
) -> None:  # pragma: no cover - compiled
    """A point mass ``mass`` (kg) at the point whose velocity Jacobian (frame axes) is
    ``U[:, :rows]`` and whose velocity-dependent acceleration is ``(bx, by)``: its terms
    added to the lower triangle of ``M`` and to ``h`` (the hub at a joint, the payload)."""
    for r in range(rows):
        u0, u1 = mass * U[0, r], mass * U[1, r]
        h[r] += u0 * bx + u1 * by
        for c in range(r + 1):
            M[r, c] += u0 * U[0, c] + u1 * U[1, c]


@nb.njit(cache=True, nogil=True, inline="always")
def assemble_local(q: F64, dq: F64, arrays: ArmArrays, ws: Workspace) -> None:  # pragma: no cover
    """Lower triangle of ``M(q)`` into ``ws.lmass`` and ``C(q, dq) dq`` into
    ``ws.lbias``, both in the link-major order of :func:`flexarm.model.dynamics.local_order`.

    In that order the coordinates link ``i``'s kinetic energy depends on (its
    joint, the joints and modes of the links before it, its own modes) are a
    prefix, so each link's terms are accumulated over a prefix of rows and, as
    only the lower triangle is formed, columns up to the row. The upper triangle
    of ``ws.lmass`` is not written.
    """
    n = q.shape[0]
    M, h, A, P = ws.lmass, ws.lbias, ws.angle, ws.rows
    U = ws.jac
    ms = arrays.mode_start
    lk = arrays.link
    v, w = arrays.mass_integral, arrays.moment_integral
    tdef, tslope, md = arrays.tip_deflection, arrays.tip_slope, arrays.modal_mass
    jt = arrays.joint
    n_links = lk.shape[0]
    nq = int(ms[n_links])  # joints and modes; the motor angles (if any) follow
    for r in range(n):
        h[r] = 0.0
        for c in range(r + 1):
            M[r, c] = 0.0
    has_joints = jt.shape[0] > 0
    has_shortening = arrays.shortening_quartic.shape[1] > 0
    if has_joints:
        M[nq, nq] += jt[0, layout.J_INERTIA]  # first rotor: its carrier is the base
    bx = 0.0  # velocity-dependent acceleration of the joint, link frame
    by = 0.0
    ad = 0.0  # absolute angular rate of the link
    for i in range(n_links):
        a0, a1 = ms[i], ms[i + 1]
        s = i + a0 - n_links  # local index of joint i; link i's modes follow
        if i > 0:
            # Frame change from the tip of link i-1 to link i: gamma = theta_i + tip slope.
            gamma = q[i]
            for g in range(ms[i - 1], a0):
                gamma += tslope[g] * q[g]
                ad += tslope[g] * dq[g]
            cg, sg = np.cos(gamma), np.sin(gamma)
            for r in range(s):
                ux, uy = U[0, r], U[1, r]
                U[0, r] = cg * ux + sg * uy
                U[1, r] = -sg * ux + cg * uy
            bx, by = cg * bx + sg * by, -sg * bx + cg * by
            # A[:s] is the angle gradient of link i-1's tip, the carrier of rotor i.
            jtip = lk[i - 1, TIP_INERTIA]  # link i-1's tip body turns with it
            if jtip != 0.0:
                for r in range(s):
                    ar = jtip * A[r]
                    for c in range(r + 1):
                        M[r, c] += ar * A[c]
            if has_joints:  # the motor: rate carrier rate / N + dq_m
                _add_rotor(jt[i, layout.J_INERTIA], jt[i, layout.J_COUPLED], nq + i, s, A, M)
            # hub mass at the joint, carried by the previous link's tip
            mh = lk[i, HUB_MASS]
            if mh != 0.0:
                _add_point_mass(mh, s, U, bx, by, M, h)
        jr = lk[i, ROTOR_INERTIA]  # a rigid joint's rotor: rate carrier rate / N + dtheta_i
        if jr != 0.0:
            _add_rotor(jr, lk[i, ROTOR_COUPLING], s, s, A, M)
        ad += dq[i]
        A[s] = 1.0
        U[0, s] = 0.0
        U[1, s] = 0.0
        L, mass, cx, ia = lk[i, LEN], lk[i, MASS], lk[i, STATIC], lk[i, INERTIA]
        vd, vdd, e, ed, dmd, dmdd = link_sums(q, dq, v, tdef, md, a0, a1)
        ialpha = ia + dmd
        cxe = cx  # int rho (x - u) dx
        stiffening = has_shortening and a1 > a0
        if stiffening:
            # Foreshortening (flexarm.model.foreshortening) into ws.axial: the link's
            # body inertia and inertial force gain the terms of u = 1/2 delta' S delta.
            cxe = link_foreshortening(q, dq, arrays, a0, a1, cx, ad, bx, by, ws.axial)
            ialpha += ws.axial[layout.AX_IALPHA, 0]
        # Rows of P = Mb Jb for (u_x, u_y, alpha) over the prefix [0, s], then the
        # lower triangle of Jb' P there; link i's own modes only see their own rows.
        for c in range(s + 1):
            u0, u1, ac = U[0, c], U[1, c], A[c]
            P[0, c] = mass * u0 - vd * ac
            P[1, c] = mass * u1 + cxe * ac
            P[2, c] = -vd * u0 + cxe * u1 + ialpha * ac
        for r in range(s + 1):
            u0, u1, ar = U[0, r], U[1, r], A[r]
            for c in range(r + 1):
                M[r, c] += u0 * P[0, c] + u1 * P[1, c] + ar * P[2, c]
        ad2 = ad * ad
        for g in range(a0, a1):
            r = s + 1 + g - a0
            vr, wr = v[g], w[g]
            for c in range(s + 1):
                M[r, c] += vr * U[1, c] + wr * A[c]
            acc = vr * by
            for c in range(a0, a1):
                mgc = md[g, c]
                if c <= g:
                    M[r, s + 1 + c - a0] += mgc
                acc -= ad2 * mgc * q[c]
            h[r] += acc
        if stiffening:
            F = ws.axial
            for g in range(a0, a1):
                r = s + 1 + g - a0
                k = g - a0
                yg, wg = F[layout.AX_Y, k], F[layout.AX_WALPHA, k]
                for c in range(s + 1):
                    M[r, c] += wg * A[c] - yg * U[0, c]
                for c in range(a0, g + 1):
                    M[r, s + 1 + c - a0] += F[layout.AX_Q + k, c - a0]
                h[r] += F[layout.AX_BETA_MODES, k]
        # Body-frame inertial force at qddot = 0.
        beta_ux = mass * bx - ad2 * cx - 2.0 * ad * vdd
        beta_uy = mass * by - ad2 * vd
        beta_al = -bx * vd + 2.0 * ad * dmdd + cx * by
        if stiffening:
            beta_ux += ws.axial[layout.AX_BETA, 0]
            beta_uy += ws.axial[layout.AX_BETA, 1]
            beta_al += ws.axial[layout.AX_BETA, 2]
        for r in range(s + 1):
            h[r] += U[0, r] * beta_ux + U[1, r] * beta_uy + A[r] * beta_al
        # Tip of link i, still in link i's frame; A becomes the tip's angle gradient.
        lt = L  # L - u(L)
        if stiffening:
            lt = L - ws.axial[layout.AX_TIP, 0]
        for c in range(s + 1):
            U[0, c] -= e * A[c]
            U[1, c] += lt * A[c]
        for g in range(a0, a1):
            r = s + 1 + g - a0
            U[0, r] = 0.0
            U[1, r] = tdef[g]
            A[r] = tslope[g]
        bx += -ad2 * lt - 2.0 * ad * ed
        by += -ad2 * e
        if stiffening:
            F = ws.axial
            for g in range(a0, a1):
                U[0, s + 1 + g - a0] = -F[layout.AX_SL, g - a0]
            bx -= F[layout.AX_TIP, 1]
            by -= 2.0 * ad * F[layout.AX_TIP, 2]
    # Payload at the last tip: point mass, and rotary inertia turning with the tip slope.
    mp, jp = arrays.payload[0], arrays.payload[1]
    if mp != 0.0:
        _add_point_mass(mp, nq, U, bx, by, M, h)
    if jp != 0.0:
        for r in range(nq):
            ar = jp * A[r]
            for c in range(r + 1):
                M[r, c] += ar * A[c]


@nb.njit(cache=True, nogil=True, inline="always")
def ldlt_factor(M: F64, a0: int, a1: int, inv_d: F64) -> None:  # pragma: no cover - compiled
    """``M[a0:a1, a0:a1] = L D L'`` in place from its lower triangle: the unit factor
    ``L`` below the diagonal, ``D`` on it, ``1 / D`` into ``inv_d[a0:a1]``."""
    for j in range(a0, a1):
        # row j of L D (unscaled), then the pivot
        for k in range(a0, j):
            t = M[j, k]
            for p in range(a0, k):
                t -= M[j, p] * M[k, p]
            M[j, k] = t  # = L[j, k] D[k], scaled below
        d = M[j, j]
        for k in range(a0, j):
            t = M[j, k]
            lk_ = t * inv_d[k]
            d -= t * lk_
            M[j, k] = lk_
        M[j, j] = d
        inv_d[j] = 1.0 / d


@nb.njit(cache=True, nogil=True, inline="always")
def ldlt_solve(M: F64, b: F64, inv_d: F64) -> None:  # pragma: no cover - compiled
    """Solve ``M x = b`` in place (``x`` into ``b``) for symmetric positive definite
    ``M`` given by its lower triangle.

    ``M``'s strict lower triangle is overwritten by the unit lower factor ``L`` of
    ``M = L D L'`` and its diagonal by ``D``; ``inv_d`` receives ``1 / D``. One
    division per row and no square root, so the chain of dependent long-latency
    operations is half that of a Cholesky factorisation.
    """
    n = M.shape[0]
    ldlt_factor(M, 0, n, inv_d)
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= M[i, k] * b[k]
        b[i] = t
    for i in range(n - 1, -1, -1):
        t = b[i] * inv_d[i]
        for k in range(i + 1, n):
            t -= M[k, i] * b[k]
        b[i] = t


@nb.njit(cache=True, nogil=True, inline="always")
def _coordinate_of(ms: NDArray[np.int64], loc: int) -> int:  # pragma: no cover - compiled
    """Index in ``q`` of the coordinate at local (link-major) index ``loc``."""
    n_links = ms.shape[0] - 1
    for i in range(n_links):
        s = i + ms[i] - n_links
        if loc == s:
            return i
        if loc <= s + ms[i + 1] - ms[i]:
            return int(ms[i] + loc - s - 1)
    return loc


@nb.njit(cache=True, nogil=True, inline="always")
def mass_and_bias(
    q: F64, dq: F64, arrays: ArmArrays, ws: Workspace
) -> None:  # pragma: no cover - compiled
    """Fill ``ws.mass`` with ``M(q)`` and ``ws.bias`` with ``C(q, dq) dq``.

    The assembly of the dense kernel, scattered back to the order of ``q`` and
    mirrored to a full symmetric matrix.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        Coordinates (rad, modal units) and their rates.
    arrays : ArmArrays
    ws : Workspace
        Overwritten: ``mass`` (n, n) and ``bias`` (n,); the rest is scratch.
    """
    assemble_local(q, dq, arrays, ws)
    n = q.shape[0]
    ms = arrays.mode_start
    for r in range(n):
        gr = _coordinate_of(ms, r)
        ws.bias[gr] = ws.lbias[r]
        for c in range(r + 1):
            gc = _coordinate_of(ms, c)
            ws.mass[gr, gc] = ws.lmass[r, c]
            ws.mass[gc, gr] = ws.lmass[r, c]


@nb.njit(cache=True, nogil=True, inline="always")
def generalized_forces(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, rhs: F64
) -> None:  # pragma: no cover - compiled
    """The generalised forces other than inertia into ``rhs`` (order of ``q``):
    ``B tau - K q - D dq``, the flexible joints' forces and gravity (if any)."""
    for r in range(q.shape[0]):
        rhs[r] = -arrays.stiffness[r] * q[r] - arrays.damping[r] * dq[r]
    if arrays.joint.shape[0] > 0:
        joint_forces(q, dq, tau, arrays, rhs)
    else:
        for r in range(tau.shape[0]):
            rhs[r] += tau[r]
        rigid_joint_friction(dq, arrays, rhs)
    gravity_forces(q, arrays, rhs)


@nb.njit(cache=True, nogil=True, inline="always")
def forward_dynamics_dense(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`flexarm.model.dynamics.forward_dynamics` for any structure by the mass
    matrix (the dense kernel).

    Assembles the lower triangle of ``M`` and ``C dq`` in the local order
    (:func:`assemble_local`), forms the right-hand side there and solves with
    an ``L D L'`` factorisation; the parameters are those of
    :func:`flexarm.model.dynamics.forward_dynamics`.
    """
    generalized_forces(q, dq, tau, arrays, ws.rhs)
    assemble_local(q, dq, arrays, ws)
    n = q.shape[0]
    rhs = ws.rhs
    y = ws.lbias  # C dq, then the right-hand side, then the solution (local order)
    ms = arrays.mode_start
    n_links = ms.shape[0] - 1
    for i in range(n_links):
        s = i + ms[i] - n_links
        y[s] = rhs[i] - y[s]
        for g in range(ms[i], ms[i + 1]):
            r = s + 1 + g - ms[i]
            y[r] = rhs[g] - y[r]
    for r in range(ms[n_links], n):
        y[r] = rhs[r] - y[r]
    ldlt_solve(ws.lmass, y, ws.inv_diag)
    for i in range(n_links):
        s = i + ms[i] - n_links
        ddq[i] = y[s]
        for g in range(ms[i], ms[i + 1]):
            ddq[g] = y[s + 1 + g - ms[i]]
    for r in range(ms[n_links], n):
        ddq[r] = y[r]
