"""The arm driven by prescribed joint motion: :func:`simulate_prescribed`.

The actuated angles (joint angles, or motor angles with flexible joints) follow
a given motion ``theta(t)`` *exactly* — the limit of an infinitely stiff servo,
imposed as a constraint (:mod:`flexarm.model.prescribed`), not approximated by
a stiff feedback loop — and the links respond. The result's ``tau`` is the
torque that constraint takes: what a perfect motion controller would deliver.

This is how flexible-multibody benchmarks drive a structure (the spin-up of
Kane, Ryan & Banerjee, :mod:`flexarm.studies.spin_up`) and how the modal
convergence check (:mod:`flexarm.studies.modal_convergence`) compares bases on
the same motion. The same fixed-step RK4 as the simulator integrates the free
coordinates; the actuated ones are set from the motion at every stage.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._compile import njit_runtime_free
from .._validation import check_array, check_int, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arrays import ArmArrays, Workspace, make_workspace
from ..model.plant import Plant, check_plant
from ..model.prescribed import free_range, prescribed_dynamics
from . import _rk4
from .chunks import DIVERGED, OK
from .open_loop import _deflection_limits, _half_substep_times, _time_grid, open_loop_result
from .results import SimulationResult
from .step_check import check_substeps

__all__ = ["JointMotion", "motion_from_samples", "simulate_prescribed"]

F64 = NDArray[np.float64]
_OWNER = "simulate_prescribed"

JointMotion = Callable[[F64], tuple[ArrayLike, ArrayLike, ArrayLike]]
"""``motion(t) -> (theta, dtheta, ddtheta)``: for times ``t`` (s, shape (m,)), the
actuated angles (rad), rates (rad/s) and accelerations (rad/s**2), each of shape
(m, n_links) (or (m,) for one link)."""


def motion_from_samples(
    t: ArrayLike, angles: ArrayLike, smoothing: float | None = None
) -> JointMotion:
    """A joint motion from sampled angles: a smoothing spline through each joint's
    samples, with its first and second derivatives as the rates and accelerations.

    Parameters
    ----------
    t : array_like, shape (K,)
        Increasing sample times, s (at least 5).
    angles : array_like, shape (K,) or (K, n_links)
        The measured actuated angles (rad): encoder readings, say.
    smoothing : float, optional
        The spline's penalty on its second derivative (``lam`` of
        :func:`scipy.interpolate.make_smoothing_spline`, in the units of the data:
        larger is smoother); default: chosen by generalised cross-validation for
        each joint.

    Returns
    -------
    callable
        ``motion(times) -> (theta, dtheta, ddtheta)``, each of shape (m, n_links)
        (rad, rad/s, rad/s**2), for :func:`simulate_prescribed`. Outside ``[t[0],
        t[-1]]`` the spline's end pieces are extrapolated. Its natural end
        conditions (no curvature at the ends) bend the accelerations near the ends
        of a motion that does not start and end at rest: there, trim the record.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 201)
    >>> motion = motion_from_samples(t, np.sin(2 * t), smoothing=1e-9)
    >>> theta, rate, acc = motion(np.array([0.5]))
    >>> np.round([theta[0, 0], rate[0, 0], acc[0, 0]], 4).tolist()   # sin 1, 2 cos 1, -4 sin 1
    [0.8415, 1.0806, -3.3659]
    """
    from scipy.interpolate import make_smoothing_spline

    owner = "motion_from_samples"
    grid = check_array(t, "t", owner, shape=(-1,))
    if grid.shape[0] < 5 or np.any(np.diff(grid) <= 0):
        raise InvalidValueError(
            f"The 't' parameter of {owner} must hold at least 5 increasing times. "
            f"Got {grid.shape[0]} times instead."
        )
    samples = check_array(angles, "angles", owner)
    if samples.ndim == 1:
        samples = samples[:, None]
    if samples.ndim != 2 or samples.shape[0] != grid.shape[0]:
        raise InvalidValueError(
            f"The 'angles' parameter of {owner} must be of shape ({grid.shape[0]},) or "
            f"({grid.shape[0]}, n_links). Got shape {np.shape(angles)} instead."
        )
    lam = None if smoothing is None else check_real(smoothing, "smoothing", owner, positive=True)
    splines = [make_smoothing_spline(grid, samples[:, j], lam=lam) for j in range(samples.shape[1])]
    derivatives = [(s, s.derivative(1), s.derivative(2)) for s in splines]

    def motion(times: F64) -> tuple[F64, F64, F64]:
        x = np.asarray(times, dtype=float)
        parts = [np.column_stack([d[k](x) for d in derivatives]) for k in range(3)]
        return parts[0], parts[1], parts[2]

    return motion


@njit_runtime_free(cache=True, nogil=True)
def _run(
    model: ArmArrays,
    table: F64,
    dt: float,
    substeps: int,
    max_deflection: F64,
    q: F64,
    dq: F64,
    ws: Workspace,
    scratch: F64,
    tau: F64,
    out_q: F64,
    out_dq: F64,
    out_tau: F64,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """RK4 over the free coordinates with the actuated ones from ``table``
    (shape (half steps + 1, 3, n_links): angle, rate, acceleration at every
    half substep). Returns ``(status, last row written)``."""
    n = q.shape[0]
    n_links = model.link.shape[0]
    f0, f1 = free_range(model, n)
    a0 = f1 if f0 == 0 else 0
    n_rows = out_q.shape[0]
    h = dt / substeps
    qs, vs, acc = scratch[0], scratch[1], scratch[2]
    sq, sv = scratch[3], scratch[4]
    for k in range(n_rows):
        row = 2 * k * substeps
        for i in range(n_links):
            q[a0 + i] = table[row, 0, i]
            dq[a0 + i] = table[row, 1, i]
        prescribed_dynamics(q, dq, table[row, 2], model, ws, acc, tau)
        for r in range(n):
            out_q[k, r] = q[r]
            out_dq[k, r] = dq[r]
        for i in range(n_links):
            out_tau[k, i] = tau[i]
        if k == n_rows - 1:
            return OK, k
        for s in range(substeps):
            base = row + 2 * s
            for r in range(n):
                sq[r] = 0.0
                sv[r] = 0.0
            for stage in range(4):
                c = 0.0 if stage == 0 else (0.5 if stage < 3 else 1.0)
                wgt = 1.0 if stage in (0, 3) else 2.0
                tr = base + (0 if stage == 0 else (1 if stage < 3 else 2))
                if stage == 0:
                    for r in range(n):
                        qs[r] = q[r]
                        vs[r] = dq[r]
                else:
                    # the previous stage's rates and accelerations advance the state
                    for r in range(f0, f1):
                        qs[r] = q[r] + c * h * vs[r]
                    for r in range(f0, f1):
                        vs[r] = dq[r] + c * h * acc[r]
                for i in range(n_links):
                    qs[a0 + i] = table[tr, 0, i]
                    vs[a0 + i] = table[tr, 1, i]
                prescribed_dynamics(qs, vs, table[tr, 2], model, ws, acc, tau)
                for r in range(f0, f1):
                    sq[r] += wgt * vs[r]
                    sv[r] += wgt * acc[r]
            for r in range(f0, f1):
                q[r] += h / 6.0 * sq[r]
                dq[r] += h / 6.0 * sv[r]
            last = base + 2
            for i in range(n_links):
                q[a0 + i] = table[last, 0, i]
                dq[a0 + i] = table[last, 1, i]
            if _rk4.diverged(q, dq, model, max_deflection):
                return DIVERGED, k
    return OK, n_rows - 1


def _motion_table(motion: JointMotion, t: F64, substeps: int, n_links: int) -> F64:
    """The motion at every half substep, shape (2 (K - 1) substeps + 1, 3, n_links)."""
    if not callable(motion):
        raise InvalidTypeError(
            f"The 'motion' parameter of {_OWNER} must be a function of time returning "
            f"(theta, dtheta, ddtheta). Got {type(motion).__name__} instead."
        )
    times = _half_substep_times(t, substeps)
    out = motion(times)
    if not isinstance(out, tuple) or len(out) != 3:
        raise InvalidValueError(
            f"The 'motion' parameter of {_OWNER} must return (theta, dtheta, ddtheta). "
            f"Got {type(out).__name__} instead."
        )
    table = np.empty((times.shape[0], 3, n_links))
    for j, (name, part) in enumerate(zip(("theta", "dtheta", "ddtheta"), out, strict=True)):
        arr = np.asarray(part, dtype=float)
        if arr.ndim == 1 and n_links == 1:
            arr = arr[:, None]
        if arr.shape != (times.shape[0], n_links) or not np.all(np.isfinite(arr)):
            raise InvalidValueError(
                f"The 'motion' parameter of {_OWNER} must give finite {name} of shape "
                f"({times.shape[0]}, {n_links}) for {times.shape[0]} times. Got shape "
                f"{arr.shape} instead."
            )
        table[:, j, :] = arr
    return table


def simulate_prescribed(
    arm: Plant,
    t: ArrayLike,
    motion: JointMotion | ArrayLike,
    *,
    initial_state: ArrayLike | None = None,
    substeps: int | str = "auto",
    max_deflection: float | None = None,
) -> SimulationResult:
    """The arm's response when its actuated angles follow ``motion`` exactly.

    Parameters
    ----------
    arm : FlexibleArm
        The plant.
    t : array_like, shape (K,)
        Evenly spaced, increasing times of the result, s; ``substeps`` RK4
        steps per interval.
    motion : callable or array_like
        ``motion(times) -> (theta, dtheta, ddtheta)``, vectorised over times
        (shape (m,), s): the joint angles (rad), rates (rad/s) and accelerations
        (rad/s**2) — the motor angles with flexible joints — each of shape
        (m, n_links). Evaluated once, at every half substep. ``dtheta`` and
        ``ddtheta`` must be the derivatives of ``theta``. Or the measured angles
        at ``t`` themselves, shape (K,) or (K, n_links) (rad): the motion is then
        :func:`motion_from_samples` of them (a smoothing spline).
    initial_state : array_like, shape (2 n_dof,), optional
        ``(q, dq)`` at ``t[0]``; its actuated entries are replaced by the
        motion's. Default: straight links at rest (and, with flexible joints,
        link angles equal to the motor angles).
    substeps : int or "auto"
        RK4 steps per interval (>= 1), checked against the RK4 stability bound of
        the free coordinates' dynamics linearised at rest (refused beyond it, naming
        the substeps that work); ``"auto"`` (default) takes 1 where one step is
        stable, else the fewest within 90 % of the bound.
    max_deflection : float, optional
        Tip deflection of any link (m) beyond which the run counts as diverged
        (default: that link's length).

    Returns
    -------
    SimulationResult
        ``tau`` holds the torques that produce the motion (N m); there is no
        reference or measurement.

    Raises
    ------
    SimulationError
        If the state diverges; the partial result is attached.

    Examples
    --------
    >>> import numpy as np
    >>> import flexarm as fa
    >>> arm = fa.FlexibleArm([fa.Link(1.0, 10.0, 1.0, n_modes=0)])  # a rigid rod
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> res = simulate_prescribed(arm, t, lambda s: (s**2 / 2, s, np.ones_like(s)))
    >>> round(float(res.tau[-1, 0]), 6)    # J theta'' with J = rho L**3 / 3
    0.333333
    """
    arm = check_plant(arm, _OWNER)
    grid, dt = _time_grid(t, _OWNER)
    if substeps != "auto":
        substeps = check_int(substeps, "substeps", _OWNER, minimum=1)
    n, n_links = arm.n_dof, arm.n_links
    free = np.ones(n, dtype=bool)
    actuated = getattr(arm, "actuated_slice", slice(0, n_links))
    free[actuated] = False  # the actuated angles follow the motion
    substeps = check_substeps(arm, dt, substeps, _OWNER, None, free)
    source = motion
    if isinstance(motion, np.ndarray | list | tuple):  # measured angles: a spline through them
        source = motion_from_samples(grid, motion)
    table = _motion_table(source, grid, substeps, n_links)  # type: ignore[arg-type]
    x0 = (
        np.zeros(2 * n)
        if initial_state is None
        else check_array(initial_state, "initial_state", _OWNER, shape=(2 * n,)).copy()
    )
    if initial_state is None and arm.has_flexible_joints:
        x0[:n_links] = table[0, 0]
        x0[n : n + n_links] = table[0, 1]
    max_defl = _deflection_limits(arm, max_deflection, _OWNER)
    k_rows = grid.shape[0]
    q_state, dq_state = np.array(x0[:n], dtype=float), np.array(x0[n:], dtype=float)
    ws, scratch, tau_s = make_workspace(n), np.zeros((6, n)), np.zeros(n_links)
    q, dq, tau = np.empty((k_rows, n)), np.empty((k_rows, n)), np.empty((k_rows, n_links))

    start = time.perf_counter()
    status, k_end = _run(
        arm.arrays, table, dt, substeps, max_defl, q_state, dq_state, ws, scratch, tau_s, q, dq, tau
    )
    return open_loop_result(
        arm,
        grid,
        q,
        dq,
        tau,
        diverged=status != OK,
        last_row=int(k_end),
        head={"controller": "prescribed joint motion"},
        dt=dt,
        substeps=substeps,
        wall_time_s=time.perf_counter() - start,
    )
