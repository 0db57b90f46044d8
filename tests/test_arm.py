"""The flexible-link arm: closed forms, invariants and cross-checks.

Oracles used here are independent of the closed-form mass matrix: the textbook
rigid two-link model, exact clamped-mass frequencies, pinned-free beam roots,
finite differences of the kinematics, energy conservation under a tight
integrator, and the power balance. The independent SymPy derivation of M and
C dq lives in ``test_sympy_derivation.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import flexarm as fa
from flexarm.modes import BeamModes
from helpers.arms import LINEAR_CLAMPED_FREE, random_state, three_links, two_short_links

ARMS = {
    "paper": lambda: fa.FlexibleArm.paper(),
    "paper-2modes": lambda: fa.FlexibleArm.paper(n_modes=2),
    "one-link": lambda: fa.FlexibleArm(
        [fa.Link(1.2, 3.0, 0.8, n_modes=3, hub_inertia=0.1)], **LINEAR_CLAMPED_FREE
    ),
    "three-links-mixed": lambda: three_links(**LINEAR_CLAMPED_FREE),
    "clamped-mass": lambda: two_short_links(2, boundary="clamped-mass", geometric_stiffening=False),
    # geometric stiffening (the default of an arm a user builds): foreshortening in the map
    "stiffening-three-links": lambda: three_links(
        boundary="clamped-mass", geometric_stiffening=True
    ),
    "stiffening-defaults": lambda: two_short_links(payload_inertia=0.0),
    "amplitude-normalised": lambda: fa.FlexibleArm.paper(
        n_modes=2, mode_normalization="amplitude", mode_amplitude=0.1
    ),
    "damped": lambda: fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.1, n_modes=2, modal_damping=0.05)] * 2,
        payload_mass=0.2,
        **LINEAR_CLAMPED_FREE,
    ),
    "damped-stiffening": lambda: fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.1, n_modes=2, modal_damping=0.05)] * 2,
        payload_mass=0.2,
        geometric_stiffening=True,
    ),
}


@pytest.fixture(params=sorted(ARMS), scope="module")
def arm(request) -> fa.FlexibleArm:
    return ARMS[request.param]()


# ---------------------------------------------------------------- the paper arm
def test_paper_arm_parameters():
    arm = fa.FlexibleArm.paper()
    assert arm.n_links == 2 and arm.n_dof == 4 and arm.n_modes == (1, 1)
    for lk in arm.links:
        assert (lk.length, lk.flexural_rigidity, lk.linear_density) == (4.5, 1676.0, 0.335)
    # paper.md: omega_1 = 12.281 rad/s (the paper prints "12.28 Hz"; it is rad/s)
    for w in arm.link_frequencies:
        assert w[0] == pytest.approx(12.281, abs=5e-4)
    assert arm.coordinate_names == ["theta1", "theta2", "delta1_1", "delta2_1"]


# ------------------------------------------------------------------ rigid limit
def textbook_two_link(m1, m2, l1, l2, th2, dth1, dth2):
    """Spong's two-link arm with uniform rods (lc = l/2, I = m l^2 / 12)."""
    lc1, lc2 = l1 / 2, l2 / 2
    i1, i2 = m1 * l1**2 / 12, m2 * l2**2 / 12
    c2, s2 = math.cos(th2), math.sin(th2)
    d11 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * c2) + i1 + i2
    d12 = m2 * (lc2**2 + l1 * lc2 * c2) + i2
    d22 = m2 * lc2**2 + i2
    hh = -m2 * l1 * lc2 * s2
    h = np.array([hh * (2 * dth1 * dth2 + dth2**2), -hh * dth1**2])
    return np.array([[d11, d12], [d12, d22]]), h


