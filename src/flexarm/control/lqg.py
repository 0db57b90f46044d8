"""An observer-based law that tracks with a distant sensor: :class:`LQG`.

Jacobian-transpose PD on a noncollocated point is unstable (the torque-to-tip
transfer function has a real right-half-plane zero pair); an observer-based
design is not, because it never inverts the plant. :class:`LQG` is a
steady-state Kalman filter and a linear-quadratic regulator, both designed from
the arm linearised at rest (:func:`flexarm.control.linearize.linearize`) and
discretised at the control period, reading **only the sensor in use** (the
sensed point's position and velocity, or the joint encoders).

Tracking. The law regulates the deviation from the rigid reference: joint
angles and rates of the reference, straight links. The simulator adds the
rigid inverse dynamics of the reference (:mod:`flexarm.control.feedforward`;
``LQG.feedforward`` is True), and the law adds ``du = -K x`` with ``x`` the
estimated deviation, the estimator driven by the measured minus the reference
output of the sensor.

The reference it asks for (:meth:`LQG.reference_smoothing`, what
:func:`flexarm.simulate` uses unless told otherwise). The feedforward carries the
reference's acceleration straight to the torques, and the loop leaves the arm's
first flexible mode nearly undamped (a damping ratio of 0.02 on the paper's arm,
at 55 rad/s): a raw corner of the square, a jump of the velocity, rings it. So
the law asks for the path smoothed by the narrowest zero-phase Gaussian that
takes the reference's content at its closed loop's slowest ringing frequency
``omega_r`` down by 40 dB, ``sigma = sqrt(2 ln 100) / omega_r`` (0.056 s on the
paper's arm, for the tip and for a point of link 2 alike).

Gain scheduling. A planar arm's dynamics depend on the joint angles only through
the elbow angle ``theta_2`` (two links), and its Cartesian outputs turn with
``theta_1``. The design is therefore repeated on a grid of ``theta_2`` spanning
the reference (``schedule_points``, evenly spaced, with a margin of 0.05 rad) at
``theta_1 = 0``, and at run time every matrix is interpolated linearly in the
reference's ``theta_2`` while Cartesian measurements are turned by ``-theta_1``.
Re-solving on the way would cost a Riccati solution per step; the grid costs a
few hundred multiply-adds.

Weights (documented defaults, SI units): the regulator penalises the end
effector's position and velocity deviation (``position_weight``,
``velocity_weight``; Bryson's rule: the inverse square of an acceptable
deviation) and the torques (``torque_weight``); the filter assumes a torque
disturbance ``torque_noise`` (N m, standing for everything the linear model
leaves out, the feedforward's mismatch included) and measurement noise
``position_noise`` and ``velocity_noise`` (m, m/s; default: the sensor's own
noise if it has some, else 1 mm and 1 cm/s; rad and rad/s for encoders).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numba as nb
import numpy as np
from numba.core.ccallback import CFunc

from .._types import F64
from .._validation import check_int, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..fuzzy import FuzzySystem, paper_system, workspace_size
from ..fuzzy._kernels import evaluate_into_kernel, unpack_system_kernel
from ..fuzzy.compiled import pack_system
from ..model.arm import FlexibleArm
from ..model.plant import Plant
from ..sensing.sensors import Sensor, TipSensor
from ._lqg_design import TABLE_REFINEMENT, Geometry, design_blocks, operating_table
from ._lqg_layout import (
    ABSOLUTE,
    FUZZY,
    GAIN,
    HEAD,
    KS,
    LAMBDA0,
    N_GRID,
    N_GRID1,
    NX,
    NY,
    OPS,
    OPS_N,
    OPS_N1,
    POINT,
    LQGLayout,
    block_parts,
    operating_parts,
    pack_parameters,
    state_parts,
)
from .controllers import Controller, gaussian_smoothing, ringing_frequency, wrap_control_function
from .linearize import linearize
from .signals import (
    r_angles,
    r_position,
    r_rates,
    r_velocity,
    y_angles,
    y_point,
    y_point_rate,
    y_rates,
)

__all__ = ["LQG", "closed_loop_growth", "lqg_law"]

_OWNER = "LQG"


@nb.njit(cache=True, nogil=True, inline="always")
def _lerp(
    p: F64, o00: int, o01: int, o10: int, o11: int, u: float, w: float, k: int
) -> float:  # pragma: no cover
    """Entry ``k`` of the blocks at ``o..`` blended bilinearly (``w`` along the elbow
    grid, ``u`` along the shoulder's; ``u = 0``: the elbow's alone, exactly)."""
    v = (1.0 - w) * p[o00 + k] + w * p[o01 + k]
    if u == 0.0:
        return float(v)
    return float((1.0 - u) * v + u * ((1.0 - w) * p[o10 + k] + w * p[o11 + k]))


@nb.njit(cache=True, nogil=True, inline="always")
def _cell(grid: F64, x: float) -> tuple[int, float]:  # pragma: no cover
    """The cell of ``grid`` (increasing) holding ``x`` and the weight of its upper end
    (clamped to [0, 1] outside; one point: cell 0, weight 0)."""
    g = grid.shape[0]
    j = 0
    while j < g - 2 and x > grid[j + 1]:
        j += 1
    w = 0.0
    if g > 1:
        w = (x - grid[j]) / (grid[j + 1] - grid[j])
        w = min(max(w, 0.0), 1.0)
    return j, w


@nb.njit(cache=True, nogil=True)
def lqg_law(t: float, y: F64, r: F64, p: F64, s: F64, tau: F64) -> None:  # pragma: no cover
    """The LQG step (module docstring); the parameter and state layout in :class:`LQG`'s
    Notes."""
    nu = tau.shape[0]
    nx, ny, ng = int(p[NX]), int(p[NY]), int(p[N_GRID])
    ng1, absolute = int(p[N_GRID1]), p[ABSOLUTE] != 0.0
    point = p[POINT] != 0.0
    gain, ks, lam0, fo = p[GAIN], p[KS], p[LAMBDA0], int(p[FUZZY])
    f_phi, f_gam, f_c, f_k, f_m, blk = block_parts(nx, nu, ny)
    base = HEAD + ng + ng1
    # --- the schedule: interpolate between the grid points around (theta_1,) theta_2
    ra = r_angles(nu)
    th1, th2 = r[ra], r[ra + 1]
    j, w = _cell(p[HEAD : HEAD + ng], th2)
    i, u = _cell(p[HEAD + ng : HEAD + ng + ng1], th1)
    j1, i1 = min(j + 1, ng - 1), min(i + 1, ng1 - 1)
    o00, o01 = base + (i * ng + j) * blk, base + (i * ng + j1) * blk
    o10, o11 = base + (i1 * ng + j) * blk, base + (i1 * ng + j1) * blk
    # the operating point: holding torques and output offset, from the finer table
    ops, width = int(p[OPS]), nu + ny
    q00 = q01 = q10 = q11 = 0
    uo = wo = 0.0
    d2 = d1 = 0.0  # the reference's rates over the table's spacings (1/s)
    if ops > 0:
        h, h1 = int(p[OPS_N]), int(p[OPS_N1])
        g2o, g1o, rows = operating_parts(ops, nu, ny, h, h1)
        jo, wo = _cell(p[g2o : g2o + h], th2)
        io, uo = _cell(p[g1o : g1o + h1], th1)
        jo1, io1 = min(jo + 1, h - 1), min(io + 1, h1 - 1)
        q00, q01 = rows + (io * h + jo) * width, rows + (io * h + jo1) * width
        q10, q11 = rows + (io1 * h + jo) * width, rows + (io1 * h + jo1) * width
        if jo1 > jo:
            d2 = r[r_rates(nu) + 1] / (p[g2o + jo1] - p[g2o + jo])
        if io1 > io:
            d1 = r[r_rates(nu)] / (p[g1o + io1] - p[g1o + io])
    s_du, s_xp, s_innov, s_fuzzy, s_gain, s_work = state_parts(nx, nu, ny)
    xh = s[0:s_du]
    du = s[s_du : s_du + nu]
    xp = s[s_xp : s_xp + nx]
    innov = s[s_innov : s_innov + ny]
    # --- prediction: xp = Phi xh + Gamma du
    for a in range(nx):
        acc = 0.0
        for b in range(nx):
            acc += (
                _lerp(p, o00 + f_phi, o01 + f_phi, o10 + f_phi, o11 + f_phi, u, w, a * nx + b)
                * xh[b]
            )
        for b in range(nu):
            acc += (
                _lerp(p, o00 + f_gam, o01 + f_gam, o10 + f_gam, o11 + f_gam, u, w, a * nu + b)
                * du[b]
            )
        xp[a] = acc
    # --- the measurement's deviation from the reference (in the design frame)
    if point:
        yp, yv, rp, rv = y_point(nu), y_point_rate(nu), r_position(nu), r_velocity(nu)
        c, sn = (1.0, 0.0) if absolute else (np.cos(th1), np.sin(th1))
        ex, ey = y[yp] - r[rp], y[yp + 1] - r[rp + 1]
        vx, vy = y[yv] - r[rv], y[yv + 1] - r[rv + 1]
        innov[0] = c * ex + sn * ey
        innov[1] = -sn * ex + c * ey
        innov[2] = c * vx + sn * vy
        innov[3] = -sn * vx + c * vy
    else:
        ya, yr, rr = y_angles(nu), y_rates(nu), r_rates(nu)
        for i in range(nu):
            innov[i] = y[ya + i] - r[ra + i]
            innov[nu + i] = y[yr + i] - r[rr + i]
    half = ny // 2
    for a in range(ny):  # less the output's offset at the operating point, and C xp
        acc = 0.0
        if ops > 0 and a < half:  # the offset (the sag) ...
            acc = _lerp(p, q00, q01, q10, q11, uo, wo, nu + a)
        elif ops > 0:  # ... and its rate along the reference: d y0/d theta . dtheta_ref
            k = nu + a - half
            f00, f01, f10, f11 = p[q00 + k], p[q01 + k], p[q10 + k], p[q11 + k]
            acc = d2 * ((1.0 - uo) * (f01 - f00) + uo * (f11 - f10))
            acc += d1 * ((1.0 - wo) * (f10 - f00) + wo * (f11 - f01))
        for b in range(nx):
            acc += _lerp(p, o00 + f_c, o01 + f_c, o10 + f_c, o11 + f_c, u, w, a * nx + b) * xp[b]
        innov[a] -= acc
    # --- measurement update and control
    for a in range(nx):
        acc = xp[a]
        for b in range(ny):
            acc += _lerp(p, o00 + f_m, o01 + f_m, o10 + f_m, o11 + f_m, u, w, a * ny + b) * innov[b]
        xh[a] = acc
    if ks > 0.0:  # fuzzy adaptation: the paper's system reads the estimated deflections
        nd = nx // 2
        x_in = s[s_fuzzy : s_fuzzy + nu]
        for i in range(nu):
            acc = 0.0
            for q in range(nd):
                acc += p[fo + i * nd + q] * xh[q]
            x_in[i] = ks * acc
        system = unpack_system_kernel(p, fo + nu * nd)
        gain = gain * evaluate_into_kernel(system, x_in, s[s_work:]) / lam0
        s[s_gain] = gain  # the last gain, for the record
    for a in range(nu):
        acc = 0.0
        for b in range(nx):
            acc -= _lerp(p, o00 + f_k, o01 + f_k, o10 + f_k, o11 + f_k, u, w, a * nx + b) * xh[b]
        du[a] = gain * acc
        tau[a] = gain * acc
        if ops > 0:  # the holding torques of the reference posture
            tau[a] += _lerp(p, q00, q01, q10, q11, uo, wo, a)


lqg_cfunc = wrap_control_function(lqg_law, cache=True)


@dataclass(frozen=True)
class LQG(Controller):
    """Observer-based LQG from the sensor in use alone (module docstring).

    Parameters
    ----------
    model : FlexibleArm, optional
        The design model (default: the simulated arm). A model with fewer modes
        than the plant is the usual case on a real arm.
    position_weight : float
        Regulator weight on the end effector's position deviation, 1/m**2.
    velocity_weight : float
        Regulator weight on its velocity deviation, s**2/m**2.
    torque_weight : float
        Regulator weight on the torques, 1/(N m)**2.
    torque_noise : float
        Filter: torque disturbance standard deviation per joint, N m.
    position_noise, velocity_noise : float, optional
        Filter: measurement noise of the sensed position and velocity (m, m/s;
        rad, rad/s for encoders). Default: the sensor's own noise and 1e-2 added
        in quadrature (``hypot``): the filter distrusts the measurement by at
        least 1 cm and 1 cm/s, standing for what the linear model leaves out
        (a slow filter is what keeps unmodelled modes out of the loop).
    schedule_points : int
        Points of the ``theta_2`` grid (>= 1).
    gain : float
        A constant scale of the feedback ``du`` (> 0; 1 is the design).
    ks : float
        Fuzzy adaptation (0: off). The paper's fuzzy system
        (:func:`flexarm.fuzzy.paper_system`, or ``fls``) reads ``ks`` times the
        links' tip deflections estimated by the filter (m) and scales the
        feedback by ``gain * lambda / lambda(0, 0)`` (1 to 5 for the paper's
        system), as :class:`~flexarm.control.adaptive.FuzzyAdaptiveJTPD` does for
        Jacobian-transpose PD. Judge it against constant gains over that range.
    fls : FuzzySystem, optional
        One input per link, centroid defuzzifier, positive output at rest.

    Notes
    -----
    The parameter vector: a header (``nx, ny``, the grid's size ``G``, the
    point-sensor flag, ``gain``, ``ks``, ``lambda0`` and the offset of the fuzzy
    part), the grid of elbow angles (``G``, rad), one block per grid point of
    ``Phi`` (nx, nx), ``Gamma`` (nx, nu), ``C`` (ny, nx), ``K`` (nu, nx) and
    ``M`` (nx, ny) row-major, then with ``ks > 0`` the links' tip-deflection rows
    (nu, nx / 2) and the packed fuzzy system. The state: the estimate (nx), the
    last ``du`` (nu), the prediction (nx) and the innovation (ny); with ``ks > 0``
    the fuzzy inputs (nu), the last gain and the fuzzy workspace. Both layouts
    are defined once, in the internal module ``flexarm.control._lqg_layout``.
    """

    model: FlexibleArm | None = None
    position_weight: float = 1e4
    velocity_weight: float = 10.0
    torque_weight: float = 1.0
    torque_noise: float = 0.3
    position_noise: float | None = None
    velocity_noise: float | None = None
    schedule_points: int = 9
    gain: float = 1.0
    ks: float = 0.0
    fls: FuzzySystem | None = None
    name = "lqg"
    feedforward = True

    @property
    def gravity_compensation(self) -> bool:  # type: ignore[override]
        """Whether the simulator adds the measured posture's holding torques: only for
        a design model without gravity given apart from the plant (a design with
        gravity holds the weight itself, module docstring)."""
        return self.model is not None and self.model.gravity is None

    def __post_init__(self) -> None:
        if self.model is not None and not isinstance(self.model, FlexibleArm):
            raise InvalidTypeError(
                f"The 'model' parameter of {_OWNER} must be a FlexibleArm. "
                f"Got {type(self.model).__name__} instead."
            )
        for name in ("position_weight", "velocity_weight", "torque_weight", "torque_noise"):
            object.__setattr__(
                self, name, check_real(getattr(self, name), name, _OWNER, positive=True)
            )
        for name in ("position_noise", "velocity_noise"):
            if getattr(self, name) is not None:
                value = check_real(getattr(self, name), name, _OWNER, positive=True)
                object.__setattr__(self, name, value)
        object.__setattr__(
            self,
            "schedule_points",
            check_int(self.schedule_points, "schedule_points", _OWNER, minimum=1),
        )
        object.__setattr__(self, "gain", check_real(self.gain, "gain", _OWNER, positive=True))
        object.__setattr__(self, "ks", check_real(self.ks, "ks", _OWNER, nonnegative=True))
        if self.fls is not None and not isinstance(self.fls, FuzzySystem):
            raise InvalidTypeError(
                f"The 'fls' parameter of {_OWNER} must be a flexarm.fuzzy.FuzzySystem. "
                f"Got {type(self.fls).__name__} instead."
            )

    @property
    def cfunc(self) -> CFunc:
        return lqg_cfunc

    def _model(self, arm: Plant) -> FlexibleArm:
        model = self.model if self.model is not None else arm
        if not isinstance(model, FlexibleArm) or model.n_links != 2:
            raise InvalidValueError(
                f"The 'model' parameter of {_OWNER} must be a two-link FlexibleArm (the "
                "schedule runs on the elbow angle). Got "
                f"{type(model).__name__} with {model.n_links} links instead."
            )
        return model

    def parameters(self, arm: Plant) -> F64:
        raise InvalidValueError(
            f"{_OWNER} is designed for a control period and a reference: simulate() calls "
            "design(arm, sensor, dt, reference)."
        )

    def initial_state(self, arm: Plant) -> F64:
        model = self._model(arm)
        nx, nu = 2 * model.n_dof, model.n_links
        ny = 4  # the largest measurement: a point's position and velocity, or 2 x 2 encoders
        _, _, _, fuzzy_inputs, gain, workspace = state_parts.py_func(nx, nu, ny)
        if self.ks <= 0:
            return np.zeros(fuzzy_inputs)
        state = np.zeros(workspace + int(workspace_size(self._fuzzy().compiled())))
        state[gain] = self.gain
        return state

    def _fuzzy(self) -> FuzzySystem:
        return paper_system() if self.fls is None else self.fls

    def _noise(self, sensor: Sensor) -> tuple[float, float]:
        pos = self.position_noise
        vel = self.velocity_noise
        if pos is None:
            pos = float(np.hypot(sensor.noise_std, _MEASUREMENT_FLOOR))
        if vel is None:
            vel = float(np.hypot(sensor.rate_noise_std, _MEASUREMENT_FLOOR))
        return float(pos), float(vel)

    def reference_smoothing(
        self,
        arm: Plant,
        sensor: Sensor | None,
        dt: float,
        path: F64,
        elbow: str = "positive",
    ) -> float:
        """The smoothing of the path this law asks for, s (module docstring):
        ``sqrt(2 ln 100) / omega_r``, 40 dB down at ``omega_r``, the slowest ringing
        frequency (:func:`~flexarm.control.controllers.ringing_frequency`: damping
        ratio below 0.5) of the design's closed loop, the regulator's poles
        ``eig(Phi - Gamma K)`` and the estimator's ``eig(Phi - M C Phi)`` (the
        separation principle), at the lowest, the middle and the highest elbow angle of
        ``path`` (end-effector points, shape (P, 2), m). 0 for a path out of reach
        (the simulator then says where).
        """
        model = self._model(arm)
        try:
            theta2 = np.asarray(model.inverse_kinematics(np.asarray(path), elbow=elbow))[:, 1]
        except ValueError:
            return 0.0
        reference = np.zeros((theta2.shape[0], 6 + 4 * model.n_links))
        reference[:, r_angles(model.n_links) + 1] = theta2
        probe = dataclasses.replace(self, schedule_points=3, ks=0.0)
        params = probe.design(model, sensor, dt, reference)
        layout = LQGLayout.of(params, model.n_links)
        poles = []
        for j in range(layout.grid(params).shape[0]):
            phi, gamma, c, k, m = layout.matrices(params, j)
            for z in (np.linalg.eigvals(phi - gamma @ k), np.linalg.eigvals(phi - m @ c @ phi)):
                poles.append(np.log(z.astype(complex)) / dt)
        return gaussian_smoothing(ringing_frequency(np.concatenate(poles)), 100.0)

    def design(self, arm: Plant, sensor: Sensor | None, dt: float, reference: F64) -> F64:
        """The parameter vector for ``arm`` read through ``sensor`` at period ``dt`` (s)
        along ``reference`` (the reference vectors of the run, shape (K, 6 + 4 N))."""
        model = self._model(arm)
        sensor = TipSensor() if sensor is None else sensor
        link, _, _ = sensor.resolve(model)
        point = link >= 0
        n_links = model.n_links
        ra = r_angles(n_links)
        grid = self._grid(reference[:, ra + 1])
        # with gravity the dynamics depend on theta_1 too: a grid of it, absolute frame
        shoulder = self._grid(reference[:, ra]) if model.gravity is not None else None
        pos_noise, vel_noise = self._noise(sensor)
        nx = 2 * model.n_dof
        link, distance, _ = sensor.resolve(model)
        geometry = Geometry(link=link, distance=distance, model=sensor.model)
        weights = (self.position_weight, self.velocity_weight, self.torque_weight)
        noises = (self.torque_noise, pos_noise, vel_noise)
        shoulder_points = None if shoulder is None else tuple(shoulder)
        blocks, ny = design_blocks(
            model, geometry, float(dt), tuple(grid), weights, noises, shoulder_points
        )
        fuzzy: list[F64] = []
        lam0 = 1.0
        if self.ks > 0:
            fls = self._fuzzy()
            if len(fls.inputs) != n_links:
                raise InvalidValueError(
                    f"The 'fls' parameter of {_OWNER} must have one input per link ({n_links}). "
                    f"Got {len(fls.inputs)} inputs instead."
                )
            lam0 = float(fls(*([0.0] * n_links)))
            if not (np.isfinite(lam0) and lam0 > 0):
                raise InvalidValueError(
                    f"The 'fls' parameter of {_OWNER} must give a positive output at rest. "
                    f"Got {lam0!r} instead."
                )
            # each link's tip deflection from the estimated coordinates, rows (n_links, n_dof)
            tips = np.zeros((n_links, model.n_dof))
            ms = model.arrays.mode_start
            for i in range(n_links):
                tips[i, ms[i] : ms[i + 1]] = model.arrays.tip_deflection[ms[i] : ms[i + 1]]
            fuzzy = [tips.ravel(), pack_system(fls.compiled())]
        head = (nx, ny, grid.shape[0], 1.0 if point else 0.0, self.gain, self.ks, lam0)
        operating = None
        if shoulder is not None:  # the weight held by the law, on a finer grid
            fine = [
                np.linspace(g[0], g[-1], TABLE_REFINEMENT * (g.shape[0] - 1) + 1)
                for g in (grid, shoulder)
            ]
            rows = operating_table(model, geometry, tuple(fine[0]), tuple(fine[1]))
            operating = (fine[0], fine[1], rows)
        return pack_parameters(head, grid, blocks, fuzzy, shoulder, operating)

    def _grid(self, angles: F64) -> F64:
        """``schedule_points`` evenly spaced over ``angles``' range and 0.05 rad beyond."""
        lo, hi = float(np.min(angles)) - 0.05, float(np.max(angles)) + 0.05
        if self.schedule_points > 1:
            return np.linspace(lo, hi, self.schedule_points)
        return np.array([0.5 * (lo + hi)])


