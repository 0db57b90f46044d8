"""Flexible joints: the spring laws, Makkar friction, and arms with joints.

Oracles: the two-inertia closed form sqrt(k (1/I + 1/J_m)), a zero-crossing
period measured from a simulation, the paper's coupling matrix S, energy
conservation and the power balance, convergence to the rigid-joint arm.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import flexarm as fa
from flexarm.model import dynamics
from flexarm.model.arrays import make_workspace
from flexarm.model.joints import LinearJoint, MakkarFriction, NonlinearJoint
from helpers.arms import assert_mass_matrix_and_kernels, two_rigid_rods_mass_matrix


def simulate(arm, x0, t_end, torque=None, n_eval=201, rtol=1e-11, atol=1e-12):
    n = arm.n_dof

    def rhs(t, x):
        tau = np.zeros(arm.n_links) if torque is None else torque(t)
        return np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], tau, backend="compiled")]

    sol = solve_ivp(
        rhs,
        (0, t_end),
        x0,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        t_eval=np.linspace(0, t_end, n_eval),
    )
    assert sol.success
    return sol


# ----------------------------------------------------------------- spring laws
def test_linear_joint_torque_and_potential():
    j = LinearJoint(250.0, 0.2)
    d = np.linspace(-0.1, 0.1, 7)
    np.testing.assert_allclose(j.torque(d), 250.0 * d)
    np.testing.assert_allclose(j.potential(d), 125.0 * d**2)
    np.testing.assert_allclose(j.tangent_stiffness(d), 250.0)


def test_nonlinear_torque_matches_its_formula_and_is_odd():
    j = NonlinearJoint(1.0e4, 4.0e7, 6.0e3, 1.6e7, 0.3)
    d = np.linspace(-0.01, 0.01, 101)
    expected = 1.0e4 * d + 4.0e7 * d**3 - 6.0e3 * np.exp(-1.6e7 * d**2) * d
    np.testing.assert_allclose(j.torque(d), expected, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(j.torque(-d), -j.torque(d), rtol=0, atol=1e-12)
    assert j.torque(np.array([[0.001]])).shape == (1, 1)


def test_soft_windup_lowers_the_slope_near_zero():
    j = NonlinearJoint.default()
    eps = 1e-7
    slope0 = (j.torque(eps) - j.torque(-eps)) / (2 * eps)
    assert slope0 == pytest.approx(j.a1 - j.ksw, rel=1e-6)
    assert slope0 < j.a1
    # far outside the windup region the slope exceeds a1 (cubic hardening)
    d = 10 / np.sqrt(j.asw)
    assert (j.torque(d + eps) - j.torque(d - eps)) / (2 * eps) > j.a1


def test_tangent_stiffness_and_potential_are_consistent_with_torque():
    j = NonlinearJoint(300.0, 5e4, 200.0, 400.0, 0.1)
    d = np.linspace(-0.2, 0.2, 41)
    eps = 1e-6
    fd_slope = (j.torque(d + eps) - j.torque(d - eps)) / (2 * eps)
    np.testing.assert_allclose(j.tangent_stiffness(d), fd_slope, rtol=1e-7, atol=1e-6)
    fd_torque = (j.potential(d + eps) - j.potential(d - eps)) / (2 * eps)
    np.testing.assert_allclose(fd_torque, j.torque(d), rtol=1e-6, atol=1e-7)
    assert j.potential(0.0) == 0.0
    assert np.all(j.potential(d) >= 0)


def test_makkar_friction_matches_formula_and_is_odd():
    g = (0.25, 100.0, 10.0, 0.1, 100.0, 0.01)  # Makkar et al.'s example
    f = MakkarFriction(*g)
    v = np.linspace(-2, 2, 81)
    expected = g[0] * (np.tanh(g[1] * v) - np.tanh(g[2] * v)) + g[3] * np.tanh(g[4] * v) + g[5] * v
    np.testing.assert_allclose(f(v), expected, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(f.friction(-v), -f.friction(v), atol=1e-15)
    assert f(0.0) == 0.0


def test_makkar_static_level():
    """With well separated rates the low-speed plateau is g1 + g4."""
    f = MakkarFriction(0.4, 1e4, 1.0, 0.6, 1e4, 0.0)
    v = np.geomspace(1e-4, 1e-1, 400)
    assert f(v).max() == pytest.approx(f.static_level, rel=1e-2)
    assert f.static_level == pytest.approx(1.0)
    # the Stribeck hump: friction falls from the plateau towards the Coulomb level
    assert f(5.0) == pytest.approx(0.6, rel=1e-3)


# ------------------------------------------------------------ arms with joints
def one_link_on_a_joint(joint, **kw):
    return fa.FlexibleArm(
        [fa.Link(1.2, 1.0, 2.0, n_modes=0, hub_inertia=0.1)], joints=[joint], **kw
    )


def test_one_rigid_link_on_a_linear_joint_oscillates_at_the_two_inertia_frequency():
    k, jm = 40.0, 0.25
    arm = one_link_on_a_joint(LinearJoint(k, jm))
    inertia = 2.0 * 1.2**3 / 3 + 0.1
    omega = np.sqrt(k * (1 / inertia + 1 / jm))
    np.testing.assert_allclose(arm.natural_frequencies(joints="free"), [omega], rtol=1e-12)
    np.testing.assert_allclose(
        arm.natural_frequencies(joints="locked"), [np.sqrt(k / inertia)], rtol=1e-12
    )
    # and in the time domain: the spring deflection crosses zero every half period
    sol = simulate(arm, np.array([0.0, 0.1, 0.0, 0.0]), 10 * 2 * np.pi / omega, n_eval=20001)
    deflection = sol.y[1] - sol.y[0]
    crossings = np.flatnonzero(np.diff(np.sign(deflection)) != 0)
    t = sol.t
    # linear interpolation of the crossing instants
    tc = t[crossings] - deflection[crossings] * (t[crossings + 1] - t[crossings]) / (
        deflection[crossings + 1] - deflection[crossings]
    )
    period = 2 * np.mean(np.diff(tc))
    assert period == pytest.approx(2 * np.pi / omega, rel=1e-6)


def test_coupling_matrix_is_the_papers_S():
    """Rigid links: M's (theta, q_m) block is S = [[0, J_m2], [0, 0]] with coupling,
    and zero with Spong's simplification."""
    jm1, jm2 = 0.3, 0.2
    links = [fa.Link(1.0, 1.0, 1.0, n_modes=0), fa.Link(0.8, 1.0, 1.0, n_modes=0)]
    joints = [LinearJoint(100.0, jm1), LinearJoint(80.0, jm2)]
    q = np.array([0.3, -0.7, 0.1, 0.2])
    coupled = fa.FlexibleArm(links, joints=joints)
    np.testing.assert_allclose(coupled.mass_matrix(q)[:2, 2:], [[0.0, jm2], [0.0, 0.0]], atol=1e-15)
    np.testing.assert_allclose(np.diag(coupled.mass_matrix(q))[2:], [jm1, jm2])
    spong = fa.FlexibleArm(links, joints=joints, rotor_coupling=False)
    np.testing.assert_allclose(spong.mass_matrix(q)[:2, 2:], 0.0, atol=1e-15)
    # the carried rotor adds its inertia to the link-side inertia about joint 1
    rigid = fa.FlexibleArm(links)
    np.testing.assert_allclose(
        coupled.mass_matrix(q)[:2, :2] - rigid.mass_matrix(q[:2]), [[jm2, 0], [0, 0]], atol=1e-14
    )
    np.testing.assert_allclose(spong.mass_matrix(q)[:2, :2], rigid.mass_matrix(q[:2]), atol=1e-14)


