"""The damped extra-insensitive (EI) shaper: its five constraints solved numerically.

At ``w0 = 1 rad/s`` the unknowns are the amplitudes ``A_0..A_2``, the times ``t_1``,
``t_2`` and the two zero-vibration frequencies; the constraints are unit sum,
``V(w0) = V_tol``, a hump of ``V`` at ``w0`` and ``V = 0`` at the two frequencies
(:mod:`flexarm.control.shapers`). Powell's hybrid method solves them, continued in
damping from the undamped closed form.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidValueError

__all__ = ["ei_unit"]

_DAMPING_STEP = 0.02  # continuation step in damping
_RESIDUAL_TOL = 1e-10


def _ei_equations(x: NDArray[np.float64], z: float, v: float) -> NDArray[np.float64]:
    """EI constraints at ``w0 = 1`` for ``x = (A0, A1, A2, t1, t2, w_lo, w_hi)``."""
    amps = x[:3]
    c = complex(z, math.sqrt(1.0 - z * z))
    tau = np.array([-x[4], x[3] - x[4], 0.0])
    e0 = amps * np.exp(c * tau)
    w0 = e0.sum()
    dw0 = (c * tau * e0).sum()
    lo = (amps * np.exp(x[5] * c * tau)).sum()
    hi = (amps * np.exp(x[6] * c * tau)).sum()
    return np.array(
        [
            amps.sum() - 1.0,
            abs(w0) - v,
            (w0.conjugate() * dw0).real,  # d|W|**2/dw / 2 = 0: a hump at w0
            lo.real,
            lo.imag,
            hi.real,
            hi.imag,
        ]
    )


def ei_unit(z: float, v: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Damped EI amplitudes and times (s at ``w0 = 1 rad/s``), by continuation in ``z``."""
    from scipy.optimize import root  # loaded on first use

    xz = math.acos(-(1.0 - v) / (1.0 + v))  # zeros of the undamped closed form
    x = np.array(
        [
            (1 + v) / 4,
            (1 - v) / 2,
            (1 + v) / 4,
            math.pi,
            2 * math.pi,
            xz / math.pi,
            2 - xz / math.pi,
        ]
    )
    steps = max(1, math.ceil(z / _DAMPING_STEP))
    for zk in np.linspace(0.0, z, steps + 1)[1:]:
        with np.errstate(all="ignore"):
            sol = root(
                _ei_equations, x, args=(float(zk), v), method="hybr", options={"xtol": 1e-13}
            )
            resid = np.max(np.abs(_ei_equations(sol.x, float(zk), v)))
        xn = sol.x
        ok = (
            np.isfinite(resid)
            and resid < _RESIDUAL_TOL
            and np.all(xn[:3] > 0.0)
            and 0.0 < xn[3] < xn[4]
            and 0.0 < xn[5] < 1.0 < xn[6]
        )
        if not ok:
            raise InvalidValueError(
                f"The 'damping' parameter of ei must be small enough for the EI constraints "
                f"(tolerance={v!r}) to have a solution; none was found beyond damping "
                f"{float(zk):.3g}. Got {z!r} instead (use zvd for heavily damped modes)."
            )
        x = xn
    return x[:3].copy(), np.array([0.0, x[3], x[4]])