_MEASUREMENT_FLOOR = 1e-2
"""The measurement noise the filter assumes on top of the sensor's own (m, m/s; rad,
rad/s for encoders): what the linear model leaves out of the measurement (the
unmodelled modes first)."""


def closed_loop_growth(
    plant: FlexibleArm,
    law: LQG,
    sensor: Sensor,
    dt: float,
    theta2: Sequence[float],
) -> float:
    """The largest growth rate (1/s) of ``plant`` under ``law`` with ``sensor``, both
    linearised at rest at each elbow angle of ``theta2`` (rad), the law's design
    model as it designs it, sampled at ``dt`` (s): ``log|z| / dt`` of the closed
    loop's largest eigenvalue. Negative: decaying; positive: the linear loop grows.

    The plant may differ from the law's design model (more modes, another
    boundary): this is the linear test of the robustness rows.
    """
    model = law._model(plant)
    if model.gravity is not None or plant.gravity is not None:
        raise InvalidValueError(
            "The 'plant' parameter of closed_loop_growth must be an arm without gravity (the "
            "linear loop about rest on the elbow schedule). Got an arm with gravity "
            f"{(model.gravity if model.gravity is not None else plant.gravity)!r} instead."
        )
    reference = np.zeros((len(theta2), 6 + 4 * model.n_links))
    reference[:, r_angles(model.n_links) + 1] = theta2
    params = law.design(model, sensor, dt, reference)
    layout = LQGLayout.of(params, model.n_links)
    nx = layout.nx
    grid = layout.grid(params)
    worst = -np.inf
    for th in theta2:
        j = int(np.argmin(np.abs(grid - th)))
        phi, gam, c, k, m = layout.matrices(params, j)
        p = linearize(plant, np.array([0.0, grid[j]]), sensor=sensor, rates=True).discretize(dt)
        n_p = p.n_states
        eye = np.eye(nx)
        loop = np.zeros((n_p + nx, n_p + nx))
        loop[:n_p, :n_p] = p.A
        loop[:n_p, n_p:] = -p.B @ k
        loop[n_p:, :n_p] = m @ p.C @ p.A
        loop[n_p:, n_p:] = (eye - m @ c) @ (phi - gam @ k) - m @ p.C @ p.B @ k
        radius = float(np.max(np.abs(np.linalg.eigvals(loop))))
        worst = max(worst, float(np.log(radius) / dt))
    return worst
