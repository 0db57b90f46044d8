"""Input-driven simulation: :func:`simulate_open_loop`.

The plant driven by joint torques, with no controller in the loop, as
python-control's ``input_output_response(sys, T, U, X0)`` drives a system: the
torque is given as samples on an evenly spaced time grid (held between samples,
or interpolated linearly), as a Numba-compiled function of time, or as any
Python function of time. The same compiled RK4 integrator as the closed loop
(:mod:`flexarm.sim.integrator`) advances the state, the same result object
comes back.

Within each RK4 step the torque is evaluated where the method needs it: at the
start, the middle and the end of the step. A held torque is constant over a
sample interval, so an open-loop run fed the torque record of a closed-loop
run, on the same grid with the same substeps, reproduces that run bit for bit.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import NamedTuple, cast

import numba as nb
import numpy as np
from numba import carray, types  # type: ignore[attr-defined]
from numba.core.ccallback import CFunc
from numpy.typing import ArrayLike, NDArray

from .._compile import njit_runtime_free
from .._io import JSONValue
from .._validation import check_array, check_bool, check_int, check_option, check_real
from ..errors import InvalidValueError
from ..model.arrays import ArmArrays, Workspace, make_workspace
from ..model.dynamics._two_links import is_two_links_one_mode
from ..model.plant import Plant, check_plant
from . import _rk4
from .chunks import DIVERGED, OK, run_in_chunks
from .results import SimulationResult, assemble_result
from .step_check import check_substeps

__all__ = [
    "INTERPOLATIONS",
    "TORQUE_SIGNATURE",
    "OpenLoopState",
    "open_loop_result",
    "run_open_loop",
    "simulate_open_loop",
    "wrap_torque_function",
]

F64 = NDArray[np.float64]
_OWNER = "simulate_open_loop"

INTERPOLATIONS = ("zoh", "linear")
# how the driver finds the torque at a stage time
_HOLD, _LINEAR, _STAGES, _FUNCTION = 0, 1, 2, 3

_P = types.CPointer(types.float64)  # type: ignore[no-untyped-call]
TORQUE_SIGNATURE = types.void(types.float64, _P, types.intp)
"""``void(t, tau*, n_links)``: a compiled torque source writes ``tau(t)`` (N m)."""

TorqueFunction = Callable[[float], ArrayLike]


class OpenLoopState(NamedTuple):
    """What carries over between chunks (updated in place)."""

    q: F64  # (n,)
    dq: F64  # (n,)
    stage_tau: F64  # (3, N) torque at the start, middle and end of a step
    scratch: F64  # (6, n) RK4 stages
    ws: Workspace  # dynamics scratch


def wrap_torque_function(fn: Callable[..., None]) -> CFunc:
    """Turn ``fn(t, tau)`` (a ``numba.njit`` function writing ``tau``, shape (n_links,),
    in N m) into a ``numba.cfunc`` with :data:`TORQUE_SIGNATURE`."""

    def wrapper(t, tau, n):  # type: ignore[no-untyped-def]
        fn(t, carray(tau, n))

    return nb.cfunc(TORQUE_SIGNATURE)(wrapper)


@nb.cfunc(TORQUE_SIGNATURE, cache=True)
def _no_source(t, tau, n):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """The source passed when the torque comes from a table (never called)."""
    for i in range(n):
        tau[i] = 0.0


@nb.njit(cache=True, nogil=True, inline="always")
def _torque(
    mode: int,
    table: F64,
    source: CFunc,
    k: int,
    s: int,
    half: int,
    substeps: int,
    t: float,
    out: F64,
) -> None:  # pragma: no cover - compiled
    """The torque at ``t``: substep ``s`` of interval ``k``, ``half`` = 0, 1, 2 for the
    substep's start, middle and end."""
    n = out.shape[0]
    if mode == _HOLD:
        for i in range(n):
            out[i] = table[k, i]
    elif mode == _LINEAR:
        f = (s + 0.5 * half) / substeps
        if f == 0.0:
            for i in range(n):
                out[i] = table[k, i]
        else:
            for i in range(n):
                out[i] = (1.0 - f) * table[k, i] + f * table[k + 1, i]
    elif mode == _STAGES:
        row = 2 * (k * substeps + s) + half
        for i in range(n):
            out[i] = table[row, i]
    else:
        source(t, out.ctypes, n)


