"""The recursive (articulated-body) forward dynamics against the dense one and the
NumPy reference, on every feature of the model; the general kernel takes the
recursive one from RECURSIVE_FROM_LINKS links on.

Oracles: the dense kernel (mass matrix and L D L' solve) and the NumPy
reference of flexarm.model.arm (body Jacobians, numpy.linalg.solve), two
formulations that share no code with the recursion's elimination.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import flexarm as fa
from flexarm.errors import InvalidValueError
from flexarm.model import dynamics
from flexarm.model.arrays import make_workspace
from helpers.arms import random_states

TOL = 1e-10
JOINT = fa.NonlinearJoint.default(fa.MakkarFriction.default())


def chain(n_links, modes, **kwargs):
    """``n_links`` links of 9 m in all, ``modes`` per link (one number or one each)."""
    counts = [modes] * n_links if isinstance(modes, int) else list(modes)
    links = [
        fa.Link(9.0 / n_links, 1676.0, 0.335, n_modes=k, hub_mass=0.2 * i, hub_inertia=0.01 * i)
        for i, k in enumerate(counts)
    ]
    return fa.FlexibleArm(links, **kwargs)


ARMS = {
    "one rigid link": lambda: chain(1, 0),
    "one link, 3 modes, stiffening": lambda: chain(1, 3),
    "rigid 2-link": lambda: chain(2, 0),
    "paper": lambda: fa.FlexibleArm.paper(),
    "paper, 3 modes, clamped-mass, stiffening": lambda: fa.FlexibleArm.paper(
        n_modes=3, boundary="clamped-mass", geometric_stiffening=True
    ),
    "rigid 6-link": lambda: chain(6, 0),
    "4 links, mixed modes, payload": lambda: chain(
        4, [2, 0, 3, 1], payload_mass=0.7, payload_inertia=0.05, geometric_stiffening=False
    ),
    "5 links, 2 modes, stiffening, clamped-free": lambda: chain(
        5, 2, boundary="clamped-free", payload_mass=0.3
    ),
    "3 links, nonlinear joints, link friction": lambda: chain(
        3, 1, joints=[JOINT] * 3, geometric_stiffening=False
    ),
    "3 links, joints, motor friction, stiffening, payload": lambda: chain(
        3,
        [2, 1, 2],
        joints=[JOINT, fa.LinearJoint.default(), JOINT],
        joint_friction="motor",
        payload_mass=0.5,
        payload_inertia=0.02,
    ),
    "4 links, joints, rotors uncoupled": lambda: chain(
        4, 1, joints=[fa.LinearJoint.default()] * 4, rotor_coupling=False
    ),
    "3 links, joints of three gear ratios, coupled rotors": lambda: chain(
        3,
        [1, 2, 0],
        joints=[
            fa.LinearJoint(4e3, 0.2, gear_ratio=3.0),
            fa.LinearJoint(2e3, 0.3, gear_ratio=50.0),
            fa.NonlinearJoint(1e3, 1e5, 300.0, 1e4, 0.1),
        ],
    ),
    "4 links, rigid geared joints with friction, a rigid link, tip bodies": lambda: fa.FlexibleArm(
        [
            fa.Link(2.0, 1676.0, 0.335, n_modes=2, tip_mass=0.3, tip_inertia=0.02),
            fa.RigidLink(1.5, 0.8, 0.6, 0.1, hub_mass=0.2, tip_inertia=0.05),
            fa.Link(1.2, 800.0, 0.3, n_modes=1, tip_mass=0.1),
            fa.Link(1.0, 600.0, 0.3, n_modes=2, tip_mass=0.2, tip_inertia=0.01),
        ],
        joints=[
            fa.RigidJoint(0.3, 0.1, fa.MakkarFriction.default(), gear_ratio=100.0),
            fa.RigidJoint(0.2, 0.05, gear_ratio=4.0),
            fa.RigidJoint(0.0),
            fa.RigidJoint(0.05, friction=fa.MakkarFriction.default()),
        ],
        payload_mass=0.4,
    ),
    "3 links, flexible joints, tip bodies, stiffening": lambda: fa.FlexibleArm(
        [
            fa.Link(3.0, 1676.0, 0.335, n_modes=1, tip_mass=0.5, tip_inertia=0.03),
            fa.RigidLink(3.0, 1.0, 1.4, 0.7, tip_mass=0.2, tip_inertia=0.01),
            fa.Link(3.0, 1676.0, 0.335, n_modes=2, hub_mass=0.1),
        ],
        joints=[JOINT] * 3,
        payload_mass=0.2,
    ),
    "12 links, 1 mode": lambda: chain(12, 1, geometric_stiffening=False),
}


def states(arm, m, seed=5, deflection=0.03):
    """``m`` random states and torques, the motors turning ~1 rad/s against their links."""
    return random_states(arm, m, seed, deflection, motor_rates=True)


def run(kernel, arm, q, dq, tau):
    ddq = np.empty(arm.n_dof)
    kernel(q, dq, tau, arm.arrays, make_workspace(arm.n_dof), ddq)
    return ddq


def rel(a, b):
    return np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))


@pytest.mark.parametrize("name", list(ARMS))
def test_recursive_equals_dense_and_the_reference(name):
    arm = ARMS[name]()
    for q, dq, tau in zip(*states(arm, 10), strict=True):
        rec = run(dynamics.forward_dynamics_recursive, arm, q, dq, tau)
        dense = run(dynamics.forward_dynamics_dense, arm, q, dq, tau)
        assert rel(rec, dense) < TOL
        assert rel(rec, arm.forward_dynamics(q, dq, tau, backend="numpy")) < TOL


@pytest.mark.parametrize("name", list(ARMS))
def test_the_general_kernel_takes_the_recursive_one_from_three_links(name):
    arm = ARMS[name]()
    q, dq, tau = (x[0] for x in states(arm, 1, seed=9))
    general = run(dynamics.forward_dynamics_general, arm, q, dq, tau)
    chosen = (
        dynamics.forward_dynamics_recursive
        if arm.n_links >= dynamics.RECURSIVE_FROM_LINKS
        else dynamics.forward_dynamics_dense
    )
    assert np.array_equal(general, run(chosen, arm, q, dq, tau))
    if not dynamics.is_two_links_one_mode(arm.arrays):
        assert np.array_equal(general, run(dynamics.forward_dynamics, arm, q, dq, tau))
        assert np.array_equal(general, arm.forward_dynamics(q, dq, tau))


def test_large_deflections_and_rates_still_agree():
    """Far from the linear regime (tip deflections a third of the link, fast joints)
    the two algorithms still solve the same equations."""
    arm = ARMS["5 links, 2 modes, stiffening, clamped-free"]()
    q, dq, tau = states(arm, 10, seed=2, deflection=0.3)
    dq *= 5.0
    for b in range(10):
        rec = run(dynamics.forward_dynamics_recursive, arm, q[b], dq[b], tau[b])
        assert rel(rec, run(dynamics.forward_dynamics_dense, arm, q[b], dq[b], tau[b])) < TOL


def test_a_stale_workspace_changes_nothing():
    arm = ARMS["3 links, joints, motor friction, stiffening, payload"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    want = run(dynamics.forward_dynamics_recursive, arm, q, dq, tau)
    ws = make_workspace(arm.n_dof)
    for field in ws:
        field[...] = np.nan
    ddq = np.empty(arm.n_dof)
    dynamics.forward_dynamics_recursive(q, dq, tau, arm.arrays, ws, ddq)
    assert np.array_equal(ddq, want)


def test_the_recursive_kernels_check_their_arguments():
    arm = ARMS["rigid 6-link"]()
    n = arm.n_dof
    q, dq, tau = np.zeros(n), np.zeros(n), np.zeros(arm.n_links)
    with pytest.raises(InvalidValueError, match="'ddq' parameter of forward_dynamics_recursive"):
        dynamics.forward_dynamics_recursive(q, dq, tau, arm.arrays, make_workspace(n), np.empty(2))
    with pytest.raises(InvalidValueError, match="'tau' parameter of forward_dynamics_dense"):
        dynamics.forward_dynamics_dense(q, dq, np.zeros(n + 1), arm.arrays, make_workspace(n), q)
    with pytest.raises(InvalidValueError, match=r"'ws\.chain' parameter of accelerations_rec"):
        ws = make_workspace(n)._replace(chain=np.zeros((n, 3)))
        dynamics.accelerations_recursive(q, dq, arm.arrays, ws, np.empty(n))


@settings(max_examples=25, deadline=None)
@given(
    modes=st.lists(st.integers(0, 3), min_size=1, max_size=5),
    stiffening=st.booleans(),
    joints=st.booleans(),
    payload=st.floats(0.0, 2.0),
    seed=st.integers(0, 2**31),
)
def test_property_any_chain(modes, stiffening, joints, payload, seed):
    arm = chain(
        len(modes),
        modes,
        geometric_stiffening=stiffening,
        joints=[JOINT] * len(modes) if joints else None,
        payload_mass=payload,
    )
    q, dq, tau = (x[0] for x in states(arm, 1, seed=seed))
    rec = run(dynamics.forward_dynamics_recursive, arm, q, dq, tau)
    assert rel(rec, run(dynamics.forward_dynamics_dense, arm, q, dq, tau)) < TOL


@nb.njit
def _users_loop(q, dq, tau, model, ws, ddq):  # pragma: no cover - compiled
    dynamics.forward_dynamics_recursive(q, dq, tau, model, ws, ddq)
    return ddq[0]


def test_inside_compiled_code_the_name_is_the_kernel():
    arm = ARMS["4 links, mixed modes, payload"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    ddq = np.empty(arm.n_dof)
    _users_loop(q, dq, tau, arm.arrays, make_workspace(arm.n_dof), ddq)
    assert np.array_equal(ddq, run(dynamics.forward_dynamics_recursive, arm, q, dq, tau))
