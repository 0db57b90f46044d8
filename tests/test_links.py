"""Rigid links and tip bodies: :class:`flexarm.RigidLink`, ``Link.tip_mass`` /
``tip_inertia``.

Oracles: the textbook mass matrix of two rigid links on revolute joints
(written out by hand, each body's mass, centre-of-mass distance and inertia),
the frequency equation of a clamped beam with a tip mass and rotary inertia
(solved here with brentq), the compiled and NumPy backends held together.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import flexarm as fa
from helpers.arms import assert_mass_matrix_and_kernels


def two_link_mass_matrix(bodies1, bodies2, l1, theta2):
    """Two rigid links on revolute joints, each carrying bodies ``(m, lc, I)``: mass
    ``m``, its centre ``lc`` m from its link's joint along the link, inertia ``I``
    about that centre. The textbook terms, by hand."""
    c2 = math.cos(theta2)
    M = np.zeros((2, 2))
    for m, lc, inertia in bodies1:
        M[0, 0] += inertia + m * lc**2
    for m, lc, inertia in bodies2:
        M[0, 0] += inertia + m * (l1**2 + lc**2 + 2 * l1 * lc * c2)
        M[0, 1] += inertia + m * (lc**2 + l1 * lc * c2)
        M[1, 1] += inertia + m * lc**2
    M[1, 0] = M[0, 1]
    return M


@pytest.mark.parametrize("theta2", [0.0, -0.7, 2.4])
def test_two_rigid_links_with_tip_bodies_have_the_textbook_mass_matrix(theta2):
    l1, l2 = 1.0, 0.8
    links = [
        fa.RigidLink(l1, 1.3, 0.4, 0.05, tip_mass=0.2, tip_inertia=0.01),
        fa.RigidLink(l2, 0.56, 0.3, 0.02, hub_mass=0.05, tip_mass=0.1, tip_inertia=0.003),
    ]
    arm = fa.FlexibleArm(links, payload_mass=0.07, payload_inertia=0.001)
    q = np.array([0.3, theta2])
    # link 1: its body and its tip body; the hub of joint 2 at link 1's tip
    bodies1 = [(1.3, 0.4, 0.05), (0.2, l1, 0.01), (0.05, l1, 0.0)]
    # link 2: its body, its tip body and the payload at its tip
    bodies2 = [(0.56, 0.3, 0.02), (0.1, l2, 0.003), (0.07, l2, 0.001)]
    expected = two_link_mass_matrix(bodies1, bodies2, l1, theta2)
    dq = assert_mass_matrix_and_kernels(arm, q, expected, seed=2)
    # the velocity terms of the same bodies: h = C dq with the textbook Christoffel form
    s2 = math.sin(theta2)
    hh = sum(m * l1 * lc for m, lc, _ in bodies2) * s2
    h = np.array([-hh * (2 * dq[0] * dq[1] + dq[1] ** 2), hh * dq[0] ** 2])
    np.testing.assert_allclose(arm.velocity_terms(q, dq), h, rtol=1e-12, atol=1e-14)


def test_a_rigid_link_is_the_rigid_uniform_rod():
    """RigidLink(L, rho L, L / 2, rho L**3 / 12) is Link(n_modes=0): the same arrays."""
    L, rho = 1.4, 0.9
    rod = fa.Link(L, 10.0, rho, n_modes=0, hub_inertia=0.1, tip_mass=0.3)
    rigid = fa.RigidLink(L, rho * L, L / 2, rho * L**3 / 12, hub_inertia=0.1, tip_mass=0.3)
    assert rigid.n_modes == 0 and rigid.joint_inertia == pytest.approx(rod.rod_inertia)
    a, b = fa.FlexibleArm([rod, rod]), fa.FlexibleArm([rigid, rigid])
    np.testing.assert_allclose(b.arrays.link, a.arrays.link, rtol=1e-15)
    q = np.array([0.2, 1.1])
    np.testing.assert_allclose(b.mass_matrix(q), a.mass_matrix(q), rtol=1e-14)
    # a rigid link keeps no modes when the others change theirs
    mixed = fa.FlexibleArm([fa.Link(L, 10.0, rho), rigid]).with_modes(2)
    assert mixed.n_modes == (2, 0)
    with pytest.raises(ValueError, match=r"'n_modes'.*RigidLink"):
        mixed.with_modes([2, 1])


def tip_loaded_roots(mu, j, count):
    """The first ``count`` roots lambda = beta L of a clamped beam carrying a tip mass
    M = mu rho L and rotary inertia J = j rho L**3. With w = a (cosh - cos) +
    b (sinh - sin) the tip conditions EI w''(L) = J omega**2 w'(L) and
    EI w'''(L) = -M omega**2 w(L), omega**2 = EI beta**4 / rho, make a 2 x 2 system
    whose determinant vanishes."""

    def det(lam):
        ch, c, sh, s = math.cosh(lam), math.cos(lam), math.sinh(lam), math.sin(lam)
        # w, w', w'', w''' at L of the two shape functions, in units of beta**k
        u = (ch - c, sh + s, ch + c, sh - s)
        v = (sh - s, ch - c, sh + s, ch + c)
        r1 = [f[2] - j * lam**3 * f[1] for f in (u, v)]  # w'' - (J/rho) beta**4 w' ...
        r2 = [f[3] + mu * lam * f[0] for f in (u, v)]  # w''' + (M/rho) beta**4 w ...
        return (r1[0] * r2[1] - r1[1] * r2[0]) / ch**2

    grid = np.linspace(0.05, 4 * count + 4, 4000)
    vals = [det(x) for x in grid]
    roots = [
        brentq(det, grid[k], grid[k + 1], xtol=1e-15)
        for k in range(len(grid) - 1)
        if vals[k] * vals[k + 1] < 0
    ]
    return np.array(roots[:count])