@njit_runtime_free(cache=True, nogil=True)
def run_open_loop(
    model: ArmArrays,
    mode: int,
    table: F64,
    source: CFunc,
    t0: float,
    dt: float,
    substeps: int,
    max_deflection: F64,
    state: OpenLoopState,
    k0: int,
    k1: int,
    out_q: F64,
    out_dq: F64,
    out_tau: F64,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Advance the plant over sample instants ``k0 <= k < k1``: record ``q, dq`` and the
    torque at ``t_k``, then integrate to ``t_{k+1}`` (unless ``k`` is the last row).

    Returns ``(status, k)`` as :func:`flexarm.sim.loop.run` does.
    """
    n_rows = out_q.shape[0]
    h = dt / substeps
    q, dq, st = state.q, state.dq, state.stage_tau
    two_links_one_mode = is_two_links_one_mode(model)
    for k in range(k0, k1):
        tk = t0 + k * dt
        for r in range(q.shape[0]):
            out_q[k, r] = q[r]
            out_dq[k, r] = dq[r]
        _torque(mode, table, source, k, 0, 0, substeps, tk, st[0])
        for i in range(st.shape[1]):
            out_tau[k, i] = st[0, i]
        if k == n_rows - 1:
            return OK, k1
        for s in range(substeps):
            ts = tk + s * h
            for half in range(3):
                _torque(mode, table, source, k, s, half, substeps, ts + 0.5 * half * h, st[half])
            if two_links_one_mode:
                _rk4.rk4_step_two_links_one_mode(q, dq, st[0], st[1], st[2], h, model)
            else:
                _rk4.rk4_step(q, dq, st[0], st[1], st[2], h, model, state.ws, state.scratch)
            if _rk4.diverged(q, dq, model, max_deflection):
                return DIVERGED, k
    return OK, k1


def _time_grid(t: ArrayLike, owner: str = _OWNER) -> tuple[F64, float]:
    """``t`` checked: 1-D, finite, at least two samples, increasing, evenly spaced;
    with its step ``dt``, s."""
    grid = check_array(t, "t", owner, shape=(-1,))
    if grid.shape[0] < 2:
        raise InvalidValueError(
            f"The 't' parameter of {owner} must hold at least 2 times. Got {grid.shape[0]} instead."
        )
    dt = float(grid[-1] - grid[0]) / (grid.shape[0] - 1)
    steps = np.diff(grid)
    tol = 1e-9 * dt + 8 * np.finfo(float).eps * float(np.max(np.abs(grid)))
    if not dt > 0 or np.any(np.abs(steps - dt) > tol):
        raise InvalidValueError(
            f"The 't' parameter of {owner} must be increasing and evenly spaced (the "
            f"fixed-step integrator steps through it). Got steps from {steps.min():.6g} to "
            f"{steps.max():.6g} s instead."
        )
    return grid, dt


def _half_substep_times(t: F64, substeps: int) -> F64:
    """The start, middle and end of every RK4 substep over the grid ``t`` (s): the
    times, shape ``(2 (K - 1) substeps + 1,)``, at which a function of time is
    evaluated beforehand."""
    h = float(t[1] - t[0]) / substeps
    times: F64 = t[0] + 0.5 * h * np.arange(2 * (t.shape[0] - 1) * substeps + 1)
    return times


def _deflection_limits(arm: Plant, max_deflection: float | None, owner: str) -> F64:
    """The tip deflection of each link (m, shape (n_links,)) beyond which a run counts
    as diverged: ``max_deflection`` for all, or by default each link's length."""
    if max_deflection is None:
        return np.array(arm.link_lengths, dtype=float)
    limit = check_real(max_deflection, "max_deflection", owner, positive=True)
    return np.full(arm.n_links, limit)


def _torque_source(
    torque: ArrayLike | TorqueFunction, t: F64, substeps: int, n_links: int
) -> tuple[int, F64, CFunc, str]:
    """``(mode, table, source, kind)`` for the driver from the user's ``torque``."""
    if hasattr(torque, "py_func"):  # a numba.njit function writing tau(t)
        compiled = wrap_torque_function(cast(Callable[..., None], torque))
        return _FUNCTION, np.zeros((1, n_links)), compiled, "compiled function"
    if callable(torque):
        times = _half_substep_times(t, substeps)
        table = np.empty((times.shape[0], n_links))
        for j, tj in enumerate(times):
            row = np.asarray(torque(float(tj)), dtype=float)
            if row.shape not in ((n_links,), () if n_links == 1 else (n_links,)):
                raise InvalidValueError(
                    f"The 'torque' parameter of {_OWNER} must return an array of shape "
                    f"({n_links},) (N m). Got shape {row.shape} at t = {tj} s instead."
                )
            table[j] = row
        if not np.all(np.isfinite(table)):
            raise InvalidValueError(
                f"The 'torque' parameter of {_OWNER} must return finite torques. "
                "Got a non-finite value instead."
            )
        return _STAGES, table, _no_source, "function"
    table = check_array(torque, "torque", _OWNER)
    if table.ndim == 1 and n_links == 1:
        table = table[:, None]
    if table.shape != (t.shape[0], n_links):
        raise InvalidValueError(
            f"The 'torque' parameter of {_OWNER} must be of shape ({t.shape[0]}, {n_links}) "
            f"(one row per time, N m) or a function of time. Got shape {table.shape} instead."
        )
    return -1, np.ascontiguousarray(table, dtype=float), _no_source, "samples"


def _drive_torques(arm: Plant, current: ArrayLike, k_rows: int) -> F64:
    """The joint torques (N m) of motor-current samples through ``arm``'s drives."""
    drives = getattr(arm, "drives", None)
    if drives is None:
        raise InvalidValueError(
            f"The 'current' parameter of {_OWNER} needs an arm with drives "
            "(FlexibleArm(drives=...)); this arm has none: give 'torque' instead."
        )
    n_links = arm.n_links
    samples = check_array(current, "current", _OWNER, real=True)
    if samples.ndim == 1 and n_links == 1:
        samples = samples[:, None]
    if samples.shape != (k_rows, n_links):
        raise InvalidValueError(
            f"The 'current' parameter of {_OWNER} must be of shape ({k_rows}, {n_links}) "
            f"(one row per time, A). Got shape {samples.shape} instead."
        )
    return cast(F64, arm.joint_torques(samples))  # type: ignore[attr-defined]


def simulate_open_loop(
    arm: Plant,
    t: ArrayLike,
    torque: ArrayLike | TorqueFunction | None = None,
    *,
    current: ArrayLike | None = None,
    initial_state: ArrayLike | None = None,
    interpolation: str = "zoh",
    substeps: int | str = "auto",
    max_deflection: float | None = None,
    progress: bool | None = None,
) -> SimulationResult:
    """Drive ``arm`` by joint torques from an initial state (no controller).

    Parameters
    ----------
    arm : FlexibleArm
        The plant.
    t : array_like, shape (K,)
        Evenly spaced, increasing times, s: the samples of ``torque`` and of the
        result. The integrator takes ``substeps`` RK4 steps per interval.
    torque : array_like, shape (K, n_links), or callable
        Joint torques in N m (on the motors for flexible joints): samples at
        ``t`` (a 1-D array for a one-link arm), or a function of time —
        a ``numba.njit`` function ``f(t, tau)`` writing ``tau`` (called inside
        the compiled loop), or any Python callable ``f(t) -> tau`` (evaluated
        beforehand at every time the integrator needs). Give ``torque`` or
        ``current``, one of them.
    current : array_like, shape (K, n_links), optional
        Motor currents in A, samples at ``t``, for an arm built with drives
        (``FlexibleArm(drives=...)``): each sample becomes the joint torque of
        :meth:`~flexarm.model.arm.FlexibleArm.joint_torques` (the drive's gain,
        offset and current limit; a joint without a drive takes its column as a
        torque), then held or interpolated as torque samples are.
    initial_state : array_like, shape (2 n_dof,), optional
        ``(q, dq)`` at ``t[0]`` (default: at rest, all zero).
    interpolation : {"zoh", "linear"}
        For samples: held over each interval (zero-order hold) or linear
        between samples. Functions are evaluated exactly where needed.
    substeps : int or "auto"
        RK4 steps per interval (>= 1). An integer whose step is beyond the RK4
        stability bound of the arm's dynamics linearised at the initial state is
        refused, naming the substeps that work (:mod:`flexarm.sim.step_check`);
        ``"auto"`` (default) takes 1 where one step is stable, else the fewest
        within 90 % of the bound (the result's ``info["substeps"]`` says which).
    max_deflection : float, optional
        Tip deflection of any link (m) beyond which the run counts as diverged
        (default: that link's length).
    progress : bool, optional
        Show a progress bar on stderr (default: for long runs on a terminal).

    Returns
    -------
    SimulationResult
        ``tau`` holds the torque at each ``t_k``; there is no reference and no
        measurement, and the tracking metrics are NaN.

    Raises
    ------
    SimulationError
        If the state diverges; the partial result is attached.

    Examples
    --------
    >>> import numpy as np
    >>> import flexarm as fa
    >>> arm = fa.FlexibleArm([fa.Link(1.0, 10.0, 1.0, n_modes=0)])  # a rigid rod
    >>> t = np.linspace(0.0, 1.0, 101)
    >>> res = fa.simulate_open_loop(arm, t, np.ones((101, 1)))      # 1 N m
    >>> round(float(res.q[-1, 0]), 6)       # theta = tau t**2 / (2 J), J = rho L**3 / 3
    1.5
    """
    arm = check_plant(arm, _OWNER)
    grid, dt = _time_grid(t)
    check_option(interpolation, "interpolation", _OWNER, INTERPOLATIONS)
    if substeps != "auto":
        substeps = check_int(substeps, "substeps", _OWNER, minimum=1)
    n, n_links = arm.n_dof, arm.n_links
    if initial_state is None:
        x0 = np.zeros(2 * n)
    else:
        x0 = check_array(initial_state, "initial_state", _OWNER, shape=(2 * n,))
    substeps = check_substeps(arm, dt, substeps, _OWNER, x0[:n])
    if current is not None:
        if torque is not None:
            raise InvalidValueError(
                f"{_OWNER} takes a 'torque' or a 'current', one of them. Got both instead."
            )
        torque = _drive_torques(arm, current, grid.shape[0])
    elif torque is None:
        raise InvalidValueError(f"{_OWNER} takes a 'torque' or a 'current'. Got neither.")
    mode, table, source, kind = _torque_source(torque, grid, substeps, n_links)
    if current is not None:
        kind = "current samples"
    if mode < 0:
        mode = _HOLD if interpolation == "zoh" else _LINEAR
    max_defl = _deflection_limits(arm, max_deflection, _OWNER)
    check_bool(progress, "progress", _OWNER, optional=True)
    k_rows = grid.shape[0]
    state = OpenLoopState(
        q=np.array(x0[:n], dtype=float),
        dq=np.array(x0[n:], dtype=float),
        stage_tau=np.zeros((3, n_links)),
        scratch=np.zeros((6, n)),
        ws=make_workspace(n),
    )
    q, dq, tau = np.empty((k_rows, n)), np.empty((k_rows, n)), np.empty((k_rows, n_links))

    def chunk(k0: int, k1: int) -> tuple[int, int]:
        status, k = run_open_loop(
            arm.arrays,
            mode,
            table,
            source,
            float(grid[0]),
            dt,
            substeps,
            max_defl,
            state,
            k0,
            k1,
            q,
            dq,
            tau,
        )
        return int(status), int(k)

    start = time.perf_counter()
    status, k_end = run_in_chunks(chunk, k_rows, k_rows * substeps * n, progress)
    return open_loop_result(
        arm,
        grid,
        q,
        dq,
        tau,
        diverged=status != OK,
        last_row=k_end,
        head={
            "controller": "open loop",
            "torque": kind,
            "interpolation": interpolation if kind.endswith("samples") else "exact",
        },
        dt=dt,
        substeps=substeps,
        wall_time_s=time.perf_counter() - start,
    )


def open_loop_result(
    arm: Plant,
    grid: F64,
    q: F64,
    dq: F64,
    tau: F64,
    *,
    diverged: bool,
    last_row: int,
    head: dict[str, JSONValue],
    dt: float,
    substeps: int,
    wall_time_s: float,
) -> SimulationResult:
    """The result of a run without a controller's signals (no measurement, reference
    or desired path) on the instants ``grid`` (s), rows ``q, dq`` of shape
    ``(len(grid), n_dof)`` and ``tau`` of shape ``(len(grid), n_links)`` (N m); ``head``
    opens its ``info`` (what drove the arm), the settings and ``wall_time_s`` follow."""
    k_rows = grid.shape[0]
    info: dict[str, JSONValue] = {
        **head,
        "dt_s": dt,
        "substeps": substeps,
        "t0_s": float(grid[0]),
        "duration_s": float(grid[-1] - grid[0]),
        "n_links": arm.n_links,
        "n_modes": list(arm.n_modes),
        "flexible_joints": bool(arm.has_flexible_joints),
        "wall_time_s": wall_time_s,
    }
    return assemble_result(
        arm,
        t=grid.copy(),
        q=q,
        dq=dq,
        tau=tau,
        measurement=np.zeros((k_rows, 0)),
        reference=np.zeros((k_rows, 0)),
        desired=np.full((k_rows, 2), np.nan),
        diverged=diverged,
        last_row=last_row,
        info=info,
    )
