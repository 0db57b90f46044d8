"""The scenario file's ``[arm]`` tables build the real-arm parts: rigid links, tip
bodies, rigid joints with their motor dynamics, spring dampers and gravity; a bad
table is one error naming its key."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import flexarm as fa
from flexarm.errors import ScenarioError
from flexarm.model.joints import LinearJoint, MakkarFriction, RigidJoint
from flexarm.model.link import Link, RigidLink
from flexarm.sim.scenario import arm_from_tables

STRIP = {"length": 0.2, "flexural_rigidity": 2.7, "linear_density": 0.76, "n_modes": 1}
BAR = {"kind": "rigid", "length": 0.3, "mass": 1.2, "com": 0.1, "inertia": 0.004}


def test_a_rigid_link_and_a_tip_body_are_the_library_objects():
    data = {"arm": {"links": [BAR, {**STRIP, "tip_mass": 0.1, "tip_inertia": 1e-4}]}}
    arm = arm_from_tables(data)
    by_hand = fa.FlexibleArm(
        [
            RigidLink(0.3, 1.2, 0.1, 0.004),
            Link(0.2, 2.7, 0.76, n_modes=1, tip_mass=0.1, tip_inertia=1e-4),
        ]
    )
    q = np.array([0.3, -0.2, 0.01])
    np.testing.assert_array_equal(arm.mass_matrix(q), by_hand.mass_matrix(q))
    # the rigid link's inertia about its joint by the parallel-axis theorem
    assert arm.links[0].joint_inertia == pytest.approx(0.004 + 1.2 * 0.1**2, rel=1e-15)


def test_rigid_joints_with_motor_dynamics_and_flexible_ones_with_a_damper():
    rigid = {
        "kind": "rigid",
        "motor_inertia": 0.06,
        "damping": 2.0,
        "friction": {"g1": 0.0, "g4": 0.8, "g5": 20.0, "g6": 0.0},
    }
    arm = arm_from_tables({"arm": {"links": [STRIP, STRIP], "joints": rigid}})
    assert (
        list(arm.joints)
        == [
            RigidJoint(
                0.06,
                2.0,
                MakkarFriction(0.0, *MakkarFriction.default().params[1:3], 0.8, 20.0, 0.0),
            )
        ]
        * 2
    )
    spring = {"kind": "linear", "stiffness": 500.0, "motor_inertia": 0.01, "damping": 0.3}
    arm = arm_from_tables({"arm": {"links": [STRIP], "joints": [spring]}})
    assert list(arm.joints) == [
        dataclasses.replace(LinearJoint.default(), stiffness=500.0, motor_inertia=0.01, damping=0.3)
    ]
    # a rigid joint without keys is the ideal one: no motor dynamics, no joints at all
    assert arm_from_tables({"arm": {"links": [STRIP], "joints": {"kind": "rigid"}}}).joints is None


def test_gravity_is_passed_to_the_arm():
    arm = arm_from_tables({"arm": {"links": [STRIP], "gravity": [0.0, -9.81]}})
    assert arm.gravity == (0.0, -9.81)
    assert arm_from_tables({"arm": {"links": [STRIP]}}).gravity is None


@pytest.mark.parametrize(
    ("links", "joints", "key"),
    [
        ([{**BAR, "flexural_rigidity": 1.0}], None, "arm.links[0].flexural_rigidity"),
        ([{**BAR, "kind": "stiff"}], None, "arm.links[0]"),
        ([{k: v for k, v in BAR.items() if k != "com"}], None, "arm.links[0]"),
        ([STRIP], {"kind": "rigid", "stiffness": 10.0}, "arm.joints.stiffness"),
        ([STRIP], {"kind": "rigid", "damping": -1.0}, "arm.joints"),
    ],
)
def test_a_bad_arm_table_names_its_key(links, joints, key):
    data = {"arm": {"links": links, **({} if joints is None else {"joints": joints})}}
    with pytest.raises(ScenarioError, match=key.replace("[", r"\[").replace("]", r"\]")):
        arm_from_tables(data)


def test_bad_gravity_names_the_key():
    with pytest.raises(ScenarioError, match="gravity"):
        arm_from_tables({"arm": {"links": [STRIP], "gravity": [0.0]}})