@pytest.mark.parametrize("ratio", [1.0, 7.0, 100.0])
def test_a_geared_rotor_adds_its_own_inertia_to_its_carrier(ratio):
    """Rotor 2 (own inertia J_r, gear N, link-side J_m = N**2 J_r) rides on rigid link 1
    at angle theta_1 and turns at theta_1' + N q_m2' (q_m2 link side):
    T = 1/2 J_r (theta_1' + N q_m2')**2, so M gains J_r at (theta_1, theta_1),
    N J_r at (theta_1, q_m2) and J_m at (q_m2, q_m2); rotor 1 sits on the base."""
    m1, l1, m2, l2 = 1.3, 1.0, 0.56, 0.8
    jr1, jr2 = 2e-3, 5e-4
    links = [fa.Link(l1, 1.0, m1 / l1, n_modes=0), fa.Link(l2, 1.0, m2 / l2, n_modes=0)]
    joints = [
        LinearJoint(100.0, ratio**2 * jr1, gear_ratio=ratio),
        NonlinearJoint(80.0, 0.0, 0.0, 1.0, ratio**2 * jr2, gear_ratio=ratio),
    ]
    arm = fa.FlexibleArm(links, joints=joints)
    q = np.array([0.3, -0.7, 0.1, 0.2])
    expected = np.zeros((4, 4))  # (theta1, theta2, qm1, qm2)
    expected[:2, :2] = two_rigid_rods_mass_matrix(m1, l1, m2, l2, q[1])
    expected[0, 0] += jr2
    expected[0, 3] = expected[3, 0] = ratio * jr2
    expected[2, 2] = ratio**2 * jr1
    expected[3, 3] = ratio**2 * jr2
    for backend in ("compiled", "numpy"):
        np.testing.assert_allclose(
            arm.mass_matrix(q, backend=backend), expected, rtol=1e-13, atol=1e-16
        )
    # the forward dynamics of every backend solve these equations
    rng = np.random.default_rng(3)
    dq, tau = rng.normal(size=4), rng.normal(size=2)
    ref = arm.forward_dynamics(q, dq, tau, backend="numpy")
    ws = make_workspace(4)
    for kernel in (dynamics.forward_dynamics_dense, dynamics.forward_dynamics_recursive):
        out = np.empty(4)
        kernel(q, dq, tau, arm.arrays, ws, out)
        np.testing.assert_allclose(out, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_allclose(
        expected @ ref + arm.velocity_terms(q, dq), arm.generalized_forces(q, dq, tau), atol=1e-11
    )


def test_the_gear_ratio_is_checked_and_the_defaults_are_geared():
    assert LinearJoint(1.0, 0.5).gear_ratio == 1.0  # a direct drive unless told
    assert LinearJoint.default().gear_ratio == NonlinearJoint.default().gear_ratio == 100.0
    assert NonlinearJoint.default().rotor_inertia == pytest.approx(3e-5, rel=1e-15)
    for bad in (0.5, 0.0, -2.0, float("nan")):
        with pytest.raises(ValueError, match="'gear_ratio'"):
            LinearJoint(1.0, 0.5, gear_ratio=bad)
    with pytest.raises(TypeError, match="'gear_ratio'"):
        NonlinearJoint(10.0, 0.0, 0.0, 1.0, 0.5, gear_ratio="100")


def test_rotor_on_a_flexible_link_turns_with_the_tip_slope():
    """The second rotor's carrier is link 1's deflected tip: its coupling row
    is the gradient of theta_1 + w_1'(L)."""
    jm2 = 0.2
    arm = fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.0, n_modes=2), fa.Link(0.8, 3.0, 1.0, n_modes=1)],
        joints=[LinearJoint(100.0, 0.3), LinearJoint(80.0, jm2)],
        boundary="clamped-free",
        geometric_stiffening=False,
    )
    M = arm.mass_matrix(np.zeros(arm.n_dof))
    row = np.zeros(arm.n_dof)
    row[0] = 1.0
    row[arm.modal_slice(0)] = arm.modes[0].tip_slope
    m2 = arm.motor_slice.start + 1
    np.testing.assert_allclose(M[:m2, m2], jm2 * row[:m2], atol=1e-14)