def test_rigid_limit_matches_textbook_two_link():
    rng = np.random.default_rng(1)
    l1, l2, r1, r2 = 1.1, 0.7, 2.0, 1.3
    arm = fa.FlexibleArm([fa.Link(l1, 1.0, r1, n_modes=0), fa.Link(l2, 1.0, r2, n_modes=0)])
    for _ in range(5):
        q, dq = rng.uniform(-3, 3, 2), rng.normal(size=2)
        M_ref, h_ref = textbook_two_link(r1 * l1, r2 * l2, l1, l2, q[1], *dq)
        np.testing.assert_allclose(arm.mass_matrix(q), M_ref, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(arm.velocity_terms(q, dq), h_ref, rtol=1e-12, atol=1e-13)


def test_stiff_links_approach_rigid_arm():
    """Under a smooth torque the joint trajectory converges to the rigid arm's as
    EI grows; the quasi-static deflection error scales like 1/omega**2 ~ 1/EI."""

    def torque(t):
        return np.array([0.5, -0.2]) * np.sin(np.pi * t) ** 2

    def joint_path(arm):
        n = arm.n_dof

        def rhs(t, x):
            return np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], torque(t), backend="compiled")]

        sol = solve_ivp(
            rhs,
            (0, 1.0),
            np.zeros(2 * n),
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            t_eval=np.linspace(0, 1, 11),
        )
        assert sol.success
        return sol.y[:2].T

    rigid = joint_path(fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 2))
    errors = [
        np.abs(
            joint_path(
                fa.FlexibleArm([fa.Link(1.0, ei, 1.0, n_modes=1)] * 2, **LINEAR_CLAMPED_FREE)
            )
            - rigid
        ).max()
        for ei in (1e2, 1e3, 1e4)
    ]
    assert errors[0] > errors[1] > errors[2]
    assert errors[0] / errors[1] > 5 and errors[1] / errors[2] > 5
    assert errors[2] < 1e-3 * np.abs(rigid).max()


# --------------------------------------------------------- structural invariants
def test_mass_matrix_symmetric_positive_definite(arm):
    rng = np.random.default_rng(2)
    for _ in range(5):
        q, _ = random_state(arm, rng)
        M = arm.mass_matrix(q)
        np.testing.assert_allclose(M, M.T, rtol=0, atol=1e-14 * np.abs(M).max())
        assert np.linalg.eigvalsh(M).min() > 0
        np.linalg.cholesky(M)


def test_christoffel_coriolis_equals_recursive_velocity_terms(arm):
    """Two independent routes to C dq: Christoffel symbols of dM/dq (complex step)
    and the body-frame d'Alembert recursion."""
    rng = np.random.default_rng(3)
    for _ in range(4):
        q, dq = random_state(arm, rng)
        h = arm.velocity_terms(q, dq)
        np.testing.assert_allclose(
            arm.coriolis(q, dq) @ dq, h, rtol=1e-11, atol=1e-11 * np.abs(h).max()
        )


def test_mdot_minus_2c_is_skew_symmetric(arm):
    """Mdot by central finite differences of M along dq (independent of the
    complex-step derivatives that build C)."""
    rng = np.random.default_rng(4)
    q, dq = random_state(arm, rng)
    eps = 1e-6
    mdot = (arm.mass_matrix(q + eps * dq) - arm.mass_matrix(q - eps * dq)) / (2 * eps)
    S = mdot - 2 * arm.coriolis(q, dq)
    scale = np.abs(mdot).max()
    np.testing.assert_allclose(S, -S.T, atol=1e-7 * scale)
    # and the skew part is not trivially zero
    assert np.abs(S).max() > 1e-3 * scale


def test_compiled_kernel_matches_numpy_reference(arm):
    rng = np.random.default_rng(5)
    for _ in range(10):
        q, dq = random_state(arm, rng)
        tau = rng.normal(size=arm.n_links)
        ref = arm.forward_dynamics(q, dq, tau, backend="numpy")
        got = arm.forward_dynamics(q, dq, tau, backend="compiled")
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


