r"""Gravity in the plane of motion, compiled: :func:`gravity_forces`.

Internal: the generalised gravity forces ``-dV/dq`` that the kernels add to their
right-hand sides (the dense and recursive kernels through
``_dense.generalized_forces``, the prescribed-motion kernel, and the scalar
two-link kernel through :func:`gravity_forces_two_links_one_mode`).
:mod:`flexarm.model.gravity` is their NumPy reference and derives the potential.

With ``alpha_i`` link ``i``'s absolute angle and ``g_i = R(alpha_i)' g`` gravity
in its frame, the potential is

.. math:: V = -\sum_i g_i \cdot b_i(\delta_i), \qquad
          b_i = \int \rho \, [x - u_i, w_i]^T dx + m^{out}_i \, [L_i - u_i(L_i), w_i(L_i)]^T,

``m^out_i`` the mass the tip of link ``i`` carries (every outboard link and hub
and the payload). Then ``dV/dalpha_i = g_i . J b_i`` (``J`` the quarter turn),
the joint ``k`` force is ``-sum_{i >= k} dV/dalpha_i``, and a mode of link ``k``
gets its direct term and ``-sum_{i > k} dV/dalpha_i`` times its tip slope. The
links are visited from the last inwards (each link's angle recovered from the
next one's), so no scratch is needed.

An arm without gravity has ``arrays.gravity == (0, 0)``: every function here
returns at once and the kernels' results are those of the arm without these
terms, bit for bit.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ..arrays import HUB_MASS, LEN, MASS, STATIC, ArmArrays

__all__ = ["gravity_forces", "gravity_forces_two_links_one_mode", "has_gravity"]

F64 = NDArray[np.float64]


@nb.njit(cache=True, nogil=True, inline="always")
def has_gravity(arrays: ArmArrays) -> bool:  # pragma: no cover - compiled
    """Whether the arm has gravity (``arrays.gravity`` not ``(0, 0)``)."""
    return bool(arrays.gravity[0] != 0.0 or arrays.gravity[1] != 0.0)


@nb.njit(cache=True, nogil=True, inline="always")
def gravity_forces(q: F64, arrays: ArmArrays, rhs: F64) -> float:  # pragma: no cover - compiled
    """Add the generalised gravity forces ``-dV/dq`` to ``rhs`` (order of ``q``, N m
    and modal units) and return the potential ``V`` (J); without gravity add
    nothing and return 0.

    Parameters
    ----------
    q : ndarray, shape (n_dof,)
    arrays : ArmArrays
    rhs : ndarray, shape (n_dof,)
        Added to.
    """
    if not has_gravity(arrays):
        return 0.0
    gx, gy = arrays.gravity[0], arrays.gravity[1]
    ms = arrays.mode_start
    lk = arrays.link
    v, tdef, tslope = arrays.mass_integral, arrays.tip_deflection, arrays.tip_slope
    st, sm = arrays.shortening_tip, arrays.shortening_mass
    shortening = arrays.shortening_quartic.shape[1] > 0
    n_links = lk.shape[0]
    alpha = 0.0  # absolute angle of the last link
    for i in range(n_links):
        gamma = q[i]
        if i > 0:
            for g in range(ms[i - 1], ms[i]):
                gamma += tslope[g] * q[g]
        alpha += gamma
    carried = arrays.payload[0]  # mass at the tip of the current link, kg
    outer = 0.0  # sum of dV/dalpha over the links beyond the current one
    potential = 0.0
    for i in range(n_links - 1, -1, -1):
        a0, a1 = ms[i], ms[i + 1]
        c, s = np.cos(alpha), np.sin(alpha)
        glx, gly = c * gx + s * gy, -s * gx + c * gy  # gravity in the link's frame
        L = lk[i, LEN]
        bx = lk[i, STATIC] + carried * L
        by = 0.0
        for g in range(a0, a1):
            by += (v[g] + carried * tdef[g]) * q[g]
        if shortening:
            for g in range(a0, a1):
                ym, yt = 0.0, 0.0
                for k in range(a0, a1):
                    ym += sm[g, k] * q[k]
                    yt += st[g, k] * q[k]
                bx -= 0.5 * q[g] * (ym + carried * yt)
        for g in range(a0, a1):
            dbx = 0.0
            if shortening:
                ym, yt = 0.0, 0.0
                for k in range(a0, a1):
                    ym += sm[g, k] * q[k]
                    yt += st[g, k] * q[k]
                dbx = -(ym + carried * yt)
            dby = v[g] + carried * tdef[g]
            rhs[g] += glx * dbx + gly * dby - outer * tslope[g]
        potential -= glx * bx + gly * by
        outer += glx * by - gly * bx
        rhs[i] -= outer
        carried += lk[i, MASS] + lk[i, HUB_MASS]
        if i > 0:
            gamma = q[i]
            for g in range(ms[i - 1], ms[i]):
                gamma += tslope[g] * q[g]
            alpha -= gamma
    return potential


@nb.njit(cache=True, nogil=True, inline="always")
def gravity_forces_two_links_one_mode(
    a1: float, a2: float, d1: float, d2: float, arrays: ArmArrays
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """:func:`gravity_forces` of the paper's structure (two links, one mode each,
    rigid joints, no geometric stiffening) in scalars: the forces on
    ``(theta1, theta2, delta1, delta2)``, N m and modal units."""
    gx, gy = arrays.gravity[0], arrays.gravity[1]
    lk = arrays.link
    v, tdef, tslope = arrays.mass_integral, arrays.tip_deflection, arrays.tip_slope
    alpha0 = a1
    alpha1 = alpha0 + (a2 + tslope[2] * d1)
    # link 1 (the outer one) carries the payload
    carried = arrays.payload[0]
    c, s = np.cos(alpha1), np.sin(alpha1)
    glx, gly = c * gx + s * gy, -s * gx + c * gy
    bx = lk[1, STATIC] + carried * lk[1, LEN]
    dby = v[3] + carried * tdef[3]
    by = dby * d2
    f3 = gly * dby
    outer = glx * by - gly * bx
    f1 = -outer
    # link 0 carries link 1 and its hub
    carried += lk[1, MASS] + lk[1, HUB_MASS]
    c, s = np.cos(alpha0), np.sin(alpha0)
    glx, gly = c * gx + s * gy, -s * gx + c * gy
    bx = lk[0, STATIC] + carried * lk[0, LEN]
    dby = v[2] + carried * tdef[2]
    by = dby * d1
    f2 = gly * dby - outer * tslope[2]
    outer += glx * by - gly * bx
    f0 = -outer
    return f0, f1, f2, f3
