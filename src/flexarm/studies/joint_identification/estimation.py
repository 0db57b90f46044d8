"""The joint study's estimates, from the measurements alone (plus the data-sheet values).

* :func:`estimate_stiffness` — ``tau_s(Delta)`` from the motor's torque balance
  (quasi-static samples) or a joint torque sensor;
* :func:`estimate_friction` — ``f(v)`` from the link's torque balance over a
  sliding window;
* :func:`windup_secants` — the secant stiffness inside and outside the
  soft-windup region, estimate and truth;
* :func:`fit_hammerstein` — the Hammerstein model from command to link
  acceleration, scored on held-out data beside a FIR model on the true drive map;
* :func:`dead_band_summary` — how well its static part resolves the drive's dead band.

The curves are estimated by the paper's semi-recursive kernel regression
(eq. 14, Epanechnikov kernel, ``h_1`` a fraction of the regressor's standard
deviation, decay 0.2) on a grid spanning a central quantile range of the data.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64
from ...ident.hammerstein.identifier import HammersteinIdentifier
from ...ident.hammerstein.prediction import fit_percent
from ...ident.hammerstein.whiteness import IdentificationWarning
from ...ident.regression.bandwidth import Silverman
from ...ident.regression.estimators import SemiRecursiveKernelRegression
from ...model.joints import LinearJoint, NonlinearJoint
from .experiment import JointMeasurements, JointRecord
from .parameters import DriveNonlinearity
from .result import CurveEstimate

__all__ = [
    "HammersteinFit",
    "dead_band_summary",
    "estimate_friction",
    "estimate_stiffness",
    "fit_hammerstein",
    "windup_secants",
]

Joint = NonlinearJoint | LinearJoint


def estimate_stiffness(
    record: JointRecord,
    meas: JointMeasurements,
    joint: Joint,
    *,
    torque_measurement: str,
    quasi_static_fraction: float,
    bandwidth: float,
) -> tuple[CurveEstimate, int]:
    """The stiffness torque ``tau_s(Delta)``, rad to N m, and the number of samples used.

    With ``"motor-balance"``, ``tau_s = tau - c_m qd_m - J_m qdd_m`` (``qdd_m`` the
    central difference of the measured motor rate) on the samples where the
    torque does not switch, and of those the ``quasi_static_fraction`` with the
    smallest measured deflection rate ``|qd_m - qd|``. With ``"sensor"``, the
    torque sensor's reading on the samples where the torque does not switch.
    """
    tau, dt, n = record.tau, record.dt, record.q.shape[0]
    k = np.arange(1, n - 1)
    k = k[tau[k - 1] == tau[k]]  # no torque switch at t_k (known: it is our command)
    delta = meas.q_m - meas.q
    if torque_measurement == "motor-balance":
        # Keep the quasi-static samples: the central difference's error, about
        # tau_s''(Delta) dDelta/dt**2 dt**2 / 6, is largest where the joint sweeps
        # quickly through the curved soft-windup region.
        rate = np.abs(meas.v_m[k] - meas.v[k])
        k = k[rate <= np.quantile(rate, quasi_static_fraction)]
        J_m, c_m = joint.motor_inertia, joint.motor_damping
        ts = meas.tau[k] - c_m * meas.v_m[k] - J_m * (meas.v_m[k + 1] - meas.v_m[k - 1]) / (2 * dt)
    else:
        ts = meas.tau_s[k]
    curve = _curve("stiffness", delta[k], ts, joint.torque, 0.005, bandwidth, ("rad", "N m"))
    return curve, int(k.shape[0])


def estimate_friction(
    record: JointRecord,
    meas: JointMeasurements,
    joint: Joint,
    inertia: float,
    *,
    torque_measurement: str,
    window: int,
    bandwidth: float,
) -> CurveEstimate:
    """The friction curve ``f(v)``, rad/s to N m, from the link's balance ``I qdd = tau_s - f(qd)``.

    Averaged over ``window`` samples so that the noisy acceleration enters only
    as ``(qd(t + T) - qd(t)) / T``: ``f_bar = mean(tau_s) - I (qd(t+T) - qd(t)) / T``
    paired with ``mean(qd)``; ``inertia`` is the link's ``I``, kg m**2.
    """
    dt, n, mf = record.dt, record.q.shape[0], window
    if torque_measurement == "motor-balance":
        J_m, c_m = joint.motor_inertia, joint.motor_damping
        ts_window = (
            _held_mean(meas.tau, mf)[: n - mf]
            - c_m * _window_mean(meas.v_m, mf)
            - J_m * (meas.v_m[mf:] - meas.v_m[:-mf]) / (mf * dt)
        )
    else:
        ts_window = _window_mean(meas.tau_s, mf)
    f_meas = ts_window - inertia * (meas.v[mf:] - meas.v[:-mf]) / (mf * dt)
    v_bar = _window_mean(meas.v, mf)
    friction = joint.friction

    def f_true(x: ArrayLike) -> F64:
        if friction is None:
            return np.zeros_like(np.asarray(x, dtype=np.float64))
        return friction(x)

    return _curve("friction", v_bar, f_meas, f_true, 0.01, bandwidth, ("rad/s", "N m"))


def windup_secants(stiffness: CurveEstimate, joint: Joint) -> tuple[dict[str, float], float]:
    """Secant stiffnesses (N m/rad) inside and outside the soft-windup region, and its width.

    The width is ``1 / sqrt(asw)``, rad; inside means ``|Delta| <= 0.2 width``,
    outside between ``2`` and ``4`` widths (both signs, averaged). Empty (and
    width 0) for a joint without windup, and empty when the grid does not
    reach 4 widths on both sides.
    """
    if not (isinstance(joint, NonlinearJoint) and joint.ksw > 0):
        return {}, 0.0
    width = 1.0 / math.sqrt(joint.asw)
    inner = 0.2 * width
    x, est, tru = stiffness.x, stiffness.estimate, stiffness.truth
    if not (x[0] < -4 * width and x[-1] > 4 * width):
        return {}, width

    def outside(y: F64) -> float:
        return 0.5 * (_secant(x, y, 2 * width, 4 * width) + _secant(x, y, -4 * width, -2 * width))

    return {
        "inner_halfwidth_rad": inner,
        "stiffness_inside_estimate": _secant(x, est, -inner, inner),
        "stiffness_inside_true": _secant(x, tru, -inner, inner),
        "stiffness_outside_estimate": outside(est),
        "stiffness_outside_true": outside(tru),
    }, width


@dataclass(frozen=True)
class HammersteinFit:
    """The Hammerstein model and how well it predicts held-out data.

    Attributes
    ----------
    model : HammersteinIdentifier
        Fitted on the first ``n_fit`` holds (commanded torque, N m, to link
        acceleration, rad/s**2).
    drive : CurveEstimate
        Its static part against the true drive map, N m to N m.
    validation : dict of str to ndarray
        ``"t"`` (s), ``"u"`` (N m), ``"y"``, ``"y_hat"`` (rad/s**2) on the held-out holds.
    fit_percent, reference_fit_percent : float
        Free-run fit of the model, and of a least-squares FIR model driven by
        the true ``phi(u)``, on the held-out holds, %.
    n_fit : int
        Holds used for fitting.
    dead_band : dict of str to float
        :func:`dead_band_summary` of the static part.
    """

    model: HammersteinIdentifier
    drive: CurveEstimate
    validation: dict[str, F64]
    fit_percent: float
    reference_fit_percent: float
    n_fit: int
    dead_band: dict[str, float]


def fit_hammerstein(
    record: JointRecord,
    meas: JointMeasurements,
    drive: DriveNonlinearity,
    amplitude: float,
    *,
    n_lags: int,
    validation_fraction: float,
    method: str = "auto",
    n_knots: int | str = "auto",
    span: float = 6.0,
) -> HammersteinFit:
    """Fit the model from the command ``u_n`` to the accelerometer ``y_n``, one sample per hold.

    The two-point normalisation comes from the drive's data sheet: ``phi(0) = 0``
    and the rated torque at 80 % of ``amplitude`` (N m). ``method`` is the
    identifier's path and ``n_knots`` its knots (correlated path); ``span`` (N m)
    the half-range of :func:`dead_band_summary`.
    """
    starts = record.hold_starts
    n_holds = starts.shape[0]
    u = record.command[:n_holds]
    y = meas.acceleration
    n_fit = round((1.0 - validation_fraction) * n_holds)
    u_known = 0.8 * amplitude
    with warnings.catch_warnings():  # the report keeps the warnings (model.report_)
        warnings.simplefilter("ignore", IdentificationWarning)
        model = HammersteinIdentifier(
            n_lags=n_lags,
            known_points=((0.0, 0.0), (u_known, float(drive(u_known)))),
            method=method,
            n_knots=n_knots,
        ).fit(u[:n_fit], y[:n_fit])
    y_hat = model.predict(u)[n_fit:]
    grid = np.linspace(-amplitude, amplitude, 241)
    validation = {
        "t": (starts[n_fit:] * record.dt).astype(np.float64),
        "u": u[n_fit:],
        "y": y[n_fit:],
        "y_hat": y_hat,
    }
    return HammersteinFit(
        model=model,
        drive=CurveEstimate("drive", grid, model.nonlinearity(grid), drive(grid), "N m", "N m"),
        validation=validation,
        fit_percent=fit_percent(y[n_fit:], y_hat),
        reference_fit_percent=_fir_reference(drive(u), y, n_fit, n_lags),
        n_fit=n_fit,
        dead_band=dead_band_summary(model.nonlinearity, drive, span),
    )


def _hinge(x: F64, phi: F64) -> tuple[float, float]:
    """``(d, s)`` minimising ``sum (phi - s max(x - d, 0))**2`` over ``x >= 0``."""
    best = (math.inf, 0.0, 0.0)
    for d in x[:-2]:
        ramp = np.maximum(x - d, 0.0)
        s = float(ramp @ phi) / float(ramp @ ramp)
        r = float(np.sum((phi - s * ramp) ** 2))
        if r < best[0]:
            best = (r, float(d), s)
    return best[1], best[2]


def dead_band_summary(
    phi: Callable[[F64], F64], drive: DriveNonlinearity, span: float, points: int = 241
) -> dict[str, float]:
    """How an estimated drive map ``phi`` (N m to N m) resolves the dead band, against the truth.

    On ``[-span, span]`` (N m): the RMS and largest error of ``phi``; and, on each
    side, the dead band read off the estimate by the hinge ``s max(|x| - d, 0)``
    fitted by least squares (``d`` on the grid): ``d`` beside the true half-width.
    The hinge summarises the nonparametric estimate; it is not assumed by the
    identification.
    """
    x = np.linspace(-span, span, points)
    est, truth = phi(x), drive(x)
    right = x >= 0.0
    d_pos, s_pos = _hinge(x[right], est[right])
    d_neg, s_neg = _hinge(-x[~right][::-1], -est[~right][::-1])
    return {
        "span_Nm": float(span),
        "true_half_width_Nm": float(drive.dead_band),
        "half_width_positive_Nm": d_pos,
        "half_width_negative_Nm": d_neg,
        "slope_positive": s_pos,
        "slope_negative": s_neg,
        "rms_error_Nm": float(np.sqrt(np.mean((est - truth) ** 2))),
        "max_error_Nm": float(np.max(np.abs(est - truth))),
    }


# --------------------------------------------------------------------------- helpers


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
    truth: Callable[[F64], ArrayLike],
    quantile: float,
    smoothing: float,
    units: tuple[str, str],
    grid_size: int = 401,
) -> CurveEstimate:
    """Kernel-regression estimate of ``y(x)`` on a grid over ``x``'s central quantile range."""
    lo, hi = np.quantile(x, [quantile, 1.0 - quantile])
    grid = np.linspace(lo, hi, grid_size)
    reg = SemiRecursiveKernelRegression(
        kernel="epanechnikov",
        bandwidth=Silverman(smoothing),
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
