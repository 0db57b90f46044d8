"""Trajectories: closed-form oracles, finite-difference consistency."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from flexarm import FlexibleArm
from flexarm.control.trajectories import (
    Circle,
    Line,
    PointToPoint,
    Square,
    Trajectory,
    Waypoints,
    sample,
)
from helpers.control import central_difference


@pytest.fixture(scope="module")
def arm():
    return FlexibleArm.paper()


def assert_derivatives(traj, t, atol=1e-6):
    """velocity = d position/dt and acceleration = d velocity/dt at ``t``."""
    _, v, a = traj.evaluate(t)
    v_fd = central_difference(lambda s: traj.evaluate(s)[0], t)
    a_fd = central_difference(lambda s: traj.evaluate(s)[1], t)
    np.testing.assert_allclose(v, v_fd, atol=atol)
    np.testing.assert_allclose(a, a_fd, atol=atol * 10)


def interior_times(breaks, n=7, margin=1e-3):
    """Times strictly inside each interval between consecutive breaks."""
    out = [np.linspace(lo + margin, hi - margin, n) for lo, hi in itertools.pairwise(breaks)]
    return np.concatenate(out)


# ------------------------------------------------------------------ Square
def test_square_default_corners_and_duration():
    sq = Square()
    assert sq.duration == 20.0
    assert sq.corner_times == (5.0, 10.0, 15.0, 20.0)
    np.testing.assert_array_equal(sq.corners, [[3, -2], [7, -2], [7, 2], [3, 2]])
    p, _, _ = sq.evaluate([0.0, 5.0, 10.0, 15.0, 20.0])
    np.testing.assert_array_equal(p, [[3, -2], [7, -2], [7, 2], [3, 2], [3, -2]])
    # corners inside the paper arm's reach, away from 0 and 9 m
    r = np.hypot(*sq.corners.T)
    assert r.min() == pytest.approx(math.hypot(3, 2)) and r.max() == pytest.approx(math.hypot(7, 2))


def test_square_midpoints_and_constant_speed():
    sq = Square(center=(1.0, 2.0), side=2.0, time_per_side=4.0)
    p, v, a = sq.evaluate([2.0, 6.0, 10.0, 14.0])
    np.testing.assert_allclose(p, [[1, 1], [2, 2], [1, 3], [0, 2]], atol=1e-15)
    np.testing.assert_allclose(v, [[0.5, 0], [0, 0.5], [-0.5, 0], [0, -0.5]], atol=1e-15)
    np.testing.assert_array_equal(a, 0.0)


def test_square_path_length_and_speed_per_lap():
    sq = Square(side=3.0, time_per_side=2.0, laps=2)
    t = np.linspace(0.0, sq.duration, 8001)
    p, v, _ = sq.evaluate(t)
    lap = t <= sq.duration / 2
    assert np.sum(np.linalg.norm(np.diff(p[lap], axis=0), axis=1)) == pytest.approx(12.0)
    speed = np.linalg.norm(v[:-1], axis=1)
    np.testing.assert_allclose(speed, 1.5, rtol=1e-14)


def test_square_constant_velocity_jumps_at_corners_right_limit():
    sq = Square()
    _, v, a = sq.evaluate(np.array([5.0 - 1e-9, 5.0]))
    np.testing.assert_allclose(v, [[0.8, 0.0], [0.0, 0.8]])
    np.testing.assert_array_equal(a, 0.0)


def test_square_constant_derivatives_away_from_corners():
    sq = Square()
    assert_derivatives(sq, interior_times([0.0, *sq.corner_times]))


def test_square_quintic_smooth_and_rest_at_corners():
    sq = Square(timing="quintic", side=2.0, time_per_side=3.0, dwell=0.5)
    t_corner = np.array([0.0, *sq.corner_times])
    _, v, a = sq.evaluate(t_corner)
    np.testing.assert_allclose(v, 0.0, atol=1e-15)
    np.testing.assert_allclose(a, 0.0, atol=1e-15)
    arrive = np.array(sq.corner_times)
    knots = np.sort(np.concatenate([[0.0], arrive, arrive + sq.dwell]))
    assert_derivatives(sq, interior_times(knots[:-1], n=31))
    # peak speed of the quintic is 15/8 of the mean
    _, v_mid, _ = sq.evaluate(1.5)
    assert np.linalg.norm(v_mid) == pytest.approx(15 / 8 * 2.0 / 3.0)


def test_square_dwell_rests_after_each_corner():
    sq = Square(time_per_side=2.0, dwell=1.0)
    assert sq.duration == 12.0
    assert sq.corner_times == (2.0, 5.0, 8.0, 11.0)
    p, v, a = sq.evaluate([2.0, 2.5, 3.0 - 1e-12, 3.0, 4.0, 11.5, 12.0])
    np.testing.assert_allclose(p[:3], [[7, -2]] * 3)
    np.testing.assert_array_equal(v[:3], 0.0)
    np.testing.assert_allclose(v[3], [0.0, 2.0])  # leaves after the dwell
    np.testing.assert_allclose(p[4], [7, 0])
    np.testing.assert_allclose(p[5:], [[3, -2]] * 2)
    np.testing.assert_array_equal(v[5:], 0.0)
    np.testing.assert_array_equal(a, 0.0)


def test_square_cw_mirrors_ccw_about_the_start_diagonal():
    ccw, cw = Square(direction="ccw"), Square(direction="cw")
    t = np.linspace(-1.0, 21.0, 97)
    c = np.array(ccw.center)
    p1, v1, _ = ccw.evaluate(t)
    p2, v2, _ = cw.evaluate(t)
    np.testing.assert_allclose((p2 - c)[:, ::-1], p1 - c, atol=1e-14)
    np.testing.assert_allclose(v2[:, ::-1], v1, atol=1e-14)
    np.testing.assert_allclose(cw.evaluate(5.0)[0], [3.0, 2.0])


@pytest.mark.parametrize("corner", [1, 2, 3])
@pytest.mark.parametrize("direction", ["ccw", "cw"])
def test_square_start_corner_shifts_the_sequence(corner, direction):
    base = Square(direction=direction)
    shifted = Square(start_corner=corner, direction=direction)
    offset = 5.0 * (corner if direction == "ccw" else 4 - corner)
    t = np.linspace(0.0, 20.0 - offset - 1e-9, 41)
    for x, y in zip(shifted.evaluate(t), base.evaluate(t + offset), strict=True):
        np.testing.assert_allclose(x, y, atol=1e-12)
    np.testing.assert_allclose(shifted.evaluate(0.0)[0], base.corners[corner])
    np.testing.assert_allclose(shifted.evaluate(20.0)[0], base.corners[corner])


def test_square_laps_repeat():
    one, three = Square(timing="quintic"), Square(timing="quintic", laps=3)
    assert three.duration == 60.0
    assert three.corner_times == tuple(5.0 * k for k in range(1, 13))
    t = np.linspace(0.0, 19.9, 50)
    for k in range(3):
        for x, y in zip(three.evaluate(t + 20.0 * k), one.evaluate(t), strict=True):
            np.testing.assert_allclose(x, y, atol=1e-12)


@pytest.mark.parametrize(
    "traj",
    [
        Square(dwell=0.5),
        Square(timing="quintic", direction="cw", start_corner=2),
        Circle(phase=0.3),
        Line((0.0, 1.0), (2.0, 3.0), 2.0, timing="constant"),
        PointToPoint((0.0, 1.0), (2.0, 3.0), 2.0),
    ],
    ids=["square-dwell", "square-quintic", "circle", "line", "p2p"],
)
def test_hold_before_start_and_after_end(traj):
    p, v, a = traj.evaluate([-5.0, -1e-9, traj.duration, traj.duration + 3.0])
    start = traj.evaluate(0.0)[0]
    end = traj.evaluate(traj.duration - 1e-12)[0]
    np.testing.assert_allclose(p[:2], [start, start])
    np.testing.assert_allclose(p[2:], [end, end], atol=1e-9)
    np.testing.assert_array_equal(v[[0, 1, 2, 3]], 0.0)
    np.testing.assert_array_equal(a[[0, 1, 2, 3]], 0.0)


def test_evaluate_shapes_scalar_and_vector():
    sq = Square()
    for x in sq.evaluate(1.0):
        assert x.shape == (2,)
    for x in sq.evaluate(np.float64(1.0)):
        assert x.shape == (2,)
    for x in sq.evaluate([1.0, 2.0, 3.0]):
        assert x.shape == (3, 2)
    for x in sq.evaluate(np.array([], dtype=float)):
        assert x.shape == (0, 2)


def test_trajectories_are_frozen_hashable_and_store_tuples():
    sq = Square(center=np.array([5, 0]))
    assert sq.center == (5.0, 0.0) and isinstance(sq.center, tuple)
    assert isinstance(sq.side, float)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sq.side = 2.0  # type: ignore[misc]
    w = Waypoints([[0, 0], [1, 1]], np.array([0, 1]))
    assert w.points == ((0.0, 0.0), (1.0, 1.0)) and w.times == (0.0, 1.0)
    assert hash(w) == hash(Waypoints(((0.0, 0.0), (1.0, 1.0)), (0.0, 1.0)))
    for traj in (sq, w, Circle(), Line((0, 0), (1, 0), 1.0), PointToPoint((0, 0), (1, 0), 1.0)):
        assert isinstance(traj, Trajectory)


# ------------------------------------------------------------------ Circle
def test_circle_radius_speed_and_centripetal_acceleration():
    c = Circle(center=(4.0, 1.0), radius=1.5, period=6.0, laps=2, phase=0.4)
    assert c.duration == 12.0 and c.corner_times == ()
    t = np.linspace(0.0, 11.99, 200)
    p, v, a = c.evaluate(t)
    rel = p - np.array(c.center)
    np.testing.assert_allclose(np.linalg.norm(rel, axis=1), 1.5, rtol=1e-14)
    speed = 2 * math.pi * 1.5 / 6.0
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), speed, rtol=1e-14)
    np.testing.assert_allclose(a, -(speed**2 / 1.5) * rel / 1.5, atol=1e-13)
    np.testing.assert_allclose(np.sum(v * rel, axis=1), 0.0, atol=1e-13)
    np.testing.assert_allclose(p[0], [4.0 + 1.5 * math.cos(0.4), 1.0 + 1.5 * math.sin(0.4)])
    assert_derivatives(c, t[1:-1])


def test_circle_direction_and_laps():
    ccw, cw = Circle(period=8.0), Circle(period=8.0, direction="cw")
    np.testing.assert_allclose(ccw.evaluate(2.0)[0], [5.0, 2.0], atol=1e-14)
    np.testing.assert_allclose(cw.evaluate(2.0)[0], [5.0, -2.0], atol=1e-14)
    two = Circle(period=8.0, laps=2)
    t = np.linspace(0.0, 7.9, 20)
    for x, y in zip(two.evaluate(t + 8.0), ccw.evaluate(t), strict=True):
        np.testing.assert_allclose(x, y, atol=1e-12)


# ------------------------------------------------------------------ Line, PointToPoint
def test_line_constant_and_quintic():
    const = Line((1.0, 1.0), (4.0, 5.0), 2.0, timing="constant")
    p, v, a = const.evaluate([0.0, 1.0, 1.5])
    np.testing.assert_allclose(p, [[1, 1], [2.5, 3], [3.25, 4]])
    np.testing.assert_allclose(v, [[1.5, 2]] * 3)
    np.testing.assert_array_equal(a, 0.0)
    quint = Line((1.0, 1.0), (4.0, 5.0), 2.0)
    p, v, a = quint.evaluate([0.0, 1.0, 2.0])
    np.testing.assert_allclose(p, [[1, 1], [2.5, 3], [4, 5]])
    np.testing.assert_allclose(v[[0, 2]], 0.0)
    np.testing.assert_allclose(v[1], 1.875 * np.array([1.5, 2.0]))
    np.testing.assert_allclose(a, 0.0, atol=1e-14)  # zero at both ends and the midpoint
    assert_derivatives(quint, np.linspace(0.01, 1.99, 50))
    assert quint.corner_times == ()


def test_point_to_point_is_a_quintic_line():
    p2p = PointToPoint((0.0, 0.0), (1.0, 2.0), 3.0)
    assert isinstance(p2p, Line) and p2p.timing == "quintic"
    t = np.linspace(-1.0, 4.0, 33)
    for x, y in zip(p2p.evaluate(t), Line((0, 0), (1, 2), 3.0).evaluate(t), strict=True):
        np.testing.assert_array_equal(x, y)
    with pytest.raises(TypeError):
        PointToPoint((0.0, 0.0), (1.0, 2.0), 3.0, timing="constant")  # type: ignore[call-arg]


# ------------------------------------------------------------------ Waypoints
POINTS = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [2.0, 1.0], [0.0, 3.0]])
TIMES = np.array([0.5, 1.5, 2.0, 3.0, 5.0])


@pytest.mark.parametrize("interp", ["linear", "quintic"])
def test_waypoints_pass_through_points(interp):
    w = Waypoints(POINTS, TIMES, interpolation=interp)
    assert w.duration == 5.0 and w.corner_times == (1.5, 2.0, 3.0)
    p, _, _ = w.evaluate(TIMES)
    np.testing.assert_allclose(p, POINTS, atol=1e-15)
    p, v, a = w.evaluate([0.0, 0.2, 6.0])
    np.testing.assert_allclose(p, [POINTS[0], POINTS[0], POINTS[-1]])
    np.testing.assert_array_equal(v, 0.0)
    np.testing.assert_array_equal(a, 0.0)
    assert_derivatives(w, interior_times(TIMES))
    _, v, _ = w.evaluate(2.5)  # repeated point: a rest
    np.testing.assert_array_equal(v, 0.0)


def test_waypoints_linear_velocity_is_piecewise_constant():
    w = Waypoints(POINTS, TIMES)
    _, v, a = w.evaluate([0.7, 1.4, 1.6, 1.9, 4.0])
    np.testing.assert_allclose(v, [[2, 0], [2, 0], [0, 2], [0, 2], [-1, 1]])
    np.testing.assert_array_equal(a, 0.0)


def test_waypoints_quintic_rests_at_every_point():
    w = Waypoints(POINTS, TIMES, interpolation="quintic")
    _, v, a = w.evaluate(TIMES)
    np.testing.assert_allclose(v, 0.0, atol=1e-15)
    np.testing.assert_allclose(a, 0.0, atol=1e-15)


# ------------------------------------------------------------------ sample
def test_sample_columns():
    traj = Square(timing="quintic")
    t = np.linspace(0.0, 20.0, 11)
    table = sample(traj, t)
    assert table.shape == (11, 6)
    p, v, a = traj.evaluate(t)
    np.testing.assert_array_equal(table[:, 0:2], p)
    np.testing.assert_array_equal(table[:, 2:4], v)
    np.testing.assert_array_equal(table[:, 4:6], a)
    assert sample(traj, 2.0).shape == (1, 6)
    with pytest.raises(TypeError, match="'trajectory'"):
        sample(object(), t)  # type: ignore[arg-type]


# ------------------------------------------------------------------ bad input
BAD = [
    (Square, {"side": -1.0}, ValueError, "'side' parameter of Square must be > 0. Got -1.0"),
    (Square, {"side": 0.0}, ValueError, "'side'"),
    (Square, {"side": float("nan")}, ValueError, "'side'"),
    (Square, {"side": "4"}, TypeError, "'side'"),
    (Square, {"time_per_side": 0.0}, ValueError, "'time_per_side'"),
    (Square, {"time_per_side": float("inf")}, ValueError, "'time_per_side'"),
    (Square, {"dwell": -0.1}, ValueError, "'dwell'"),
    (Square, {"start_corner": 4}, ValueError, "'start_corner'"),
    (Square, {"start_corner": -1}, ValueError, "'start_corner'"),
    (Square, {"start_corner": 1.0}, TypeError, "'start_corner'"),
    (Square, {"direction": "clockwise"}, ValueError, "'direction'"),
    (Square, {"laps": 0}, ValueError, "'laps'"),
    (Square, {"laps": 1.5}, TypeError, "'laps'"),
    (Square, {"timing": "cubic"}, ValueError, "'timing'"),
    (Square, {"center": (1.0, 2.0, 3.0)}, ValueError, "'center'"),
    (Square, {"center": (float("nan"), 0.0)}, ValueError, "'center'"),
    (Circle, {"radius": -2.0}, ValueError, "'radius' parameter of Circle must be > 0"),
    (Circle, {"radius": float("nan")}, ValueError, "'radius'"),
    (Circle, {"period": 0.0}, ValueError, "'period'"),
    (Circle, {"laps": 0}, ValueError, "'laps'"),
    (Circle, {"phase": float("nan")}, ValueError, "'phase'"),
    (Circle, {"direction": "up"}, ValueError, "'direction'"),
    (Circle, {"center": 5.0}, ValueError, "'center'"),
]


@pytest.mark.parametrize(("cls", "kwargs", "exc", "match"), BAD)
def test_bad_parameters(cls, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        cls(**kwargs)


LINE_OK = {"start": (0.0, 0.0), "end": (1.0, 0.0), "duration": 1.0}


@pytest.mark.parametrize(
    ("cls", "kwargs", "match"),
    [
        (Line, {"duration": 0.0}, "'duration' parameter of Line must be > 0"),
        (Line, {"duration": -1.0}, "'duration'"),
        (Line, {"duration": float("nan")}, "'duration'"),
        (Line, {"timing": "linear"}, "'timing'"),
        (Line, {"start": (0.0,)}, "'start'"),
        (Line, {"end": (0.0, float("inf"))}, "'end'"),
        (PointToPoint, {"duration": -2.0}, "'duration' parameter of PointToPoint"),
    ],
)
def test_bad_line_parameters(cls, kwargs, match):
    args = {**LINE_OK, **kwargs}
    if cls is PointToPoint:
        args.pop("timing", None)
    with pytest.raises(ValueError, match=match):
        cls(**args)


@pytest.mark.parametrize(
    ("points", "times", "kwargs", "match"),
    [
        ([[0, 0], [1, 1]], [0.0, 0.0], {}, "'times'.*strictly increasing"),
        ([[0, 0], [1, 1]], [1.0, 0.5], {}, "'times'.*strictly increasing"),
        ([[0, 0], [1, 1]], [-1.0, 1.0], {}, "'times'.*>= 0"),
        ([[0, 0], [1, 1]], [0.0, 1.0, 2.0], {}, "'times'.*shape"),
        ([[0, 0], [1, 1]], [0.0, float("nan")], {}, "'times'"),
        ([[0, 0], [1, 1]], [[0.0, 1.0]], {}, "'times'.*shape"),
        ([[0, 0, 0], [1, 1, 1]], [0.0, 1.0], {}, "'points'.*shape"),
        ([0, 1], [0.0, 1.0], {}, "'points'.*shape"),
        ([[0, 0]], [0.0], {}, "'points'.*>= 2"),
        ([[0, float("nan")], [1, 1]], [0.0, 1.0], {}, "'points'"),
        ([[0, 0], [1, 1]], [0.0, 1.0], {"interpolation": "cubic"}, "'interpolation'"),
    ],
)
def test_bad_waypoints(points, times, kwargs, match):
    with pytest.raises(ValueError, match=match):
        Waypoints(points, times, **kwargs)


@pytest.mark.parametrize(
    ("t", "exc"),
    [(float("nan"), ValueError), ([[0.0, 1.0]], ValueError), ("1.0", TypeError), (1j, TypeError)],
)
def test_bad_times(t, exc):
    for traj in (Square(), Circle(), Line((0, 0), (1, 1), 1.0), Waypoints(POINTS, TIMES)):
        with pytest.raises(exc, match="'t' parameter"):
            traj.evaluate(t)