@pytest.mark.parametrize(
    "joint",
    [
        LinearJoint(40.0, 0.25, damping=0.6),
        NonlinearJoint(40.0, 0.0, 0.0, 1.0, 0.25, damping=0.6),
    ],
    ids=["linear", "nonlinear"],
)
def test_a_damped_joint_decays_as_the_closed_form_oscillator(joint):
    """One rigid link (inertia I) on a spring k with a damper c across it, motor J_m,
    released at rest with deflection D0: the momentum I q' + J_m q_m' stays zero, so
    D = q_m - q obeys D'' + (c / mu) D' + (k / mu) D = 0 with 1/mu = 1/I + 1/J_m:
    D(t) = D0 exp(-zeta w0 t) (cos wd t + zeta w0 / wd sin wd t),
    w0 = sqrt(k / mu), zeta = c / (2 sqrt(k mu)), wd = w0 sqrt(1 - zeta**2)."""
    k, jm, c = 40.0, 0.25, 0.6
    arm = one_link_on_a_joint(joint)
    inertia = 2.0 * 1.2**3 / 3 + 0.1
    mu = 1.0 / (1.0 / inertia + 1.0 / jm)
    w0, zeta = math.sqrt(k / mu), c / (2.0 * math.sqrt(k * mu))
    wd = w0 * math.sqrt(1.0 - zeta**2)
    d0 = 0.1
    sol = simulate(arm, np.array([0.0, d0, 0.0, 0.0]), 6 * 2 * np.pi / wd, n_eval=401)
    t = sol.t
    expected = d0 * np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(sol.y[1] - sol.y[0], expected, rtol=0, atol=1e-9 * d0)
    # the ratio of successive peaks, exp(-2 pi zeta / sqrt(1 - zeta**2)), is far from 1
    assert math.exp(-2 * math.pi * zeta / math.sqrt(1 - zeta**2)) < 0.6
    np.testing.assert_allclose(arm.damping_matrix, [[c, -c], [-c, c]], rtol=1e-15)


def test_friction_acts_on_the_side_each_joint_chooses():
    """Joint 1 puts its friction on the motor, joint 2 takes the arm's link side: the
    friction torque -f(v) appears on q_m1 and theta_2, with f Makkar's law by hand."""
    g = (0.3, 50.0, 5.0, 0.7, 40.0, 0.2)
    friction = MakkarFriction(*g)

    def f(v):
        return (
            g[0] * (math.tanh(g[1] * v) - math.tanh(g[2] * v))
            + g[3] * math.tanh(g[4] * v)
            + g[5] * v
        )

    links = [fa.Link(1.0, 5.0, 1.0, n_modes=1), fa.Link(0.8, 3.0, 1.0, n_modes=1)]

    def arm(fr, side):
        joints = [
            LinearJoint(100.0, 0.3, friction=fr, friction_side=side, gear_ratio=4.0),
            NonlinearJoint(80.0, 1e3, 30.0, 50.0, 0.2, friction=fr),
        ]
        return fa.FlexibleArm(links, joints=joints, joint_friction="link")

    mixed, smooth = arm(friction, "motor"), arm(None, "motor")
    assert mixed.friction_sides == ("motor", "link")
    assert mixed.friction_coordinates == (4, 1)
    rng = np.random.default_rng(8)
    q, dq = random_state(mixed, rng)
    tau = rng.normal(size=2)
    diff = mixed.generalized_forces(q, dq, tau) - smooth.generalized_forces(q, dq, tau)
    expected = np.zeros(mixed.n_dof)
    expected[4], expected[1] = -f(dq[4]), -f(dq[1])
    np.testing.assert_allclose(diff, expected, rtol=1e-13, atol=1e-15)
    # the kernels read each joint's side
    ref = mixed.forward_dynamics(q, dq, tau, backend="numpy")
    got = mixed.forward_dynamics(q, dq, tau, backend="compiled")
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())
    # the global choice stays the default
    both_motor = fa.FlexibleArm(
        links, joints=[LinearJoint(100.0, 0.3, friction=friction)] * 2, joint_friction="motor"
    )
    assert both_motor.friction_sides == ("motor", "motor")


