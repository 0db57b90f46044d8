r"""The recursive forward dynamics of the arm, O(n_links): :func:`accelerations_recursive`.

Internal: the bare kernel behind :func:`flexarm.model.dynamics.forward_dynamics_recursive`.

The dense kernel (:func:`flexarm.model.dynamics.forward_dynamics_dense`) forms the
mass matrix and factors it: its cost grows as the cube of the number of links.
This is the articulated-body algorithm (Featherstone's, with each link's modes
eliminated as Book's and Jain & Rodriguez's recursive flexible-body algorithms
do), in the plane. It computes the same accelerations from the same body terms,
in time linear in the number of links (and cubic in one link's modes).

Each link ``i`` has a frame at its joint, ``F_i``. Planar motion vectors in it
are ``(a_x, a_y, alpha_ddot)`` (the acceleration of the joint and the link's
angular acceleration, in ``F_i``'s axes), forces ``(f_x, f_y, n)`` (about the
joint). With ``A_i`` the motion of ``F_i`` and ``ddelta_i`` the link's modal
accelerations, link ``i``'s generalised inertial force is ``Mb_i [A_i;
ddelta_i] + beta_i``: its body inertia ``Mb_i`` and the velocity terms
``beta_i`` of the dense kernel (without the part that moves with
the frame's own velocity-dependent acceleration, which ``A_i`` carries here).
The tip of link ``i`` moves as ``T_i A_i + E_i ddelta_i + c_i`` (``T_i`` the
rigid transfer to the tip, ``E_i`` the modes' tip displacements and slopes,
``c_i`` the velocity-dependent terms); link ``i+1``'s frame turns from the tip's
by the joint angle ``theta_{i+1}`` (and the tip slope).

Inward, from the last link: the subtree of link ``i+1`` answers an acceleration
of its frame with the force ``I_{i+1} A + p_{i+1}`` (its articulated inertia and
bias, its joint eliminated). Carried to link ``i``'s tip with the hub mass of
joint ``i+1``, the rotor of joint ``i+1`` (which passes its own generalised
force to its carrier) and, after the last link, the payload, it adds
``G' I G`` and ``G' p`` (``G = [T_i, E_i]``) to link ``i``'s
``(3 + m) x (3 + m)`` system ``K``, ``k``. Eliminating the link's ``m`` modes
(an ``L D L'`` factorisation of ``K``'s modal block) and then its joint leaves
``I_i``, ``p_i`` (a rigid joint's rotor, turning at ``alpha_p / N + theta_i'``
with ``alpha_p`` the parent frame's rate, joins that elimination: it adds ``J_m``
to the pivot, ``J_m / N`` to the joint's coupling with ``alpha_p`` and
``J_m / N**2`` to ``I_i``'s angular entry, which is then not zero). Outward,
from the base: the joint acceleration, then the modal accelerations, then the
next frame's motion, then the rotors'.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .. import arrays as layout
from ..arrays import (
    CH_AD,
    CH_COS,
    CH_CX,
    CH_CY,
    CH_D,
    CH_E,
    CH_EX,
    CH_IAH,
    CH_LT,
    CH_SIN,
    CH_U,
    CH_Z,
    CH_ZB,
    HUB_MASS,
    INERTIA,
    LEN,
    MASS,
    ROTOR_COUPLING,
    ROTOR_INERTIA,
    STATIC,
    TIP_INERTIA,
    ArmArrays,
    Workspace,
)
from ._dense import ldlt_factor
from ._link_terms import link_foreshortening, link_sums

__all__ = ["accelerations_recursive"]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True, inline="always")
def _solve_block(
    M: F64, a0: int, a1: int, inv_d: F64, X: F64, col: int
) -> None:  # pragma: no cover - compiled
    """``X[a0:a1, col]`` replaced by the solution of ``L D L' x = X[a0:a1, col]``."""
    for i in range(a0, a1):
        t = X[i, col]
        for k in range(a0, i):
            t -= M[i, k] * X[k, col]
        X[i, col] = t
    for i in range(a1 - 1, a0 - 1, -1):
        t = X[i, col] * inv_d[i]
        for k in range(i + 1, a1):
            t -= M[k, i] * X[k, col]
        X[i, col] = t


