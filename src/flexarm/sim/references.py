"""The reference pipeline: trajectory -> shaped -> delayed -> joint references.

:func:`reference_signals` builds, at every control instant, the reference vector
``r`` a controller reads (layout in :mod:`flexarm.control.signals`):

1. the trajectory gives the desired end-effector path;
   optionally smoothed by a zero-phase Gaussian filter (``smoothing``, s): the
   reference is known in advance, so a corner can be cut symmetrically and
   with finite acceleration instead of overshot (preview);
2. an input shaper (:mod:`flexarm.control.shapers`) reshapes it;
3. with a reference delay, it is delayed by the sensor's transport delay (the
   paper's correction of the non-minimum-phase response, "time delays for
   command signals input to the control law");
4. inverse kinematics (two-link arms) turns it into joint angles and rates
   (:func:`joint_path`);
5. for a sensed point short of the end effector, the operational-space command
   is that point's position and velocity on the rigid arm following the joint
   references (paper.md §4: ``e = x_c - x`` with ``x`` the sensed point).

Tracking errors are measured against the desired path of step 1 (unshaped,
undelayed), which the pipeline returns beside ``r``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_option, check_real
from ..control.signals import (
    r_acceleration,
    r_angle_accelerations,
    r_angles,
    r_feedforward,
    r_position,
    r_rates,
    r_velocity,
    reference_size,
)
from ..control.trajectories import (
    ELBOWS,
    Trajectory,
    check_trajectory,
    evaluation_times,
    straight_segments,
)
from ..errors import InvalidValueError
from ..model.kinematics import lever_lengths, rigid_point

if TYPE_CHECKING:
    from ._reference_kernels import ReferenceStream

__all__ = [
    "BLOCK",
    "ReferencePipeline",
    "ReferenceSignals",
    "joint_path",
    "joint_reference",
    "reference_signals",
    "smoothed_path",
]

F64 = NDArray[np.float64]
PathFunction = Callable[[F64], tuple[F64, F64, F64]]
Feedforward = Callable[[F64, F64, F64], F64]
"""``feedforward(theta, dtheta, ddtheta) -> tau``, arrays of shape (K, n_links)."""


class KinematicArm(Protocol):
    """What the pipeline reads of an arm: its links' lengths and inverse kinematics."""

    @property
    def n_links(self) -> int: ...
    @property
    def link_lengths(self) -> F64: ...

    def inverse_kinematics(self, position: ArrayLike, elbow: str = ...) -> F64: ...


class PathShaper(Protocol):
    """What the pipeline needs of an input shaper (:class:`flexarm.control.shapers.Shaper`)."""

    def apply_function(self, fn: PathFunction) -> PathFunction: ...


class ReferenceSignals(NamedTuple):
    """What :func:`reference_signals` returns.

    reference : ndarray, shape (K, 6 + 2 n_links)
        ``r`` at each control instant (:mod:`flexarm.control.signals`).
    desired : ndarray, shape (K, 2)
        The desired end-effector path, m (unshaped, undelayed).
    initial_angles : ndarray, shape (n_links,) or None
        Joint angles that put the rigid arm on the desired path's first point
        (two-link arms), rad.
    """

    reference: F64
    desired: F64
    initial_angles: F64 | None