@pytest.mark.parametrize("side", ["link", "motor"])
def test_viscous_friction_on_one_side_gives_the_linear_solution(side):
    """One rigid link (I) on a spring k, motor J_m, viscous friction b on one side:
    M x'' + D x' + K x = 0 with M = diag(I, J_m), K = k [[1, -1], [-1, 1]] and
    D = b on the chosen coordinate, solved by the matrix exponential."""
    import scipy.linalg

    k, jm, b = 40.0, 0.25, 0.4
    joint = LinearJoint(k, jm, friction=MakkarFriction(0, 0, 0, 0, 0, b), friction_side=side)
    arm = one_link_on_a_joint(joint)
    inertia = 2.0 * 1.2**3 / 3 + 0.1
    M = np.diag([inertia, jm])
    K = k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    D = np.zeros((2, 2))
    D[(0, 0) if side == "link" else (1, 1)] = b
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K, -Minv @ D]])
    x0 = np.array([0.0, 0.1, 0.3, -0.2])
    sol = simulate(arm, x0, 3.0, n_eval=31)
    for t, x in zip(sol.t, sol.y.T, strict=True):
        np.testing.assert_allclose(x, scipy.linalg.expm(A * t) @ x0, rtol=0, atol=1e-9)


# ---------------------------------------------------------------- rigid joints
@pytest.mark.parametrize("coupled", [True, False])
def test_rigid_joints_add_their_geared_rotors_by_hand(coupled):
    """Two rigid rods on RigidJoints: rotor 1 on the base adds J_m1 to theta_1;
    rotor 2 on link 1 turns at theta_1' + N theta_2' (rotor side), so
    T = 1/2 J_r2 (theta_1' + N theta_2')**2 adds J_r2, N J_r2, N**2 J_r2 = J_m2
    (Spong's uncoupled rotor: J_m2 at theta_2 only). No motor coordinates."""
    m1, l1, m2, l2, n2 = 1.3, 1.0, 0.56, 0.8, 6.0
    jm1, jm2 = 0.2, 0.09
    links = [fa.Link(l1, 1.0, m1 / l1, n_modes=0), fa.Link(l2, 1.0, m2 / l2, n_modes=0)]
    joints = [fa.RigidJoint(jm1, damping=0.1, gear_ratio=3.0), fa.RigidJoint(jm2, gear_ratio=n2)]
    arm = fa.FlexibleArm(links, joints=joints, rotor_coupling=coupled)
    assert (arm.n_dof, arm.has_flexible_joints, arm.coordinate_names) == (
        2,
        False,
        ["theta1", "theta2"],
    )
    q = np.array([0.3, -0.7])
    expected = two_rigid_rods_mass_matrix(m1, l1, m2, l2, q[1])
    expected[0, 0] += jm1
    expected[1, 1] += jm2
    if coupled:
        jr2 = jm2 / n2**2
        expected[0, 0] += jr2
        expected[0, 1] += n2 * jr2
        expected[1, 0] += n2 * jr2
    assert_mass_matrix_and_kernels(arm, q, expected, seed=4)
    assert not dynamics.is_two_links_one_mode(arm.arrays)


def test_a_rigid_joint_with_viscous_friction_spins_down_exponentially():
    """One rigid link (I about the joint) on a RigidJoint (rotor J_m, damping c,
    Makkar friction g6 = b): theta' = w0 exp(-(c + b) t / (I + J_m))."""
    c, b, jm = 0.3, 0.2, 0.15
    joint = fa.RigidJoint(jm, damping=c, friction=MakkarFriction(0, 0, 0, 0, 0, b), gear_ratio=9)
    arm = one_link_on_a_joint(joint)
    inertia = 2.0 * 1.2**3 / 3 + 0.1
    sol = simulate(arm, np.array([0.0, 2.0]), 3.0, n_eval=31)
    rate = 2.0 * np.exp(-(c + b) * sol.t / (inertia + jm))
    np.testing.assert_allclose(sol.y[1], rate, rtol=1e-9)
    np.testing.assert_allclose(
        sol.y[0], 2.0 * (inertia + jm) / (c + b) * (1 - rate / 2.0), rtol=1e-9
    )
    np.testing.assert_allclose(arm.damping_matrix, [[c]])


