"""Prescribed motion from measured angles: a smoothing spline gives the angle, rate and
acceleration, and a run driven by samples matches the run driven by the exact motion."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.errors import InvalidValueError
from flexarm.sim.prescribed import motion_from_samples


def test_the_spline_recovers_a_smooth_motion_and_its_derivatives():
    t = np.linspace(0.0, 2.0, 1001)
    theta = np.column_stack([np.sin(3 * t), 0.5 * t**3])
    motion = motion_from_samples(t, theta, smoothing=1e-12)
    inner = t[50:-50]
    th, rate, acc = motion(inner)
    np.testing.assert_allclose(th, theta[50:-50], atol=1e-9)
    np.testing.assert_allclose(rate[:, 0], 3 * np.cos(3 * inner), atol=1e-6)
    np.testing.assert_allclose(rate[:, 1], 1.5 * inner**2, atol=1e-6)
    np.testing.assert_allclose(acc[:, 0], -9 * np.sin(3 * inner), atol=1e-3)
    np.testing.assert_allclose(acc[:, 1], 3 * inner, atol=1e-3)


def test_a_run_driven_by_samples_is_the_run_driven_by_the_motion():
    """A rigid rod: the torque is J theta'' with J = rho L^3 / 3 (the closed form), and
    a flexible arm's response to the sampled motion matches the exact motion's."""
    t = np.linspace(0.0, 1.0, 501)
    rod = fa.FlexibleArm([fa.Link(1.0, 10.0, 1.0, n_modes=0)])
    res = fa.simulate_prescribed(rod, t, np.sin(2 * t))
    # the spline chosen by cross-validation, away from the ends (0.2 s), where its
    # natural end conditions (no curvature) bend the accelerations of a motion that
    # does not start and end at rest
    inner = slice(100, -100)
    np.testing.assert_allclose(res.tau[inner, 0], -4 * np.sin(2 * t[inner]) / 3, atol=1e-5)
    arm = fa.FlexibleArm([fa.Link(1.0, 20.0, 1.0, n_modes=2)])
    exact = fa.simulate_prescribed(
        arm, t, lambda s: (np.sin(2 * s), 2 * np.cos(2 * s), -4 * np.sin(2 * s)), substeps=2
    )
    sampled = fa.simulate_prescribed(arm, t, np.sin(2 * t), substeps=2)
    scale = np.max(np.abs(exact.q[:, 1:]))
    assert np.max(np.abs(sampled.q[:, 1:] - exact.q[:, 1:])) < 0.02 * scale


@pytest.mark.parametrize(
    ("t", "angles", "match"),
    [
        (np.linspace(0, 1, 4), np.zeros(4), "'t'"),
        (np.array([0.0, 0.2, 0.1, 0.3, 0.4]), np.zeros(5), "'t'"),
        (np.linspace(0, 1, 10), np.zeros(9), "'angles'"),
        (np.linspace(0, 1, 10), np.zeros((10, 2, 1)), "'angles'"),
    ],
)
def test_bad_samples_are_refused_by_name(t, angles, match):
    with pytest.raises(InvalidValueError, match=match):
        motion_from_samples(t, angles)
