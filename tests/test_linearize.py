"""Linearised closed loops against closed forms for rigid two-link arms, and what the
poles predict for the simulated paper arm."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.control.controllers import JacobianTransposePD, JointPD
from flexarm.control.linearize import closed_loop_matrix, closed_loop_poles
from flexarm.control.trajectories import Line
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor
from flexarm.sim import SimulationError, simulate

L1, L2, RHO, HUB = 1.2, 0.9, 2.0, 0.05


@pytest.fixture(scope="module")
def rigid():
    return fa.FlexibleArm(
        [fa.Link(L1, 1.0, RHO, n_modes=0, hub_inertia=HUB), fa.Link(L2, 1.0, RHO, n_modes=0)]
    )


def rod_mass_matrix(theta2):
    """Two uniform rods (mass rho L, inertia m L^2 / 3 about the joint) and a hub."""
    m2 = RHO * L2
    i1 = RHO * L1**3 / 3 + HUB
    i2 = m2 * L2**2 / 3
    c = np.cos(theta2)
    m11 = i1 + i2 + m2 * L1**2 + m2 * L1 * L2 * c
    m12 = i2 + m2 * L1 * L2 * c / 2
    return np.array([[m11, m12], [m12, i2]])


def rigid_jacobian(theta, l1=L1, l2=L2):
    s1, c1 = np.sin(theta[0]), np.cos(theta[0])
    s12, c12 = np.sin(theta.sum()), np.cos(theta.sum())
    return np.array([[-l1 * s1 - l2 * s12, -l2 * s12], [l1 * c1 + l2 * c12, l2 * c12]])


def closed_form(stiffness, damping, theta):
    m_inv = np.linalg.inv(rod_mass_matrix(theta[1]))
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-m_inv @ stiffness, -m_inv @ damping]])


POINT = (1.4, 0.7)


def test_joint_pd_on_a_rigid_arm(rigid):
    kp, kd = np.array([40.0, 25.0]), np.array([6.0, 3.0])
    a = closed_loop_matrix(rigid, JointPD(kp=kp, kd=kd), POINT)
    theta = rigid.inverse_kinematics(np.array(POINT))
    np.testing.assert_allclose(a, closed_form(np.diag(kp), np.diag(kd), theta), atol=1e-6)


@pytest.mark.parametrize("sensor", [JointSensor(), TipSensor()])
def test_jacobian_transpose_pd_on_a_rigid_arm(rigid, sensor):
    kp, kd = 300.0, 40.0
    a = closed_loop_matrix(rigid, JacobianTransposePD(kp=kp, kd=kd), POINT, sensor)
    theta = rigid.inverse_kinematics(np.array(POINT))
    jac = rigid_jacobian(theta)
    expected = closed_form(kp * jac.T @ jac, kd * jac.T @ jac, theta)
    np.testing.assert_allclose(a, expected, atol=1e-6)


def test_point_sensor_uses_the_points_jacobian(rigid):
    kp, kd, d = 300.0, 40.0, 0.4
    a = closed_loop_matrix(rigid, JacobianTransposePD(kp=kp, kd=kd), POINT, PointSensor(1, d))
    theta = rigid.inverse_kinematics(np.array(POINT))
    jac = rigid_jacobian(theta, L1, d)
    expected = closed_form(kp * jac.T @ jac, kd * jac.T @ jac, theta)
    np.testing.assert_allclose(a, expected, atol=1e-6)


def test_poles_predict_the_paper_arms_simulations():
    arm = fa.FlexibleArm.paper()
    ctrl = JacobianTransposePD.from_arm(arm)
    start = np.array([6.0, -1.0])
    hold = Line(start, start, 1.0)  # rest at the linearisation point
    collocated = closed_loop_poles(arm, ctrl, start, JointSensor())
    assert collocated[0].real < 0
    res = simulate(arm, ctrl, hold, initial_state=None, duration=1.0)
    assert np.max(np.abs(res.error)) < 1e-9  # at rest on an equilibrium
    tip = closed_loop_poles(arm, ctrl, start, TipSensor())
    assert tip[0].real > 10.0
    kick = np.zeros(2 * arm.n_dof)
    kick[:2] = arm.inverse_kinematics(start)
    kick[2] = 1e-6  # a micrometre-scale modal disturbance grows like exp(Re p t)
    with pytest.raises(SimulationError):
        simulate(arm, ctrl, hold, sensor=TipSensor(), initial_state=kick, duration=1.0)


def test_poles_are_sorted_by_real_part(rigid):
    poles = closed_loop_poles(rigid, JointPD(kp=40.0, kd=2.0), POINT)
    assert np.all(np.diff(poles.real) <= 0)


@pytest.mark.parametrize(
    ("args", "exc", "match"),
    [
        ({"controller": "pd"}, TypeError, "'controller'"),
        ({"sensor": "tip"}, TypeError, "'sensor'"),
        ({"position": (1.0, 2.0, 3.0)}, ValueError, "'position'"),
        ({"position": (np.nan, 0.0)}, ValueError, "'position'"),
        ({"elbow": "up"}, ValueError, "'elbow'"),
        ({"step": 0.0}, ValueError, "'step'"),
    ],
)
def test_bad_input(rigid, args, exc, match):
    kwargs = {"controller": JointPD(), "position": POINT, **args}
    with pytest.raises(exc, match=match):
        closed_loop_matrix(rigid, **kwargs)


def test_needs_two_links():
    arm3 = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 3)
    with pytest.raises(ValueError, match="two links"):
        closed_loop_matrix(arm3, JointPD(), (1.0, 1.0))