def test_a_rigid_joint_is_the_limit_of_stiff_geared_joints():
    """Three flexible links on geared, coupled joints with damping on the motor: as
    the springs stiffen the motion tends to that on RigidJoints of the same rotors
    and damping (the recursive kernel, three links, and the dense one agree)."""
    links = [
        fa.Link(1.0, 40.0, 1.0, n_modes=1),
        fa.Link(0.8, 30.0, 1.0, n_modes=1),
        fa.Link(0.5, 20.0, 1.0, n_modes=0),
    ]
    ratios, jms, damp = (3.0, 8.0, 2.0), (0.05, 0.03, 0.02), (0.1, 0.05, 0.02)

    def torque(t):
        return np.array([0.4, -0.15, 0.05]) * np.sin(np.pi * t) ** 2

    rigid_joints = [
        fa.RigidJoint(j, damping=c, gear_ratio=n) for j, c, n in zip(jms, damp, ratios, strict=True)
    ]
    kw = {"boundary": "clamped-free", "geometric_stiffening": False}
    rigid = fa.FlexibleArm(links, joints=rigid_joints, **kw)
    ref = simulate(rigid, np.zeros(2 * rigid.n_dof), 1.0, torque, n_eval=11).y[:3]
    errors = []
    for k in (1e3, 1e4, 1e5):
        joints = [
            LinearJoint(k, j, motor_damping=c, gear_ratio=n)
            for j, c, n in zip(jms, damp, ratios, strict=True)
        ]
        arm = fa.FlexibleArm(links, joints=joints, **kw)
        y = simulate(arm, np.zeros(2 * arm.n_dof), 1.0, torque, n_eval=11).y[:3]
        errors.append(np.abs(y - ref).max())
    assert errors[0] > errors[1] > errors[2]
    assert errors[0] / errors[1] > 5 and errors[1] / errors[2] > 5
    assert errors[2] < 1e-3 * np.abs(ref).max()


def test_a_prescribed_rigid_joint_needs_the_torque_of_its_rotor_and_friction():
    """Prescribed motion on a RigidJoint: the servo torque is (I + J_m) theta'' + c theta'
    + f(theta'), by hand, in the compiled kernel and the NumPy reference."""
    from flexarm.model.prescribed import prescribed_accelerations, prescribed_dynamics

    g = (0.3, 50.0, 5.0, 0.7, 40.0, 0.2)
    jm, c = 0.15, 0.3
    arm = one_link_on_a_joint(fa.RigidJoint(jm, damping=c, friction=MakkarFriction(*g)))
    inertia = 2.0 * 1.2**3 / 3 + 0.1
    v, acc = 0.4, 1.7
    f = g[0] * (math.tanh(g[1] * v) - math.tanh(g[2] * v)) + g[3] * math.tanh(g[4] * v) + g[5] * v
    expected = (inertia + jm) * acc + c * v + f
    q, dq, a = np.array([0.2]), np.array([v]), np.array([acc])
    _, tau = prescribed_accelerations(arm, q, dq, a)
    assert float(tau[0]) == pytest.approx(expected, rel=1e-13)
    ddq, tau_c = np.empty(1), np.empty(1)
    prescribed_dynamics(q, dq, a, arm.arrays, make_workspace(1), ddq, tau_c)
    assert float(tau_c[0]) == pytest.approx(expected, rel=1e-13)


def test_an_arm_mixing_rigid_and_flexible_joints_is_refused():
    links = [fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 2
    with pytest.raises(
        ValueError, match=r"'joints'.*all flexible joints.*or all RigidJoint.*\[1\]"
    ):
        fa.FlexibleArm(links, joints=[LinearJoint(10.0, 0.1), fa.RigidJoint(0.1)])


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"motor_inertia": -0.1}, ValueError, "'motor_inertia'"),
        ({"damping": -1.0}, ValueError, "'damping'"),
        ({"gear_ratio": 0.5}, ValueError, "'gear_ratio'"),
        ({"friction": 1.0}, TypeError, "'friction'"),
    ],
)
def test_rigid_joint_rejects_bad_parameters(kwargs, error, match):
    with pytest.raises(error, match=match):
        fa.RigidJoint(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"damping": -0.1}, ValueError, "'damping'"),
        ({"friction_side": "gear"}, ValueError, "'friction_side'"),
        ({"friction_side": 1}, TypeError, "'friction_side'"),
    ],
)
def test_spring_damping_and_friction_side_are_checked(kwargs, error, match):
    with pytest.raises(error, match=match):
        LinearJoint(10.0, 0.1, **kwargs)
    with pytest.raises(error, match=match):
        NonlinearJoint(10.0, 0.0, 0.0, 1.0, 0.1, **kwargs)


