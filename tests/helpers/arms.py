"""Arms and random states shared by the plant's tests (flexarm.model).

The arms exercise every term of the dynamics: hubs, payload, rigid links among
flexible ones, clamped-mass modes, geometric stiffening. The state generators scale
each link's modal coordinates by its tip deflection, so that a tip deflects by a
chosen fraction of its link whatever the mode normalisation.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

import flexarm as fa

__all__ = [
    "LINEAR_CLAMPED_FREE",
    "assert_mass_matrix_and_kernels",
    "random_state",
    "random_states",
    "three_links",
    "two_rigid_rods_mass_matrix",
    "two_short_links",
]

LINEAR_CLAMPED_FREE: dict[str, Any] = {"boundary": "clamped-free", "geometric_stiffening": False}
"""The model before geometric stiffening and clamped-mass modes became the defaults of an
arm a user builds: the tests written for it state it."""


def three_links(**kwargs: Any) -> fa.FlexibleArm:
    """Three links: two modes and a hub inertia, a rigid link with a hub, three modes
    with a hub; a payload with rotary inertia at the tip. ``kwargs`` go to the arm."""
    links = [
        fa.Link(1.0, 5.0, 1.1, n_modes=2, hub_inertia=0.2),
        fa.Link(0.8, 2.0, 0.6, n_modes=0, hub_mass=0.5, hub_inertia=0.03),
        fa.Link(0.6, 1.5, 0.4, n_modes=3, hub_mass=0.2, hub_inertia=0.01),
    ]
    return fa.FlexibleArm(links, payload_mass=0.3, payload_inertia=0.02, **kwargs)


def two_short_links(n_modes: int | None = None, **kwargs: Any) -> fa.FlexibleArm:
    """Two short links (1.3 m and 0.9 m) with a hub mass of 0.3 kg at the shoulder and a
    payload of 0.4 kg and 0.05 kg m**2 at the tip; ``n_modes`` per link (the links'
    default if None), ``kwargs`` override the arm's parameters."""
    modes = {} if n_modes is None else {"n_modes": n_modes}
    links = [fa.Link(1.3, 4.0, 0.9, hub_mass=0.3, **modes), fa.Link(0.9, 2.5, 0.5, **modes)]
    return fa.FlexibleArm(links, **{"payload_mass": 0.4, "payload_inertia": 0.05, **kwargs})


def random_state(
    arm: fa.FlexibleArm, rng: np.random.Generator, scale: float = 0.1
) -> tuple[np.ndarray, np.ndarray]:
    """One state: angles in [-pi, pi], joint rates ~1 rad/s, modal coordinates giving
    tip deflections ~``scale`` L and tip deflection rates ~L per second; motor angles
    (if any) within ~0.05 rad of their links."""
    q = np.empty(arm.n_dof)
    dq = rng.normal(size=arm.n_dof)
    q[: arm.n_links] = rng.uniform(-np.pi, np.pi, arm.n_links)
    for i, (lk, bm) in enumerate(zip(arm.links, arm.modes, strict=True)):
        s = arm.modal_slice(i)
        if lk.n_modes:
            unit = lk.length / np.abs(bm.tip_deflection)
            q[s] = rng.normal(size=lk.n_modes) * scale * unit
            dq[s] *= unit
    if arm.has_flexible_joints:
        q[arm.motor_slice] = q[: arm.n_links] + rng.normal(size=arm.n_links) * 0.05
    return q, dq


def random_states(
    arm: fa.FlexibleArm,
    m: int,
    seed: int,
    deflection: float = 0.03,
    motor_rates: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``m`` states and torques, rows of ``(q, dq, tau)``: angles in [-pi, pi], rates
    ~1 rad/s, tip deflections ~``deflection`` L and their rates ~0.3 L per second,
    motors within 2 mrad of their links (their rates ~1 rad/s faster with
    ``motor_rates``), torques in [-5, 5] N m."""
    rng = np.random.default_rng(seed)
    n, nl = arm.n_dof, arm.n_links
    q = np.empty((m, n))
    dq = rng.normal(size=(m, n))
    q[:, :nl] = rng.uniform(-np.pi, np.pi, (m, nl))
    for i, (lk, bm) in enumerate(zip(arm.links, arm.modes, strict=True)):
        if lk.n_modes:
            unit = lk.length / np.abs(bm.tip_deflection)
            s = arm.modal_slice(i)
            q[:, s] = rng.normal(size=(m, lk.n_modes)) * deflection * unit
            dq[:, s] *= 0.3 * unit
    if arm.has_flexible_joints:
        q[:, arm.motor_slice] = q[:, :nl] + rng.uniform(-2e-3, 2e-3, (m, nl))
        if motor_rates:
            dq[:, arm.motor_slice] += rng.normal(size=(m, nl))
    tau = rng.uniform(-5.0, 5.0, (m, nl))
    return q, dq, tau


def assert_mass_matrix_and_kernels(
    arm: fa.FlexibleArm, q: np.ndarray, expected: np.ndarray, seed: int
) -> np.ndarray:
    """``arm``'s mass matrix at ``q`` is ``expected`` (a hand-derived oracle) on both
    backends, and the dense and recursive kernels give the NumPy forward dynamics at a
    seeded random rate and torque; returns that rate."""
    from flexarm.model import dynamics
    from flexarm.model.arrays import make_workspace

    for backend in ("compiled", "numpy"):
        np.testing.assert_allclose(arm.mass_matrix(q, backend=backend), expected, rtol=1e-13)
    rng = np.random.default_rng(seed)
    n = arm.n_dof
    dq, tau = rng.normal(size=n), rng.normal(size=arm.n_links)
    ref = arm.forward_dynamics(q, dq, tau, backend="numpy")
    for kernel in (dynamics.forward_dynamics_dense, dynamics.forward_dynamics_recursive):
        out = np.empty(n)
        kernel(q, dq, tau, arm.arrays, make_workspace(n), out)
        np.testing.assert_allclose(out, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    return dq


def two_rigid_rods_mass_matrix(
    m1: float, l1: float, m2: float, l2: float, theta2: float
) -> np.ndarray:
    """The textbook mass matrix of two uniform rods on revolute joints (centres of
    mass at mid-length, I_c = m l**2 / 12), written out by hand."""
    lc1, lc2 = l1 / 2, l2 / 2
    i1, i2 = m1 * l1**2 / 12, m2 * l2**2 / 12
    c2 = math.cos(theta2)
    m11 = m1 * lc1**2 + i1 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * c2) + i2
    m12 = m2 * (lc2**2 + l1 * lc2 * c2) + i2
    m22 = m2 * lc2**2 + i2
    return np.array([[m11, m12], [m12, m22]])
