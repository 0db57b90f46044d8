"""Compiled dynamics of the flexible arm: plain arrays in, plain arrays out.

These Numba functions are what the simulator calls millions of times. They take
the packed model :class:`ArmArrays` (built once by
:attr:`flexarm.FlexibleArm.arrays`) and a :class:`Workspace` allocated once, so
a call allocates nothing. The readable NumPy implementation in
:mod:`flexarm.model.arm` is their reference; the tests hold the two together.

The model (see :mod:`flexarm.model.arm` for the derivation): the kinetic energy of
link ``i`` in its clamped frame is ``1/2 nu' Mb(delta) nu`` with body velocity
``nu = (u_x, u_y, alpha_dot, delta_dot) = Jb qdot``; ``M = sum Jb' Mb Jb`` and
the velocity terms ``h = C(q, qdot) qdot = sum Jb' beta`` with ``beta`` the
body-frame inertial force at ``qddot = 0``.

Three algorithms compute ``qddot``; :func:`forward_dynamics` takes the fastest
for the arm's structure:

* the dense kernel (:func:`forward_dynamics_dense`) works in a link-major order
  of the coordinates (:func:`local_order`: joint 1, link 1's modes, joint 2,
  ...), in which each link's body Jacobian is zero beyond a prefix; it forms
  only the lower triangle of ``M`` and solves with an ``L D L'``
  factorisation. Its cost grows as the cube of the number of links;
* the recursive kernel (:func:`forward_dynamics_recursive`,
  :mod:`flexarm.model.dynamics_recursive`) is the articulated-body algorithm
  on the same body terms, linear in the number of links. From
  :data:`RECURSIVE_FROM_LINKS` links on it is the faster (BENCHMARKS.md, "Cost
  growth"), and :func:`forward_dynamics_general` takes it there;
* the paper's structure (two links, one mode each, rigid joints) has the dense
  computation written out in scalars.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .._compile import compiled_as
from .arrays import (
    AX_BETA,
    AX_BETA_MODES,
    AX_IALPHA,
    AX_Q,
    AX_SL,
    AX_TIP,
    AX_WALPHA,
    AX_Y,
    HUB_MASS,
    INERTIA,
    J_A1,
    J_A2,
    J_ASW,
    J_COUPLED,
    J_DAMPING,
    J_FRICTION_ON_MOTOR,
    J_G1,
    J_HAS_FRICTION,
    J_INERTIA,
    J_KSW,
    LEN,
    MASS,
    STATIC,
    ArmArrays,
    Workspace,
    make_workspace,
)
from .dynamics_foreshortening import link_foreshortening, link_sums
from .dynamics_points import point_kinematics
from .dynamics_recursive import _accelerations_recursive
from .dynamics_two_links import (
    _forward_dynamics_two_links_one_mode,
    _is_two_links_one_mode,
    accelerations_two_links_one_mode,
    forward_dynamics_two_links_one_mode,
    is_two_links_one_mode,
)
from .kernel_checks import check_model, check_state, check_vector, check_workspace

__all__ = [
    "RECURSIVE_FROM_LINKS",
    "ArmArrays",
    "Workspace",
    "accelerations_two_links_one_mode",
    "forward_dynamics",
    "forward_dynamics_dense",
    "forward_dynamics_general",
    "forward_dynamics_recursive",
    "forward_dynamics_two_links_one_mode",
    "is_two_links_one_mode",
    "joint_forces",
    "local_order",
    "make_workspace",
    "mass_and_bias",
    "point_kinematics",
]

F64 = NDArray[np.float64]

RECURSIVE_FROM_LINKS = 3
"""Arms with this many links or more take the recursive algorithm (measured,
BENCHMARKS.md "Cost growth"); fewer links, the dense one."""


@nb.njit(cache=True, nogil=True, inline="always")
def _joint_forces(
    q: F64, dq: F64, tau: F64, model: ArmArrays, rhs: F64
) -> None:  # pragma: no cover
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
def _assemble_local(q: F64, dq: F64, model: ArmArrays, ws: Workspace) -> None:  # pragma: no cover
    """Lower triangle of ``M(q)`` into ``ws.lmass`` and ``C(q, dq) dq`` into
    ``ws.lbias``, both in the link-major order of :func:`local_order`.

    In that order the coordinates link ``i``'s kinetic energy depends on (its
    joint, the joints and modes of the links before it, its own modes) are a
    prefix, so each link's terms are accumulated over a prefix of rows and, as
    only the lower triangle is formed, columns up to the row. The upper triangle
    of ``ws.lmass`` is not written.
    """
    n = q.shape[0]
    M, h, A, P = ws.lmass, ws.lbias, ws.angle, ws.rows
    U = ws.jac
    ms = model.mode_start
    lk = model.link
    v, w = model.mass_integral, model.moment_integral
    tdef, tslope, md = model.tip_deflection, model.tip_slope, model.modal_mass
    jt = model.joint
    n_links = lk.shape[0]
    nq = ms[n_links]  # joints and modes; the motor angles (if any) follow
    for r in range(n):
        h[r] = 0.0
        for c in range(r + 1):
            M[r, c] = 0.0
    has_joints = jt.shape[0] > 0
    has_shortening = model.shortening_quartic.shape[1] > 0
    if has_joints:
        M[nq, nq] += jt[0, J_INERTIA]  # first rotor: its carrier is the base
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
            if has_joints:
                m = nq + i
                jm = jt[i, J_INERTIA]
                M[m, m] += jm
                if jt[i, J_COUPLED] != 0.0:
                    for r in range(s):
                        ar = jm * A[r]
                        M[m, r] += ar
                        for c in range(r + 1):
                            M[r, c] += ar * A[c]
            # hub mass at the joint, carried by the previous link's tip
            mh = lk[i, HUB_MASS]
            if mh != 0.0:
                for r in range(s):
                    u0, u1 = mh * U[0, r], mh * U[1, r]
                    h[r] += u0 * bx + u1 * by
                    for c in range(r + 1):
                        M[r, c] += u0 * U[0, c] + u1 * U[1, c]
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
            cxe = link_foreshortening(q, dq, model, a0, a1, cx, ad, bx, by, ws.axial)
            ialpha += ws.axial[AX_IALPHA, 0]
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
                yg, wg = F[AX_Y, k], F[AX_WALPHA, k]
                for c in range(s + 1):
                    M[r, c] += wg * A[c] - yg * U[0, c]
                for c in range(a0, g + 1):
                    M[r, s + 1 + c - a0] += F[AX_Q + k, c - a0]
                h[r] += F[AX_BETA_MODES, k]
        # Body-frame inertial force at qddot = 0.
        beta_ux = mass * bx - ad2 * cx - 2.0 * ad * vdd
        beta_uy = mass * by - ad2 * vd
        beta_al = -bx * vd + 2.0 * ad * dmdd + cx * by
        if stiffening:
            beta_ux += ws.axial[AX_BETA, 0]
            beta_uy += ws.axial[AX_BETA, 1]
            beta_al += ws.axial[AX_BETA, 2]
        for r in range(s + 1):
            h[r] += U[0, r] * beta_ux + U[1, r] * beta_uy + A[r] * beta_al
        # Tip of link i, still in link i's frame; A becomes the tip's angle gradient.
        lt = L  # L - u(L)
        if stiffening:
            lt = L - ws.axial[AX_TIP, 0]
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
                U[0, s + 1 + g - a0] = -F[AX_SL, g - a0]
            bx -= F[AX_TIP, 1]
            by -= 2.0 * ad * F[AX_TIP, 2]
    # Payload at the last tip: point mass, and rotary inertia turning with the tip slope.
    mp, jp = model.payload[0], model.payload[1]
    if mp != 0.0:
        for r in range(nq):
            u0, u1 = mp * U[0, r], mp * U[1, r]
            h[r] += u0 * bx + u1 * by
            for c in range(r + 1):
                M[r, c] += u0 * U[0, c] + u1 * U[1, c]
    if jp != 0.0:
        for r in range(nq):
            ar = jp * A[r]
            for c in range(r + 1):
                M[r, c] += ar * A[c]


@nb.njit(cache=True, nogil=True, inline="always")
def _ldlt_solve(M: F64, b: F64, inv_d: F64) -> None:  # pragma: no cover - compiled
    """Solve ``M x = b`` in place (``x`` into ``b``) for symmetric positive definite
    ``M`` given by its lower triangle.

    ``M``'s strict lower triangle is overwritten by the unit lower factor ``L`` of
    ``M = L D L'`` and its diagonal by ``D``; ``inv_d`` receives ``1 / D``. One
    division per row and no square root, so the chain of dependent long-latency
    operations is half that of a Cholesky factorisation.
    """
    n = M.shape[0]
    for j in range(n):
        # row j of L D (unscaled), then the pivot
        for k in range(j):
            t = M[j, k]
            for p in range(k):
                t -= M[j, p] * M[k, p]
            M[j, k] = t  # = L[j, k] D[k], scaled below
        d = M[j, j]
        for k in range(j):
            t = M[j, k]
            lk_ = t * inv_d[k]
            d -= t * lk_
            M[j, k] = lk_
        M[j, j] = d
        inv_d[j] = 1.0 / d
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


def local_order(mode_start: NDArray[np.int64], n_dof: int) -> NDArray[np.int64]:
    """The link-major order the solver works in, as indices into ``q``.

    Joint 1, link 1's modes, joint 2, link 2's modes, ..., then the motor angles
    (if any): entry ``l`` is the index in ``q`` of the coordinate at local index
    ``l``. In this order link ``i``'s kinetic energy depends on a prefix of the
    coordinates.
    """
    ms = np.asarray(mode_start, dtype=np.int64)
    order: list[int] = []
    for i in range(ms.shape[0] - 1):
        order.append(i)
        order.extend(range(int(ms[i]), int(ms[i + 1])))
    order.extend(range(int(ms[-1]), n_dof))
    return np.array(order, dtype=np.int64)


@nb.njit(cache=True, nogil=True, inline="always")
def _mass_and_bias(
    q: F64, dq: F64, model: ArmArrays, ws: Workspace
) -> None:  # pragma: no cover - compiled
    """Fill ``ws.mass`` with ``M(q)`` and ``ws.bias`` with ``C(q, dq) dq``.

    The general assembly of :func:`forward_dynamics_general`, scattered back to
    the order of ``q`` and mirrored to a full symmetric matrix.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        Coordinates (rad, modal units) and their rates.
    model : ArmArrays
    ws : Workspace
        Overwritten: ``mass`` (n, n) and ``bias`` (n,); the rest is scratch.
    """
    _assemble_local(q, dq, model, ws)
    n = q.shape[0]
    ms = model.mode_start
    for r in range(n):
        gr = _coordinate_of(ms, r)
        ws.bias[gr] = ws.lbias[r]
        for c in range(r + 1):
            gc = _coordinate_of(ms, c)
            ws.mass[gr, gc] = ws.lmass[r, c]
            ws.mass[gc, gr] = ws.lmass[r, c]


@nb.njit(cache=True, nogil=True, inline="always")
def _generalized_forces(
    q: F64, dq: F64, tau: F64, model: ArmArrays, rhs: F64
) -> None:  # pragma: no cover - compiled
    """The generalised forces other than inertia into ``rhs`` (order of ``q``):
    ``B tau - K q - D dq`` and the flexible joints' forces."""
    for r in range(q.shape[0]):
        rhs[r] = -model.stiffness[r] * q[r] - model.damping[r] * dq[r]
    if model.joint.shape[0] > 0:
        _joint_forces(q, dq, tau, model, rhs)
    else:
        for r in range(tau.shape[0]):
            rhs[r] += tau[r]


