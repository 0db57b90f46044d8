"""The reference pipeline: joint references of a path (inverse kinematics, rates,
accelerations) checked against the path itself and against finite differences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexarm import FlexibleArm, Link
from flexarm.control.trajectories import Circle, Line, Square, Waypoints
from flexarm.sim.references import joint_reference
from helpers.control import central_difference


@pytest.fixture(scope="module")
def arm():
    return FlexibleArm.paper()


# ------------------------------------------------------------------ joint_reference
REFERENCE_PATHS = [
    Square(timing="quintic"),
    Circle(center=(4.0, 3.0), radius=2.5, period=7.0, phase=1.0),
    Waypoints([[6.0, -1.0], [3.0, 2.0], [5.0, 4.0]], [0.0, 2.0, 5.0], interpolation="quintic"),
]


@pytest.mark.parametrize("elbow", ["positive", "negative"])
@pytest.mark.parametrize("traj", REFERENCE_PATHS, ids=["square", "circle", "waypoints"])
def test_joint_reference_matches_the_path(arm, traj, elbow):
    t = np.linspace(0.0123, traj.duration - 0.0123, 59)  # no sample at a segment boundary
    theta, dtheta, ddtheta = joint_reference(arm, traj, t, elbow=elbow)
    assert theta.shape == dtheta.shape == ddtheta.shape == (t.size, 2)
    assert np.all(np.sign(theta[:, 1]) == (1 if elbow == "positive" else -1))
    p, v, _ = traj.evaluate(t)
    np.testing.assert_allclose(arm.forward_kinematics(theta), p, atol=1e-10)
    np.testing.assert_allclose(np.einsum("mij,mj->mi", arm.jacobian(theta), dtheta), v, atol=1e-12)
    dth_fd = central_difference(lambda s: joint_reference(arm, traj, s, elbow=elbow)[1], t)
    np.testing.assert_allclose(ddtheta, dth_fd, atol=1e-5)
    th_fd = central_difference(lambda s: joint_reference(arm, traj, s, elbow=elbow)[0], t)
    np.testing.assert_allclose(dtheta, th_fd, atol=1e-7)


def test_joint_reference_acceleration_on_a_circle_about_the_base(arm):
    """Circle about the base: theta_2 fixed, theta_1 turns at omega uniformly."""
    traj = Circle(center=(0.0, 0.0), radius=6.0, period=12.0)
    t = np.linspace(0.1, 11.9, 9)
    theta, dtheta, ddtheta = joint_reference(arm, traj, t)
    np.testing.assert_allclose(theta[:, 1], theta[0, 1])
    np.testing.assert_allclose(dtheta, [[2 * math.pi / 12.0, 0.0]] * 9, atol=1e-13)
    np.testing.assert_allclose(ddtheta, 0.0, atol=1e-12)


def test_joint_reference_scalar_time(arm):
    theta, dtheta, ddtheta = joint_reference(arm, Square(), 2.5)
    assert theta.shape == dtheta.shape == ddtheta.shape == (2,)
    np.testing.assert_allclose(arm.forward_kinematics(theta), [5.0, -2.0], atol=1e-12)


def test_joint_reference_outside_the_reach_raises(arm):
    far = Square(center=(8.0, 0.0), side=4.0)  # corners 10.2 m from the base
    with pytest.raises(ValueError, match=r"'trajectory'.*workspace"):
        joint_reference(arm, far, np.linspace(0.0, 20.0, 41))


@pytest.mark.parametrize(
    "traj",
    [
        Circle(center=(0.0, 0.0), radius=9.0 - 1e-7, period=10.0),  # fully stretched
        Line((-1.0, 0.0), (1.0, 0.0), 2.0),  # through the base: theta_2 = pi
    ],
    ids=["full-reach", "through-base"],
)
def test_joint_reference_near_a_singularity_raises(arm, traj):
    t = np.linspace(0.0, traj.duration, 21)
    with pytest.raises(ValueError, match=r"'trajectory'.*singularities"):
        joint_reference(arm, traj, t)


def test_joint_reference_singularity_tolerance(arm):
    # passes 0.5 m from the base: |sin theta_2| = 0.111 there
    traj = Line((-1.0, 0.5), (1.0, 0.5), 2.0)
    t = np.linspace(0.0, 2.0, 21)
    joint_reference(arm, traj, t)
    joint_reference(arm, traj, t, singularity_tol=0.11)
    with pytest.raises(ValueError, match=r"singularities.*at t = 1.0 s"):
        joint_reference(arm, traj, t, singularity_tol=0.112)


def test_joint_reference_needs_two_links():
    link = Link(3.0, 1676.0, 0.335, n_modes=0)
    three = FlexibleArm(links=(link, link, link))
    with pytest.raises(ValueError, match=r"'arm'.*2 links"):
        joint_reference(three, Square(), [0.0])


def test_joint_reference_bad_arguments(arm):
    with pytest.raises(ValueError, match="'elbow'"):
        joint_reference(arm, Square(), [0.0], elbow="up")
    with pytest.raises(ValueError, match="'singularity_tol'"):
        joint_reference(arm, Square(), [0.0], singularity_tol=0.0)
    with pytest.raises(TypeError, match="'trajectory'"):
        joint_reference(arm, "square", [0.0])  # type: ignore[arg-type]