@nb.njit(cache=True, nogil=True, inline="always")
def accelerations_recursive(
    q: F64, dq: F64, arrays: ArmArrays, ws: Workspace, ddq: F64
) -> None:  # pragma: no cover - compiled
    """``ddq`` from ``q, dq`` and the generalised forces in ``ws.rhs`` (order of ``q``:
    everything but inertia, as :func:`flexarm.model.dynamics.forward_dynamics_dense`
    forms them), by the articulated-body recursion of the module docstring.

    ``ws.chain`` keeps the records (:data:`flexarm.model.arrays.CH_AD` ...),
    ``ws.lmass`` each link's modal block and its factor, ``ws.rows`` the block
    coupling a link's frame to its modes, ``ws.axial`` one link's foreshortening
    terms.
    """
    n_links = arrays.link.shape[0]
    ms, lk, jt = arrays.mode_start, arrays.link, arrays.joint
    v, w = arrays.mass_integral, arrays.moment_integral
    tdef, tslope, md = arrays.tip_deflection, arrays.tip_slope, arrays.modal_mass
    nq = int(ms[n_links])  # joints and modes; the motor angles follow
    has_joints = jt.shape[0] > 0
    has_shortening = arrays.shortening_quartic.shape[1] > 0
    rhs, ch, K, B, F = ws.rhs, ws.chain, ws.lmass, ws.rows, ws.axial
    # ---- outward: the links' angular rates and the turns between their frames
    ad = 0.0
    for i in range(n_links):
        if i > 0:
            gamma = q[i]
            for g in range(ms[i - 1], ms[i]):
                gamma += tslope[g] * q[g]
                ad += tslope[g] * dq[g]
            ch[i, CH_COS] = np.cos(gamma)
            ch[i, CH_SIN] = np.sin(gamma)
        ad += dq[i]
        ch[i, CH_AD] = ad
    # ---- inward: the child's articulated inertia (symmetric) and bias, child frame
    c00 = c01 = c11 = 0.0
    c02 = c12 = c22 = 0.0  # nonzero only past a rigid joint's rotor
    p0 = p1 = p2 = 0.0
    for i in range(n_links - 1, -1, -1):
        a0, a1 = ms[i], ms[i + 1]
        ad = ch[i, CH_AD]
        ad2 = ad * ad
        L, mass, cx, ia = lk[i, LEN], lk[i, MASS], lk[i, STATIC], lk[i, INERTIA]
        vd, vdd, e, ed, dmd, dmdd = link_sums(q, dq, v, tdef, md, a0, a1)
        stiff = has_shortening and a1 > a0
        cxe = cx
        ialpha = ia + dmd
        lt = L
        if stiff:  # with the frame's own acceleration zero: it is in A here
            cxe = link_foreshortening(q, dq, arrays, a0, a1, cx, ad, 0.0, 0.0, F)
            ialpha += F[layout.AX_IALPHA, 0]
            lt = L - F[layout.AX_TIP, 0]
        # velocity-dependent acceleration of the tip relative to the joint, F_i axes
        tx = -ad2 * lt - 2.0 * ad * ed
        ty = -ad2 * e
        if stiff:
            tx -= F[layout.AX_TIP, 1]
            ty -= 2.0 * ad * F[layout.AX_TIP, 2]
        # ---- what rides on the tip, in F_i's axes about the tip: the child turned
        # back by gamma_{i+1}, the hub of joint i+1, or the payload
        j00 = j01 = j02 = j11 = j12 = j22 = 0.0
        f0 = f1 = f2 = 0.0
        if i + 1 < n_links:
            cg, sg = ch[i + 1, CH_COS], ch[i + 1, CH_SIN]
            t00 = cg * c00 - sg * c01
            t01 = sg * c00 + cg * c01
            t10 = cg * c01 - sg * c11
            t11 = sg * c01 + cg * c11
            mh = lk[i + 1, HUB_MASS]
            j00 = cg * t00 - sg * t10 + mh
            j01 = cg * t01 - sg * t11
            j11 = sg * t01 + cg * t11 + mh
            j02 = cg * c02 - sg * c12
            j12 = sg * c02 + cg * c12
            j22 = c22 + lk[i, TIP_INERTIA]  # link i's tip body turns with its tip
            f0 = cg * p0 - sg * p1
            f1 = sg * p0 + cg * p1
            f2 = p2
            if has_joints and jt[i + 1, layout.J_COUPLED] != 0.0:
                # the rotor passes its generalised force on, times 1 / N
                f2 += jt[i + 1, layout.J_COUPLED] * rhs[nq + i + 1]
        else:
            mp = arrays.payload[0]
            j00 = mp
            j11 = mp
            j22 = arrays.payload[1]
        f0 += j00 * tx + j01 * ty
        f1 += j01 * tx + j11 * ty
        f2 += j02 * tx + j12 * ty
        # ---- link i's system K [A; ddelta] + k: Mb + G' J G and beta + G' f
        # rigid transfer to the tip: column 2 of T is (-e, lt, 1)
        r0 = -e * j00 + lt * j01 + j02  # J T[:, 2]
        r1 = -e * j01 + lt * j11 + j12
        r2 = -e * j02 + lt * j12 + j22
        k00 = mass + j00
        k01 = j01
        k11 = mass + j11
        k02 = -vd + r0
        k12 = cxe + r1
        k22 = ialpha - e * r0 + lt * r1 + r2
        b0 = -ad2 * cx - 2.0 * ad * vdd + f0
        b1 = -ad2 * vd + f1
        b2 = 2.0 * ad * dmdd - e * f0 + lt * f1 + f2
        if stiff:
            b0 += F[layout.AX_BETA, 0]
            b1 += F[layout.AX_BETA, 1]
            b2 += F[layout.AX_BETA, 2]
        for g in range(a0, a1):
            kk = g - a0
            ex = -F[layout.AX_SL, kk] if stiff else 0.0
            ey, et = tdef[g], tslope[g]
            ch[g, CH_EX] = ex
            je0 = j00 * ex + j01 * ey + j02 * et  # J E[:, g]
            je1 = j01 * ex + j11 * ey + j12 * et
            je2 = j02 * ex + j12 * ey + j22 * et
            # the frame-mode block (rows ux, uy, alpha), into B
            B[0, g] = je0 - (F[layout.AX_Y, kk] if stiff else 0.0)
            B[1, g] = v[g] + je1
            B[2, g] = w[g] - e * je0 + lt * je1 + je2 + (F[layout.AX_WALPHA, kk] if stiff else 0.0)
            # the modal block (lower triangle), into K
            for h in range(a0, g + 1):
                ex_h = ch[h, CH_EX]
                jh0 = j00 * ex_h + j01 * tdef[h] + j02 * tslope[h]
                jh1 = j01 * ex_h + j11 * tdef[h] + j12 * tslope[h]
                jh2 = j02 * ex_h + j12 * tdef[h] + j22 * tslope[h]
                kgh = md[g, h] + ex * jh0 + ey * jh1 + et * jh2
                if stiff:
                    kgh += F[layout.AX_Q + kk, h - a0]
                K[g, h] = kgh
            bg = ex * f0 + ey * f1 + et * f2
            for c in range(a0, a1):
                bg -= ad2 * md[g, c] * q[c]
            if stiff:
                bg += F[layout.AX_BETA_MODES, kk]
            # right-hand sides of the modal block: K_da (3 columns) and Q - k
            ch[g, CH_Z] = B[0, g]
            ch[g, CH_Z + 1] = B[1, g]
            ch[g, CH_Z + 2] = B[2, g]
            ch[g, CH_ZB] = rhs[g] - bg
        # ---- eliminate the modes: Z = K_dd^-1 K_da, z = K_dd^-1 (Q - k)
        if a1 > a0:
            ldlt_factor(K, a0, a1, ws.inv_diag)
            for col in range(CH_Z, CH_ZB + 1):
                _solve_block(K, a0, a1, ws.inv_diag, ch, col)
        for g in range(a0, a1):
            z0, z1, z2, zb = ch[g, CH_Z], ch[g, CH_Z + 1], ch[g, CH_Z + 2], ch[g, CH_ZB]
            u0, u1, u2 = B[0, g], B[1, g], B[2, g]
            k00 -= u0 * z0
            k01 -= u0 * z1
            k02 -= u0 * z2
            k11 -= u1 * z1
            k12 -= u1 * z2
            k22 -= u2 * z2
            b0 += u0 * zb
            b1 += u1 * zb
            b2 += u2 * zb
        # ---- eliminate the joint (axis (0, 0, 1)): what the parent sees. A rigid
        # joint's rotor J_m turns at cr alpha_p + theta_i' (alpha_p the parent frame's
        # rate, cr = 1 / N): it adds J_m to the pivot, cr J_m to the joint's coupling
        # to alpha_p and cr**2 J_m to the parent's angular inertia.
        jr = lk[i, ROTOR_INERTIA]
        cr = lk[i, ROTOR_COUPLING]
        d = k22 + jr
        iah2 = k22 + cr * jr
        u = rhs[i] - b2
        ch[i, CH_IAH] = k02
        ch[i, CH_IAH + 1] = k12
        ch[i, CH_IAH + 2] = iah2
        ch[i, CH_D] = d
        ch[i, CH_U] = u
        ch[i, CH_LT] = lt
        ch[i, CH_E] = e
        ch[i, CH_CX] = tx
        ch[i, CH_CY] = ty
        c00 = k00 - k02 * k02 / d
        c01 = k01 - k02 * k12 / d
        c11 = k11 - k12 * k12 / d
        p0 = b0 + k02 * u / d
        p1 = b1 + k12 * u / d
        if jr == 0.0:
            c02 = c12 = c22 = 0.0
            p2 = rhs[i]  # b2 + d * u / d: the joint passes its own force on
        else:
            c02 = k02 - k02 * iah2 / d
            c12 = k12 - k12 * iah2 / d
            c22 = k22 + cr * cr * jr - iah2 * iah2 / d
            p2 = b2 + iah2 * u / d
    # ---- outward: accelerations
    if has_joints:
        ddq[nq] = rhs[nq] / jt[0, layout.J_INERTIA]  # the first rotor's carrier is the base
    ax = ay = ath = 0.0  # the motion of F_i, less the joint's own acceleration
    for i in range(n_links):
        a0, a1 = ms[i], ms[i + 1]
        if i > 0:
            cg, sg = ch[i, CH_COS], ch[i, CH_SIN]
            ax, ay = cg * ax + sg * ay, -sg * ax + cg * ay
        acc = ch[i, CH_U] - (ch[i, CH_IAH] * ax + ch[i, CH_IAH + 1] * ay + ch[i, CH_IAH + 2] * ath)
        acc /= ch[i, CH_D]
        ddq[i] = acc
        ath += acc
        e, lt = ch[i, CH_E], ch[i, CH_LT]
        tx = ax - e * ath + ch[i, CH_CX]
        ty = ay + lt * ath + ch[i, CH_CY]
        tt = ath
        for g in range(a0, a1):
            dd = ch[g, CH_ZB] - (ch[g, CH_Z] * ax + ch[g, CH_Z + 1] * ay + ch[g, CH_Z + 2] * ath)
            ddq[g] = dd
            tx += ch[g, CH_EX] * dd
            ty += tdef[g] * dd
            tt += tslope[g] * dd
        if has_joints and i + 1 < n_links:
            m = nq + i + 1
            acc = rhs[m] / jt[i + 1, layout.J_INERTIA]
            if jt[i + 1, layout.J_COUPLED] != 0.0:
                acc -= jt[i + 1, layout.J_COUPLED] * tt
            ddq[m] = acc
        ax, ay, ath = tx, ty, tt
