"""The reference pipeline block by block, and its compiled kernels.

The compiled path and joint-path kernels are held against their NumPy
references (the trajectories' own evaluation, :func:`joint_path`); the block
pipeline against itself asked for other rows (a block's numbers may not depend
on which rows were asked for) and against ``numpy.gradient`` for a sensed
point's acceleration.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flexarm import FlexibleArm
from flexarm.control._piecewise import COMPILED_FROM
from flexarm.control.shapers import zv
from flexarm.control.signals import r_acceleration, r_position, r_velocity
from flexarm.control.trajectories import Circle, Line, Square, Waypoints
from flexarm.errors import InvalidValueError
from flexarm.sim._reference_kernels import OK, SINGULAR, UNREACHABLE, joint_path_rows
from flexarm.sim.references import BLOCK, ReferencePipeline, joint_path


@pytest.fixture(scope="module")
def arm():
    return FlexibleArm.paper()


# ------------------------------------------------------------------ compiled paths
PIECEWISE = [
    Square(),
    Square(timing="quintic", dwell=0.7, laps=2, direction="cw", start_corner=2),
    Line((6.0, -1.0), (3.0, 2.0), 2.5, timing="constant"),
    Waypoints([[6.0, -1.0], [3.0, 2.0], [5.0, 4.0]], [0.5, 2.0, 5.0], interpolation="quintic"),
]


@pytest.mark.parametrize("path", PIECEWISE, ids=["square", "square-q", "line", "waypoints"])
def test_compiled_piecewise_path_matches_numpy(path):
    """A long grid (the compiled kernel) against the same times in short pieces (the
    NumPy evaluation), over and beyond the path's span and on its knots."""
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(-1.0, path.duration + 1.0, 20_000))
    t[:3] = [0.0, path.duration, path.duration / 2]
    assert t.shape[0] >= COMPILED_FROM > 1000
    compiled = path.evaluate(t)
    pieces = [path.evaluate(t[i : i + 1000]) for i in range(0, t.shape[0], 1000)]
    for j, got in enumerate(compiled):
        np.testing.assert_allclose(got, np.concatenate([p[j] for p in pieces]), rtol=0, atol=1e-13)


@pytest.mark.parametrize("elbow", ["positive", "negative"])
@pytest.mark.parametrize(
    "path",
    [Square(timing="quintic"), Circle(center=(4.0, 3.0), radius=2.5, period=7.0, phase=1.0)],
    ids=["square", "circle"],
)
def test_compiled_joint_path_matches_numpy(arm, path, elbow):
    t = np.linspace(0.0, path.duration, 5001)
    p, v, a = path.evaluate(t)
    theta, dtheta, ddtheta = (np.empty_like(p) for _ in range(3))
    sign = 1.0 if elbow == "positive" else -1.0
    code, _, _ = joint_path_rows(4.5, 4.5, sign, 1e-6, p, v, a, theta, dtheta, ddtheta)
    assert code == OK
    want = joint_path(arm, p, v, a, elbow=elbow)
    for got, ref in zip((theta, dtheta, ddtheta), want, strict=True):
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


def test_compiled_joint_path_reports_the_first_bad_row():
    rows = np.array([[5.0, 0.0], [9.5, 0.0], [10.0, 0.0]])
    zeros = np.zeros_like(rows)
    out = [np.empty_like(rows) for _ in range(3)]
    assert joint_path_rows(4.5, 4.5, 1.0, 1e-6, rows, zeros, zeros, *out)[:2] == (UNREACHABLE, 1)
    folded = np.array([[5.0, 0.0], [9.0, 0.0]])  # full reach: sin(theta_2) = 0
    code, row, near = joint_path_rows(4.5, 4.5, 1.0, 1e-6, folded, folded * 0, folded * 0, *out)
    assert (code, row) == (SINGULAR, 1) and near < 1e-6