@pytest.mark.parametrize(("tip_mass", "tip_inertia"), [(0.6, 0.0), (0.6, 0.05), (0.0, 0.08)])
def test_a_clamped_link_with_a_tip_body_has_the_frequencies_of_its_equation(tip_mass, tip_inertia):
    L, EI, rho = 1.2, 30.0, 0.8
    lam = tip_loaded_roots(tip_mass / (rho * L), tip_inertia / (rho * L**3), 2)
    omega = (lam / L) ** 2 * math.sqrt(EI / rho)
    link = fa.Link(L, EI, rho, n_modes=2, tip_mass=tip_mass, tip_inertia=tip_inertia)
    # clamped-mass modes are the exact modes of the loaded beam
    arm = fa.FlexibleArm([link], boundary="clamped-mass")
    np.testing.assert_allclose(arm.link_frequencies[0], omega, rtol=1e-9)
    np.testing.assert_allclose(arm.natural_frequencies(joints="locked"), omega, rtol=1e-9)
    # cantilever modes ignore the tip body; the dynamics carry it, and converge to it
    # (slowly under a rotary inertia: a cantilever mode has no bending moment at its
    # tip, which the rotary inertia asks for)
    errors = []
    for k in (2, 4, 8):
        free = fa.FlexibleArm([dataclasses.replace(link, n_modes=k)], boundary="clamped-free")
        got = free.natural_frequencies(joints="locked")[:2]
        assert np.all(got >= omega * (1 - 1e-12))  # Rayleigh-Ritz: from above
        errors.append(got[0] / omega[0] - 1)
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-2


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"length": 0.0}, ValueError, "'length'"),
        ({"mass": -1.0}, ValueError, "'mass'"),
        ({"inertia": -0.1}, ValueError, "'inertia'"),
        ({"com": float("nan")}, ValueError, "'com'"),
        ({"com": "0.5"}, TypeError, "'com'"),
        ({"tip_mass": -1.0}, ValueError, "'tip_mass'"),
        ({"tip_inertia": -1.0}, ValueError, "'tip_inertia'"),
    ],
)
def test_rigid_link_rejects_bad_parameters(kwargs, error, match):
    params = {"length": 1.0, "mass": 1.0, "com": 0.5, "inertia": 0.1} | kwargs
    with pytest.raises(error, match=match):
        fa.RigidLink(**params)


def test_link_tip_body_is_checked():
    with pytest.raises(ValueError, match="'tip_mass'"):
        fa.Link(1.0, 1.0, 1.0, tip_mass=-0.1)
    with pytest.raises(TypeError, match=r"'links'.*Link or RigidLink"):
        fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0), "rigid"])


def test_an_arm_of_rigid_parts_and_tip_bodies_conserves_its_energy():
    """No damping, no friction: T + V stays constant along a free motion of an arm of
    geared rigid joints, a rigid link and flexible links with tip bodies."""
    from scipy.integrate import solve_ivp

    arm = fa.FlexibleArm(
        [
            fa.Link(2.0, 1676.0, 0.335, n_modes=2, tip_mass=0.3, tip_inertia=0.02),
            fa.RigidLink(1.5, 0.8, 0.6, 0.1, hub_mass=0.2, tip_inertia=0.05),
            fa.Link(1.2, 800.0, 0.3, n_modes=1, tip_mass=0.1, tip_inertia=0.004),
        ],
        joints=[
            fa.RigidJoint(0.3, gear_ratio=100.0),
            fa.RigidJoint(0.2, gear_ratio=4.0),
            fa.RigidJoint(0.0),
        ],
        payload_mass=0.4,
    )
    rng = np.random.default_rng(1)
    n = arm.n_dof
    x0 = np.r_[rng.normal(size=n) * 0.03, rng.normal(size=n)]
    sol = solve_ivp(
        lambda t, x: np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], np.zeros(3))],
        (0.0, 0.5),
        x0,
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        t_eval=np.linspace(0.0, 0.5, 11),
    )
    energies = np.array([sum(arm.energy(x[:n], x[n:])) for x in sol.y.T])
    assert np.abs(energies - energies[0]).max() <= 1e-8 * energies[0]
    np.testing.assert_allclose(
        arm.coriolis(x0[:n], x0[n:]) @ x0[n:], arm.velocity_terms(x0[:n], x0[n:]), atol=1e-12
    )