def test_compiled_mass_and_bias_match_numpy(arm):
    from flexarm.model import dynamics

    rng = np.random.default_rng(6)
    ws = dynamics.make_workspace(arm.n_dof)
    q, dq = random_state(arm, rng)
    dynamics.mass_and_bias(q, dq, arm.arrays, ws)
    np.testing.assert_allclose(ws.mass, arm.mass_matrix(q), rtol=1e-12, atol=1e-12)
    h = arm.velocity_terms(q, dq)
    np.testing.assert_allclose(ws.bias, h, rtol=1e-12, atol=1e-12 * np.abs(h).max())


# ------------------------------------------------------------------- energy
def _integrate(arm, q0, dq0, tau, t_end):
    n = arm.n_dof

    def rhs(_t, x):
        return np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], tau, backend="compiled")]

    return solve_ivp(
        rhs,
        (0, t_end),
        np.r_[q0, dq0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=False,
        t_eval=np.linspace(0, t_end, 21),
    )


@pytest.mark.parametrize(
    "name",
    [
        "paper",
        "paper-2modes",
        "three-links-mixed",
        "clamped-mass",
        "stiffening-three-links",
        "stiffening-defaults",
    ],
)
def test_energy_conserved_without_torque_or_damping(name):
    arm = ARMS[name]()
    rng = np.random.default_rng(7)
    q0, dq0 = random_state(arm, rng, scale=0.05)
    e0 = sum(arm.energy(q0, dq0))
    sol = _integrate(arm, q0, dq0, np.zeros(arm.n_links), 1.0)
    assert sol.success
    n = arm.n_dof
    energies = np.array([sum(arm.energy(x[:n], x[n:])) for x in sol.y.T])
    assert np.abs(energies - e0).max() <= 1e-8 * e0
    # the motion is not trivial: energy moved between kinetic and potential
    kin = np.array([arm.energy(x[:n], x[n:])[0] for x in sol.y.T])
    assert kin.max() - kin.min() > 1e-3 * e0


@pytest.mark.parametrize("name", ["damped", "damped-stiffening"])
def test_power_balance_with_torque_and_damping(name):
    """dE/dt = dq' B tau - dq' D dq, with dE/dt from M, dM/dq and the accelerations."""
    arm = ARMS[name]()
    rng = np.random.default_rng(8)
    q, dq = random_state(arm, rng)
    tau = rng.normal(size=arm.n_links)
    ddq = arm.forward_dynamics(q, dq, tau)
    M = arm.mass_matrix(q)
    mdot = np.einsum("kij,k->ij", arm.mass_matrix_derivatives(q), dq)
    de = dq @ M @ ddq + 0.5 * dq @ mdot @ dq + q @ arm.stiffness_matrix @ dq
    power = dq @ arm.input_matrix @ tau - dq @ arm.damping_matrix @ dq
    assert de == pytest.approx(power, rel=1e-10, abs=1e-10)


@pytest.mark.parametrize("name", ["damped", "damped-stiffening"])
def test_damping_dissipates_energy(name):
    arm = ARMS[name]()
    rng = np.random.default_rng(9)
    q0, dq0 = random_state(arm, rng, scale=0.05)
    sol = _integrate(arm, q0, dq0, np.zeros(arm.n_links), 2.0)
    n = arm.n_dof
    energies = np.array([sum(arm.energy(x[:n], x[n:])) for x in sol.y.T])
    assert np.all(np.diff(energies) <= 1e-12 * energies[0])
    assert energies[-1] < 0.9 * energies[0]


def test_modal_damping_matrix():
    arm = fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.1, n_modes=2, modal_damping=0.05)], **LINEAR_CLAMPED_FREE
    )
    w = arm.link_frequencies[0]
    # mass-normalised modes: D = 2 zeta omega
    np.testing.assert_allclose(np.diag(arm.damping_matrix)[1:], 2 * 0.05 * w, rtol=1e-12)
    assert arm.damping_matrix[0, 0] == 0.0


