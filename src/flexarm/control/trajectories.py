"""Planar end-effector reference paths.

Every trajectory is a frozen, validated dataclass that maps time ``t`` (s) to
the position (m), velocity (m/s) and acceleration (m/s**2) of the end
effector in the base frame, through one interface (:class:`Trajectory`):

``duration``
    Total time in s, dwells included. For ``t > duration`` the trajectory holds
    its final point with zero velocity and acceleration; for ``t`` before its
    start (``t < 0``, or ``t < times[0]`` for :class:`Waypoints`) it holds its
    first point, likewise at rest.
``evaluate(t)``
    ``(position, velocity, acceleration)``, each of shape ``(m, 2)`` for ``t``
    of shape ``(m,)`` or ``(2,)`` for a scalar ``t``. Vectorised over ``t``.
    Where the velocity jumps (``timing="constant"`` at a corner, the start and
    the end), the value returned is the right-hand limit: the velocity of the
    segment that starts at ``t``, zero at ``t = duration``; the acceleration
    is reported as 0 there.
``corner_times``
    The times in s of the path's corners or segment boundaries, which metrics
    use for "the error after each corner".

The square is the paper's experiment (Sasiadek et al., 2014, Sec. V) but its
size, placement and speed are not given; :class:`Square`'s defaults are
flexarm's choice, documented there. :func:`sample` turns a path into a
six-column table; :func:`flexarm.sim.references.joint_reference` into joint
angles, rates and accelerations of a rigid two-link arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_int, check_option, check_real, validate_real_fields
from ..errors import InvalidTypeError, InvalidValueError
from ._piecewise import COMPILED_FROM, piecewise_numpy

__all__ = [
    "Circle",
    "Line",
    "PointToPoint",
    "Square",
    "Trajectory",
    "Waypoints",
    "check_trajectory",
    "evaluation_times",
    "sample",
    "straight_segments",
]

DIRECTIONS = ("ccw", "cw")
TIMINGS = ("constant", "quintic")
INTERPOLATIONS = ("linear", "quintic")
ELBOWS = ("positive", "negative")

_F = NDArray[np.float64]
_Triple = tuple[_F, _F, _F]


@runtime_checkable
class Trajectory(Protocol):
    """What the simulator, the metrics and the reference pipeline need of a path."""

    @property
    def duration(self) -> float:
        """Total time, s."""

    @property
    def corner_times(self) -> tuple[float, ...]:
        """Times of the corners or segment boundaries, s."""

    def evaluate(self, t: ArrayLike) -> _Triple:
        """Position (m), velocity (m/s) and acceleration (m/s**2) at ``t`` (s)."""


def _point(value: Any, name: str, owner: str) -> tuple[float, float]:
    arr = check_array(value, name, owner, shape=(2,))
    if arr.dtype.kind == "c":
        raise InvalidTypeError(
            f"The '{name}' parameter of {owner} must be real. Got a complex array instead."
        )
    return (float(arr[0]), float(arr[1]))


def evaluation_times(t: ArrayLike, owner: str) -> tuple[_F, bool]:
    """``t`` as a float array of shape ``(m,)`` and whether it was a scalar."""
    arr = check_array(t, "t", owner)
    if arr.dtype.kind == "c":
        raise InvalidTypeError(
            f"The 't' parameter of {owner} must be real. Got a complex array instead."
        )
    if arr.ndim > 1:
        raise InvalidValueError(
            f"The 't' parameter of {owner} must be a scalar or of shape (m,). "
            f"Got shape {arr.shape} instead."
        )
    return np.atleast_1d(arr).astype(np.float64), arr.ndim == 0


def _shape_out(triple: _Triple, scalar: bool) -> _Triple:
    if scalar:
        return triple[0][0], triple[1][0], triple[2][0]
    return triple


def _piecewise(t: _F, knot_t: _F, knot_p: _F, quintic: bool) -> _Triple:
    """Straight segments between consecutive knots, each with its own time scaling.

    ``knot_t`` (k,) strictly increasing, s; ``knot_p`` (k, 2), m. A repeated
    point is a dwell. Outside ``[knot_t[0], knot_t[-1])`` the path is at rest.
    Long time grids go to the compiled twin
    (:func:`flexarm.control._path_kernels.piecewise_path`), short ones stay in
    NumPy (no compilation or cache loading for a few points).
    """
    if t.shape[0] >= COMPILED_FROM:
        from ._path_kernels import piecewise_path

        out = np.empty((3, t.shape[0], 2))
        piecewise_path(
            np.ascontiguousarray(t),
            np.ascontiguousarray(knot_t, dtype=np.float64),
            np.ascontiguousarray(knot_p, dtype=np.float64),
            quintic,
            out[0],
            out[1],
            out[2],
        )
        return out[0], out[1], out[2]
    return piecewise_numpy(t, knot_t, knot_p, quintic)


# ------------------------------------------------------------------ paths
class _Path:
    """What every path shares: :meth:`evaluate` checks the times and gives scalars for
    a scalar ``t``; :meth:`_evaluate` computes the path at times of shape (m,)."""

    def _evaluate(self, t: _F) -> _Triple:
        """Position (m), velocity (m/s) and acceleration (m/s**2), each of shape
        (m, 2), at the times ``t`` of shape (m,), s."""
        raise NotImplementedError

    def evaluate(self, t: ArrayLike) -> _Triple:
        """Position, velocity and acceleration at ``t``.

        Parameters
        ----------
        t : float or array_like, shape (m,)
            Time, s.

        Returns
        -------
        position, velocity, acceleration : ndarray, shape (m, 2) or (2,)
            In m, m/s and m/s**2.
        """
        tt, scalar = evaluation_times(t, f"{type(self).__name__}.evaluate")
        return _shape_out(self._evaluate(tt), scalar)


class _StraightSegments(_Path):
    """What the paths made of straight segments share: the path from their knots
    (:meth:`_segments`, also what :func:`straight_segments` gives the loop)."""

    def _segments(self) -> tuple[_F, _F, bool]:
        """Knot times (k,) in s, knot points (k, 2) in m, and whether each segment
        has quintic timing."""
        raise NotImplementedError

    def _evaluate(self, t: _F) -> _Triple:
        knot_t, knot_p, quintic = self._segments()
        return _piecewise(t, knot_t, knot_p, quintic)


@dataclass(frozen=True)
class Square(_StraightSegments):
    """A square traced side by side, the paper's tracking experiment.

    Corners are numbered 0..3 counter-clockwise from the lower-left one,
    ``(x_c - side/2, y_c - side/2)``. The path starts at ``start_corner``,
    runs one side in ``time_per_side``, rests ``dwell`` at the corner it
    reaches, and so on: side, dwell, side, dwell, ... for ``4 * laps`` sides,
    ending (after a last dwell) back at the start corner.

    Parameters
    ----------
    center : array_like, shape (2,)
        ``(x_c, y_c)`` in m.
    side : float
        Side length in m (> 0).
    time_per_side : float
        Travel time along one side in s (> 0), dwell excluded.
    dwell : float
        Rest at every corner after arriving, s (>= 0).
    start_corner : int
        Corner where motion starts, 0..3.
    direction : {"ccw", "cw"}
        Sense of travel.
    laps : int
        Number of times round (>= 1).
    timing : {"constant", "quintic"}
        ``"constant"``: constant speed ``side / time_per_side`` along each side,
        so the velocity jumps at the corners (this is what excites the flexible
        modes) and the acceleration is 0 within the sides and reported as 0 at
        the jumps. ``"quintic"``: rest-to-rest time scaling
        ``s(tau) = 10 tau**3 - 15 tau**4 + 6 tau**5`` on each side (smooth).

    Notes
    -----
    The paper gives no size, placement or speed for its square. The defaults
    are flexarm's choice: centre (5, 0) m, side 4 m, 5 s per side (0.8 m/s),
    counter-clockwise from the lower-left corner, constant speed, no dwell,
    20 s in all. The square then lies inside the workspace of the paper's arm
    (two 4.5 m links, reach 0 to 9 m) with its corners 3.6 m and 7.3 m from
    the base, away from the singular full reach, and the velocity jumps at
    its corners excite the flexible modes. (A related paper by the same group
    used a 12.6 m square whose corners sit near the 9 m reach.)

    ``corner_times`` holds the ``4 * laps`` arrival times at a corner,
    ``k * time_per_side + (k - 1) * dwell`` for ``k = 1 .. 4 * laps``. The last
    one is the closing corner; the departures after a dwell are at
    ``corner_times[k] + dwell``.

    Examples
    --------
    >>> sq = Square()
    >>> sq.duration
    20.0
    >>> p, v, a = sq.evaluate(2.5)
    >>> p.tolist(), v.tolist()
    ([5.0, -2.0], [0.8, 0.0])
    """

    center: tuple[float, float] = (5.0, 0.0)
    side: float = 4.0
    time_per_side: float = 5.0
    dwell: float = 0.0
    start_corner: int = 0
    direction: str = "ccw"
    laps: int = 1
    timing: str = "constant"

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, "center", _point(self.center, "center", owner))
        validate_real_fields(
            self, owner, positive=("side", "time_per_side"), nonnegative=("dwell",)
        )
        corner = check_int(self.start_corner, "start_corner", owner, minimum=0)
        if corner > 3:
            raise InvalidValueError(
                f"The 'start_corner' parameter of {owner} must be one of (0, 1, 2, 3). "
                f"Got {corner!r} instead."
            )
        object.__setattr__(self, "start_corner", corner)
        check_option(self.direction, "direction", owner, DIRECTIONS)
        object.__setattr__(self, "laps", check_int(self.laps, "laps", owner, minimum=1))
        check_option(self.timing, "timing", owner, TIMINGS)

    @property
    def corners(self) -> _F:
        """The four corners, numbered counter-clockwise from the lower left, shape (4, 2), m."""
        h = 0.5 * self.side
        offsets = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
        corners: _F = np.asarray(self.center) + offsets
        return corners

    @property
    def duration(self) -> float:
        """Total time ``4 * laps * (time_per_side + dwell)``, s."""
        return 4 * self.laps * (self.time_per_side + self.dwell)

    @property
    def corner_times(self) -> tuple[float, ...]:
        """Arrival times at the corners (see Notes), s."""
        k = np.arange(1, 4 * self.laps + 1)
        return tuple(float(x) for x in k * self.time_per_side + (k - 1) * self.dwell)

    def _knots(self) -> tuple[_F, _F]:
        n = 4 * self.laps
        step = 1 if self.direction == "ccw" else -1
        order = (self.start_corner + step * np.arange(n + 1)) % 4
        points = self.corners[order]
        k = np.arange(n + 1)
        arrive = k * self.time_per_side + np.maximum(k - 1, 0) * self.dwell
        if self.dwell == 0.0:
            return arrive.astype(np.float64), points
        leave = k * (self.time_per_side + self.dwell)
        # knots: start, then for each side its arrival and the end of its dwell
        times = np.concatenate([[0.0], np.column_stack([arrive[1:], leave[1:]]).ravel()])
        pts = np.concatenate([points[:1], np.repeat(points[1:], 2, axis=0)])
        return times, pts

    def _segments(self) -> tuple[_F, _F, bool]:
        knot_t, knot_p = self._knots()
        return knot_t, knot_p, self.timing == "quintic"


@dataclass(frozen=True)
class Circle(_Path):
    """A circle traced at constant angular speed.

    Parameters
    ----------
    center : array_like, shape (2,)
        Centre in m.
    radius : float
        Radius in m (> 0).
    period : float
        Time for one lap in s (> 0).
    laps : int
        Number of laps (>= 1).
    phase : float
        Polar angle of the start point about the centre, rad.
    direction : {"ccw", "cw"}
        Sense of travel.

    Notes
    -----
    Speed ``2 pi radius / period``; acceleration ``speed**2 / radius`` towards the
    centre while moving. The velocity jumps from 0 at the start and back to 0
    at the end. ``corner_times`` is empty.

    Examples
    --------
    >>> c = Circle(radius=2.0, period=8.0)
    >>> p, v, a = c.evaluate(2.0)
    >>> p.round(12).tolist()
    [5.0, 2.0]
    """

    center: tuple[float, float] = (5.0, 0.0)
    radius: float = 2.0
    period: float = 10.0
    laps: int = 1
    phase: float = 0.0
    direction: str = "ccw"

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, "center", _point(self.center, "center", owner))
        validate_real_fields(self, owner, positive=("radius", "period"))
        object.__setattr__(self, "laps", check_int(self.laps, "laps", owner, minimum=1))
        object.__setattr__(self, "phase", check_real(self.phase, "phase", owner))
        check_option(self.direction, "direction", owner, DIRECTIONS)

    @property
    def duration(self) -> float:
        """Total time ``laps * period``, s."""
        return self.laps * self.period

    @property
    def corner_times(self) -> tuple[float, ...]:
        """Empty: a circle has no corners."""
        return ()

    def _evaluate(self, tt: _F) -> _Triple:
        omega = (2.0 * math.pi / self.period) * (1.0 if self.direction == "ccw" else -1.0)
        moving = ((tt >= 0.0) & (tt < self.duration))[:, None]
        angle = self.phase + omega * np.clip(tt, 0.0, self.duration)
        radial = np.column_stack([np.cos(angle), np.sin(angle)])
        tangent = np.column_stack([-np.sin(angle), np.cos(angle)])
        pos = np.asarray(self.center) + self.radius * radial
        vel = np.where(moving, self.radius * omega * tangent, 0.0)
        acc = np.where(moving, -self.radius * omega**2 * radial, 0.0)
        return pos, vel, acc


@dataclass(frozen=True)
class Line(_StraightSegments):
    """A straight line from ``start`` to ``end`` in ``duration``.

    Parameters
    ----------
    start, end : array_like, shape (2,)
        End points in m.
    duration : float
        Travel time in s (> 0).
    timing : {"quintic", "constant"}
        ``"quintic"``: rest-to-rest ``s(tau) = 10 tau**3 - 15 tau**4 + 6 tau**5``;
        ``"constant"``: constant speed, velocity jumps at both ends.

    Notes
    -----
    ``corner_times`` is empty. ``start == end`` is allowed (a rest of
    ``duration``).

    Examples
    --------
    >>> p, v, a = Line((0.0, 0.0), (2.0, 0.0), 4.0).evaluate([0.0, 2.0, 4.0])
    >>> p[:, 0].tolist(), v[:, 0].tolist()
    ([0.0, 1.0, 2.0], [0.0, 0.9375, 0.0])
    """

    start: tuple[float, float]
    end: tuple[float, float]
    duration: float
    timing: str = "quintic"

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, "start", _point(self.start, "start", owner))
        object.__setattr__(self, "end", _point(self.end, "end", owner))
        validate_real_fields(self, owner, positive=("duration",))
        check_option(self.timing, "timing", owner, TIMINGS)

    @property
    def corner_times(self) -> tuple[float, ...]:
        """Empty: a line has no corners."""
        return ()

    def _segments(self) -> tuple[_F, _F, bool]:
        return (
            np.array([0.0, self.duration]),
            np.array([self.start, self.end]),
            self.timing == "quintic",
        )


@dataclass(frozen=True)
class PointToPoint(Line):
    """A rest-to-rest move: :class:`Line` with ``timing="quintic"`` fixed.

    It takes the parameters of :class:`Line` but ``timing``: ``start``, ``end`` (m)
    and ``duration`` (s).

    Examples
    --------
    >>> PointToPoint((0.0, 0.0), (1.0, 1.0), 2.0).timing
    'quintic'
    """

    timing: str = field(default="quintic", init=False, repr=False)


@dataclass(frozen=True)
class Waypoints(_StraightSegments):
    """A path through ``points`` reached at ``times``.

    Parameters
    ----------
    points : array_like, shape (k, 2)
        Waypoints in m, ``k >= 2``; a repeated point is a rest.
    times : array_like, shape (k,)
        Strictly increasing times in s at which the points are reached,
        ``times[0] >= 0``. Before ``times[0]`` the path rests at ``points[0]``.
    interpolation : {"linear", "quintic"}
        ``"linear"``: straight segments at constant velocity (piecewise linear
        position); ``"quintic"``: straight segments, each rest-to-rest quintic.

    Notes
    -----
    ``duration`` is ``times[-1]`` (the end, measured from ``t = 0``);
    ``corner_times`` holds the interior times ``times[1:-1]``.

    Examples
    --------
    >>> w = Waypoints([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], [1.0, 2.0, 4.0])
    >>> w.duration, w.corner_times
    (4.0, (2.0,))
    >>> w.evaluate(3.0)[0].tolist()
    [1.0, 0.5]
    """

    points: tuple[tuple[float, float], ...]
    times: tuple[float, ...]
    interpolation: str = "linear"

    def __post_init__(self) -> None:
        owner = type(self).__name__
        pts = check_array(self.points, "points", owner, shape=(-1, 2))
        tms = check_array(self.times, "times", owner, shape=(-1,))
        for name, arr in (("points", pts), ("times", tms)):
            if arr.dtype.kind == "c":
                raise InvalidTypeError(
                    f"The '{name}' parameter of {owner} must be real. Got a complex array instead."
                )
        if pts.shape[0] < 2:
            raise InvalidValueError(
                f"The 'points' parameter of {owner} must hold >= 2 points. "
                f"Got {pts.shape[0]} instead."
            )
        if tms.shape[0] != pts.shape[0]:
            raise InvalidValueError(
                f"The 'times' parameter of {owner} must be of shape ({pts.shape[0]},), "
                f"one per point. Got shape {tms.shape} instead."
            )
        if tms[0] < 0.0:
            raise InvalidValueError(
                f"The 'times' parameter of {owner} must start at >= 0. Got {tms[0]!r} instead."
            )
        if np.any(np.diff(tms) <= 0.0):
            raise InvalidValueError(
                f"The 'times' parameter of {owner} must be strictly increasing. "
                f"Got {tms.tolist()!r} instead."
            )
        check_option(self.interpolation, "interpolation", owner, INTERPOLATIONS)
        object.__setattr__(self, "points", tuple((float(x), float(y)) for x, y in pts))
        object.__setattr__(self, "times", tuple(float(x) for x in tms))

    @property
    def duration(self) -> float:
        """End time ``times[-1]``, s."""
        return self.times[-1]

    @property
    def corner_times(self) -> tuple[float, ...]:
        """The interior waypoint times ``times[1:-1]``, s."""
        return self.times[1:-1]

    def _segments(self) -> tuple[_F, _F, bool]:
        return np.array(self.times), np.array(self.points), self.interpolation == "quintic"


# ------------------------------------------------------------------ consumers
def check_trajectory(trajectory: object, owner: str) -> None:
    """Raise InvalidTypeError naming ``owner`` unless ``trajectory`` is a :class:`Trajectory`."""
    if not isinstance(trajectory, Trajectory):
        raise InvalidTypeError(
            f"The 'trajectory' parameter of {owner} must be a trajectory (with duration, "
            f"corner_times and evaluate). Got {type(trajectory).__name__} instead."
        )


def sample(trajectory: Trajectory, t: ArrayLike) -> _F:
    """The reference table: position, velocity and acceleration side by side.

    Parameters
    ----------
    trajectory : Trajectory
        Any path of this module.
    t : float or array_like, shape (m,)
        Times, s.

    Returns
    -------
    ndarray, shape (m, 6)
        Columns ``x, y`` (m), ``vx, vy`` (m/s), ``ax, ay`` (m/s**2); a scalar
        ``t`` gives one row.

    Examples
    --------
    >>> sample(Square(), [0.0, 5.0]).tolist()
    [[3.0, -2.0, 0.8, 0.0, 0.0, 0.0], [7.0, -2.0, 0.0, 0.8, 0.0, 0.0]]
    """
    check_trajectory(trajectory, "sample")
    pos, vel, acc = trajectory.evaluate(np.atleast_1d(np.asarray(t, dtype=float)))
    return np.column_stack([pos, vel, acc])


def straight_segments(trajectory: object) -> tuple[_F, _F, bool] | None:
    """A path of this module made of straight segments as knots: times (k,) in s,
    points (k, 2) in m, and whether each segment has quintic timing; None for any
    other path (a circle, a subclass, a user's own).

    What the simulation loop needs to compute the path instant by instant itself
    (a compiled twin of the formulas of ``evaluate``).
    """
    if type(trajectory) in (Square, Line, PointToPoint, Waypoints):
        segments: tuple[_F, _F, bool] = trajectory._segments()  # type: ignore[attr-defined]
        return segments
    return None