# ------------------------------------------------------------------ blocks
def _pipeline(arm, **kw):
    n_steps = kw.pop("n_steps", 2 * BLOCK + 123)
    return ReferencePipeline(arm, kw.pop("trajectory", Square()), 2e-4, n_steps, **kw)


VARIANTS = {
    "plain": {},
    "point": {"point": (1, 2.0)},
    "smoothed point": {"point": (1, 2.0), "smoothing": 0.05},
    "shaped, delayed": {"shaper": zv(2.0, 0.01), "delay": 0.013},
}


@settings(max_examples=25, deadline=None)
@given(
    variant=st.sampled_from(sorted(VARIANTS)),
    k0=st.integers(0, 2 * BLOCK + 123),
    length=st.integers(1, BLOCK + 500),
)
def test_rows_do_not_depend_on_what_was_asked(arm, variant, k0, length):
    """Any range of rows, bit for bit the same rows of the whole run."""
    whole, _ = _pipeline(arm, **VARIANTS[variant]).rows(0, 2 * BLOCK + 124)
    k1 = min(k0 + length, 2 * BLOCK + 124)
    part, _ = _pipeline(arm, **VARIANTS[variant]).rows(k0, k1)
    np.testing.assert_array_equal(part, whole[k0:k1])


def test_point_acceleration_is_numpy_gradient_of_its_velocity(arm):
    """Across block boundaries the sensed point's acceleration is the central
    difference of its velocity, one-sided at the run's two ends."""
    r, _ = _pipeline(arm, point=(1, 2.0)).rows(0, 2 * BLOCK + 124)
    rv, ra = r_velocity(2), r_acceleration(2)
    np.testing.assert_array_equal(r[:, ra : ra + 2], np.gradient(r[:, rv : rv + 2], 2e-4, axis=0))


def test_the_plain_pipeline_is_the_path(arm):
    r, desired = _pipeline(arm).rows(0, 2 * BLOCK + 124)
    t = np.arange(2 * BLOCK + 124) * 2e-4
    p, v, a = Square().evaluate(t)
    rp, rv, ra = r_position(2), r_velocity(2), r_acceleration(2)
    np.testing.assert_array_equal(r[:, rp : rp + 2], p)
    np.testing.assert_array_equal(r[:, rv : rv + 2], v)
    np.testing.assert_array_equal(r[:, ra : ra + 2], a)
    np.testing.assert_array_equal(desired, p)


def test_a_path_out_of_reach_names_the_time_and_point(arm):
    far = Line((5.00005, 0.0), (12.00005, 0.0), 7.0, timing="constant")  # 9 m at 4 s
    with pytest.raises(InvalidValueError, match=r"workspace.*reachable.*at t = 4 s"):
        ReferencePipeline(arm, far, 1e-3, 7000).rows(0, 7001)


# ------------------------------------------------------------------ other link counts
@pytest.mark.parametrize(
    "lengths, where",
    [((1.0,), r"1-link arm, at a distance of 1\.0 m"), ((1.0, 1.0, 1.0), r"\[0\.0, 3\.0\] m")],
)
def test_arms_of_other_link_counts_refuse_a_path_out_of_reach(lengths, where):
    """A one-link arm reaches a circle; three links an annulus: the default square
    (3.6 m to 7.3 m from the base) is out of reach of both, named with the time."""
    from flexarm import Link, simulate

    arm = FlexibleArm([Link(length, 1676.0, 0.335) for length in lengths])
    with pytest.raises(InvalidValueError, match=rf"'trajectory'.*{where}.*at t = 0 s"):
        simulate(arm, duration=0.5)


def test_a_one_link_arm_on_its_circle_runs():
    from flexarm import Link, simulate

    arm = FlexibleArm([Link(1.0, 1676.0, 0.335, n_modes=1, hub_inertia=1.0)])  # a motor's hub
    circle = Circle(center=(0.0, 0.0), radius=1.0, period=4.0)
    result = simulate(arm, trajectory=circle, duration=0.05)
    assert result.info["status"] == "ok"
