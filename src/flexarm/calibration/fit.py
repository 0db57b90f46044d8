"""Fitting the parameters: least squares on the free-run prediction of the records.

:func:`calibrate_records` (what :func:`flexarm.calibrate` runs) estimates the delays
that are to be estimated (how much later a measured channel departs from its start
than the initial prediction), finds the parameters the training records cannot
determine (holds them at their initial values and says so), then fits the rest by
bounded least squares (:func:`scipy.optimize.least_squares`, trust region
reflective) on every training record's channels, each channel weighted by the
inverse of its measured standard deviation so that channels in different units count
alike. The Jacobian is formed by forward differences, its columns run at once on a
pool of threads (the simulator's compiled loops release the GIL). Seeded restarts
from random points within the bounds guard against a local minimum. The result
(:class:`flexarm.calibration.result.Calibration`) carries the values with 95 %
confidence intervals, their correlations, the fit of every record before and after.

Confidence intervals are the usual ones of nonlinear least squares, ``s^2 (J'
J)^-1`` with ``s^2`` the residual variance: right when the residuals are white.
Measured residuals are rarely white (the model leaves structure out); the result
reports each channel's lag-one residual correlation and intervals widened by
``sqrt((1 + r) / (1 - r))``, the variance factor of an AR(1) residual."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._types import F64
from .config import CalibrationConfig, Parameter
from .model import Plant, Predictor, build_plant
from .records import Record, load_record

__all__ = [
    "IDENTIFIABILITY_TOL",
    "Fit",
    "calibrate_records",
    "fit_percent",
    "initial_states",
    "load_records",
]


IDENTIFIABILITY_TOL = 1e-6
"""A parameter whose scaled sensitivity is below this fraction of the largest, or
that lies in a direction of the scaled Jacobian whose singular value is below this
fraction of the largest, is not determined by the data."""
_FAILED = 1e3
"""The weighted residual of a sample a diverged prediction did not reach."""


def fit_percent(measured: F64, predicted: F64) -> float:
    """``100 (1 - |y - yhat| / |y - mean y|)``: 100 for a perfect prediction, 0 for
    the mean of the measurement, negative for worse."""
    y, yh = np.asarray(measured), np.asarray(predicted)
    spread = float(np.linalg.norm(y - y.mean()))
    if not np.all(np.isfinite(yh)) or spread == 0.0:
        return float("nan")
    return float(100.0 * (1.0 - np.linalg.norm(y - yh) / spread))


def load_records(config: CalibrationConfig) -> list[Record]:
    """Every record of ``config``, read from its data directory."""
    return [
        load_record(spec, config.root, config.source, k) for k, spec in enumerate(config.records)
    ]


@dataclass
class Fit:
    """What the least squares found (the raw numbers behind a
    :class:`~flexarm.calibration.result.Calibration`).

    Attributes
    ----------
    values : ndarray, shape (n_parameters,)
        The fitted numbers (factors for scale parameters), held ones at their start.
    initial : ndarray
        The numbers the fit started from (delays as estimated).
    free : ndarray of bool
        Which parameters were fitted (the others: not determined by the data).
    held : dict of str to str
        Held parameter -> why.
    covariance : ndarray, shape (n_free, n_free)
        Of the free parameters' numbers.
    dof : int
        Residuals minus free unknowns (nuisance included).
    nuisance : list of ndarray
        The fitted initial states of each record (empty unless fitted).
    residual_correlation : dict of str to float
        Lag-one correlation of each channel's residuals.
    cost : float
        Half the sum of squared weighted residuals.
    evaluations : int
    """

    values: F64
    initial: F64
    free: NDArray[np.bool_]
    held: dict[str, str]
    covariance: F64
    dof: int
    nuisance: list[F64]
    residual_correlation: dict[str, float]
    cost: float
    evaluations: int


class _Problem:
    """The residual of the training records as a function of the free unknowns."""

    def __init__(
        self,
        config: CalibrationConfig,
        predictor: Predictor,
        training: Sequence[int],
        values: F64,
        free: NDArray[np.bool_],
        workers: int,
    ) -> None:
        self.config, self.predictor = config, predictor
        self.training = list(training)
        self.values, self.free = values.copy(), free.copy()
        plant = build_plant(config, values)
        self.n_nuisance = [predictor.n_nuisance(plant, k) for k in self.training]
        records = predictor.records
        self.weights: dict[str, float] = {}
        for name in sorted({c for k in self.training for c in records[k].outputs}):
            y = np.concatenate(
                [records[k].outputs[name] for k in self.training if name in records[k].outputs]
            )
            std = float(np.std(y))
            self.weights[name] = 1.0 / std if std > 0 else 1.0
        self.pool = ThreadPoolExecutor(workers) if workers > 1 else None
        self.evaluations = 0

    # ---------------------------------------------------------------- unknowns
    def split(self, z: F64) -> tuple[F64, list[F64]]:
        values = self.values.copy()
        n_free = int(self.free.sum())
        values[self.free] = z[:n_free]
        nuisance, c = [], n_free
        for n in self.n_nuisance:
            nuisance.append(z[c : c + n])
            c += n
        return values, nuisance

    def record_residual(self, plant: Plant | None, k: int, nuisance: F64) -> F64:
        rec = self.predictor.records[k]
        n = sum(1 for _ in rec.outputs) * rec.t.shape[0]
        if plant is None:
            return np.full(n, _FAILED)
        predicted = self.predictor.predict(plant, k, nuisance)
        parts = []
        for name, y in rec.outputs.items():
            r = (predicted[name] - y) * self.weights[name]
            parts.append(np.where(np.isfinite(r), r, _FAILED))
        return np.concatenate(parts)

    def _plant(self, values: F64) -> Plant | None:
        try:
            return build_plant(self.config, values)
        except ValueError:  # values the library refuses (a bound reached exactly, say)
            return None

    def residual(self, z: F64) -> F64:
        values, nuisance = self.split(z)
        plant = self._plant(values)
        self.evaluations += 1
        return np.concatenate(
            [
                self.record_residual(plant, k, nu)
                for k, nu in zip(self.training, nuisance, strict=True)
            ]
        )

    def jacobian(self, z: F64, steps: F64) -> F64:
        """Forward differences, one column per unknown, columns run at once; a
        nuisance column recomputes only its own record."""
        base = self.residual(z)
        n_free = int(self.free.sum())
        offsets = np.cumsum(
            [0]
            + [
                r.outputs.__len__() * r.t.shape[0]
                for r in (self.predictor.records[k] for k in self.training)
            ]
        )

        def column(j: int) -> F64:
            zz = z.copy()
            zz[j] += steps[j]
            if j < n_free:
                return np.asarray((self.residual(zz) - base) / steps[j], dtype=np.float64)
            c, which = n_free, 0
            while j >= c + self.n_nuisance[which]:
                c += self.n_nuisance[which]
                which += 1
            v2, nu2 = self.split(zz)
            col = np.zeros_like(base)
            k = self.training[which]
            part = self.record_residual(self._plant(v2), k, nu2[which])
            a, b = offsets[which], offsets[which + 1]
            col[a:b] = (part - base[a:b]) / steps[j]
            return col

        indices = range(z.shape[0])
        columns = list(self.pool.map(column, indices) if self.pool else map(column, indices))
        if not columns:
            return np.zeros((base.shape[0], 0))
        return np.asarray(np.column_stack(columns), dtype=np.float64)

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown()


def _steps(z: F64, scales: F64) -> F64:
    return 1e-5 * np.maximum(np.abs(z), scales)


def _scales(params: Sequence[Parameter], values: F64) -> F64:
    """A typical size of each parameter's number: its value, else a tenth of its range."""
    return np.array(
        [max(abs(v), 0.1 * (p.upper - p.lower)) for p, v in zip(params, values, strict=True)]
    )


