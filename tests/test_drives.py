"""A drive's current-to-torque map by hand (the Quanser data sheet's stage 1), its limit
and offset, and bad parameters named."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexarm as fa
from flexarm.errors import InvalidValueError
from flexarm.model.drives import Drive

STAGE1 = {"torque_constant": 0.119, "gear_ratio": 100, "efficiency": 0.75}


def test_torque_gain_is_the_data_sheets_product():
    # config_2dslf.m: Ktg1 = 0.75 * Kt1 * Kg1 = 8.925 N m/A
    assert Drive(**STAGE1).torque_gain == pytest.approx(8.925, rel=1e-12)
    assert Drive(**STAGE1, rotor_inertia=6.28e-6).reflected_inertia == pytest.approx(0.0628)


def test_current_is_clipped_at_the_limit_after_its_offset():
    d = Drive(**STAGE1, current_limit=1.0, current_offset=0.02)
    i = np.array([-2.0, 0.02, 0.52, 1.5])
    expected = 8.925 * np.array([-1.0, 0.0, 0.5, 1.0])
    np.testing.assert_allclose(d.joint_torque(current=i), expected, rtol=1e-12, atol=1e-15)


def test_motor_torque_passes_the_gear_and_its_efficiency():
    d = Drive(**STAGE1)
    np.testing.assert_allclose(d.joint_torque(motor_torque=[0.1, -0.2]), [7.5, -15.0])


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"torque_constant": 0.0}, "torque_constant"),
        ({"gear_ratio": 0.5}, "gear_ratio"),
        ({"efficiency": 1.2}, "efficiency"),
        ({"efficiency": 0.0}, "efficiency"),
        ({"current_limit": 0.0}, "current_limit"),
        ({"current_limit": math.nan}, "current_limit"),
        ({"rotor_inertia": -1.0}, "rotor_inertia"),
        ({"current_offset": math.nan}, "current_offset"),
    ],
)
def test_a_bad_parameter_is_named(change, name):
    with pytest.raises(InvalidValueError, match=name):
        Drive(**{**STAGE1, **change})


def test_joint_torque_takes_one_input():
    d = Drive(**STAGE1)
    with pytest.raises(InvalidValueError, match="one of them"):
        d.joint_torque()
    with pytest.raises(InvalidValueError, match="one of them"):
        d.joint_torque(current=1.0, motor_torque=1.0)


def test_an_arm_with_drives_turns_currents_into_joint_torques():
    """FlexibleArm(drives=...): a driven joint's input is its current, by hand
    eta K_t N (i - i0) clipped at the limit (0.75 x 0.119 x 100 = 8.925 N m/A, limit
    1 A); a joint without a drive takes its input as the torque."""
    drive = Drive(
        torque_constant=0.119,
        gear_ratio=100,
        efficiency=0.75,
        current_limit=1.0,
        current_offset=0.02,
    )
    links = [fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 2
    arm = fa.FlexibleArm(links, drives=[drive, None])
    inputs = np.array([[0.52, 3.0], [3.0, -1.5], [-2.0, 0.0]])
    expected = np.array([[8.925 * 0.5, 3.0], [8.925, -1.5], [-8.925, 0.0]])
    np.testing.assert_allclose(arm.joint_torques(inputs), expected, rtol=1e-14)
    np.testing.assert_allclose(arm.joint_torques(inputs[0]), expected[0], rtol=1e-14)
    undriven = fa.FlexibleArm(links)
    np.testing.assert_array_equal(undriven.joint_torques(inputs), inputs)
    with pytest.raises(ValueError, match=r"'drives'.*one Drive"):
        fa.FlexibleArm(links, drives=[drive])
    with pytest.raises(TypeError, match=r"'drives'.*Drive objects"):
        fa.FlexibleArm(links, drives=[drive, 1.0])
    with pytest.raises(ValueError, match=r"'inputs'.*2 entries"):
        arm.joint_torques([1.0, 2.0, 3.0])


def _driven_arm() -> fa.FlexibleArm:
    drive = Drive(**STAGE1, current_limit=1.0, current_offset=0.02)
    return fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 2, drives=[drive, None])


def test_an_open_loop_run_takes_motor_currents_through_the_drives():
    """simulate_open_loop(current=...) is the run of the torques worked out by hand
    (8.925 N m/A on the driven joint after the offset, clipped at 1 A; the other
    joint's column is its torque), held between samples; a single rigid rod of
    inertia J = rho L**3 / 3 under a constant current turns by tau t**2 / (2 J)."""
    arm = _driven_arm()
    t = np.linspace(0.0, 0.5, 51)
    rng = np.random.default_rng(4)
    current = rng.uniform(-2.0, 2.0, size=(51, 2))
    by_hand = current.copy()
    by_hand[:, 0] = 8.925 * np.clip(current[:, 0] - 0.02, -1.0, 1.0)
    driven = fa.simulate_open_loop(arm, t, current=current)
    torqued = fa.simulate_open_loop(arm, t, by_hand)
    np.testing.assert_allclose(driven.tau, by_hand, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(driven.q, torqued.q, rtol=1e-12, atol=1e-14)
    assert driven.info["torque"] == "current samples"
    rod = fa.FlexibleArm([fa.Link(1.0, 10.0, 3.0, n_modes=0)], drives=[Drive(**STAGE1)])
    res = fa.simulate_open_loop(rod, t, current=np.full(51, 0.1))
    # tau = 0.8925 N m, J = 3 x 1 / 3 = 1 kg m**2 (no rotor inertia on the joint)
    assert res.q[-1, 0] == pytest.approx(0.8925 * 0.5**2 / 2, rel=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"torque": np.zeros((3, 2)), "current": np.zeros((3, 2))}, "one of them"),
        ({}, "'torque' or a 'current'"),
        ({"current": np.zeros((4, 2))}, r"'current'.*\(3, 2\)"),
        ({"current": np.full((3, 2), np.nan)}, "'current'"),
    ],
)
def test_an_open_loop_run_refuses_a_bad_current(kwargs, match):
    with pytest.raises(InvalidValueError, match=match):
        fa.simulate_open_loop(_driven_arm(), np.linspace(0.0, 0.02, 3), **kwargs)


def test_currents_need_an_arm_with_drives():
    arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=0)] * 2)
    with pytest.raises(InvalidValueError, match=r"'current'.*drives"):
        fa.simulate_open_loop(arm, np.linspace(0.0, 0.02, 3), current=np.zeros((3, 2)))
