"""One link's terms, compiled: its modal sums (:func:`link_sums`) and its
foreshortening terms (:func:`link_foreshortening`).

The dense and the recursive kernels (:func:`flexarm.model.dynamics.forward_dynamics_dense`,
:func:`flexarm.model.dynamics.forward_dynamics_recursive`) call both for every link, the
second only for a link with modes when the arm has geometric stiffening
(:mod:`flexarm.model.foreshortening`); the NumPy reference is
:func:`flexarm.model.lagrangian.body_terms`. Internal: the kernels' building blocks.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..._compile import njit_runtime_free
from .. import arrays as layout
from ..arrays import ArmArrays

__all__ = ["link_foreshortening", "link_sums"]

F64 = NDArray[np.float64]


@njit_runtime_free(cache=True, nogil=True, inline="always")
def link_sums(
    q: F64, dq: F64, v: F64, tdef: F64, md: F64, a0: int, a1: int
) -> tuple[float, float, float, float, float, float]:  # pragma: no cover - compiled
    """The sums over one link's modes that every dynamics kernel needs.

    Over the modes ``a0 <= g < a1``: ``v @ delta`` and ``v @ delta_dot`` (``v`` the
    mass integrals), the tip deflection (m) and its rate, ``delta' Md delta`` and
    ``delta' Md delta_dot``.
    """
    vd = 0.0
    vdd = 0.0
    e = 0.0
    ed = 0.0
    dmd = 0.0
    dmdd = 0.0
    for g in range(a0, a1):
        vd += v[g] * q[g]
        vdd += v[g] * dq[g]
        e += tdef[g] * q[g]
        ed += tdef[g] * dq[g]
        for c in range(a0, a1):
            dmd += q[g] * md[g, c] * q[c]
            dmdd += q[g] * md[g, c] * dq[c]
    return vd, vdd, e, ed, dmd, dmdd


@njit_runtime_free(cache=True, nogil=True)
def link_foreshortening(
    q: F64,
    dq: F64,
    arrays: ArmArrays,
    a0: int,
    a1: int,
    cx: float,
    ad: float,
    bx: float,
    by: float,
    F: F64,
) -> float:  # pragma: no cover - compiled
    """The foreshortening terms of the link whose modes are ``q[a0:a1]``, into ``F``
    (rows ``AX_*`` of :mod:`flexarm.model.arrays`); returns ``int rho (x - u) dx``.

    With ``u = 1/2 delta' S(x) delta`` (:mod:`flexarm.model.foreshortening`),
    ``y = int rho S delta``, ``R[a, b] = int rho phi_a (S delta)_b``,
    ``Q[b, d] = int rho (S delta)_b (S delta)_d`` and
    ``Q~[b, d] = int rho (S delta)_b (S delta_dot)_d``, the link's body inertia
    gains ``Mb[ux, delta] = -y``, ``Mb[uy, alpha] = -1/2 delta' y``,
    ``Mb[alpha, alpha] += -delta' X delta + 1/4 delta' Q delta``,
    ``Mb[alpha, delta] += R' delta - 1/2 R delta``, ``Mb[delta, delta] += Q``, and
    its inertial force at ``qddot = 0`` the terms written below (the NumPy
    reference ``flexarm.model.lagrangian._link_body`` has the derivation).
    """
    nm = a1 - a0
    St, Sm, X = arrays.shortening_tip, arrays.shortening_mass, arrays.shortening_moment
    T3, T4 = arrays.shortening_cubic, arrays.shortening_quartic
    rq, rr, rt = layout.AX_Q, layout.AX_Q + nm, layout.AX_Q + 2 * nm  # rows of Q, R, Q~
    p = 0.0  # delta' y
    px = 0.0  # delta' X delta
    pxd = 0.0  # delta' X delta_dot
    ul2 = 0.0  # delta' S(L) delta
    sdd = 0.0  # delta_dot' S(L) delta_dot
    sld = 0.0  # (S(L) delta) . delta_dot
    ydd = 0.0  # y . delta_dot
    dsd = 0.0  # delta_dot' (int rho S) delta_dot
    rdd = 0.0  # delta' Rd delta_dot, Rd[a, b] = int rho phi_a (S delta_dot)_b
    for j in range(nm):
        g = a0 + j
        yj = 0.0
        slj = 0.0
        xj = 0.0
        sdj = 0.0
        for c in range(nm):
            qc, dc = q[a0 + c], dq[a0 + c]
            yj += Sm[g, a0 + c] * qc
            slj += St[g, a0 + c] * qc
            xj += X[g, a0 + c] * qc
            sdj += St[g, a0 + c] * dc
            dsd += dq[g] * Sm[g, a0 + c] * dc
        F[layout.AX_Y, j] = yj
        F[layout.AX_SL, j] = slj
        F[layout.AX_BETA_MODES, j] = xj  # X delta, for now
        p += q[g] * yj
        px += q[g] * xj
        pxd += dq[g] * xj
        ul2 += q[g] * slj
        sdd += dq[g] * sdj
        sld += slj * dq[g]
        ydd += yj * dq[g]
        for b in range(nm):
            r = 0.0
            t = 0.0
            for c in range(nm):
                r += T3[g, b, c] * q[a0 + c]
                t += T3[g, b, c] * dq[a0 + c]
            F[rr + j, b] = r
            rdd += q[g] * t * dq[a0 + b]
    for b in range(nm):
        gb = a0 + b
        for d in range(nm):
            qbd = 0.0
            tbd = 0.0
            for a in range(nm):
                sq = 0.0
                sd = 0.0
                for c in range(nm):
                    t4 = T4[gb, a, d, c]
                    sq += t4 * q[a0 + c]
                    sd += t4 * dq[a0 + c]
                qbd += q[a0 + a] * sq
                tbd += q[a0 + a] * sd
            F[rq + b, d] = qbd
            F[rt + b, d] = tbd
    dqd = 0.0  # delta' Q delta
    dqdd = 0.0  # delta' Q delta_dot
    for b in range(nm):
        for d in range(nm):
            dqd += q[a0 + b] * F[rq + b, d] * q[a0 + d]
            dqdd += q[a0 + b] * F[rq + b, d] * dq[a0 + d]
    ad2 = ad * ad
    for j in range(nm):
        wa = 0.0  # (R' delta - 1/2 R delta)_j
        bm = 0.0  # beta_delta_j
        for a in range(nm):
            wa += F[rr + a, j] * q[a0 + a] - 0.5 * F[rr + j, a] * q[a0 + a]
            bm += (
                -2.0 * ad * F[rr + j, a] * dq[a0 + a]
                + 2.0 * ad * F[rr + a, j] * dq[a0 + a]
                - 0.5 * ad2 * F[rq + j, a] * q[a0 + a]
                + F[rt + j, a] * dq[a0 + a]
            )
        F[layout.AX_WALPHA, j] = wa
        F[layout.AX_BETA_MODES, j] = bm + ad2 * F[layout.AX_BETA_MODES, j] - bx * F[layout.AX_Y, j]
    F[layout.AX_IALPHA, 0] = -px + 0.25 * dqd
    F[layout.AX_BETA, 0] = 0.5 * ad2 * p - dsd
    F[layout.AX_BETA, 1] = -2.0 * ad * ydd
    F[layout.AX_BETA, 2] = -0.5 * by * p + rdd - 2.0 * ad * (pxd - 0.5 * dqdd)
    F[layout.AX_TIP, 0] = 0.5 * ul2
    F[layout.AX_TIP, 1] = sdd
    F[layout.AX_TIP, 2] = sld
    return cx - 0.5 * p
