"""Driving a compiled loop from Python: chunks, a progress bar, the SciPy reference.

:func:`run_in_chunks` calls a compiled loop over consecutive ranges of control
instants (one range, or fifty with a progress bar on stderr) and stops at the
first divergence; :func:`run_scipy` is the closed loop with SciPy's adaptive
``solve_ivp`` between control instants, the accuracy reference of the
fixed-step integrator.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Protocol

import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import NDArray

from ..errors import Cancelled, InvalidValueError
from ..model.plant import Plant
from ._reference_kernels import no_stream
from .loop import DIVERGED, OK, LoopState, SensorArrays, run

__all__ = ["LoopOutputs", "StopFlag", "run_in_chunks", "run_scipy"]

F64 = NDArray[np.float64]
LoopOutputs = dict[str, F64]
"""The arrays a loop writes row by row: ``q``, ``dq``, ``tau`` (and ``measurement``)."""

Chunk = Callable[[int, int], tuple[int, int]]
"""``chunk(k0, k1) -> (status, k)``: advance a compiled loop over ``k0 <= k < k1``."""


class StopFlag(Protocol):
    """What stops a run between chunks: a :class:`threading.Event` or alike."""

    def is_set(self) -> bool: ...


def run_in_chunks(
    chunk: Chunk,
    n_rows: int,
    work: float,
    progress: bool | None,
    *,
    block: int | None = None,
    stop: StopFlag | None = None,
) -> tuple[int, int]:
    """Run ``chunk`` over ``0 <= k < n_rows``; return ``(status, last row written)``.

    Parameters
    ----------
    chunk : callable
        ``chunk(k0, k1) -> (status, k)`` (status 0: done; else diverged at ``k``).
    n_rows : int
        Rows (control instants) in all.
    work : float
        A size of the run (rows x substeps x coordinates) for the default of
        ``progress``.
    progress : bool or None
        Show a progress bar on stderr; default: when stderr is a terminal and the
        run is long (``work > 5e6``).
    block : int, optional
        Run in chunks of ``block`` rows starting at its multiples (the progress
        bar then moves once a chunk). Default: one chunk, or fifty with a
        progress bar.
    stop : threading.Event or alike, optional
        Checked before every chunk: once set, the run ends with
        :class:`~flexarm.errors.Cancelled`.

    Raises
    ------
    Cancelled
        If ``stop`` was set.
    """
    show = sys.stderr.isatty() and work > 5e6 if progress is None else bool(progress)
    if block is not None:
        bounds = np.r_[np.arange(0, n_rows, block), n_rows]
    else:
        bounds = np.linspace(0, n_rows, (50 if show else 1) + 1).astype(int)
    n_chunks = bounds.shape[0] - 1
    status, k = OK, 0
    for c in range(n_chunks):
        k0, k1 = int(bounds[c]), int(bounds[c + 1])
        if k1 <= k0:
            continue
        if stop is not None and stop.is_set():
            if show:
                sys.stderr.write("\n")
            raise Cancelled("the run was stopped before its end (its stop flag was set)")
        status, k = chunk(k0, k1)
        if show:
            _progress_bar((c + 1) / n_chunks)
        if status != OK:
            break
    if show:
        sys.stderr.write("\n")
    return int(status), min(int(k), n_rows - 1)


def _progress_bar(fraction: float) -> None:
    width = 40
    filled = round(width * fraction)
    sys.stderr.write(f"\rsimulating [{'#' * filled}{'.' * (width - filled)}] {fraction:5.1%}")
    sys.stderr.flush()


def run_scipy(
    arm: Plant,
    control: CFunc,
    params: F64,
    sensor: SensorArrays,
    reference: F64,
    dt: float,
    limit: F64,
    max_defl: F64,
    state: LoopState,
    out: LoopOutputs,
) -> tuple[int, int]:
    """The sampled-data loop with solve_ivp (DOP853, rtol 1e-10) between instants.

    Only undelayed, noise-free sensing is supported here: it is the accuracy
    reference for the integrator, not a second simulator. ``control`` is the
    controller's compiled function (``Controller.cfunc``).
    """
    from scipy.integrate import solve_ivp

    if sensor.delay_steps[0] or sensor.pade_ad.shape[0] or sensor.noise.shape[0]:
        raise InvalidValueError(
            "The 'method' parameter of simulate='scipy' supports undelayed, noise-free "
            "sensing only (it is the integrator's accuracy reference)."
        )
    n = arm.n_dof
    ms = arm.arrays.mode_start
    q, dq = state.q.copy(), state.dq.copy()
    n_rows = reference.shape[0]
    # At each instant the compiled loop, run for that one row on a copy of the state,
    # forms the measurement and the torque exactly as the fixed-step path does (its
    # own RK4 step lands in the copy and is discarded); solve_ivp then integrates
    # the plant over the period under that held torque.
    nowhere = np.zeros((0, 0))
    for k in range(n_rows):
        st = state._replace(q=q.copy(), dq=dq.copy())
        last = k == n_rows - 1
        run(
            arm.arrays,
            control,
            params,
            sensor,
            reference[k : k + 1],
            no_stream(),
            dt,
            1,
            limit,
            max_defl,
            st,
            k,
            k + 1,
            n_rows - 1,
            1,
            out["q"][k:],
            out["dq"][k:],
            out["tau"][k:],
            out["measurement"][k:],
            nowhere,  # the streamed reference's outputs: not streamed here
            nowhere,
            np.zeros(0),  # no tip recorded here (assemble_result computes it)
            nowhere,
        )
        if last:
            return OK, k
        tau = out["tau"][k].copy()

        def rhs(_t: float, x: F64, tau: F64 = tau) -> F64:
            ddq = arm.forward_dynamics(x[:n], x[n:], tau, backend="compiled")
            return np.concatenate([x[n:], ddq])

        sol = solve_ivp(rhs, (0.0, dt), np.r_[q, dq], method="DOP853", rtol=1e-10, atol=1e-12)
        x = sol.y[:, -1]
        q, dq = x[:n].copy(), x[n:].copy()
        if not np.all(np.isfinite(x)) or not sol.success:
            return DIVERGED, k
        tips = [
            arm.arrays.tip_deflection[ms[i] : ms[i + 1]] @ q[ms[i] : ms[i + 1]]
            for i in range(arm.n_links)
        ]
        if np.any(np.abs(np.array(tips)) > max_defl):
            return DIVERGED, k
    return OK, n_rows - 1
