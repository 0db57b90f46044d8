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
