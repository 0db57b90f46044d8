"""The paper's sensor model beside the physical one, and the rigid feedforward."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.control.controllers import JointPD
from flexarm.control.feedforward import RigidDynamics, rigid_projection
from flexarm.control.signals import r_feedforward, y_point, y_point_rate
from flexarm.control.trajectories import Square, Waypoints
from flexarm.model.kinematics import lever_lengths, rigid_point
from flexarm.sensing.delays import DelayModel
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor, parse_sensor
from flexarm.sim import simulate

COLLOCATED = JointPD(kp=2000.0, kd=300.0)  # stable on the encoders; the sensor is only read
SQUARE = Square(center=(5.0, 0.0), side=2.0, time_per_side=0.5)


@pytest.fixture(scope="module")
def paper():
    return fa.FlexibleArm.paper()


def test_paper_model_is_rigid_kinematics_of_the_encoders_delayed_exactly(paper):
    """What the law reads from PointSensor(1, 0.5, model="paper") under an exact delay
    of 40 control periods is the rigid kinematics (distance 0.5 m in place of L2)
    of the joint angles 40 periods earlier."""
    dt, lag = 2e-4, 40
    sensor = PointSensor(1, 0.5, model="paper")
    res = simulate(
        paper,
        COLLOCATED,
        SQUARE,
        sensor=sensor,
        duration=0.3,
        dt=dt,
        delay=DelayModel(lag * dt, "exact"),
    )
    levers = lever_lengths(paper.link_lengths, 1, 0.5)
    pos, vel = rigid_point(levers, res.q[:, :2], res.dq[:, :2])
    y = res.measurement
    np.testing.assert_allclose(y[lag:, y_point(2) : y_point(2) + 2], pos[:-lag], atol=1e-12)
    np.testing.assert_allclose(
        y[lag:, y_point_rate(2) : y_point_rate(2) + 2], vel[:-lag], atol=1e-11
    )
    # the physical model at the same place reads the deflected point: not the same
    physical = simulate(paper, COLLOCATED, SQUARE, sensor=PointSensor(1, 0.5), duration=0.3)
    deflected = paper.point_position(physical.q, 1, 0.5)
    np.testing.assert_allclose(physical.measurement[:, 4:6], deflected, atol=1e-12)
    assert np.abs(deflected - rigid_point(levers, physical.q[:, :2])[0]).max() > 1e-4


def test_paper_tip_sensor_without_delay_reads_what_the_encoders_imply(paper):
    joint = simulate(paper, COLLOCATED, SQUARE, sensor=JointSensor(), duration=0.2)
    tip = simulate(paper, COLLOCATED, SQUARE, sensor=TipSensor(model="paper"), duration=0.2)
    np.testing.assert_array_equal(tip.q, joint.q)
    np.testing.assert_allclose(tip.measurement, joint.measurement, atol=1e-12)
    assert tip.info["sensor"] == "tip (paper model)"


def test_names_and_parsing():
    assert PointSensor(1, 0.5).describe(fa.FlexibleArm.paper()) == "point:1:0.5"
    assert parse_sensor("point:1:0.5", model="paper") == PointSensor(1, 0.5, model="paper")
    assert parse_sensor("tip", model="paper").model == "paper"
    with pytest.raises(ValueError, match="'model' parameter of PointSensor"):
        PointSensor(1, 0.5, model="rigid")
    with pytest.raises(TypeError, match="'model' parameter of TipSensor"):
        TipSensor(model=1)


# ------------------------------------------------------------------ rigid feedforward
@pytest.mark.parametrize(
    "arm",
    [
        fa.FlexibleArm.paper(),
        fa.FlexibleArm(
            [
                fa.Link(1.0, 5.0, 1.1, n_modes=2, hub_inertia=0.2),
                fa.Link(0.8, 2.0, 0.6, hub_mass=0.5),
            ],
            payload_mass=0.3,
            payload_inertia=0.02,
        ),
        fa.FlexibleArm.paper(joints=[fa.LinearJoint.default()] * 2),
        fa.FlexibleArm.paper(joints=[fa.LinearJoint(1e4, 0.3)] * 2, rotor_coupling=False),
        fa.FlexibleArm(
            [fa.Link(1.0, 5.0, 1.1, n_modes=1), fa.RigidLink(0.8, 0.5, 0.3, 0.02, tip_mass=0.1)],
            joints=[fa.RigidJoint(0.2, gear_ratio=7.0), fa.RigidJoint(0.05, gear_ratio=20.0)],
        ),
    ],
    ids=["paper", "hubs-payload", "flexible-joints", "spong-rotors", "rigid-geared-joints"],
)
def test_rigid_dynamics_is_the_arms_dynamics_in_rigid_motion(arm):
    """tau = P' (M(q0) P ddtheta + C(q0, P dtheta) P dtheta) with q0 = P theta: the
    arm's own NumPy model with the modes held at zero and the motors on the links."""
    rd = RigidDynamics.of(arm)
    p = rigid_projection(arm)
    rng = np.random.default_rng(5)
    for _ in range(4):
        th, w, a = rng.normal(size=(3, 2))
        q0, dq0 = p @ th, p @ w
        expected = p.T @ (arm.mass_matrix(q0) @ (p @ a) + arm.velocity_terms(q0, dq0))
        np.testing.assert_allclose(rd(th, w, a), expected, rtol=1e-10, atol=1e-10)
    batch = rng.normal(size=(5, 3, 2))
    np.testing.assert_allclose(
        rd(batch[:, 0], batch[:, 1], batch[:, 2]),
        [rd(*row) for row in batch],
        rtol=1e-13,
    )


def test_feedforward_alone_drives_a_rigid_arm_along_the_path():
    """A rigid two-link arm under its own inverse dynamics and no feedback follows a
    smooth path; what is left is the zero-order hold of the torque, first order in
    the period (halving dt halves the error)."""
    rigid = fa.FlexibleArm([fa.Link(1.0, 1.0, 2.0, n_modes=0), fa.Link(0.8, 1.0, 1.5, n_modes=0)])
    path = Waypoints([[1.2, 0.3], [0.9, 0.9], [0.4, 1.1]], [0.0, 1.0, 2.0], interpolation="quintic")
    errors = []
    for dt in (1e-3, 5e-4, 2.5e-4):
        res = simulate(rigid, JointPD(kp=0.0, kd=0.0), path, dt=dt, duration=2.0, feedforward=True)
        errors.append(res.metrics()["max_error_m"])
    assert res.info["feedforward"] is True
    np.testing.assert_allclose(np.array(errors[:-1]) / errors[1:], 2.0, rtol=0.05)
    assert errors[-1] < 2e-4
    np.testing.assert_array_equal(res.tau[:-1], res.reference[:-1, r_feedforward(2) :])
    free = simulate(rigid, JointPD(kp=0.0, kd=0.0), path, dt=2.5e-4, duration=2.0)
    assert free.metrics()["max_error_m"] > 0.1  # without it the arm stays put


def test_feedforward_needs_two_links():
    one = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=0)])
    with pytest.raises(ValueError, match="'feedforward'"):
        simulate(one, JointPD(), duration=0.1, feedforward=True)
    with pytest.raises(TypeError, match="'feedforward'"):
        simulate(fa.FlexibleArm.paper(), duration=0.1, feedforward="yes")
