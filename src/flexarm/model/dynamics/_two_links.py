"""The paper's structure in scalars, compiled: two links, one mode each, rigid joints.

Internal: the bare kernels behind
:func:`flexarm.model.dynamics.accelerations_two_links_one_mode`,
:func:`flexarm.model.dynamics.forward_dynamics_two_links_one_mode` and
:func:`flexarm.model.dynamics.is_two_links_one_mode`.

:func:`accelerations_two_links_one_mode` is the dense kernel
(:func:`flexarm.model.dynamics.forward_dynamics_dense`) written out for
``q = (theta1, theta2, delta1, delta2)``: the same quantities in the same order,
on scalars that stay in registers (about 4x faster a call). The tests hold the
two together.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ..arrays import (
    HUB_MASS,
    INERTIA,
    LEN,
    MASS,
    ROTOR_FRICTION,
    ROTOR_INERTIA,
    STATIC,
    TIP_INERTIA,
    ArmArrays,
)
from ._gravity import gravity_forces_two_links_one_mode, has_gravity

__all__ = [
    "accelerations_two_links_one_mode",
    "forward_dynamics_two_links_one_mode",
    "is_two_links_one_mode",
]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True, inline="always")
def is_two_links_one_mode(arrays: ArmArrays) -> bool:  # pragma: no cover - compiled
    """Whether :func:`forward_dynamics_two_links_one_mode` applies: two links with
    one mode each (``q = (theta1, theta2, delta1, delta2)``), rigid joints without
    rotors or friction (:class:`flexarm.model.joints.RigidJoint`), no tip body on the
    first link other than a point mass, and no geometric stiffening."""
    ms = arrays.mode_start
    if not (
        arrays.joint.shape[0] == 0
        and arrays.shortening_quartic.shape[1] == 0
        and ms.shape[0] == 3
        and ms[0] == 2
        and ms[1] == 3
        and ms[2] == 4
    ):
        return False
    lk = arrays.link
    for i in range(2):
        if lk[i, ROTOR_INERTIA] != 0.0 or lk[i, ROTOR_FRICTION] != 0.0:
            return False
    return bool(lk[0, TIP_INERTIA] == 0.0)


@nb.njit(cache=True, nogil=True, inline="always")
def accelerations_two_links_one_mode(
    a1: float,
    a2: float,
    d1: float,
    d2: float,
    da1: float,
    da2: float,
    dd1: float,
    dd2: float,
    tau1: float,
    tau2: float,
    arrays: ArmArrays,
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """The accelerations of a two-link arm with one mode per link and rigid joints
    (the paper's structure), in scalars.

    This is the dense kernel's assembly (``_dense.assemble_local``) written out
    for that structure, in the same local order ``(theta1, delta1, theta2,
    delta2)``, and a 2 x 2 block solve in place of its ``L D L'`` solve: every
    intermediate stays in a register, there is no loop, and one division is on
    the critical path. Hub mass, payload, gravity and any mode shape (the modal
    integrals) are covered; :func:`flexarm.model.dynamics.forward_dynamics` falls
    back to the general kernel for other structures.

    Parameters
    ----------
    a1, a2, d1, d2 : float
        ``q = (theta1, theta2, delta1, delta2)``.
    da1, da2, dd1, dd2 : float
        ``dq``, in the same order.
    tau1, tau2 : float
        Joint torques, N m.
    arrays : ArmArrays
        Must satisfy :func:`is_two_links_one_mode`.

    Returns
    -------
    tuple of 4 float
        ``ddq``, in the order of ``q``.
    """
    lk = arrays.link
    v, w = arrays.mass_integral, arrays.moment_integral
    tdef, tslope, md = arrays.tip_deflection, arrays.tip_slope, arrays.modal_mass
    v0, v1, w0, w1 = v[2], v[3], w[2], w[3]
    t0, t1, g0, g1 = tdef[2], tdef[3], tslope[2], tslope[3]
    md0, md1 = md[2, 2], md[3, 3]
    # ---- link 0: A = (1, 0, 0, 0), U = 0, no velocity forces at its joint
    ad = da1
    ad2 = ad * ad
    vd = v0 * d1
    e = t0 * d1
    m00 = lk[0, INERTIA] + d1 * md0 * d1
    m10 = w0
    m11 = md0
    h0 = 2.0 * ad * (d1 * md0 * dd1)
    h1 = -ad2 * md0 * d1
    # its tip, in its frame: U columns (theta1, delta1), A = (1, g0)
    u00, u10 = -e, lk[0, LEN]
    u11 = t0
    bx = -ad2 * lk[0, LEN] - 2.0 * ad * (t0 * dd1)
    by = -ad2 * e
    # ---- frame change to link 1: gamma = theta2 + tip slope of link 0
    gamma = a2 + g0 * d1
    cg, sg = np.cos(gamma), np.sin(gamma)
    u00, u10 = cg * u00 + sg * u10, -sg * u00 + cg * u10
    u01, u11 = sg * u11, cg * u11
    bx, by = cg * bx + sg * by, -sg * bx + cg * by
    mh = lk[1, HUB_MASS]
    if mh != 0.0:
        h0 += mh * (u00 * bx + u10 * by)
        h1 += mh * (u01 * bx + u11 * by)
        m00 += mh * (u00 * u00 + u10 * u10)
        m10 += mh * (u01 * u00 + u11 * u10)
        m11 += mh * (u01 * u01 + u11 * u11)
    ad += g0 * dd1 + da2
    ad2 = ad * ad
    # ---- link 1: A = (1, g0, 1, 0), U column theta2 = 0
    mass, cx = lk[1, MASS], lk[1, STATIC]
    vd = v1 * d2
    e = t1 * d2
    ia = lk[1, INERTIA] + d2 * md1 * d2
    p00, p10, p20 = mass * u00 - vd, mass * u10 + cx, -vd * u00 + cx * u10 + ia
    p01, p11 = mass * u01 - vd * g0, mass * u11 + cx * g0
    p21 = -vd * u01 + cx * u11 + ia * g0
    m00 += u00 * p00 + u10 * p10 + p20
    m10 += u01 * p00 + u11 * p10 + g0 * p20
    m11 += u01 * p01 + u11 * p11 + g0 * p21
    m20 = p20
    m21 = p21
    m22 = ia
    m30 = v1 * u10 + w1
    m31 = v1 * u11 + w1 * g0
    m32 = w1
    m33 = md1
    h3 = v1 * by - ad2 * md1 * d2
    beta_ux = mass * bx - ad2 * cx - 2.0 * ad * (v1 * dd2)
    beta_uy = mass * by - ad2 * vd
    beta_al = -bx * vd + 2.0 * ad * (d2 * md1 * dd2) + cx * by
    h0 += u00 * beta_ux + u10 * beta_uy + beta_al
    h1 += u01 * beta_ux + u11 * beta_uy + g0 * beta_al
    h2 = beta_al
    # ---- payload at the tip of link 1
    mp, jp = arrays.payload[0], arrays.payload[1]
    if mp != 0.0 or jp != 0.0:
        L1 = lk[1, LEN]
        u00, u10 = u00 - e, u10 + L1
        u01, u11 = u01 - e * g0, u11 + L1 * g0
        u02, u12 = -e, L1
        u13 = t1
        bx += -ad2 * L1 - 2.0 * ad * (t1 * dd2)
        by += -ad2 * e
        h0 += mp * (u00 * bx + u10 * by)
        h1 += mp * (u01 * bx + u11 * by)
        h2 += mp * (u02 * bx + u12 * by)
        h3 += mp * (u13 * by)
        m00 += mp * (u00 * u00 + u10 * u10) + jp
        m10 += mp * (u01 * u00 + u11 * u10) + jp * g0
        m11 += mp * (u01 * u01 + u11 * u11) + jp * g0 * g0
        m20 += mp * (u02 * u00 + u12 * u10) + jp
        m21 += mp * (u02 * u01 + u12 * u11) + jp * g0
        m22 += mp * (u02 * u02 + u12 * u12) + jp
        m30 += mp * (u13 * u10) + jp * g1
        m31 += mp * (u13 * u11) + jp * g0 * g1
        m32 += mp * (u13 * u12) + jp * g1
        m33 += mp * (u13 * u13) + jp * g1 * g1
    # ---- right-hand side, local order (theta1, delta1, theta2, delta2)
    k, c = arrays.stiffness, arrays.damping
    y0 = tau1 - k[0] * a1 - c[0] * da1 - h0
    y1 = -k[2] * d1 - c[2] * dd1 - h1
    y2 = tau2 - k[1] * a2 - c[1] * da2 - h2
    y3 = -k[3] * d2 - c[3] * dd2 - h3
    if has_gravity(arrays):
        f0, f1, f2, f3 = gravity_forces_two_links_one_mode(a1, a2, d1, d2, arrays)
        y0 += f0
        y1 += f2
        y2 += f1
        y3 += f3
    # ---- Block elimination. C = M[(theta2, delta2)] depends on delta2 only, so its
    # inverse is not on the path from gamma to ddq; the Schur complement
    # S = A - B C^-1 B' of A = M[(theta1, delta1)] (B = M[(theta1, delta1),
    # (theta2, delta2)]) then costs one division there instead of four.
    ic = 1.0 / (m22 * m33 - m32 * m32)
    c22, c32, c33 = m33 * ic, -m32 * ic, m22 * ic  # C^-1
    k00 = m20 * c22 + m30 * c32  # B C^-1
    k01 = m20 * c32 + m30 * c33
    k10 = m21 * c22 + m31 * c32
    k11 = m21 * c32 + m31 * c33
    s00 = m00 - (k00 * m20 + k01 * m30)
    s10 = m10 - (k10 * m20 + k11 * m30)
    s11 = m11 - (k10 * m21 + k11 * m31)
    r0 = y0 - (k00 * y2 + k01 * y3)
    r1 = y1 - (k10 * y2 + k11 * y3)
    i_s = 1.0 / (s00 * s11 - s10 * s10)
    x0 = (s11 * r0 - s10 * r1) * i_s
    x1 = (s00 * r1 - s10 * r0) * i_s
    e2 = y2 - (m20 * x0 + m21 * x1)
    e3 = y3 - (m30 * x0 + m31 * x1)
    x2 = c22 * e2 + c32 * e3
    x3 = c32 * e2 + c33 * e3
    return x0, x2, x1, x3


@nb.njit(cache=True, nogil=True, inline="always")
def forward_dynamics_two_links_one_mode(
    q: F64, dq: F64, tau: F64, arrays: ArmArrays, ddq: F64
) -> None:  # pragma: no cover - compiled
    """:func:`accelerations_two_links_one_mode` on arrays: ``ddq`` from ``q, dq, tau``."""
    ddq[0], ddq[1], ddq[2], ddq[3] = accelerations_two_links_one_mode(
        q[0], q[1], q[2], q[3], dq[0], dq[1], dq[2], dq[3], tau[0], tau[1], arrays
    )