def joint_path(
    arm: KinematicArm,
    position: F64,
    velocity: F64,
    acceleration: F64 | None = None,
    *,
    elbow: str = "positive",
    singularity_tol: float = 1e-3,
    times: F64 | None = None,
    owner: str = "joint_path",
) -> tuple[F64, F64, F64 | None]:
    """Joint angles, rates (and accelerations) of a rigid two-link arm on a path.

    ``theta`` from the inverse kinematics; the rates solve ``J(theta) dtheta = v``
    and the accelerations ``J(theta) ddtheta = a - Jdot(theta, dtheta) dtheta``
    with, for absolute link angles ``phi_i``,
    ``Jdot dtheta = -sum_i L_i dphi_i**2 (cos phi_i, sin phi_i)``.

    Parameters
    ----------
    arm : FlexibleArm or alike
        A two-link arm.
    position, velocity : ndarray, shape (m, 2)
        The path, m and m/s.
    acceleration : ndarray, shape (m, 2), optional
        Its acceleration, m/s**2 (for ``ddtheta``).
    elbow : {"positive", "negative"}
        The branch (sign of ``theta_2``).
    singularity_tol : float
        Smallest allowed ``|det J| / (L_1 L_2) = |sin theta_2|``.
    times : ndarray, shape (m,), optional
        The samples' times, s (named in error messages).
    owner : str
        Named in error messages.

    Returns
    -------
    theta, dtheta, ddtheta : ndarray, shape (m, 2)
        rad, rad/s, rad/s**2 (``ddtheta`` None without ``acceleration``).

    Raises
    ------
    InvalidValueError
        If the arm does not have two links, the path leaves the workspace, or
        passes within ``singularity_tol`` of a singularity.
    """
    n = int(arm.n_links)
    if n != 2:
        raise InvalidValueError(
            f"The 'arm' parameter of {owner} must have 2 links. Got {n} links instead."
        )
    try:
        theta = arm.inverse_kinematics(position, elbow=elbow)
    except ValueError as exc:
        raise InvalidValueError(
            f"The 'trajectory' parameter of {owner} must stay inside the arm's workspace. {exc}"
        ) from exc
    lengths = np.asarray(arm.link_lengths, dtype=float)
    l1, l2 = lengths
    phi1 = theta[:, 0]
    phi2 = phi1 + theta[:, 1]
    s1, c1, s2, c2 = np.sin(phi1), np.cos(phi1), np.sin(phi2), np.cos(phi2)
    a, b = -l1 * s1 - l2 * s2, -l2 * s2  # the rigid Jacobian [[a, b], [c, d]]
    c, d = l1 * c1 + l2 * c2, l2 * c2
    det = a * d - b * c
    near = np.abs(det) / (l1 * l2)
    if np.any(near < singularity_tol):
        k = int(np.argmax(near < singularity_tol))
        when = f"t = {times[k]} s, at " if times is not None else ""
        raise InvalidValueError(
            f"The 'trajectory' parameter of {owner} must stay clear of singularities, "
            f"with |det J| / (L1 L2) >= {singularity_tol}. Got {near[k]:.3g} at {when}"
            f"{position[k].tolist()} m ({int(np.sum(near < singularity_tol))} samples too "
            "close) instead."
        )

    def solve(rhs: F64) -> F64:  # J x = rhs in closed form, row by row
        x = np.stack([d * rhs[:, 0] - b * rhs[:, 1], a * rhs[:, 1] - c * rhs[:, 0]], axis=1)
        return np.asarray(x / det[:, None], dtype=np.float64)

    dtheta = solve(velocity)
    if acceleration is None:
        return theta, dtheta, None
    w1, w2 = l1 * dtheta[:, 0] ** 2, l2 * (dtheta[:, 0] + dtheta[:, 1]) ** 2
    jdot_dtheta = -np.stack([w1 * c1 + w2 * c2, w1 * s1 + w2 * s2], axis=1)
    return theta, dtheta, solve(acceleration - jdot_dtheta)


