"""Gravity compensation (flexarm.control.gravity_compensation, simulate's
``gravity_compensation``).

Oracles, none of them the code under test:

* the compiled holding torques against the statics' Newton solution
  (:meth:`FlexibleArm.equilibrium`, NumPy), and a rigid arm's against moment sums by
  hand;
* a joint PD holding a vertical arm: at rest with compensation its joints stand on
  their references (and an arm started in the posture that carries its weight does
  not move); without it, on ``theta_r - tau_g(theta) / K_p``, the fixed point solved
  here from the moment sums (rigid links) or from the statics (flexible links);
* a Jacobian-transpose PD without compensation at rest where ``J' K_p e = tau_g``.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

import flexarm as fa
from flexarm.control import JacobianTransposePD, JointPD
from flexarm.control.gravity_compensation import holding_torques, scratch_size
from flexarm.control.trajectories import Line
from helpers.arms import three_links, two_short_links

TILTED = (2.0, -9.6)  # both components, to catch a swapped or dropped one
LIGHT = (0.2, -0.96)
KP, KD = 400.0, 80.0


def _compiled_torques(arm: fa.FlexibleArm, theta) -> np.ndarray:
    scratch = np.zeros(scratch_size(arm.n_dof, arm.n_links))
    tau = np.zeros(arm.n_links)
    holding_torques(np.asarray(theta, dtype=float), arm.arrays, scratch, tau)
    return tau


def _flexible_arm(**kwargs) -> fa.FlexibleArm:
    """Two damped links with hubs, settling in about a second under the PD below."""
    links = [
        fa.Link(1.0, 400.0, 1.0, n_modes=2, hub_mass=1.0, hub_inertia=0.5, modal_damping=0.7),
        fa.Link(0.8, 200.0, 0.8, n_modes=2, hub_mass=0.5, hub_inertia=0.2, modal_damping=0.7),
    ]
    return fa.FlexibleArm(links, **{"payload_mass": 0.3, "gravity": TILTED, **kwargs})


RODS = [(1.0, 2.0), (0.8, 1.5)]  # (length m, density kg/m)
HUBS = [(1.0, 0.5), (0.5, 0.2)]  # (mass kg, inertia kg m**2)
PAYLOAD = 0.3


def _rigid_arm(**kwargs) -> fa.FlexibleArm:
    links = [
        fa.Link(L, 1.0, rho, n_modes=0, hub_mass=m, hub_inertia=j)
        for (L, rho), (m, j) in zip(RODS, HUBS, strict=True)
    ]
    return fa.FlexibleArm(links, **{"payload_mass": PAYLOAD, "gravity": TILTED, **kwargs})


def _hand_torques(theta, g=TILTED) -> np.ndarray:
    """Holding torques of the rigid arm by moment sums: joint k holds every mass
    beyond it, ``tau_k = -sum (p - o_k) x m g``."""
    (L1, r1), (L2, r2) = RODS
    a1, a12 = theta[0], theta[0] + theta[1]
    u1, u2 = np.array([np.cos(a1), np.sin(a1)]), np.array([np.cos(a12), np.sin(a12)])
    o1, o2 = np.zeros(2), L1 * u1
    beyond_1 = [(o1 + L1 / 2 * u1, r1 * L1)]  # joint 1 alone holds link 1's rod
    beyond_2 = [(o2 + L2 / 2 * u2, r2 * L2), (o2, HUBS[1][0]), (o2 + L2 * u2, PAYLOAD)]

    def holding(masses, origin):
        return -sum(m * ((p - origin)[0] * g[1] - (p - origin)[1] * g[0]) for p, m in masses)

    return np.array([holding(beyond_1 + beyond_2, o1), holding(beyond_2, o2)])


def _hold(arm, controller, point, duration, **settings):
    return fa.simulate(arm, controller, Line(point, point, duration), dt=2e-4, **settings)


# -------------------------------------------------------------- the holding torques
@pytest.mark.parametrize(
    "make",
    [
        _flexible_arm,
        # geometric stiffening; a rigid link among flexible ones (soft links: a tenth of
        # the gravity, for a sag within the model's small deflections)
        lambda: two_short_links(2, gravity=LIGHT),
        lambda: three_links(gravity=LIGHT),
        lambda: fa.FlexibleArm.paper(gravity=(0.0, -9.81)),  # 1.4 m of sag at the tip
    ],
    ids=["damped", "stiffened", "three-links", "paper"],
)
def test_compiled_holding_torques_match_the_statics(make):
    arm = make()
    rng = np.random.default_rng(3)
    for _ in range(3):
        theta = rng.uniform(-np.pi, np.pi, arm.n_links)
        want = arm.equilibrium(theta, require_stable=False).torques
        np.testing.assert_allclose(_compiled_torques(arm, theta), want, rtol=1e-9, atol=1e-9)


def test_rigid_holding_torques_are_the_moment_sums():
    arm = _rigid_arm()
    for theta in ([0.0, 0.0], [0.4, -1.1], [2.5, 0.7]):
        np.testing.assert_allclose(_compiled_torques(arm, theta), _hand_torques(theta),
                                   rtol=1e-12, atol=1e-12)  # fmt: skip


def test_no_gravity_holds_nothing():
    arm = _flexible_arm(gravity=None)
    assert np.all(_compiled_torques(arm, [0.3, 0.4]) == 0.0)


# -------------------------------------------------------------- joint PD at rest
POINT = np.array([0.9, 0.7])


def test_joint_pd_on_a_rigid_vertical_arm_stands_on_its_reference_with_compensation():
    arm = _rigid_arm()
    theta_r = np.asarray(arm.inverse_kinematics(POINT), dtype=float)
    on = _hold(arm, JointPD(KP, KD), POINT, 3.0)
    off = _hold(arm, JointPD(KP, KD), POINT, 3.0, gravity_compensation=False)
    assert on.info["gravity_compensation"] and not off.info["gravity_compensation"]
    np.testing.assert_allclose(on.q[-1, :2], theta_r, atol=1e-9)
    # without: at rest where K_p e = tau_g(theta_r - e), solved from the moment sums
    err = scipy.optimize.fsolve(lambda e: KP * e - _hand_torques(theta_r - e), np.zeros(2))
    assert np.abs(err).max() > 1e-2  # (a visible offset)
    np.testing.assert_allclose(theta_r - off.q[-1, :2], err, rtol=1e-6, atol=1e-9)
    # and to first order (in gravity's stiffness over K_p) the closed form tau_g / K_p
    first = _hand_torques(theta_r) / KP
    assert np.linalg.norm(err - first) < 0.05 * np.linalg.norm(err)


def test_joint_pd_on_a_flexible_vertical_arm_stands_on_its_reference_with_compensation():
    arm = _flexible_arm()
    theta_r = np.asarray(arm.inverse_kinematics(POINT), dtype=float)
    on = _hold(arm, JointPD(KP, KD), POINT, 3.0)
    off = _hold(arm, JointPD(KP, KD), POINT, 3.0, gravity_compensation=False)
    np.testing.assert_allclose(on.q[-1, :2], theta_r, atol=1e-8)
    # the links' sag is the statics' at the reference posture
    np.testing.assert_allclose(on.q[-1], arm.equilibrium(theta_r).q, atol=1e-7)
    # without: the fixed point of K_p e = tau_eq(theta_r - e), the statics' torques
    err = scipy.optimize.fsolve(
        lambda e: KP * e - arm.equilibrium(theta_r - e).torques, np.zeros(2), xtol=1e-12
    )
    np.testing.assert_allclose(theta_r - off.q[-1, :2], err, rtol=1e-5, atol=1e-8)


def test_started_in_the_posture_that_carries_its_weight_the_compensated_arm_stays():
    arm = _flexible_arm()
    theta_r = np.asarray(arm.inverse_kinematics(POINT), dtype=float)
    eq = arm.equilibrium(theta_r)
    x0 = tuple(np.concatenate([eq.q, np.zeros(arm.n_dof)]))
    run = _hold(arm, JointPD(KP, KD), POINT, 0.2, initial_state=x0)
    assert np.abs(run.q - eq.q).max() < 1e-9
    np.testing.assert_allclose(run.tau[-1], eq.torques, rtol=1e-9)


# -------------------------------------------------------------- Jacobian-transpose PD
def test_jacobian_transpose_pd_holds_the_point_with_compensation_and_sags_without():
    arm = _rigid_arm()
    law = JacobianTransposePD(kp=2000.0, kd=300.0)
    on = _hold(arm, law, POINT, 2.0)
    off = _hold(arm, law, POINT, 2.0, gravity_compensation=False)
    np.testing.assert_allclose(on.tip[-1], POINT, atol=1e-9)
    # without: at rest where J(theta)' K_p (x_r - x(theta)) = tau_g(theta)
    theta = off.q[-1, :2]
    (L1, _), (L2, _) = RODS
    a1, a12 = theta[0], theta[0] + theta[1]
    x = np.array([L1 * np.cos(a1) + L2 * np.cos(a12), L1 * np.sin(a1) + L2 * np.sin(a12)])
    jac = np.array(
        [
            [-L1 * np.sin(a1) - L2 * np.sin(a12), -L2 * np.sin(a12)],
            [L1 * np.cos(a1) + L2 * np.cos(a12), L2 * np.cos(a12)],
        ]
    )
    assert np.linalg.norm(POINT - x) > 1e-3
    np.testing.assert_allclose(jac.T @ (2000.0 * (POINT - x)), _hand_torques(theta), rtol=1e-6)


def test_a_horizontal_arm_runs_as_before_whatever_the_option():
    arm = _rigid_arm(gravity=None)
    base = _hold(arm, JointPD(KP, KD), POINT, 0.1)
    forced = _hold(arm, JointPD(KP, KD), POINT, 0.1, gravity_compensation=True)
    assert not forced.info["gravity_compensation"]
    assert np.array_equal(base.q, forced.q) and np.array_equal(base.tau, forced.tau)


def test_bad_gravity_compensation_is_named():
    with pytest.raises(fa.errors.InvalidTypeError, match="gravity_compensation"):
        fa.SimulationSettings(gravity_compensation="yes")