FLEX_ARMS = {
    "paper-nonlinear": lambda friction=None, **kw: fa.FlexibleArm.paper(
        joints=[NonlinearJoint(1.0e3, 4.0e6, 6.0e2, 1.6e5, 0.3, friction=friction)] * 2, **kw
    ),
    "three-rigid-links-linear": lambda friction=None, **kw: fa.FlexibleArm(
        [fa.Link(1.0, 1.0, 1.0, n_modes=0, hub_mass=0.2)] * 3,
        joints=[LinearJoint(60.0, 0.05, friction=friction)] * 3,
        payload_mass=0.1,
        **kw,
    ),
    "two-flexible-links-clamped-mass": lambda friction=None, **kw: fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.0, n_modes=2), fa.Link(0.8, 3.0, 0.7, n_modes=2, hub_mass=0.3)],
        joints=[NonlinearJoint(80.0, 1e3, 30.0, 50.0, 0.05, friction=friction)] * 2,
        boundary="clamped-mass",
        geometric_stiffening=False,
        **kw,
    ),
    "two-flexible-links-stiffening": lambda friction=None, **kw: fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.0, n_modes=2), fa.Link(0.8, 3.0, 0.7, n_modes=2, hub_mass=0.3)],
        joints=[NonlinearJoint(80.0, 1e3, 30.0, 50.0, 0.05, friction=friction)] * 2,
        boundary="clamped-mass",
        geometric_stiffening=True,
        **kw,
    ),
}


def random_state(arm, rng, scale=0.05):
    q = rng.normal(size=arm.n_dof) * scale
    q[: arm.n_links] = rng.uniform(-np.pi, np.pi, arm.n_links)
    q[arm.motor_slice] = q[: arm.n_links] + rng.normal(size=arm.n_links) * scale
    return q, rng.normal(size=arm.n_dof) * 0.5


@pytest.mark.parametrize("name", sorted(FLEX_ARMS))
@pytest.mark.parametrize("friction_side", ["link", "motor"])
def test_compiled_matches_numpy_with_joints(name, friction_side):
    arm = FLEX_ARMS[name](friction=MakkarFriction.default(), joint_friction=friction_side)
    rng = np.random.default_rng(20)
    for _ in range(5):
        q, dq = random_state(arm, rng)
        tau = rng.normal(size=arm.n_links)
        ref = arm.forward_dynamics(q, dq, tau)
        got = arm.forward_dynamics(q, dq, tau, backend="compiled")
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


@pytest.mark.parametrize("name", sorted(FLEX_ARMS))
def test_joint_arm_structure(name):
    arm = FLEX_ARMS[name]()
    rng = np.random.default_rng(21)
    q, dq = random_state(arm, rng)
    M = arm.mass_matrix(q)
    assert np.linalg.eigvalsh(M).min() > 0
    np.testing.assert_allclose(arm.coriolis(q, dq) @ dq, arm.velocity_terms(q, dq), atol=1e-10)
    B = arm.input_matrix
    np.testing.assert_array_equal(B[arm.motor_slice], np.eye(arm.n_links))
    assert arm.coordinate_names[-1] == f"qm{arm.n_links}"


@pytest.mark.parametrize("name", sorted(FLEX_ARMS))
def test_energy_conserved_with_conservative_joints(name):
    arm = FLEX_ARMS[name]()
    rng = np.random.default_rng(22)
    q0, dq0 = random_state(arm, rng)
    e0 = sum(arm.energy(q0, dq0))
    sol = simulate(arm, np.r_[q0, dq0], 0.5, n_eval=11)
    n = arm.n_dof
    energies = np.array([sum(arm.energy(x[:n], x[n:])) for x in sol.y.T])
    assert np.abs(energies - e0).max() <= 1e-8 * e0
    springs = [arm.energy(x[:n], x[n:])[1] for x in sol.y.T]
    assert max(springs) - min(springs) > 1e-4 * e0  # energy really moved through the springs


@pytest.mark.parametrize("friction_side", ["link", "motor"])
def test_energy_falls_and_never_rises_with_friction(friction_side):
    arm = FLEX_ARMS["three-rigid-links-linear"](
        friction=MakkarFriction(0.05, 100.0, 10.0, 0.1, 100.0, 0.02), joint_friction=friction_side
    )
    rng = np.random.default_rng(23)
    q0, dq0 = random_state(arm, rng)
    sol = simulate(arm, np.r_[q0, dq0], 2.0, n_eval=201)
    n = arm.n_dof
    energies = np.array([sum(arm.energy(x[:n], x[n:])) for x in sol.y.T])
    assert np.all(np.diff(energies) <= 1e-9 * energies[0])
    assert energies[-1] < 0.8 * energies[0]


def test_power_balance_with_friction_and_motor_damping():
    """dE/dt = dq' B tau - dq' D dq - sum f(v_i) v_i (friction on the link side)."""
    friction = MakkarFriction.default()
    arm = fa.FlexibleArm(
        [fa.Link(1.0, 5.0, 1.0, n_modes=2, modal_damping=0.02)] * 2,
        joints=[NonlinearJoint(80.0, 1e3, 30.0, 50.0, 0.05, friction=friction, motor_damping=0.3)]
        * 2,
        boundary="clamped-free",
        geometric_stiffening=False,
    )
    rng = np.random.default_rng(24)
    q, dq = random_state(arm, rng)
    tau = rng.normal(size=2)
    ddq = arm.forward_dynamics(q, dq, tau)
    M = arm.mass_matrix(q)
    mdot = np.einsum("kij,k->ij", arm.mass_matrix_derivatives(q), dq)
    m0 = arm.motor_slice.start
    spring_power = sum(
        float(jt.torque(q[m0 + i] - q[i])) * (dq[m0 + i] - dq[i]) for i, jt in enumerate(arm.joints)
    )
    modal_power = q @ np.diag(arm.arrays.stiffness) @ dq
    de = dq @ M @ ddq + 0.5 * dq @ mdot @ dq + modal_power + spring_power
    power = (
        dq @ arm.input_matrix @ tau
        - dq @ arm.damping_matrix @ dq
        - sum(float(friction(dq[i])) * dq[i] for i in range(2))
    )
    assert de == pytest.approx(power, rel=1e-10, abs=1e-10)