def joint_reference(
    arm: KinematicArm,
    trajectory: Trajectory,
    t: ArrayLike,
    elbow: str = "positive",
    *,
    singularity_tol: float = 1e-3,
) -> tuple[F64, F64, F64]:
    """Joint angles, rates and accelerations of a rigid two-link arm that follow a path.

    Parameters
    ----------
    arm : FlexibleArm or alike
        Two-link arm (``n_links``, ``link_lengths`` in m, ``inverse_kinematics``).
    trajectory : Trajectory
        The end-effector path.
    t : float or array_like, shape (m,)
        Times, s.
    elbow : {"positive", "negative"}
        The inverse-kinematics branch (sign of ``theta_2``).
    singularity_tol : float
        Smallest allowed ``|det J| / (L_1 L_2) = |sin theta_2|`` (> 0). The
        default 1e-3 (``theta_2`` within 0.057 deg of 0 or pi: full reach or
        folded back over the base) is where the rates exceed ~1000 times the
        path speed divided by a link length.

    Returns
    -------
    theta, dtheta, ddtheta : ndarray, shape (m, 2) or (2,)
        In rad, rad/s and rad/s**2 (:func:`joint_path`). ``theta_1`` is wrapped
        to ``[-pi, pi)`` as the inverse kinematics return it (use
        ``numpy.unwrap`` along time for a path that circles the base).

    Raises
    ------
    ValueError
        If the arm does not have two links, the path leaves the workspace at
        some ``t``, or passes within ``singularity_tol`` of a singularity at
        some ``t`` (only the sampled times are checked).

    Examples
    --------
    >>> from flexarm import FlexibleArm
    >>> from flexarm.control.trajectories import Square
    >>> th, dth, ddth = joint_reference(FlexibleArm.paper(), Square(), [0.0, 2.5])
    >>> th.shape, dth.shape
    ((2, 2), (2, 2))
    """
    owner = "joint_reference"
    check_trajectory(trajectory, owner)
    check_option(elbow, "elbow", owner, ELBOWS)
    tol = check_real(singularity_tol, "singularity_tol", owner, positive=True)
    tt, scalar = evaluation_times(t, owner)
    pos, vel, acc = trajectory.evaluate(tt)
    theta, dtheta, ddtheta = joint_path(
        arm, pos, vel, acc, elbow=elbow, singularity_tol=tol, times=tt, owner=owner
    )
    assert ddtheta is not None
    if scalar:
        return theta[0], dtheta[0], ddtheta[0]
    return theta, dtheta, ddtheta


BLOCK = 1 << 15
"""Control instants per block of the reference (blocks start at multiples of it)."""


