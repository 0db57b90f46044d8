r"""Identify a flexible joint's nonlinearities from a random-torque experiment (paper §IX).

The paper closes with "experiments will be reported in the future": identify
a real manipulator's joint nonlinearity by the nonparametric methods of its
§VI–VIII. :func:`identify_joint` does that on the simulated robot and compares
every estimate with the truth the simulation knows.

Experiment
----------
One rigid link (``n_modes = 0``) on a :class:`~flexarm.NonlinearJoint` with
Makkar friction on the link side and a motor-side (back-EMF) damping
``c_m`` — :func:`joint_test_arm`. The motor drive turns a commanded torque
``u`` into the applied torque ``tau = phi(u)`` with a dead band and a
saturation (:class:`DriveNonlinearity`). The command is a seeded
piecewise-constant random sequence, ``u ~ U(-amplitude, amplitude)`` i.i.d.,
held for ``hold`` seconds; :func:`flexarm.simulate` plays it through
a :class:`~flexarm.control.controllers.CompiledController` (open loop) at the sample
period ``dt`` (default 0.2 ms).

Measurements (:class:`JointSensors`; Gaussian noise, seeded)
    * motor and link encoders: ``q_m``, ``q`` (rad) and their rates (rad/s);
    * the motor current, giving the applied torque ``tau`` (N m);
    * optionally a joint torque sensor (``tau_s`` directly, N m);
    * a link accelerometer with an integrate-and-dump filter over each hold:
      the mean link acceleration over the hold (rad/s**2).

(a) Static identification
-------------------------
*Stiffness torque* ``tau_s(Delta)``, ``Delta = q_m - q`` from the two encoders:

* ``torque_measurement="motor-balance"`` (default): the motor's equation
  ``J_m qdd_m + c_m qd_m + tau_s = tau`` gives
  ``tau_s = tau - c_m qd_m - J_m qdd_m`` with ``qdd_m`` the central difference
  of the measured motor rate; samples where the torque switches (the central
  difference straddles a jump of ``qdd_m``) are dropped, and so is the faster
  half of the rest (by the measured deflection rate ``|qd_m - qd|``): the
  central difference errs by about ``tau_s''(Delta) dDelta/dt**2 dt**2 / 6``,
  and at 0.2 ms the joint ringing crosses the soft-windup region (where
  ``tau_s''`` is large) in two or three samples — on all samples the windup
  stiffness comes out about 40 % too high. ``J_m`` and ``c_m`` are the
  motor's data-sheet values.
* ``torque_measurement="sensor"``: a joint torque sensor reads ``tau_s``.

*Friction* ``f(v)``: the link's equation ``I qdd = tau_s - f(qd)``, averaged
over a sliding window of ``friction_window`` samples so that the noisy
acceleration enters only as ``(qd(t + T) - qd(t)) / T``:
``f_bar = mean(tau_s) - I (qd(t+T) - qd(t)) / T`` paired with ``mean(qd)``
(``I`` from the link's model). Then both curves are estimated by the paper's
semi-recursive kernel regression (eq. 14,
:class:`~flexarm.ident.SemiRecursiveKernelRegression`, Epanechnikov kernel,
``h_1`` a fixed fraction of the regressor's standard deviation, ``decay``
0.2) on a grid spanning the central 99 % (stiffness) and 98 % (friction) of
the data.

(b) Hammerstein model
---------------------
From the commanded torque ``u_n`` (one value per hold) to the accelerometer
output ``y_n``: :class:`~flexarm.ident.HammersteinIdentifier` fitted to the
first ``1 - validation_fraction`` of the record, with the two-point
normalisation from the drive's data sheet (``phi(0) = 0`` and the rated
torque at 80 % command). Its static part is compared with the true drive
map; its free-run prediction is scored on the held-out rest (fit %), beside
the *reference fit* of a least-squares FIR model driven by the **true**
``phi(u)`` — the best any Hammerstein model with that FIR length can do on
this plant, whose joint stiffness and friction (nonlinear, inside the
feedback) are not of Hammerstein form.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._io import atomic_path
from .._validation import check_int, check_option, check_real, validate_real_fields
from ..control.controllers import CompiledController
from ..errors import InvalidTypeError, InvalidValueError
from ..ident.hammerstein import HammersteinIdentifier, fit_percent
from ..ident.regression import SemiRecursiveKernelRegression
from ..ident.systems import as_generator
from ..model.arm import FlexibleArm
from ..model.joints import LinearJoint, MakkarFriction, NonlinearJoint
from ..model.link import Link
from ..sim.closed_loop import simulate

__all__ = [
    "CurveEstimate",
    "DriveNonlinearity",
    "JointExcitation",
    "JointIdentification",
    "JointSensors",
    "identify_joint",
    "joint_test_arm",
]

F64 = NDArray[np.float64]
_OWNER = "identify_joint"
_MEASUREMENTS = ("motor-balance", "sensor")


# --------------------------------------------------------------------------- parameters


@dataclass(frozen=True)
class DriveNonlinearity:
    """The motor drive's static map from commanded to applied torque (N m to N m).

    ``phi(u) = clip(sign(u) max(|u| - dead_band, 0), -limit, limit)``: a dead
    band (static friction of the gear, amplifier offset) and current limiting.

    Parameters
    ----------
    dead_band : float
        Half-width of the dead band, N m (>= 0).
    limit : float
        Saturation level, N m (> 0).

    Examples
    --------
    >>> DriveNonlinearity(2.0, 40.0)([-50.0, 1.0, 10.0])
    array([-40.,   0.,   8.])
    """

    dead_band: float = 2.0
    limit: float = 40.0

    def __post_init__(self) -> None:
        validate_real_fields(
            self, "DriveNonlinearity", positive=("limit",), nonnegative=("dead_band",)
        )

    def __call__(self, u: ArrayLike) -> F64:
        v = np.asarray(u, dtype=np.float64)
        out: F64 = np.clip(
            np.sign(v) * np.maximum(np.abs(v) - self.dead_band, 0.0), -self.limit, self.limit
        )
        return out


@dataclass(frozen=True)
class JointExcitation:
    """The random-torque experiment.

    Parameters
    ----------
    duration : float
        Length of the record, s (> 0).
    dt : float
        Simulation and sampling period, s (default 0.2 ms).
    hold : float
        Hold time of each random command, s; also the Hammerstein sample
        period. Rounded to a whole number of ``dt``.
    amplitude : float
        Commands are ``U(-amplitude, amplitude)``, N m.
    drive : DriveNonlinearity
        The drive's static map (the Hammerstein part's true ``phi``).
    """

    duration: float = 60.0
    dt: float = 2e-4
    hold: float = 0.01
    amplitude: float = 60.0
    drive: DriveNonlinearity = field(default_factory=DriveNonlinearity)

    def __post_init__(self) -> None:
        validate_real_fields(
            self, "JointExcitation", positive=("duration", "dt", "hold", "amplitude")
        )
        if not isinstance(self.drive, DriveNonlinearity):
            raise InvalidTypeError(
                "The 'drive' parameter of JointExcitation must be a DriveNonlinearity. "
                f"Got {type(self.drive).__name__} instead."
            )
        if self.hold < self.dt:
            raise InvalidValueError(
                f"The 'hold' parameter of JointExcitation must be >= dt = {self.dt}. "
                f"Got {self.hold} instead."
            )

    @property
    def hold_steps(self) -> int:
        """Samples per held command."""
        return max(1, round(self.hold / self.dt))


@dataclass(frozen=True)
class JointSensors:
    """Noise levels (standard deviations) of the measured signals.

    Parameters
    ----------
    angle_noise : float
        Motor and link encoders, rad.
    rate_noise : float
        Motor and link rates, rad/s.
    torque_noise : float
        Applied torque from the motor current, N m.
    torque_sensor_noise : float
        Joint torque sensor (``torque_measurement="sensor"``), N m.
    acceleration_noise : float
        Link accelerometer (after its hold-period filter), rad/s**2.
    """

    angle_noise: float = 1e-6
    rate_noise: float = 1e-4
    torque_noise: float = 0.05
    torque_sensor_noise: float = 0.1
    acceleration_noise: float = 0.01

    def __post_init__(self) -> None:
        validate_real_fields(
            self,
            "JointSensors",
            nonnegative=(
                "angle_noise",
                "rate_noise",
                "torque_noise",
                "torque_sensor_noise",
                "acceleration_noise",
            ),
        )


def joint_test_arm(
    joint: NonlinearJoint | LinearJoint | None = None, motor_damping: float = 10.0
) -> FlexibleArm:
    """One rigid link (the paper's 4.5 m link as a rod) on a flexible joint with friction.

    Parameters
    ----------
    joint : NonlinearJoint or LinearJoint, optional
        Default: :meth:`NonlinearJoint.default` with :meth:`MakkarFriction.default`
        and the given ``motor_damping``.
    motor_damping : float
        Motor-side damping ``c_m`` for the default joint, N m s/rad: a drive's
        back-EMF damping, which damps the joint mode (about 120–180 rad/s)
        to a damping ratio of about 0.1.

    Returns
    -------
    FlexibleArm
        ``q = (theta, q_m)``.
    """
    if joint is None:
        base = NonlinearJoint.default(friction=MakkarFriction.default())
        joint = NonlinearJoint(
            base.a1,
            base.a2,
            base.ksw,
            base.asw,
            base.motor_inertia,
            friction=base.friction,
            motor_damping=check_real(motor_damping, "motor_damping", "joint_test_arm"),
        )
    link = Link(4.5, 1676.0, 0.335, n_modes=0)
    return FlexibleArm(links=(link,), joints=(joint,))


# --------------------------------------------------------------------------- simulation


@nb.njit(cache=True)
def _play(t, y, r, params, state, tau):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Open loop: ``tau = params[1 + k]`` at the ``k``-th instant ``t = k params[0]``."""
    k = int(t / params[0] + 0.5)
    last = params.shape[0] - 2
    if k > last:
        k = last
    tau[0] = params[1 + k]


class _Still:
    """A reference that stays at the origin (the open-loop law ignores it)."""

    corner_times: tuple[float, ...] = ()

    def __init__(self, duration: float) -> None:
        self.duration = duration

    def evaluate(self, t: ArrayLike) -> tuple[F64, F64, F64]:
        n = np.atleast_1d(np.asarray(t, dtype=np.float64)).shape[0]
        z = np.zeros((n, 2))
        return z, z, z


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class CurveEstimate:
    """An estimated static curve beside the true one, on a common grid.

    Attributes
    ----------
    name : str
    x : ndarray, shape (g,)
        Grid (units ``x_unit``).
    estimate, truth : ndarray, shape (g,)
        Estimated and true values (units ``y_unit``); NaN where no sample reached.
    x_unit, y_unit : str
    """

    name: str
    x: F64
    estimate: F64
    truth: F64
    x_unit: str
    y_unit: str

    @property
    def rms_error(self) -> float:
        """Root-mean-square error over the grid, units of ``y``."""
        ok = np.isfinite(self.estimate)
        return float(np.sqrt(np.mean((self.estimate[ok] - self.truth[ok]) ** 2)))

    @property
    def max_error(self) -> float:
        """Largest absolute error over the grid, units of ``y``."""
        ok = np.isfinite(self.estimate)
        return float(np.max(np.abs(self.estimate[ok] - self.truth[ok])))

    @property
    def relative_rms_error(self) -> float:
        """:attr:`rms_error` over the range of the true curve on the grid (NaN if flat)."""
        spread = float(np.ptp(self.truth))
        return self.rms_error / spread if spread > 0.0 else math.nan

    def summary(self) -> dict[str, Any]:
        """Error figures as a JSON-able dict."""
        return {
            "grid": [float(self.x[0]), float(self.x[-1])],
            "x_unit": self.x_unit,
            "y_unit": self.y_unit,
            "rms_error": self.rms_error,
            "max_error": self.max_error,
            "relative_rms_error": (
                None if math.isnan(self.relative_rms_error) else self.relative_rms_error
            ),
        }


@dataclass(frozen=True)
class JointIdentification:
    """What :func:`identify_joint` found, beside the truth.

    Attributes
    ----------
    stiffness : CurveEstimate
        ``tau_s(Delta)``: rad to N m.
    friction : CurveEstimate
        ``f(v)``: rad/s to N m.
    drive : CurveEstimate
        The Hammerstein model's static part against the true drive map, N m to N m.
    windup : dict
        Secant stiffness (N m/rad) of the estimate and the truth inside the
        soft-windup region (``|Delta| <= 0.2 / sqrt(asw)``) and outside it
        (between ``2`` and ``4 / sqrt(asw)``, both signs); empty for a linear joint.
    hammerstein : HammersteinIdentifier
        The fitted model (commanded torque, N m, to link acceleration, rad/s**2).
    validation : dict of str to ndarray
        ``"u"``, ``"y"``, ``"y_hat"`` on the held-out part, and ``"t"`` (s).
    fit_percent : float
        Free-run fit of the Hammerstein model on the held-out part, %.
    reference_fit_percent : float
        Fit of a least-squares FIR model driven by the true ``phi(u)``, %.
    info : dict
        Settings (JSON-able).
    """

    stiffness: CurveEstimate
    friction: CurveEstimate
    drive: CurveEstimate
    windup: dict[str, float]
    hammerstein: HammersteinIdentifier
    validation: dict[str, F64]
    fit_percent: float
    reference_fit_percent: float
    info: dict[str, Any]

    def summary(self) -> dict[str, Any]:
        """Error figures and settings as a JSON-able dict."""
        return {
            "stiffness": self.stiffness.summary(),
            "friction": self.friction.summary(),
            "drive": self.drive.summary(),
            "windup": dict(self.windup),
            "hammerstein": {
                "fit_percent": self.fit_percent,
                "reference_fit_percent": self.reference_fit_percent,
                "arma_order": self.hammerstein.order_,
                "a": list(self.hammerstein.arma_.a),
                "b": list(self.hammerstein.arma_.b),
                "impulse_response": self.hammerstein.impulse_response_.tolist(),
            },
            "info": dict(self.info),
        }

    def save(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``summary.json``, ``curves.npz`` and ``identify_joint.png`` into ``directory``.

        Each file is written atomically; the directory is created if needed.

        Returns
        -------
        list of Path
            The files written.
        """
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "summary.json", out / "curves.npz", out / "identify_joint.png"]
        with atomic_path(paths[0]) as tmp:
            tmp.write_text(json.dumps(self.summary(), indent=2) + "\n")
        arrays: dict[str, F64] = {}
        for curve in (self.stiffness, self.friction, self.drive):
            arrays[f"{curve.name}_x"] = curve.x
            arrays[f"{curve.name}_estimate"] = curve.estimate
            arrays[f"{curve.name}_truth"] = curve.truth
        arrays["impulse_response"] = self.hammerstein.impulse_response_
        with atomic_path(paths[1]) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays)  # type: ignore[arg-type]
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        fig = self.plot()
        with atomic_path(paths[2]) as tmp:
            fig.savefig(tmp, format="png", dpi=110)
        plt.close(fig)
        return paths

    def plot(self, fig: Any = None) -> Any:
        """Four panels: stiffness (with the windup region enlarged), friction, drive, validation.

        Returns the matplotlib figure (never blocks).
        """
        import matplotlib.pyplot as plt

        if fig is None:
            fig = plt.figure(figsize=(11, 7.5), layout="constrained")
        axes = fig.subplots(2, 2)
        s = self.stiffness
        ax = axes[0, 0]
        ax.plot(1e3 * s.x, s.truth, "k--", lw=1, label="true")
        ax.plot(1e3 * s.x, s.estimate, lw=1.2, label="estimate")
        ax.set(xlabel="deflection Δ [mrad]", ylabel="τ_s [N m]", title="joint stiffness torque")
        ax.legend(loc="upper left", fontsize="small")
        w = self.info.get("windup_width_rad")
        if w:
            inset = ax.inset_axes((0.58, 0.08, 0.38, 0.38))
            sel = np.abs(s.x) <= 3 * w
            inset.plot(1e3 * s.x[sel], s.truth[sel], "k--", lw=1)
            inset.plot(1e3 * s.x[sel], s.estimate[sel], lw=1.2)
            inset.set_title("soft windup", fontsize="small")
            inset.tick_params(labelsize="x-small")
        f = self.friction
        ax = axes[0, 1]
        ax.plot(f.x, f.truth, "k--", lw=1, label="true")
        ax.plot(f.x, f.estimate, lw=1.2, label="estimate")
        ax.set(xlabel="link rate v [rad/s]", ylabel="f(v) [N m]", title="joint friction")
        ax.legend(loc="best", fontsize="small")
        d = self.drive
        ax = axes[1, 0]
        ax.plot(d.x, d.truth, "k--", lw=1, label="true drive map")
        ax.plot(d.x, d.estimate, lw=1.2, label="Hammerstein φ̂")
        ax.set(xlabel="command u [N m]", ylabel="torque [N m]", title="drive nonlinearity")
        ax.legend(loc="best", fontsize="small")
        v = self.validation
        ax = axes[1, 1]
        m = min(200, v["t"].shape[0])
        ax.plot(v["t"][:m], v["y"][:m], "k", lw=0.8, label="measured")
        ax.plot(v["t"][:m], v["y_hat"][:m], lw=1.0, label=f"model ({self.fit_percent:.1f} %)")
        ax.set(xlabel="t [s]", ylabel="link acceleration [rad/s²]", title="held-out data")
        ax.legend(loc="best", fontsize="small")
        return fig


# --------------------------------------------------------------------------- identification


def _window_mean(x: F64, m: int) -> F64:
    """Trapezoid mean of ``x`` over samples ``k .. k + m``, shape (n - m,)."""
    c = np.r_[0.0, np.cumsum(0.5 * (x[1:] + x[:-1]))]
    out: F64 = (c[m:] - c[:-m]) / m
    return out


def _held_mean(x: F64, m: int) -> F64:
    """Mean of the held values ``x[k] .. x[k + m - 1]``, shape (n - m,)."""
    c = np.r_[0.0, np.cumsum(x)]
    out: F64 = (c[m : x.shape[0]] - c[: x.shape[0] - m]) / m
    return out


def _curve(
    name: str,
    x: F64,
    y: F64,
    truth: Any,
    quantile: float,
    relative_bandwidth: float,
    units: tuple[str, str],
    grid_size: int = 401,
) -> CurveEstimate:
    lo, hi = np.quantile(x, [quantile, 1.0 - quantile])
    grid = np.linspace(lo, hi, grid_size)
    reg = SemiRecursiveKernelRegression(
        kernel="epanechnikov",
        bandwidth=relative_bandwidth * float(np.std(x)),
        decay=0.2,
        grid=grid,
    ).fit(x, y)
    return CurveEstimate(name, grid, reg.predict(grid), np.asarray(truth(grid)), *units)


def _secant(x: F64, y: F64, a: float, b: float) -> float:
    ya, yb = np.interp([a, b], x, y)
    return float((yb - ya) / (b - a))


def _fir_reference(w: F64, y: F64, n_fit: int, n_lags: int) -> float:
    """Fit % on ``[n_fit:]`` of a least-squares FIR(n_lags) + offset from ``w`` to ``y``."""
    n = w.shape[0]
    cols = [np.r_[np.zeros(k), w[: n - k]] for k in range(n_lags)]
    X = np.column_stack([*cols, np.ones(n)])
    coef = np.linalg.lstsq(X[:n_fit], y[:n_fit], rcond=None)[0]
    return fit_percent(y[n_fit:], X[n_fit:] @ coef)


def identify_joint(
    arm: FlexibleArm | None = None,
    excitation: JointExcitation | None = None,
    sensors: JointSensors | None = None,
    *,
    torque_measurement: str = "motor-balance",
    friction_window: int = 25,
    quasi_static_fraction: float = 0.5,
    stiffness_bandwidth: float = 0.02,
    friction_bandwidth: float = 0.05,
    n_lags: int = 40,
    validation_fraction: float = 1.0 / 3.0,
    rng: np.random.Generator | int | None = 0,
) -> JointIdentification:
    """Excite the joint with a random torque and identify its nonlinearities (module docstring).

    Parameters
    ----------
    arm : FlexibleArm, optional
        One rigid link (``n_modes = 0``) on a flexible joint; default
        :func:`joint_test_arm` ().
    excitation : JointExcitation, optional
        The experiment (default ``JointExcitation()``: 60 s at 0.2 ms).
    sensors : JointSensors, optional
        Noise levels (default ``JointSensors()``).
    torque_measurement : {"motor-balance", "sensor"}
        How ``tau_s`` is measured (module docstring).
    quasi_static_fraction : float
        With ``"motor-balance"``, the fraction of samples kept for the stiffness
        curve: those with the smallest measured deflection rate
        ``|qd_m - qd|`` (0 < fraction <= 1; module docstring).
    friction_window : int
        Samples ``m`` of the sliding window of the link's torque balance (>= 1).
    stiffness_bandwidth, friction_bandwidth : float
        ``h_1`` of the kernel regressions as a fraction of the regressor's
        standard deviation (> 0).
    n_lags : int
        Impulse-response length of the Hammerstein model, in holds.
    validation_fraction : float
        Trailing part of the record held out to score the Hammerstein model
        (0 < fraction < 1).
    rng : numpy.random.Generator or int, optional
        Source of the commands and the sensor noise (default seed 0).

    Returns
    -------
    JointIdentification
    """
    arm = joint_test_arm() if arm is None else arm
    if not isinstance(arm, FlexibleArm):
        raise InvalidTypeError(
            f"The 'arm' parameter of {_OWNER} must be a FlexibleArm. "
            f"Got {type(arm).__name__} instead."
        )
    if arm.n_links != 1 or arm.joints is None or arm.n_modes != (0,):
        raise InvalidValueError(
            f"The 'arm' parameter of {_OWNER} must be one rigid link (n_modes=0) on a "
            f"flexible joint. Got {arm.n_links} link(s), modes {arm.n_modes}, "
            f"joints {'none' if arm.joints is None else 'flexible'} instead."
        )
    excitation = JointExcitation() if excitation is None else excitation
    sensors = JointSensors() if sensors is None else sensors
    for name, value, kind in (
        ("excitation", excitation, JointExcitation),
        ("sensors", sensors, JointSensors),
    ):
        if not isinstance(value, kind):
            raise InvalidTypeError(
                f"The '{name}' parameter of {_OWNER} must be a {kind.__name__}. "
                f"Got {type(value).__name__} instead."
            )
    check_option(torque_measurement, "torque_measurement", _OWNER, _MEASUREMENTS)
    quasi_static_fraction = check_real(
        quasi_static_fraction, "quasi_static_fraction", _OWNER, positive=True
    )
    if quasi_static_fraction > 1.0:
        raise InvalidValueError(
            f"The 'quasi_static_fraction' parameter of {_OWNER} must be <= 1. "
            f"Got {quasi_static_fraction} instead."
        )
    friction_window = check_int(friction_window, "friction_window", _OWNER, minimum=1)
    stiffness_bandwidth = check_real(
        stiffness_bandwidth, "stiffness_bandwidth", _OWNER, positive=True
    )
    friction_bandwidth = check_real(friction_bandwidth, "friction_bandwidth", _OWNER, positive=True)
    n_lags = check_int(n_lags, "n_lags", _OWNER, minimum=10)
    validation_fraction = check_real(validation_fraction, "validation_fraction", _OWNER)
    if not 0.0 < validation_fraction < 1.0:
        raise InvalidValueError(
            f"The 'validation_fraction' parameter of {_OWNER} must be in (0, 1). "
            f"Got {validation_fraction} instead."
        )
    gen = as_generator(rng, _OWNER)

    joint = arm.joints[0]
    dt = excitation.dt
    steps = excitation.hold_steps
    n_steps = round(excitation.duration / dt)
    n_holds = n_steps // steps
    if n_holds < 4 * n_lags or n_holds < 300:
        raise InvalidValueError(
            f"The 'excitation' parameter of {_OWNER} must give at least "
            f"{max(4 * n_lags, 300)} holds (duration / hold). Got {n_holds} instead."
        )

    # ---------------------------------------------------------------- experiment
    command = gen.uniform(-excitation.amplitude, excitation.amplitude, n_holds + 1)
    applied = excitation.drive(command)
    per_sample = np.repeat(applied, steps)[: n_steps + 1]
    per_sample = np.r_[per_sample, np.full(n_steps + 1 - per_sample.shape[0], applied[-1])]
    controller = CompiledController(_play, params=np.r_[dt, per_sample], name="random-torque")
    res = simulate(arm, controller, _Still(n_steps * dt), duration=n_steps * dt, dt=dt)
    m_idx = arm.motor_slice.start
    q, qm = res.q[:, 0], res.q[:, m_idx]
    v, vm = res.dq[:, 0], res.dq[:, m_idx]
    tau = res.tau[:, 0]
    n = q.shape[0]

    def noisy(x: F64, sigma: float) -> F64:
        out: F64 = x + sigma * gen.standard_normal(x.shape[0]) if sigma > 0 else x.copy()
        return out

    q_meas, qm_meas = noisy(q, sensors.angle_noise), noisy(qm, sensors.angle_noise)
    v_meas, vm_meas = noisy(v, sensors.rate_noise), noisy(vm, sensors.rate_noise)
    tau_meas = noisy(tau, sensors.torque_noise)
    delta_true = qm - q
    ts_true = np.asarray(joint.torque(delta_true), dtype=np.float64)
    ts_sensor = noisy(ts_true, sensors.torque_sensor_noise)

    # ---------------------------------------------------------------- (a) stiffness
    J_m, c_m = joint.motor_inertia, joint.motor_damping
    k = np.arange(1, n - 1)
    smooth = tau[k - 1] == tau[k]  # no torque switch at t_k (known: it is our command)
    k = k[smooth]
    delta_meas = qm_meas - q_meas
    if torque_measurement == "motor-balance":
        # Keep the quasi-static samples: the central difference's error, about
        # tau_s''(Delta) dDelta/dt**2 dt**2 / 6, is largest where the joint sweeps
        # quickly through the curved soft-windup region.
        rate = np.abs(vm_meas[k] - v_meas[k])
        k = k[rate <= np.quantile(rate, quasi_static_fraction)]
        ts_meas = (
            tau_meas[k] - c_m * vm_meas[k] - J_m * (vm_meas[k + 1] - vm_meas[k - 1]) / (2 * dt)
        )
    else:
        ts_meas = ts_sensor[k]
    stiffness = _curve(
        "stiffness",
        delta_meas[k],
        ts_meas,
        joint.torque,
        0.005,
        stiffness_bandwidth,
        ("rad", "N m"),
    )

    # ---------------------------------------------------------------- (a) friction
    friction_model = joint.friction
    inertia = float(arm.mass_matrix(np.zeros(arm.n_dof))[0, 0])
    mf = friction_window
    if torque_measurement == "motor-balance":
        ts_window = (
            _held_mean(tau_meas, mf)[: n - mf]
            - c_m * _window_mean(vm_meas, mf)
            - J_m * (vm_meas[mf:] - vm_meas[:-mf]) / (mf * dt)
        )
    else:
        ts_window = _window_mean(ts_sensor, mf)
    f_meas = ts_window - inertia * (v_meas[mf:] - v_meas[:-mf]) / (mf * dt)
    v_bar = _window_mean(v_meas, mf)

    def f_true(x: ArrayLike) -> F64:
        if friction_model is None:
            return np.zeros_like(np.asarray(x, dtype=np.float64))
        return friction_model(x)

    friction = _curve("friction", v_bar, f_meas, f_true, 0.01, friction_bandwidth, ("rad/s", "N m"))

    windup: dict[str, float] = {}
    width = 0.0
    if isinstance(joint, NonlinearJoint) and joint.ksw > 0:
        width = 1.0 / math.sqrt(joint.asw)
        inner = 0.2 * width
        x, est, tru = stiffness.x, stiffness.estimate, stiffness.truth
        if x[0] < -4 * width and x[-1] > 4 * width:
            windup = {
                "inner_halfwidth_rad": inner,
                "stiffness_inside_estimate": _secant(x, est, -inner, inner),
                "stiffness_inside_true": _secant(x, tru, -inner, inner),
                "stiffness_outside_estimate": 0.5
                * (_secant(x, est, 2 * width, 4 * width) + _secant(x, est, -4 * width, -2 * width)),
                "stiffness_outside_true": 0.5
                * (_secant(x, tru, 2 * width, 4 * width) + _secant(x, tru, -4 * width, -2 * width)),
            }

    # ---------------------------------------------------------------- (b) Hammerstein
    starts = np.arange(n_holds) * steps
    u_h = command[:n_holds]
    acc = (v[starts + steps] - v[starts]) / (steps * dt)
    y_h = noisy(acc, sensors.acceleration_noise)
    n_fit = round((1.0 - validation_fraction) * n_holds)
    drive = excitation.drive
    u_known = 0.8 * excitation.amplitude
    model = HammersteinIdentifier(
        n_lags=n_lags, known_points=((0.0, 0.0), (u_known, float(drive(u_known))))
    ).fit(u_h[:n_fit], y_h[:n_fit])
    y_hat = model.predict(u_h)[n_fit:]
    fit = fit_percent(y_h[n_fit:], y_hat)
    reference = _fir_reference(drive(u_h), y_h, n_fit, n_lags)
    grid = np.linspace(-excitation.amplitude, excitation.amplitude, 241)
    drive_curve = CurveEstimate("drive", grid, model.nonlinearity(grid), drive(grid), "N m", "N m")

    info = {
        "duration_s": n_steps * dt,
        "dt_s": dt,
        "hold_s": steps * dt,
        "amplitude_Nm": excitation.amplitude,
        "drive": {"dead_band_Nm": drive.dead_band, "limit_Nm": drive.limit},
        "torque_measurement": torque_measurement,
        "friction_window": mf,
        "quasi_static_fraction": quasi_static_fraction,
        "link_inertia_kgm2": inertia,
        "motor_inertia_kgm2": J_m,
        "motor_damping_Nms": c_m,
        "n_static_samples": int(k.shape[0]),
        "n_holds": int(n_holds),
        "n_fit": int(n_fit),
        "windup_width_rad": width,
        "sensors": {
            "angle_noise_rad": sensors.angle_noise,
            "rate_noise_rad_s": sensors.rate_noise,
            "torque_noise_Nm": sensors.torque_noise,
            "torque_sensor_noise_Nm": sensors.torque_sensor_noise,
            "acceleration_noise_rad_s2": sensors.acceleration_noise,
        },
        "simulation_status": res.info.get("status"),
    }
    validation = {
        "t": (starts[n_fit:] * dt).astype(np.float64),
        "u": u_h[n_fit:],
        "y": y_h[n_fit:],
        "y_hat": y_hat,
    }
    return JointIdentification(
        stiffness, friction, drive_curve, windup, model, validation, fit, reference, info
    )
