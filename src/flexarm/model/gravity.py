r"""Gravity in the plane of motion: the potential ``V(q)`` and its forces, NumPy reference.

An arm built with ``gravity=(g_x, g_y)`` (m/s**2, base frame; ``(0, -9.81)`` for
an arm in a vertical plane with ``y`` up) has the potential of every mass in it,

.. math:: V(q) = -g \cdot \Big( \sum_i \int_0^{L_i} \rho_i \, p_i(x) \, dx
          + \sum_{i \ge 1} m_{h,i} \, o_i + m_p \, o_N \Big),

with ``p_i(x)`` the deflected point of :mod:`flexarm.model.arm` (its
foreshortening ``u_i(x) = 1/2 delta_i' S_i(x) delta_i`` included with geometric
stiffening), ``o_i`` joint ``i`` (carrying hub ``i``; the first hub sits on the
fixed base) and ``o_N`` the last tip (the payload). Motors have no mass of their
own in the model: a rotor's mass belongs in its hub's ``hub_mass``.

Written per link, in its frame at absolute angle ``alpha_i``
(the internal ``flexarm.model.dynamics._gravity`` has the same sums compiled):
``V = -sum_i (R(alpha_i)' g) . b_i`` with the link's first moment about its
joint plus the mass its tip carries,

.. math:: b_i = \Big[\rho L^2/2 - \tfrac12 \delta' (\smallint \rho S) \delta,
          \ (\smallint \rho \phi) \cdot \delta\Big]
          + m^{out}_i \big[L - \tfrac12 \delta' S(L) \delta,\ \phi(L) \cdot \delta\big].

The quadratic terms are the geometric stiffness of the axial load: with gravity
along a link pointing away from its joint (hanging) they add
``g delta' (int rho S + m_out S(L)) delta / 2 >= 0`` to ``V`` and stiffen it,
pointing towards the joint (standing) they soften it, and beyond the buckling
load (Greenhill's ``(rho g L**3)_cr = 7.837 EI`` for a uniform column under
its own weight) the straight link is unstable
(:meth:`flexarm.FlexibleArm.equilibrium`). Without geometric stiffening ``V`` is
linear in the modal coordinates.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validation import check_real
from ..errors import InvalidTypeError, InvalidValueError
from .arrays import HUB_MASS, LEN, MASS, STATIC

__all__ = ["check_gravity", "gravity_forces", "gravity_potential", "gravity_stiffness"]


def check_gravity(value: Any, owner: str) -> tuple[float, float] | None:
    """``value`` as ``(g_x, g_y)`` (two finite floats, m/s**2), or None; otherwise an
    error naming ``gravity``."""
    if value is None:
        return None
    if isinstance(value, str | bytes) or not hasattr(value, "__len__"):
        raise InvalidTypeError(
            f"The 'gravity' parameter of {owner} must be None or two real numbers "
            f"(g_x, g_y) in m/s**2. Got {value!r} instead."
        )
    if len(value) != 2:
        raise InvalidValueError(
            f"The 'gravity' parameter of {owner} must be None or two real numbers "
            f"(g_x, g_y) in m/s**2. Got {len(value)} values instead."
        )
    gx = check_real(value[0], "gravity", owner)
    gy = check_real(value[1], "gravity", owner)
    return gx, gy


def _link_terms(arm: Any, q: NDArray[Any]) -> tuple[list[Any], list[Any], list[Any], list[Any]]:
    """Per link: its absolute angle, gravity in its frame, ``b_i`` (2,) and
    ``d b_i / d delta_i`` (2, m) (module docstring)."""
    a = arm.arrays
    gx, gy = arm.gravity
    n_links = arm.n_links
    carried = np.zeros(n_links)
    mass = a.payload[0]  # the payload and the last link's tip body
    for i in range(n_links - 1, -1, -1):
        carried[i] = mass
        mass += a.link[i, MASS] + a.link[i, HUB_MASS]
    alphas, gravities, firsts, grads = [], [], [], []
    alpha: Any = 0.0
    for i in range(n_links):
        s = arm.modal_slice(i)
        alpha = alpha + q[i]
        if i > 0:
            prev = arm.modal_slice(i - 1)
            alpha = alpha + a.tip_slope[prev] @ q[prev]
        c, sn = np.cos(alpha), np.sin(alpha)
        local = np.array([c * gx + sn * gy, -sn * gx + c * gy])
        delta = q[s]
        mo = carried[i]
        lateral = a.mass_integral[s] + mo * a.tip_deflection[s]
        b = np.array([a.link[i, STATIC] + mo * a.link[i, LEN], lateral @ delta])
        db = np.zeros((2, delta.shape[0]), dtype=np.result_type(q, float))
        db[1] = lateral
        if arm.geometric_stiffening and delta.shape[0]:
            axial = a.shortening_mass[s, s] + mo * a.shortening_tip[s, s]
            b[0] = b[0] - 0.5 * delta @ axial @ delta
            db[0] = -(axial @ delta)
        alphas.append(alpha)
        gravities.append(local)
        firsts.append(b)
        grads.append(db)
    return alphas, gravities, firsts, grads


def gravity_potential(arm: Any, q: NDArray[Any]) -> Any:
    """``V(q)`` in J of ``arm`` (a :class:`flexarm.FlexibleArm` with gravity) at ``q``
    (shape (n_dof,), real or complex); 0 without gravity."""
    if arm.gravity is None:
        return 0.0
    _, gravities, firsts, _ = _link_terms(arm, q)
    return -sum(g @ b for g, b in zip(gravities, firsts, strict=True))


def gravity_forces(arm: Any, q: NDArray[Any]) -> NDArray[Any]:
    """The generalised gravity forces ``-dV/dq``, shape (n_dof,) (N m, modal units),
    of ``arm`` at ``q`` (real or complex); zeros without gravity."""
    out = np.zeros(arm.n_dof, dtype=np.result_type(q, float))
    if arm.gravity is None:
        return out
    _, gravities, firsts, grads = _link_terms(arm, q)
    quarter = np.array([[0.0, -1.0], [1.0, 0.0]])
    # dV/dalpha_i = -g_i . J b_i, J the quarter turn
    dv_dalpha = [-(g @ (quarter @ b)) for g, b in zip(gravities, firsts, strict=True)]
    outer: Any = 0.0  # sum of dV/dalpha over the links beyond link i
    a = arm.arrays
    for i in range(arm.n_links - 1, -1, -1):
        s = arm.modal_slice(i)
        out[s] = gravities[i] @ grads[i] - outer * a.tip_slope[s]
        outer = outer + dv_dalpha[i]
        out[i] = -outer
    return out


def gravity_stiffness(arm: Any, q: NDArray[np.float64]) -> NDArray[np.float64]:
    """The Hessian ``d2V/dq2`` at real ``q`` (shape (n_dof, n_dof)), by complex-step
    differentiation of :func:`gravity_forces` (exact to rounding); zeros without
    gravity."""
    n = arm.n_dof
    out = np.zeros((n, n))
    if arm.gravity is None:
        return out
    step = 1e-30
    for k in range(n):
        qc = np.asarray(q, dtype=complex)
        qc[k] += 1j * step
        out[:, k] = -gravity_forces(arm, qc).imag / step
    return 0.5 * (out + out.T)