def test_stiff_joints_approach_the_rigid_joint_arm():
    """As k grows the motor locks to its link: the limit is the rigid-joint arm
    whose hubs carry the rotor inertias (rotor i turns with link i)."""
    jm = 0.05
    links = [fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 2

    def torque(t):
        return np.array([0.4, -0.15]) * np.sin(np.pi * t) ** 2

    with_rotors = [fa.Link(1.0, 1.0, 1.0, n_modes=0, hub_inertia=jm)] * 2
    rigid = simulate(fa.FlexibleArm(with_rotors), np.zeros(4), 1.0, torque, n_eval=11).y[:2]
    errors = []
    for k in (1e2, 1e3, 1e4):
        arm = fa.FlexibleArm(links, joints=[LinearJoint(k, jm)] * 2)
        errors.append(
            np.abs(simulate(arm, np.zeros(8), 1.0, torque, n_eval=11).y[:2] - rigid).max()
        )
    assert errors[0] > errors[1] > errors[2]
    assert errors[0] / errors[1] > 5 and errors[1] / errors[2] > 5


def test_linearised_stiffness_uses_the_windup_slope():
    arm = paper_arm_with_default_joints()
    K = arm.stiffness_matrix
    k0 = NonlinearJoint.default().a1 - NonlinearJoint.default().ksw
    m = arm.motor_slice.start
    np.testing.assert_allclose(K[[0, m], :][:, [0, m]], [[k0, -k0], [-k0, k0]])


def paper_arm_with_default_joints():
    return fa.FlexibleArm.paper(joints=[NonlinearJoint.default(MakkarFriction.default())] * 2)


def documented_defaults() -> dict[str, float]:
    """The default joint's numbers as the table of flexarm.model.joints' docstring
    states them ("a1  1.0e4 N m/rad  reasoning ...", "g1, g4  0.5, 1.0 N m  ...")."""
    import flexarm.model.joints as joints

    found = {}
    row = re.compile(r"^(\w+(?:, \w+)?) {2,}([-+.\de]+(?:, [-+.\de]+)?) ")
    for line in joints.__doc__.splitlines():
        m = row.match(line)
        if m:
            names, values = m.group(1).split(", "), m.group(2).split(", ")
            found.update(zip(names, map(float, values), strict=True))
    return found


def test_the_defaults_are_the_documented_table():
    """The defaults are the numbers the docstring's table gives and reasons about."""
    doc = documented_defaults()
    assert set(doc) == {"a1", "ksw", "asw", "a2", "J_m", "g1", "g2", "g3", "g4", "g5", "g6"}
    j, f = NonlinearJoint.default(), MakkarFriction.default()
    assert (j.a1, j.a2, j.ksw, j.asw, j.motor_inertia) == tuple(
        doc[k] for k in ("a1", "a2", "ksw", "asw", "J_m")
    )
    assert tuple(f.params) == tuple(doc[f"g{k}"] for k in range(1, 7))
    assert LinearJoint.default().stiffness == j.a1
    assert LinearJoint.default().motor_inertia == j.motor_inertia
    assert j.a1 > j.ksw


def test_the_default_joint_does_what_its_table_says():
    """Each reason of the table, against the spring law's closed form
    tau(D) = D (a1 + a2 D**2 - ksw exp(-asw D**2)) evaluated here, not by the class.

    Tolerances: the law and its closed form are the same few float64 operations in
    another order, with no cancellation (every term is within a factor 3 of the
    result), so they agree to a few ulp; 1e-14 relative leaves margin. A wrong sign,
    exponent or coefficient in the law moves the torque by 1e-3 or more.
    """
    doc = documented_defaults()
    a1, a2, ksw, asw = doc["a1"], doc["a2"], doc["ksw"], doc["asw"]
    j = NonlinearJoint.default()

    def tau(d):
        return d * (a1 + a2 * d * d - ksw * math.exp(-asw * d * d))

    # stiffness at zero deflection a1 - ksw = 0.4 a1 (harmonic drives: ~0.5)
    assert float(j.tangent_stiffness(0.0)) == pytest.approx(0.4 * a1, rel=1e-15)
    # the windup region |D| < 1/sqrt(asw) = 2.5e-4 rad holds torques below
    # (a1 - ksw) 2.5e-4 = 1 N m; at its edge the law gives its closed form
    edge = 1.0 / math.sqrt(asw)
    assert edge == pytest.approx(2.5e-4, rel=1e-15)
    assert (a1 - ksw) * edge == pytest.approx(1.0, rel=1e-15)
    assert float(j.torque(edge)) == pytest.approx(tau(edge), rel=1e-14)
    assert float(j.torque(-edge)) == pytest.approx(-tau(edge), rel=1e-14)
    # hardening adds 10 % to the (secant) stiffness at 5e-3 rad, 50 N m linear:
    # the windup term is exp(-400) there, below any rounding
    assert a1 * 5e-3 == pytest.approx(50.0, rel=1e-15)
    assert float(j.torque(5e-3)) == pytest.approx(1.1 * a1 * 5e-3, rel=1e-14)
    assert float(j.torque(5e-3)) == pytest.approx(tau(5e-3), rel=1e-14)
    # J_m: a rotor of 3e-5 kg m**2 reflected through a 100:1 gear
    assert j.motor_inertia == pytest.approx(3e-5 * 100**2, rel=1e-15)
    # the shoulder's joint mode on the rigid-link estimate, sqrt(a1 / I) with I the
    # straight arm's inertia about the shoulder (a uniform rod of 9 m, closed form),
    # is 11 rad/s, next to the links' 12.3 rad/s
    arm = fa.FlexibleArm.paper()
    inertia = 0.335 * 9.0**3 / 3.0
    assert arm.mass_matrix(np.zeros(arm.n_dof))[0, 0] == pytest.approx(inertia, rel=1e-13)
    assert round(math.sqrt(a1 / inertia)) == 11
    assert arm.link_frequencies[0][0] == pytest.approx(12.281, abs=5e-4)
    # friction: breakaway about g1 + g4 = 1.5 N m, 3 % of a 50 N m rated torque;
    # above the Stribeck velocities (1/g3 = 0.1 rad/s) the Coulomb and viscous parts
    # remain, g4 + g6 v, to g1 (1 - tanh(g3 v)) ~ 2e-9 N m at 1 rad/s
    f = MakkarFriction.default()
    assert f.static_level == pytest.approx(1.5)
    assert f.static_level / 50.0 == pytest.approx(0.03, rel=1e-15)
    assert (1 / doc["g2"], 1 / doc["g3"], 1 / doc["g5"]) == pytest.approx((0.01, 0.1, 0.01))
    assert float(f(1.0)) == pytest.approx(doc["g4"] + doc["g6"] * 1.0, rel=0, abs=1e-8)


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"a1": 100.0, "ksw": 100.0}, ValueError, "'ksw'.*< a1"),
        ({"a1": 100.0, "ksw": 150.0}, ValueError, "'ksw'"),
        ({"a1": -1.0}, ValueError, "'a1'"),
        ({"a1": float("nan")}, ValueError, "'a1'"),
        ({"a2": -1.0}, ValueError, "'a2'"),
        ({"asw": 0.0}, ValueError, "'asw'"),
        ({"ksw": -1.0}, ValueError, "'ksw'"),
        ({"motor_inertia": 0.0}, ValueError, "'motor_inertia'"),
        ({"motor_inertia": float("inf")}, ValueError, "'motor_inertia'"),
        ({"motor_damping": -0.1}, ValueError, "'motor_damping'"),
        ({"friction": "makkar"}, TypeError, "'friction'"),
        ({"a1": "1e4"}, TypeError, "'a1'"),
    ],
)
def test_nonlinear_joint_rejects_bad_parameters(kwargs, error, match):
    params = {"a1": 1e4, "a2": 4e7, "ksw": 6e3, "asw": 1.6e7, "motor_inertia": 0.3} | kwargs
    with pytest.raises(error, match=match):
        NonlinearJoint(**params)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((0.0, 0.3), "'stiffness'"),
        ((-5.0, 0.3), "'stiffness'"),
        ((10.0, -0.3), "'motor_inertia'"),
        ((float("nan"), 0.3), "'stiffness'"),
    ],
)
def test_linear_joint_rejects_bad_parameters(args, match):
    with pytest.raises(ValueError, match=match):
        LinearJoint(*args)


@pytest.mark.parametrize("index", range(6))
@pytest.mark.parametrize("value", [-0.1, float("nan"), float("inf")])
def test_friction_rejects_bad_parameters(index, value):
    g = [0.25, 100.0, 10.0, 0.1, 100.0, 0.01]
    g[index] = value
    with pytest.raises(ValueError, match=f"'g{index + 1}' parameter of MakkarFriction"):
        MakkarFriction(*g)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"joints": [LinearJoint(1.0, 1.0)]}, ValueError, "one joint per link"),
        ({"joints": [LinearJoint(1.0, 1.0), "spring"]}, TypeError, "position 1"),
        ({"joints": 5}, TypeError, "'joints'"),
        ({"joint_friction": "both"}, ValueError, "'joint_friction'"),
        ({"rotor_coupling": 1}, TypeError, "'rotor_coupling'"),
    ],
)
def test_arm_rejects_bad_joint_options(kwargs, error, match):
    with pytest.raises(error, match=match):
        fa.FlexibleArm.paper(**kwargs)