# ------------------------------------------------------- natural frequencies
def test_locked_single_link_with_payload_is_exact_with_clamped_mass_modes():
    """With clamped-mass modes the assumed modes are the exact modes of a link
    carrying the payload, so the locked arm reproduces the exact frequencies."""
    L, ei, rho, mp, jp = 1.3, 2.0, 0.7, 0.4, 0.05
    arm = fa.FlexibleArm(
        [fa.Link(L, ei, rho, n_modes=4)],
        payload_mass=mp,
        payload_inertia=jp,
        boundary="clamped-mass",
        geometric_stiffening=False,
    )
    exact = BeamModes(L, ei, rho, 4, tip_mass=mp, tip_inertia=jp).frequencies
    np.testing.assert_allclose(arm.natural_frequencies(joints="locked"), exact, rtol=1e-10)


def test_locked_single_link_with_payload_converges_from_above_with_cantilever_modes():
    L, ei, rho, mp, jp = 1.3, 2.0, 0.7, 0.4, 0.05
    exact = BeamModes(L, ei, rho, 1, tip_mass=mp, tip_inertia=jp).frequencies[0]
    previous = np.inf
    for n in (1, 2, 4, 8):
        arm = fa.FlexibleArm(
            [fa.Link(L, ei, rho, n_modes=n)],
            payload_mass=mp,
            payload_inertia=jp,
            **LINEAR_CLAMPED_FREE,
        )
        w1 = arm.natural_frequencies()[0]
        assert exact < w1 < previous  # Rayleigh-Ritz: upper bounds, improving
        previous = w1
    assert previous == pytest.approx(exact, rel=2e-3)


def test_free_single_link_converges_to_pinned_free_beam():
    """An unactuated single link (pin at the base) is a pinned-free beam: tan = tanh."""
    pinned_free = [3.9266023120479, 7.0685827500527]  # roots of tan x = tanh x
    arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=16)], **LINEAR_CLAMPED_FREE)
    w = arm.natural_frequencies(joints="free")[:2]
    np.testing.assert_allclose(np.sqrt(w), pinned_free, rtol=1e-7)


# ---------------------------------------------------------------- kinematics
def test_undeflected_tip_equals_rigid_forward_kinematics(arm):
    rng = np.random.default_rng(10)
    theta = rng.uniform(-np.pi, np.pi, (7, arm.n_links))
    q = np.zeros((7, arm.n_dof))
    q[:, : arm.n_links] = theta
    np.testing.assert_allclose(arm.tip_position(q), arm.forward_kinematics(theta), atol=1e-13)


def test_links_are_connected(arm):
    rng = np.random.default_rng(11)
    q, _ = random_state(arm, rng, scale=0.2)
    for i in range(arm.n_links - 1):
        tip = arm.point_position(q, i, arm.links[i].length)
        np.testing.assert_allclose(arm.point_position(q, i + 1, 0.0), tip, atol=1e-13)


@pytest.mark.parametrize("scale", [0.01, 0.3])
def test_next_link_leaves_along_the_deflected_tip_slope(scale):
    """With theta_2 = 0 link 2 turns by the tip slope s = w'(L) of link 1 (the
    model's small-deflection convention), while the deflected tangent of link 1
    points at atan(s): the two directions differ by exactly s - atan(s)."""
    arm = fa.FlexibleArm.paper(n_modes=2)
    q = np.array([0.4, 0.0, 0.3, -0.1, 0.0, 0.0])
    q[2:4] *= scale / 0.3
    tip = arm.point_position(q, 0, 4.5)
    eps = 1e-7
    tangent = (tip - arm.point_position(q, 0, 4.5 - eps)) / eps
    direction = arm.point_position(q, 1, 1.0) - tip
    turn = np.arctan2(direction[1], direction[0]) - np.arctan2(tangent[1], tangent[0])
    s = arm.modes[0].tip_slope @ q[2:4]
    assert turn == pytest.approx(s - np.arctan(s), abs=1e-6)


def test_deflection_of_a_single_mode_is_its_shape():
    arm = fa.FlexibleArm([fa.Link(2.0, 3.0, 0.5, n_modes=2)], **LINEAR_CLAMPED_FREE)
    q = np.array([0.0, 0.25, 0.0])
    x = np.linspace(0, 2.0, 9)
    ys = [arm.point_position(q, 0, xi)[1] for xi in x]
    np.testing.assert_allclose(ys, 0.25 * arm.modes[0].shape(x)[0], atol=1e-14)