def _onset(t: F64, y: F64, fraction: float = 0.2) -> float | None:
    """When ``y`` first departs from its start by ``fraction`` of its largest
    departure (s), or None for a signal that does not move."""
    start = float(np.mean(y[: max(1, y.shape[0] // 50)]))
    departure = np.abs(y - start)
    peak = float(np.max(departure))
    if not np.isfinite(peak) or peak == 0.0:
        return None
    return float(t[int(np.argmax(departure >= fraction * peak))])


def _estimate_delays(
    config: CalibrationConfig, predictor: Predictor, training: Sequence[int], values: F64
) -> F64:
    """Initial values of the delays marked ``"estimate"``: how much later the measured
    channel departs from its start than the undelayed prediction does (the median
    over the training records, within 0 to ``max_delay``). An onset is robust to a
    model whose frequencies are still off, where a cross-correlation of oscillating
    signals is not; the least squares then refines it."""
    values = values.copy()
    estimated = [(i, p) for i, p in enumerate(config.parameters) if p.estimate]
    if not estimated:
        return values
    plant = build_plant(config, values)
    states = {k: predictor.states(plant, k) for k in training}
    for i, p in estimated:
        name = p.key.split(".")[1]
        lags = []
        for k in training:
            rec = predictor.records[k]
            if name not in rec.outputs:
                continue
            raw = plant.outputs[name].raw(plant.arm, states[k])
            measured, predicted = _onset(rec.t, rec.outputs[name]), _onset(rec.t, raw)
            if measured is not None and predicted is not None:
                lags.append(measured - predicted)
        if lags:
            values[i] = min(max(float(np.median(lags)), p.lower), p.upper)
    return values


def _undetermined(
    problem: _Problem, z: F64, scales: F64, names: Sequence[str], n_free: int
) -> dict[str, str]:
    """Free parameters (not nuisance) the training data cannot determine, with why."""
    if n_free == 0:
        return {}
    jac = problem.jacobian(z, _steps(z, scales)) * scales
    norms = np.linalg.norm(jac, axis=0)
    top = float(norms.max()) if norms.size else 0.0
    held: dict[str, str] = {}
    for j in range(n_free):
        if top == 0.0 or norms[j] <= IDENTIFIABILITY_TOL * top:
            held[names[j]] = "the training records do not depend on it"
    keep = [j for j in range(jac.shape[1]) if j >= n_free or names[j] not in held]
    if len(keep) > 1:
        sub = jac[:, keep] / np.maximum(norms[keep], 1e-300)
        _, sigma, vt = np.linalg.svd(sub, full_matrices=False)
        for s, v in zip(sigma, vt, strict=True):
            if s <= IDENTIFIABILITY_TOL * sigma[0]:
                involved = [keep[i] for i in np.flatnonzero(np.abs(v) > 0.3) if keep[i] < n_free]
                for j in involved:
                    others = [names[i] for i in involved if i != j]
                    held.setdefault(
                        names[j],
                        "the training records determine it only together with "
                        + (", ".join(others) if others else "the initial states"),
                    )
    return held


def calibrate_records(
    config: CalibrationConfig,
    records: Sequence[Record],
    *,
    workers: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> Fit:
    """Fit ``config``'s parameters on its training ``records`` (module docstring).

    Parameters
    ----------
    config : CalibrationConfig
    records : sequence of Record
        All records (validation ones are not used here).
    workers : int, optional
        Threads for the Jacobian's columns (default: the cores this process may use).
    progress : callable, optional
        Called with a line of text at each stage.
    """
    say = progress or (lambda _text: None)
    params = config.parameters
    predictor = Predictor(config, records)
    training = [k for k, r in enumerate(records) if r.role == "training"]
    if not training:
        from ..errors import CalibrationError

        raise CalibrationError(
            config.source, "records", "has no training record (role = 'training')"
        )
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
    n_workers = workers
    values0 = _estimate_delays(config, predictor, training, np.array([p.initial for p in params]))
    free = np.ones(len(params), dtype=bool)
    scales_all = _scales(params, values0)
    problem = _Problem(config, predictor, training, values0, free, n_workers)
    try:
        z0 = np.concatenate([values0, np.zeros(sum(problem.n_nuisance))])
        nuisance_scale = np.full(sum(problem.n_nuisance), 1e-2)
        scales = np.concatenate([scales_all, nuisance_scale])
        say("checking which parameters the records determine")
        held = _undetermined(problem, z0, scales, [p.name for p in params], len(params))
        free = np.array([p.name not in held for p in params])
        problem.close()
        problem = _Problem(config, predictor, training, values0, free, n_workers)
        lo = np.concatenate(
            [
                [p.lower for p, f in zip(params, free, strict=True) if f],
                np.full(sum(problem.n_nuisance), -np.inf),
            ]
        )
        hi = np.concatenate(
            [
                [p.upper for p, f in zip(params, free, strict=True) if f],
                np.full(sum(problem.n_nuisance), np.inf),
            ]
        )
        x_scale = np.concatenate([scales_all[free], nuisance_scale])
        starts = [np.concatenate([values0[free], np.zeros(sum(problem.n_nuisance))])]
        rng = np.random.default_rng(config.settings.seed)
        for _ in range(config.settings.restarts):
            draw = []
            for p in (q for q, f in zip(params, free, strict=True) if f):
                if p.lower > 0:
                    draw.append(math.exp(rng.uniform(math.log(p.lower), math.log(p.upper))))
                else:
                    draw.append(rng.uniform(p.lower, p.upper))
            starts.append(np.concatenate([draw, np.zeros(sum(problem.n_nuisance))]))
        from scipy.optimize import least_squares

        best = None
        for s, start in enumerate(starts):
            say(f"least squares from start {s + 1} of {len(starts)}")
            sol = least_squares(
                problem.residual,
                np.clip(start, lo, hi),
                jac=lambda z: problem.jacobian(z, _steps(z, x_scale)),
                bounds=(lo, hi),
                x_scale=x_scale,
                method="trf",
                max_nfev=config.settings.max_evaluations,
            )
            if best is None or sol.cost < best.cost:
                best = sol
        assert best is not None
        z = best.x
        jac = problem.jacobian(z, _steps(z, x_scale))
        residual = problem.residual(z)
        m, n = jac.shape
        dof = max(m - n, 1)
        s2 = 2.0 * float(best.cost) / dof
        covariance = s2 * np.linalg.pinv(jac.T @ jac)
        values, nuisance = problem.split(z)
        n_free = int(free.sum())
        corr = _residual_correlation(problem, residual)
        return Fit(
            values=values,
            initial=values0,
            free=free,
            held=held,
            covariance=covariance[:n_free, :n_free],
            dof=dof,
            nuisance=nuisance,
            residual_correlation=corr,
            cost=float(best.cost),
            evaluations=problem.evaluations,
        )
    finally:
        problem.close()


def initial_states(predictor: Predictor, plant: Plant, k: int) -> F64 | None:
    """The initial states of record ``k`` that best replay it on ``plant`` (the
    parameters held), as MATLAB's ``compare`` estimates a validation record's initial
    conditions; None where the file does not fit initial states
    (``initial_state = "fit"``) nor zero offsets (``offset = "fit"``, which these
    include). The replay is nearly linear in them: two Gauss-Newton steps from rest,
    each one forward-difference Jacobian."""
    n = predictor.n_nuisance(plant, k)
    if n == 0:
        return None
    rec = predictor.records[k]
    weights = {name: 1.0 / (float(np.std(y)) or 1.0) for name, y in rec.outputs.items()}

    def residual(nu: F64) -> F64:
        predicted = predictor.predict(plant, k, nu)
        parts = [(predicted[c] - y) * weights[c] for c, y in rec.outputs.items()]
        r = np.concatenate(parts)
        return np.where(np.isfinite(r), r, _FAILED)

    nu = np.zeros(n)
    step = 1e-4
    r0 = residual(nu)
    for _ in range(2):
        jac = np.column_stack([(residual(nu + step * e) - r0) / step for e in np.eye(n)])
        delta, *_ = np.linalg.lstsq(jac, -r0, rcond=None)
        if not np.all(np.isfinite(delta)):
            break
        # A step is kept only where it lowers the cost (halved up to four times): a
        # replay far from linear in its initial states must not be made worse.
        for _ in range(5):
            r1 = residual(nu + delta)
            if float(r1 @ r1) < float(r0 @ r0):
                nu, r0 = nu + delta, r1
                break
            delta = delta / 2.0
        else:
            break
    return nu


def _residual_correlation(problem: _Problem, residual: F64) -> dict[str, float]:
    """Lag-one correlation of each channel's residuals, pooled over the records."""
    pieces: dict[str, list[F64]] = {}
    c = 0
    for k in problem.training:
        rec = problem.predictor.records[k]
        n = rec.t.shape[0]
        for name in rec.outputs:
            pieces.setdefault(name, []).append(residual[c : c + n])
            c += n
    out = {}
    for name, parts in pieces.items():
        num = sum(float(np.dot(p[1:] - p.mean(), p[:-1] - p.mean())) for p in parts)
        den = sum(float(np.dot(p - p.mean(), p - p.mean())) for p in parts)
        out[name] = num / den if den > 0 else 0.0
    return out
