"""The sampled-data check: is a control period short enough for this loop?

A controller runs at its period ``dt`` with a zero-order hold. Linearised at
rest at the start of a run (with gravity, ``FlexibleArm(gravity=...)``, about the
posture that carries its weight at the start's joint angles,
:meth:`flexarm.FlexibleArm.equilibrium`: its links' sag and gravity's tangent
stiffness), the loop is

.. math:: x_{k+1} = \\Phi x_k + \\Gamma \\tau_k, \\quad
          \\tau_k = D_c C_y x_k + C_c s_k, \\quad s_{k+1} = B_c C_y x_k + A_c s_k,

with ``Phi, Gamma`` the exact zero-order-hold discretisation of the open-loop arm
(:func:`flexarm.control.linearize.linearize`), ``C_y`` the linearised
measurement (the sensor's signals in the layout of
:mod:`flexarm.control.signals`, undelayed and noise-free) and
``A_c, B_c, C_c, D_c`` the controller's compiled law differentiated in its
measurement and its state (central differences). With gravity compensation
(:mod:`flexarm.control.gravity_compensation`) the holding torques of the
measured angles are part of the law: their derivative, the posture's static
joint stiffness under gravity ``S = V_tt - V_td (K + V_dd)^-1 V_dt``
(``V`` the gravity potential, ``t`` the joint angles, ``d`` the modal
coordinates, at the posture), is added to ``D_c`` on the measured angles; on a
rigid arm ``S`` is gravity's whole stiffness, so a compensated joint loop checks
as the horizontal arm's. The loop is sampled-data stable when every eigenvalue
of that matrix lies in the unit disc.

For a static law (no controller state), the continuous closed loop
``A + B D_c C_y`` says why: a fast real pole ``lambda`` needs roughly
``dt |lambda| < 2`` under a zero-order hold. :func:`check_sampling` finds the
largest stable period by bisection and :func:`flexarm.simulate` refuses a
period beyond it before running (``check_sampling=False`` runs it anyway).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from numba.core.ccallback import CFunc

from .._types import F64
from ..errors import InvalidValueError
from ..model.arm import FlexibleArm
from ..model.gravity import gravity_stiffness
from ..sensing.delays import discretize
from ..sensing.sensors import Sensor
from .controllers import Controller
from .linearize import linearize, measure, rest_state
from .signals import y_angles

__all__ = [
    "LinearLoop",
    "SamplingCheck",
    "check_sampling",
    "holding_stiffness",
    "linear_loop",
]

_TOLERANCE = 1e-6  # |z| up to 1 + this counts as marginal (rigid modes under no feedback)


@dataclass(frozen=True)
class SamplingCheck:
    """The result of :func:`check_sampling`.

    Attributes
    ----------
    dt : float
        The period checked, s.
    spectral_radius : float
        Largest ``|z|`` of the linearised sampled loop.
    fastest_pole : complex
        The continuous closed loop's pole of largest modulus, rad/s (static laws;
        NaN for a law with state).
    max_period : float or None
        The largest stable period, s (static laws; None when unknown).
    continuous_stable : bool
        The loop with the law applied continuously is stable (True when unknown:
        a law with state).
    """

    dt: float
    spectral_radius: float
    fastest_pole: complex
    max_period: float | None

    continuous_stable: bool = True

    @property
    def stable(self) -> bool:
        """The sampled loop is stable at ``dt``."""
        return self.spectral_radius <= 1.0 + _TOLERANCE

    @property
    def period_too_long(self) -> bool:
        """The period is what makes the loop unstable: the sampled loop is unstable
        while the loop applied continuously is stable (a static law)."""
        return not self.stable and self.continuous_stable and self.max_period is not None

    def message(self, owner: str = "simulate", note: str = "") -> str:
        """One sentence for an error: which pole, which period would work (and
        ``note``, a clause about the arm, e.g. that it has no hubs)."""
        head = (
            f"The 'dt' parameter of {owner} must make the sampled loop stable: linearised at "
            f"the start, the loop sampled at dt = {self.dt:g} s has a discrete pole at |z| = "
            f"{self.spectral_radius:.4g} > 1"
        )
        if np.isfinite(self.fastest_pole):
            head += (
                f"; the continuous closed loop's fastest pole is {_fmt(self.fastest_pole)} rad/s"
            )
        if self.max_period is not None:
            use = float(f"{0.8 * self.max_period:.1g}")
            head += (
                f", and a zero-order hold needs dt < {self.max_period:.3g} s{note}. Use dt <= "
                f"{use:g} s (or an arm with hub inertia, or lower gains)"
            )
        else:
            head += f"{note}. Use a shorter period or a law designed for this one"
        return head + ", or pass check_sampling=False to run it anyway."


def _fmt(z: complex) -> str:
    def num(x: float) -> str:
        return f"{x:,.0f}" if abs(x) >= 100 else f"{x:.4g}"

    if abs(z.imag) < 1e-9 * max(1.0, abs(z)):
        return num(z.real)
    return f"{num(z.real)} ± {num(abs(z.imag))}j"


def _controller_jacobians(
    controller: Controller,
    params: F64,
    state: F64,
    y0: F64,
    r0: F64,
) -> tuple[F64, F64, F64, F64]:
    """``(A_c, B_c, C_c, D_c)``: the law's next state and torque differentiated in
    its state and measurement, by central differences (all the law's evaluations
    in one compiled call)."""
    n_s, n_y = state.shape[0], y0.shape[0]
    hy = 1e-6 * np.maximum(1.0, np.abs(y0))
    hs = 1e-6 * np.maximum(1.0, np.abs(state))
    # rows: +h then -h along each measurement, then along each state
    ys = np.tile(y0, (2 * (n_y + n_s), 1))
    states = np.tile(state, (2 * (n_y + n_s), 1))
    ys[:n_y] += np.diag(hy)
    ys[n_y : 2 * n_y] -= np.diag(hy)
    states[2 * n_y : 2 * n_y + n_s] += np.diag(hs)
    states[2 * n_y + n_s :] -= np.diag(hs)
    n_links = controller(0.0, y0, r0, params, state.copy()).shape[0]
    taus = np.zeros((ys.shape[0], n_links))
    _law_rows(controller.cfunc, ys, np.ascontiguousarray(r0, dtype=float), params, states, taus)
    dy, ds = 2 * hy[:, None], 2 * hs[:, None]  # each row's step
    d_c = ((taus[:n_y] - taus[n_y : 2 * n_y]) / dy).T
    b_c = ((states[:n_y] - states[n_y : 2 * n_y]) / dy).T
    c_c = ((taus[2 * n_y : 2 * n_y + n_s] - taus[2 * n_y + n_s :]) / ds).T
    a_c = ((states[2 * n_y : 2 * n_y + n_s] - states[2 * n_y + n_s :]) / ds).T
    return a_c, b_c, c_c, d_c


@nb.njit(cache=True, nogil=True)
def _law_rows(
    control: CFunc, ys: F64, r: F64, params: F64, states: F64, taus: F64
) -> None:  # pragma: no cover - compiled
    """The compiled law at ``t = 0`` on each row of ``ys`` with the state in the same
    row of ``states`` (updated in place), torques into ``taus``."""
    for j in range(ys.shape[0]):
        y, s, tau = ys[j], states[j], taus[j]
        control(
            0.0,
            y.ctypes,
            y.shape[0],
            r.ctypes,
            r.shape[0],
            params.ctypes,
            params.shape[0],
            s.ctypes,
            s.shape[0],
            tau.ctypes,
            tau.shape[0],
        )


@dataclass(frozen=True)
class LinearLoop:
    """The linearised loop's pieces (module docstring): the open-loop arm ``(A, B)``,
    the measurement ``C_y`` and the law's ``(A_c, B_c, C_c, D_c)``."""

    A: F64
    B: F64
    C_y: F64
    A_c: F64
    B_c: F64
    C_c: F64
    D_c: F64

    @property
    def is_static(self) -> bool:
        """The law's state does not feed its torque (``C_c = 0``)."""
        return not np.any(self.C_c)

    def continuous(self) -> F64:
        """``A + B D_c C_y``: the loop with the law applied continuously, its state held."""
        return self.A + self.B @ self.D_c @ self.C_y

    def sampled(self, dt: float) -> F64:
        """The sampled loop's matrix at period ``dt`` (exact zero-order hold)."""
        n2, m = self.B.shape
        phi, gamma, _, _ = discretize(self.A, self.B, np.zeros((1, n2)), np.zeros((1, m)), dt)
        n_s = self.A_c.shape[0]
        out = np.zeros((n2 + n_s, n2 + n_s))
        out[:n2, :n2] = phi + gamma @ self.D_c @ self.C_y
        out[:n2, n2:] = gamma @ self.C_c
        out[n2:, :n2] = self.B_c @ self.C_y
        out[n2:, n2:] = self.A_c
        return out