@pytest.mark.parametrize("stiffening", [False, True], ids=["linear", "stiffening"])
def test_payload_kinetic_energy_matches_tip_velocity(stiffening):
    """Near-massless links: T = 1/2 m |v_tip|^2 + 1/2 J (angle rate)^2 with the
    tip velocity from finite differences of tip_position (with stiffening, the
    tip's foreshortening moves the payload too)."""
    mp = 2.0
    arm = fa.FlexibleArm(
        [fa.Link(1.0, 3.0, 1e-9, n_modes=2), fa.Link(0.8, 2.0, 1e-9, n_modes=1)],
        payload_mass=mp,
        boundary="clamped-free",
        geometric_stiffening=stiffening,
    )
    rng = np.random.default_rng(12)
    q, dq = random_state(arm, rng, scale=0.1)
    eps = 1e-6
    v = (arm.tip_position(q + eps * dq) - arm.tip_position(q - eps * dq)) / (2 * eps)
    kinetic, _ = arm.energy(q, dq)
    assert kinetic == pytest.approx(0.5 * mp * v @ v, rel=1e-7)


def test_jacobian_matches_finite_differences(arm):
    rng = np.random.default_rng(13)
    theta = rng.uniform(-np.pi, np.pi, arm.n_links)
    eps = 1e-6
    fd = np.column_stack(
        [
            (arm.forward_kinematics(theta + eps * e) - arm.forward_kinematics(theta - eps * e))
            / (2 * eps)
            for e in np.eye(arm.n_links)
        ]
    )
    np.testing.assert_allclose(arm.jacobian(theta), fd, atol=1e-8)


@pytest.mark.parametrize("elbow", ["positive", "negative"])
def test_inverse_kinematics_round_trip(elbow):
    arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0), fa.Link(0.6, 1.0, 1.0)])
    rng = np.random.default_rng(14)
    r = rng.uniform(0.45, 1.55, 50)
    phi = rng.uniform(-np.pi, np.pi, 50)
    targets = np.column_stack([r * np.cos(phi), r * np.sin(phi)])
    theta = arm.inverse_kinematics(targets, elbow=elbow)
    np.testing.assert_allclose(arm.forward_kinematics(theta), targets, atol=1e-12)
    sign = 1 if elbow == "positive" else -1
    assert np.all(sign * theta[:, 1] >= 0)


def test_inverse_kinematics_branches_differ_and_reach_the_boundary():
    arm = fa.FlexibleArm.paper()
    up = arm.inverse_kinematics([3.0, 4.0], "positive")
    down = arm.inverse_kinematics([3.0, 4.0], "negative")
    assert up[1] == pytest.approx(-down[1])
    stretched = arm.inverse_kinematics([9.0, 0.0])
    np.testing.assert_allclose(stretched, [0.0, 0.0], atol=1e-7)


@pytest.mark.parametrize("target", [[1.61, 0.0], [0.0, 0.0], [0.3, 0.0], [[1.0, 1.0], [20.0, 0.0]]])
def test_inverse_kinematics_rejects_unreachable(target):
    arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0), fa.Link(0.6, 1.0, 1.0)])  # reach [0.4, 1.6] m
    with pytest.raises(ValueError, match="reachable"):
        arm.inverse_kinematics(target)


def test_inverse_kinematics_needs_two_links():
    arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0)] * 3)
    with pytest.raises(ValueError, match="two-link"):
        arm.inverse_kinematics([1.0, 1.0])


# ------------------------------------------------------------------ bad input
GOOD_LINK = {"length": 1.0, "flexural_rigidity": 2.0, "linear_density": 0.5}