class ReferencePipeline:
    """The reference ``r`` and the desired path at any control instants of a run.

    The run has instants ``t_k = k dt``, ``0 <= k <= n_steps``. The pipeline
    computes them block by block (:data:`BLOCK` instants, aligned): a block's
    values do not depend on which rows were asked for, so a long run can take
    its reference one block at a time in bounded memory and still get exactly
    the numbers a short request would.

    Parameters
    ----------
    arm : FlexibleArm or alike
    trajectory : Trajectory
        The desired end-effector path.
    dt : float
        Control period, s.
    n_steps : int
        Periods in the run (instants ``0 .. n_steps``).
    shaper : Shaper, optional
        Input shaper applied to the path.
    delay : float
        Delay of the reference fed to the law, s (0: none).
    point : (link, distance), optional
        A sensed point short of the end effector (two-link arms): the
        operational-space command becomes that point's path.
    elbow : {"positive", "negative"}
        Inverse-kinematics branch.
    singularity_tol : float
        Smallest allowed ``|det J| / (L_1 L_2)`` (:func:`joint_path`).
    feedforward : callable, optional
        ``feedforward(theta, dtheta, ddtheta) -> tau`` (arrays (K, n_links); e.g.
        :class:`flexarm.control.feedforward.RigidDynamics`): the torques put in
        the reference's feedforward columns (zero without it).
    smoothing : float
        Standard deviation of the zero-phase Gaussian smoothing of the path, s
        (0: none; :func:`smoothed_path`).
    owner : str
        Named in error messages.

    Attributes
    ----------
    size : int
        Columns of ``r`` (:func:`flexarm.control.signals.reference_size`).
    initial_angles : ndarray, shape (n_links,) or None
        Joint angles that put the rigid arm on the law's first reference point
        (two-link arms), rad.

    Raises
    ------
    InvalidValueError
        From :meth:`rows`, if the path leaves the workspace or passes too close to
        a singularity in the rows computed (with the time and the point).
    """

    def __init__(
        self,
        arm: KinematicArm,
        trajectory: Trajectory,
        dt: float,
        n_steps: int,
        *,
        shaper: PathShaper | None = None,
        delay: float = 0.0,
        point: tuple[int, float] | None = None,
        elbow: str = "positive",
        singularity_tol: float = 1e-6,
        feedforward: Feedforward | None = None,
        smoothing: float = 0.0,
        owner: str = "simulate",
    ) -> None:
        self._n_links = n_links = int(arm.n_links)
        if n_links != 2 and (point is not None or feedforward is not None):
            what = "sensor" if point is not None else "feedforward"
            raise InvalidValueError(
                f"The '{what}' parameter of {owner} needs joint references, which need "
                f"inverse kinematics (two-link arms). Got a {n_links}-link arm instead."
            )
        self._lengths = np.asarray(arm.link_lengths, dtype=float)
        self._trajectory = trajectory
        self._dt, self._n_rows = float(dt), int(n_steps) + 1
        path: PathFunction = trajectory.evaluate
        if smoothing > 0.0:
            path = smoothed_path(path, smoothing, self._dt)
        if shaper is not None:
            path = shaper.apply_function(path)
        self._path, self._delay = path, float(delay)
        self._plain = shaper is None and delay == 0.0 and smoothing == 0.0
        self._smoothed = smoothing > 0.0
        self._levers = None if point is None else lever_lengths(self._lengths, *point)
        self._sign = 1.0 if elbow == "positive" else -1.0
        self._tol = float(singularity_tol)
        self._feedforward = feedforward
        self._owner = owner
        self.size = reference_size(n_links)
        self._cache: tuple[int, F64, F64] | None = None
        self._path_start = np.zeros((1, 2))
        self.initial_angles: F64 | None = None
        self._shaped = shaper is not None
        if n_links == 2:
            if self._smoothed:  # the law's first point: the smoothed path's
                self._block(0)
                start = self._path_start
            else:  # the desired path's first point
                start = np.asarray(trajectory.evaluate(np.zeros(1))[0], dtype=float)
            theta = np.empty((1, 2))
            self._joint_path(start, np.zeros((1, 2)), np.zeros((1, 2)), theta, 0)
            self.initial_angles = theta[0]

    def stream(self) -> ReferenceStream | None:
        """The pipeline as the plain arrays (a ``ReferenceStream``) from which the
        simulation loop computes it instant by instant, with the same numbers as
        :meth:`rows`; None where it cannot (a path not of straight segments,
        shaping, smoothing, a sensed point short of the end effector, feedforward, or
        an arm without two links)."""
        from ._reference_kernels import reference_stream

        segments = straight_segments(self._trajectory)
        if (
            segments is None
            or self._n_links != 2
            or self._shaped
            or self._smoothed
            or self._levers is not None
            or self._feedforward is not None
        ):
            return None
        knot_t, knot_p, quintic = segments
        l1, l2 = (float(v) for v in self._lengths)
        return reference_stream(
            knot_t,
            knot_p,
            quintic=quintic,
            delay=self._delay,
            lengths=(l1, l2),
            sign=self._sign,
            singularity_tol=self._tol,
        )

    def raise_at(self, k: int) -> None:
        """Raise the error :meth:`rows` gives for instant ``k`` (a streamed reference
        that failed there)."""
        self.rows(k, k + 1)
        raise AssertionError(f"the reference at instant {k} is valid")  # pragma: no cover

    def rows(self, k0: int, k1: int) -> tuple[F64, F64]:
        """``r`` (shape (k1 - k0, size)) and the desired path (shape (k1 - k0, 2), m)
        at instants ``k0 <= k < k1``."""
        r = np.empty((k1 - k0, self.size))
        desired = np.empty((k1 - k0, 2))
        b = (k0 // BLOCK) * BLOCK
        while b < k1:
            rb, db = self._block(b)
            lo, hi = max(b, k0), min(b + BLOCK, k1)
            r[lo - k0 : hi - k0] = rb[lo - b : hi - b]
            desired[lo - k0 : hi - k0] = db[lo - b : hi - b]
            b += BLOCK
        return r, desired

    def _block(self, b0: int) -> tuple[F64, F64]:
        """The block of instants starting at ``b0`` (a multiple of :data:`BLOCK`)."""
        if self._cache is not None and self._cache[0] == b0:
            return self._cache[1], self._cache[2]
        n_links, dt = self._n_links, self._dt
        b1 = min(b0 + BLOCK, self._n_rows)
        # a sensed point needs its velocity at the neighbours for its acceleration
        halo = self._levers is not None and self._n_rows > 2
        e0 = max(b0 - 1, 0) if halo else b0
        e1 = min(b1 + 1, self._n_rows) if halo else b1
        t = np.arange(e0, e1, dtype=np.float64) * dt
        pos, vel, acc = (np.asarray(a, dtype=float) for a in self._path(t - self._delay))
        inner = slice(b0 - e0, b1 - e0)
        if b0 == 0:
            self._path_start = pos[:1].copy()
        if self._plain:
            desired = pos[inner]
        else:
            desired = np.asarray(self._trajectory.evaluate(t[inner])[0], dtype=float)
        r = np.zeros((b1 - b0, self.size))
        rp, rv, ra = r_position(n_links), r_velocity(n_links), r_acceleration(n_links)
        r[:, rp : rp + 2], r[:, rv : rv + 2], r[:, ra : ra + 2] = pos[inner], vel[inner], acc[inner]
        if n_links != 2:
            self._check_reach(pos[inner], b0)
        if n_links == 2:
            theta, dtheta, ddtheta = (np.empty((e1 - e0, 2)) for _ in range(3))
            self._joint_path(pos, vel, acc, theta, e0, dtheta, ddtheta)
            r[:, r_angles(2) : r_angles(2) + 2] = theta[inner]
            r[:, r_rates(2) : r_rates(2) + 2] = dtheta[inner]
            r[:, r_angle_accelerations(2) : r_angle_accelerations(2) + 2] = ddtheta[inner]
            if self._feedforward is not None:
                r[:, r_feedforward(2) : r_feedforward(2) + 2] = self._feedforward(
                    theta[inner], dtheta[inner], ddtheta[inner]
                )
            if self._levers is not None:
                p_r, v_r = rigid_point(self._levers, theta, dtheta)
                assert v_r is not None
                r[:, rp : rp + 2], r[:, rv : rv + 2] = p_r[inner], v_r[inner]
                r[:, ra : ra + 2] = _central_differences(v_r, dt, e0, b0, b1, self._n_rows)
        self._cache = (b0, r, desired)
        return r, desired

    def _check_reach(self, pos: F64, k0: int) -> None:
        """Every point of ``pos`` (rows of instants ``k0 ..``) within the annulus a
        rigid chain of these links reaches: ``max(0, 2 L_max - sum L) <= r <= sum L``
        (a circle of radius ``L`` for one link), to 1e-9 of the reach."""
        total = float(self._lengths.sum())
        inner = max(0.0, 2.0 * float(self._lengths.max()) - total)
        r = np.hypot(pos[:, 0], pos[:, 1])
        tol = 1e-9 * total
        bad = ~((r >= inner - tol) & (r <= total + tol))
        if np.any(bad):
            row = int(np.argmax(bad))
            span = f"{total} m" if inner == total else f"[{inner}, {total}] m"
            raise InvalidValueError(
                f"The 'trajectory' parameter of {self._owner} must stay inside the arm's "
                f"workspace: every point reachable by the {self._n_links}-link arm, at a "
                f"distance of {span} from the base. Got {pos[row].tolist()} m "
                f"({r[row]:.6g} m from the base) at t = {(k0 + row) * self._dt:.6g} s "
                "instead."
            )

    def _joint_path(
        self,
        pos: F64,
        vel: F64,
        acc: F64,
        theta: F64,
        k0: int,
        dtheta: F64 | None = None,
        ddtheta: F64 | None = None,
    ) -> None:
        """The compiled joint path of rows starting at instant ``k0``, with the
        messages of :func:`joint_path` for a path out of reach or singular."""
        from ._reference_kernels import SINGULAR, UNREACHABLE, joint_path_rows

        dtheta = np.empty_like(theta) if dtheta is None else dtheta
        ddtheta = np.empty_like(theta) if ddtheta is None else ddtheta
        l1, l2 = (float(v) for v in self._lengths)
        code, row, value = joint_path_rows(
            l1, l2, self._sign, self._tol, pos, vel, acc, theta, dtheta, ddtheta
        )
        if code == UNREACHABLE:
            raise InvalidValueError(
                f"The 'trajectory' parameter of {self._owner} must stay inside the arm's "
                f"workspace: every point reachable, at a distance in [{abs(l1 - l2)}, {l1 + l2}] m "
                f"from the base. "
                f"Got {pos[row].tolist()} m ({value:.6g} m from the base) at "
                f"t = {(k0 + row) * self._dt:.6g} s instead."
            )
        if code == SINGULAR:
            raise InvalidValueError(
                f"The 'trajectory' parameter of {self._owner} must stay clear of "
                f"singularities, with |det J| / (L1 L2) >= {self._tol}. Got {value:.3g} at "
                f"t = {(k0 + row) * self._dt:.6g} s, at {pos[row].tolist()} m instead."
            )


def _central_differences(v: F64, dt: float, e0: int, b0: int, b1: int, n_rows: int) -> F64:
    """d/dt of ``v`` (rows of instants ``e0 ..``) at instants ``b0 <= k < b1``:
    central differences inside the run, one-sided at its two ends (as
    ``numpy.gradient``), zero for a run of two instants or fewer."""
    out = np.zeros((b1 - b0, v.shape[1]))
    if n_rows <= 2:
        return out
    lo, hi = max(b0, 1), min(b1, n_rows - 1)  # instants with both neighbours
    if hi > lo:
        out[lo - b0 : hi - b0] = (v[lo + 1 - e0 : hi + 1 - e0] - v[lo - 1 - e0 : hi - 1 - e0]) / (
            2.0 * dt
        )
    if b0 == 0:
        out[0] = (v[1 - e0] - v[0 - e0]) / dt
    if b1 == n_rows:
        out[-1] = (v[n_rows - 1 - e0] - v[n_rows - 2 - e0]) / dt
    return out


def reference_signals(
    arm: KinematicArm, trajectory: Trajectory, t: F64, **options: Any
) -> ReferenceSignals:
    """The reference ``r`` at all the control instants ``t = k dt`` of a run at once
    (``t`` must be ``arange(K) * dt``).

    ``options`` are the keyword parameters of :class:`ReferencePipeline`
    (``shaper``, ``delay``, ``point``, ``elbow``, ``singularity_tol``,
    ``feedforward``, ``smoothing``, ``owner``); any other raises TypeError.
    """
    dt = float(t[1] - t[0]) if t.shape[0] > 1 else 1.0
    pipeline = ReferencePipeline(arm, trajectory, dt, t.shape[0] - 1, **options)
    r, desired = pipeline.rows(0, t.shape[0])
    return ReferenceSignals(reference=r, desired=desired, initial_angles=pipeline.initial_angles)


def smoothed_path(path: PathFunction, sigma: float, step: float) -> PathFunction:
    """``path`` filtered by a zero-phase Gaussian of standard deviation ``sigma`` (s).

    Position and velocity are the Gaussian's convolution with the path's own
    position and velocity; the acceleration is the Gaussian's derivative
    convolved with the velocity, so a velocity jump (a corner taken at constant
    speed) becomes a finite, bell-shaped acceleration. The convolution (by FFT,
    the kernel cut at 5 sigma) runs on a grid of spacing ``step`` (s) around the
    times asked for, which must be evenly spaced at that step; the path holds
    its ends beyond its duration.
    """
    from scipy.signal import fftconvolve

    half = int(np.ceil(5.0 * sigma / step))
    u = step * np.arange(-half, half + 1)
    kernel = np.exp(-0.5 * (u / sigma) ** 2)
    kernel /= kernel.sum()
    slope = -u / sigma**2 * kernel  # d/dt of the kernel, 1/s

    def smoothed(tq: F64) -> tuple[F64, F64, F64]:
        tq = np.atleast_1d(np.asarray(tq, dtype=float))
        grid = tq[0] + step * np.arange(-half, tq.shape[0] + half)
        pos, vel, _ = (np.asarray(a, dtype=float) for a in path(grid))

        def conv(signal: F64, k: F64) -> F64:
            return np.stack([fftconvolve(signal[:, j], k, mode="valid") for j in range(2)], 1)

        return conv(pos, kernel), conv(vel, kernel), conv(vel, slope)

    return smoothed
