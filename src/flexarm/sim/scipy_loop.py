"""The closed loop with SciPy's adaptive integrator: the accuracy reference.

:func:`run_scipy` runs the same sampled-data loop as :mod:`flexarm.sim.loop`, but
integrates the plant between control instants with ``solve_ivp`` (DOP853, rtol
1e-10) instead of fixed RK4 substeps: ``simulate(..., method="scipy")``, the
reference the fixed-step integrator is checked against. Only undelayed,
noise-free sensing recorded at every instant is supported: it is a reference, not
a second simulator.
"""

from __future__ import annotations

import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import NDArray

from ..errors import InvalidValueError
from ..model.plant import Plant
from .chunks import DIVERGED, OK
from .loop import Loop, run

__all__ = ["run_scipy"]

F64 = NDArray[np.float64]


def run_scipy(arm: Plant, loop: Loop, control: CFunc, reference: F64) -> tuple[int, int]:
    """The sampled-data loop with ``solve_ivp`` between instants; ``(status, k)``.

    Parameters
    ----------
    arm : FlexibleArm
        The plant (its compiled forward dynamics between instants).
    loop : Loop
        The run's inputs (:func:`flexarm.sim.loop.loop_inputs`, recording every
        instant); its state and outputs are written.
    control : CFunc
        The law's compiled function (``Controller.cfunc``).
    reference : ndarray, shape (n_steps + 1, reference_size)
        The reference at every instant.
    """
    from scipy.integrate import solve_ivp

    sensor = loop.sensor
    if sensor.delay_steps[0] or sensor.pade_ad.shape[0] or np.any(sensor.levels > 0):
        raise InvalidValueError(
            "The 'method' parameter of simulate='scipy' supports undelayed, noise-free "
            "sensing only (it is the integrator's accuracy reference)."
        )
    model = loop.model
    n = loop.state.q.shape[0]
    ms = model.mode_start
    n_links = model.link.shape[0]
    q, dq = loop.state.q.copy(), loop.state.dq.copy()
    n_rows = reference.shape[0]
    no_noise = np.zeros((0, sensor.levels.shape[0]))
    # At each instant the compiled loop, run for that one row on a copy of the state,
    # forms the measurement and the torque exactly as the fixed-step path does (its
    # own RK4 step lands in the copy and is discarded); solve_ivp then integrates
    # the plant over the period under that held torque.
    step = loop._replace(substeps=1, n_steps=n_rows - 1, every=1)
    for k in range(n_rows):
        one = step._replace(state=step.state._replace(q=q.copy(), dq=dq.copy()))
        run(one, control, reference[k : k + 1], no_noise, k, k + 1)
        if k == n_rows - 1:
            return OK, k
        tau = loop.out.tau[k].copy()

        def rhs(_t: float, x: F64, tau: F64 = tau) -> F64:
            ddq = arm.forward_dynamics(x[:n], x[n:], tau, backend="compiled")
            return np.concatenate([x[n:], ddq])

        sol = solve_ivp(rhs, (0.0, loop.dt), np.r_[q, dq], method="DOP853", rtol=1e-10, atol=1e-12)
        x = sol.y[:, -1]
        q, dq = x[:n].copy(), x[n:].copy()
        if not np.all(np.isfinite(x)) or not sol.success:
            return DIVERGED, k
        tips = [
            model.tip_deflection[ms[i] : ms[i + 1]] @ q[ms[i] : ms[i + 1]] for i in range(n_links)
        ]
        if np.any(np.abs(np.array(tips)) > loop.max_deflection):
            return DIVERGED, k
    return OK, n_rows - 1