@nb.njit(cache=True, nogil=True, inline="always")
def _forward_dynamics_dense(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`forward_dynamics` for any structure by the mass matrix (the dense kernel).

    Assembles the lower triangle of ``M`` and ``C dq`` in the local order
    (:func:`_assemble_local`), forms the right-hand side there and solves with
    an ``L D L'`` factorisation; the parameters are those of
    :func:`forward_dynamics`.
    """
    _generalized_forces(q, dq, tau, model, ws.rhs)
    _assemble_local(q, dq, model, ws)
    n = q.shape[0]
    rhs = ws.rhs
    y = ws.lbias  # C dq, then the right-hand side, then the solution (local order)
    ms = model.mode_start
    n_links = ms.shape[0] - 1
    for i in range(n_links):
        s = i + ms[i] - n_links
        y[s] = rhs[i] - y[s]
        for g in range(ms[i], ms[i + 1]):
            r = s + 1 + g - ms[i]
            y[r] = rhs[g] - y[r]
    for r in range(ms[n_links], n):
        y[r] = rhs[r] - y[r]
    _ldlt_solve(ws.lmass, y, ws.inv_diag)
    for i in range(n_links):
        s = i + ms[i] - n_links
        ddq[i] = y[s]
        for g in range(ms[i], ms[i + 1]):
            ddq[g] = y[s + 1 + g - ms[i]]
    for r in range(ms[n_links], n):
        ddq[r] = y[r]


@nb.njit(cache=True, nogil=True, inline="always")
def _forward_dynamics_recursive(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`forward_dynamics` for any structure by the articulated-body recursion
    (:mod:`flexarm.model.dynamics_recursive`), in time linear in the links."""
    _generalized_forces(q, dq, tau, model, ws.rhs)
    _accelerations_recursive(q, dq, model, ws, ddq)


@nb.njit(cache=True, nogil=True, inline="always")
def _prefers_recursive(model: ArmArrays) -> bool:  # pragma: no cover - compiled
    """Whether the recursive algorithm is the faster for this structure: from
    RECURSIVE_FROM_LINKS links on (BENCHMARKS.md, "Cost growth")."""
    return bool(model.link.shape[0] >= RECURSIVE_FROM_LINKS)


@nb.njit(cache=True, nogil=True, inline="always")
def _forward_dynamics_general(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`forward_dynamics` for any structure: :func:`_forward_dynamics_recursive`
    or :func:`_forward_dynamics_dense`, whichever is the faster for it
    (:func:`_prefers_recursive`); the parameters are those of
    :func:`forward_dynamics`."""
    if _prefers_recursive(model):
        _forward_dynamics_recursive(q, dq, tau, model, ws, ddq)
    else:
        _forward_dynamics_dense(q, dq, tau, model, ws, ddq)


@nb.njit(cache=True, nogil=True, inline="always")
def _forward_dynamics(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """``ddq = M(q)^-1 (B tau - C(q, dq) dq - K q - D dq + joint forces)``, into ``ddq``.

    Two links with one mode each and rigid joints (the paper's structure) take
    the scalar kernel :func:`forward_dynamics_two_links_one_mode`, which
    computes the dense kernel's quantities in the same order; every other arm
    :func:`forward_dynamics_general` (the dense kernel up to two links, the
    recursive one from :data:`RECURSIVE_FROM_LINKS` on).

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
    tau : ndarray, shape (n_links,)
        Joint torques in N m: on the joint angles for rigid joints, on the motor
        angles for flexible joints.
    model : ArmArrays
    ws : Workspace
        Scratch (overwritten; not used by the scalar kernel).
    ddq : ndarray, shape (n_dof,)
        Output accelerations.
    """
    if _is_two_links_one_mode(model):
        _forward_dynamics_two_links_one_mode(q, dq, tau, model, ddq)
    else:
        _forward_dynamics_general(q, dq, tau, model, ws, ddq)


# ------------------------------------------------------------------ checked public faces
# From Python each name checks its arguments first (an output shorter than n_dof
# would otherwise be written past its end); inside compiled code (the simulator's
# loops, a user's own) the same name is the kernel itself, through an overload.
def forward_dynamics(q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64) -> None:
    """``ddq = M(q)^-1 (B tau - C(q, dq) dq - K q - D dq + joint forces)``, into ``ddq``
    (``_forward_dynamics``; the parameters are checked when called from Python).

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        Coordinates and rates, float64, C-contiguous.
    tau : ndarray, shape (n_links,)
        Joint (motor) torques, N m.
    model : ArmArrays
        :attr:`flexarm.FlexibleArm.arrays`.
    ws : Workspace
        :func:`make_workspace` ``(n_dof)`` (overwritten).
    ddq : ndarray, shape (n_dof,)
        Output accelerations (writable).

    Raises
    ------
    InvalidTypeError, InvalidValueError
        Naming the argument of the wrong type, dtype, layout or shape.
    """
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics")
    _forward_dynamics(q, dq, tau, model, ws, ddq)


def _check_forward(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64, owner: str
) -> None:
    """The arguments of a forward-dynamics kernel, checked (errors name ``owner``)."""
    _, n = check_state(q, dq, tau, model, owner)
    check_workspace(ws, n, owner)
    check_vector(ddq, "ddq", owner, (n,), writable=True)


def forward_dynamics_general(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:
    """:func:`forward_dynamics` by the general kernels for any structure, the dense
    or the recursive one, whichever is the faster for it (checked)."""
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics_general")
    _forward_dynamics_general(q, dq, tau, model, ws, ddq)


def forward_dynamics_dense(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:
    """:func:`forward_dynamics` by the mass matrix and its factorisation, for any
    structure (checked)."""
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics_dense")
    _forward_dynamics_dense(q, dq, tau, model, ws, ddq)


def forward_dynamics_recursive(
    q: F64, dq: F64, tau: F64, model: ArmArrays, ws: Workspace, ddq: F64
) -> None:
    """:func:`forward_dynamics` by the articulated-body recursion
    (:mod:`flexarm.model.dynamics_recursive`), for any structure (checked)."""
    _check_forward(q, dq, tau, model, ws, ddq, "forward_dynamics_recursive")
    _forward_dynamics_recursive(q, dq, tau, model, ws, ddq)


def mass_and_bias(q: F64, dq: F64, model: ArmArrays, ws: Workspace) -> None:
    """Fill ``ws.mass`` with ``M(q)`` and ``ws.bias`` with ``C(q, dq) dq`` (checked)."""
    owner = "mass_and_bias"
    _, n = check_model(model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_workspace(ws, n, owner)
    _mass_and_bias(q, dq, model, ws)


def joint_forces(q: F64, dq: F64, tau: F64, model: ArmArrays, rhs: F64) -> None:
    """Add the flexible joints' generalised forces to ``rhs`` (checked)."""
    owner = "joint_forces"
    _, n = check_state(q, dq, tau, model, owner)
    check_vector(rhs, "rhs", owner, (n,), writable=True)
    _joint_forces(q, dq, tau, model, rhs)


@compiled_as(forward_dynamics, runtime_free=True)
def _forward_dynamics_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward_dynamics(q, dq, tau, model, ws, ddq)


@compiled_as(forward_dynamics_general, runtime_free=True)
def _forward_dynamics_general_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward_dynamics_general(q, dq, tau, model, ws, ddq)


@compiled_as(forward_dynamics_dense, runtime_free=True)
def _forward_dynamics_dense_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward_dynamics_dense(q, dq, tau, model, ws, ddq)


@compiled_as(forward_dynamics_recursive, runtime_free=True)
def _forward_dynamics_recursive_compiled(q, dq, tau, model, ws, ddq):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, ws, ddq: _forward_dynamics_recursive(
        q, dq, tau, model, ws, ddq
    )


@compiled_as(mass_and_bias, runtime_free=True)
def _mass_and_bias_compiled(q, dq, model, ws):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, ws: _mass_and_bias(q, dq, model, ws)


@compiled_as(joint_forces, runtime_free=True)
def _joint_forces_compiled(q, dq, tau, model, rhs):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau, model, rhs: _joint_forces(q, dq, tau, model, rhs)