@pytest.mark.parametrize(
    ("name", "value", "error"),
    [
        ("length", -1.0, ValueError),
        ("length", 0.0, ValueError),
        ("length", float("nan"), ValueError),
        ("length", float("inf"), ValueError),
        ("length", "1", TypeError),
        ("flexural_rigidity", -2.0, ValueError),
        ("flexural_rigidity", 0.0, ValueError),
        ("flexural_rigidity", float("nan"), ValueError),
        ("linear_density", -0.5, ValueError),
        ("linear_density", float("inf"), ValueError),
        ("n_modes", -1, ValueError),
        ("n_modes", 1.5, TypeError),
        ("n_modes", True, TypeError),
        ("hub_mass", -0.1, ValueError),
        ("hub_inertia", float("nan"), ValueError),
        ("modal_damping", -0.01, ValueError),
    ],
)
def test_link_rejects_bad_parameters(name, value, error):
    kwargs = dict(GOOD_LINK) | {name: value}
    with pytest.raises(error, match=f"'{name}' parameter of Link"):
        fa.Link(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"payload_mass": -1.0}, ValueError, "'payload_mass'"),
        ({"payload_inertia": float("nan")}, ValueError, "'payload_inertia'"),
        ({"boundary": "pinned"}, ValueError, "'boundary'"),
        ({"boundary": 3}, TypeError, "'boundary'"),
        ({"mode_normalization": "unit"}, ValueError, "'mode_normalization'"),
        ({"mode_amplitude": 0.0}, ValueError, "'mode_amplitude'"),
        ({"links": []}, ValueError, "'links'"),
        ({"links": [1.0]}, TypeError, "'links'"),
        ({"links": "link"}, TypeError, "'links'"),
    ],
)
def test_arm_rejects_bad_parameters(kwargs, error, match):
    params = {"links": [fa.Link(**GOOD_LINK)]} | kwargs
    with pytest.raises(error, match=match):
        fa.FlexibleArm(**params)


@pytest.mark.parametrize(
    ("method", "args", "match"),
    [
        ("mass_matrix", (np.zeros(3),), r"'q'.*shape \(4,\)"),
        ("mass_matrix", (np.zeros((4, 1)),), "'q'"),
        ("mass_matrix", (np.array([0, 0, np.nan, 0]),), "'q'.*finite"),
        ("velocity_terms", (np.zeros(4), np.zeros(5)), "'dq'"),
        ("forward_dynamics", (np.zeros(4), np.zeros(4), np.zeros(3)), "'tau'"),
        ("forward_dynamics", (np.zeros(4), np.zeros(4), [np.inf, 0]), "'tau'"),
        ("energy", (np.zeros(4), [0, 0, 0]), "'dq'"),
        ("point_position", (np.zeros(4), 2, 0.0), "'link'"),
        ("point_position", (np.zeros(4), -1, 0.0), "'link'"),
        ("point_position", (np.zeros(4), 1, 4.6), "'distance'"),
        ("point_position", (np.zeros(4), 1, -0.1), "'distance'"),
        ("tip_position", (np.zeros((3, 5)),), "'q'"),
        ("forward_kinematics", (np.zeros(3),), "'theta'"),
        ("jacobian", (np.zeros((2, 3)),), "'theta'"),
        ("inverse_kinematics", ([1.0, 2.0, 3.0],), "'position'"),
        ("natural_frequencies", (None, "pinned"), "'joints'"),
    ],
)
def test_methods_reject_bad_arrays(method, args, match):
    arm = fa.FlexibleArm.paper()
    with pytest.raises(ValueError, match=match):
        getattr(arm, method)(*args)


def test_unknown_backend_and_elbow():
    arm = fa.FlexibleArm.paper()
    with pytest.raises(ValueError, match="'backend'"):
        arm.forward_dynamics(np.zeros(4), np.zeros(4), np.zeros(2), backend="jax")
    with pytest.raises(ValueError, match="'elbow'"):
        arm.inverse_kinematics([1.0, 1.0], elbow="up")


def test_arm_is_immutable_and_arrays_read_only():
    arm = fa.FlexibleArm.paper()
    with pytest.raises(AttributeError):
        arm.payload_mass = 1.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        arm.arrays.stiffness[0] = 1.0
    assert arm == fa.FlexibleArm.paper()