def holding_stiffness(arm: FlexibleArm, q: F64) -> F64:
    """``d tau_eq / d theta`` (N m/rad, shape (n_links, n_links)): how the holding
    torques of gravity compensation change with the joint angles at the posture
    ``q`` (shape (n_dof,), its links' static sag; module docstring), the Schur
    complement of the modal block in gravity's Hessian plus the links' stiffness.
    Zeros without gravity."""
    n_links = arm.n_links
    if arm.gravity is None:
        return np.zeros((n_links, n_links))
    h = gravity_stiffness(arm, q)
    j = np.arange(n_links)
    m = np.arange(n_links, int(arm.arrays.mode_start[-1]))
    out = h[np.ix_(j, j)]
    if m.size:
        k = np.diag(np.asarray(arm.arrays.stiffness, dtype=float)[m]) + h[np.ix_(m, m)]
        out = out - h[np.ix_(j, m)] @ np.linalg.solve(k, h[np.ix_(m, j)])
    return np.asarray(out, dtype=float)


def linear_loop(
    arm: FlexibleArm,
    controller: Controller,
    sensor: Sensor,
    theta: F64,
    reference: F64,
    params: F64,
    state: F64,
    gravity_compensation: bool = False,
) -> LinearLoop:
    """The loop linearised at rest at ``theta`` (rad), with the controller's parameters,
    state and a reference vector; with gravity about the posture that carries its
    weight, and ``gravity_compensation``'s holding torques in the law (module
    docstring)."""
    n = arm.n_dof
    plant = linearize(arm, theta)
    q0 = rest_state(arm, theta)
    if arm.gravity is not None:  # the sagging posture linearize linearised about
        q0 = arm.equilibrium(theta).q
    h = 1e-7  # central differences: the state at rest, then +h and -h along each coordinate
    steps = np.concatenate([np.zeros((1, 2 * n)), h * np.eye(2 * n), -h * np.eye(2 * n)])
    ys = measure(arm, sensor, q0 + steps[:, :n], steps[:, n:], 1e-5)
    y0 = ys[0]
    c_y = ((ys[1 : 2 * n + 1] - ys[2 * n + 1 :]) / (2 * h)).T
    a_c, b_c, c_c, d_c = _controller_jacobians(controller, params, state, y0, reference)
    if gravity_compensation and arm.gravity is not None:
        ya = y_angles(arm.n_links)
        d_c = d_c.copy()
        d_c[:, ya : ya + arm.n_links] += holding_stiffness(arm, q0)
    return LinearLoop(plant.A, plant.B, c_y, a_c, b_c, c_c, d_c)


def _radius(matrix: F64) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(matrix)))) if matrix.size else 0.0


def check_sampling(
    arm: FlexibleArm,
    controller: Controller,
    sensor: Sensor,
    theta: F64,
    reference: F64,
    params: F64,
    state: F64,
    dt: float,
    gravity_compensation: bool = False,
) -> SamplingCheck:
    """Check the period ``dt`` (module docstring) at rest at ``theta`` (rad), with the
    controller's parameters, initial state and first reference vector.

    With gravity the loop is linearised about the posture that carries its weight
    at ``theta``; ``gravity_compensation`` (what :func:`flexarm.simulate` adds to the
    law's torque) puts the holding torques' derivative in the law. The largest
    stable period is searched for static laws only (a law whose state feeds its
    torque, e.g. an observer, was designed for its period).
    """
    if not dt > 0:
        raise InvalidValueError(f"The 'dt' parameter of check_sampling must be > 0. Got {dt}.")
    loop = linear_loop(
        arm, controller, sensor, theta, reference, params, state, gravity_compensation
    )
    radius = _radius(loop.sampled(dt))
    fastest: complex = complex("nan")
    max_period = None
    continuous_stable = True
    if loop.is_static:
        poles = np.linalg.eigvals(loop.continuous())
        fastest = complex(poles[np.argmax(np.abs(poles))])
        continuous_stable = bool(np.all(poles.real < 1e-9 * max(1.0, float(np.max(np.abs(poles))))))
        if radius > 1.0 + _TOLERANCE and continuous_stable:
            max_period = _largest_stable_period(loop, dt)
    return SamplingCheck(dt, radius, fastest, max_period, continuous_stable)


def _largest_stable_period(loop: LinearLoop, dt: float) -> float | None:
    """Bisection below ``dt`` for the stability boundary (None if even ``dt / 2**14``
    is unstable)."""

    def stable(h: float) -> bool:
        return _radius(loop.sampled(h)) <= 1.0 + _TOLERANCE

    lo = dt
    for _ in range(14):
        lo /= 2.0
        if stable(lo):
            break
    else:
        return None
    hi = 2.0 * lo
    while hi - lo > 1e-4 * lo:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo
