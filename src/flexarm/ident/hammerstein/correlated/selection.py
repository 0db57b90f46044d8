r"""Choosing the order and the knots of an ARX-Hammerstein model from held-out data.

The record is cut into :data:`VALIDATION_BLOCKS` ``* p`` contiguous blocks,
``p = round(1 / validation_fraction)``; every ``p``-th block is held out (blocked
cross-validation: Racine 2000; Bergmeir & Benítez 2012). The other blocks
estimate every candidate structure (:func:`flexarm.ident.hammerstein.correlated.arx.fit_structure`:
the knots, the means and the regression rows come from them only), and the
held-out blocks validate it by its **free-run** mean square error: the model is
simulated from rest over the whole record (the inputs are known everywhere;
no held-out output enters) and scored on the held-out samples. Interleaving
the blocks keeps both parts alike for a non-stationary input — the last
quarter of a sine sweep holds frequencies the first three quarters never
excite. A free-run error punishes a surplus of poles and zeros that a one-step
or impulse-response criterion such as BIC on a noisy impulse response lets
through.

Candidates
----------
Orders ``l = 1 .. max_order`` and knot counts on a geometric grid
(:data:`KNOT_GRID`, ``K = 2`` being the linear model), with at least
:data:`ROWS_PER_PARAMETER` estimation rows per parameter and at most
:data:`MAX_PARAMS` parameters (the cost of a solution grows as their cube). The linear models
(``K = 2``) are tried at every order ``1 .. max_order``, also when the order of
the nonlinear model is given: they are the baseline. The nonlinear ones are
searched by coordinates: the orders at :data:`START_KNOTS` knots, then the
knots at the best order, then the orders at the best knots, and so on until
the pair repeats (at most :data:`ROUNDS` rounds; an order scan stops after
:data:`PATIENCE` orders without improvement).

Choice: the one-standard-error rule
-----------------------------------
Among the candidates whose validation error is within one standard error of
the smallest, the one with the fewest parameters is chosen (Breiman et al.
1984, §3.4.3; Hastie, Tibshirani & Friedman 2009, §7.10). The standard error
of the difference of two candidates' errors has two parts. The held-out part
comes from :data:`BATCHES` contiguous batch means of the validation errors,
which allows for their serial correlation. One split does not show how the
fitted models themselves scatter, so the spread of their estimation excess is
added: a model with ``d`` parameters fitted to ``N`` rows exceeds the best
attainable error by about ``sigma**2 chi2_d / N`` (Akaike's final prediction
error), of standard deviation ``sigma**2 sqrt(2 d) / N``; for two models,
``sigma**2 sqrt(2 (d_1 + d_2)) / N``, with ``sigma**2`` the smallest
validation error. The same rule restricted to ``K = 2`` chooses the linear
baseline. A nonlinear model is kept only if it **beats the best linear model**
(the smallest validation error over every order tried) by more than the
standard error of their difference: the rule is applied to those nonlinear
candidates alone; if there is none, the linear model wins and the structure
chosen is the baseline's (with a given order: the linear model of that order,
the baseline recommended beside it). :attr:`Selection.winner` says which won,
:attr:`Selection.margin` by how much, on the held-out part
(``Selection.part``).

A record longer than :data:`SELECTION_SAMPLES` samples chooses its structure
on an excerpt: the blocks become windows of ``SELECTION_SAMPLES / (5 p)``
samples spread evenly over the record, each simulated from rest over the
:data:`BURN_IN` samples before it (which are not scored). With more than
:data:`MAX_ROWS` estimation rows the sums use every ``s``-th row (a systematic
subsample). The chosen structure is then fitted to the whole record.

References
----------
* L. Breiman, J. H. Friedman, R. A. Olshen, C. J. Stone, *Classification and
  Regression Trees*, Wadsworth (1984).
* T. Hastie, R. Tibshirani, J. Friedman, *The Elements of Statistical
  Learning*, 2nd ed., Springer (2009).
* J. Racine, "Consistent cross-validatory model-selection for dependent data:
  hv-block cross-validation", J. Econometrics 99 (2000) 39–61.
* C. Bergmeir, J. M. Benítez, "On the use of cross-validation for time series
  predictor evaluation", Information Sciences 191 (2012) 192–213.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ...._types import F64, I64
from .arx import Design, Located, StructureFit, fit_structure, n_params, one_blas_thread

__all__ = [
    "BATCHES",
    "BURN_IN",
    "KNOT_GRID",
    "MAX_PARAMS",
    "MAX_ROWS",
    "PATIENCE",
    "ROUNDS",
    "ROWS_PER_PARAMETER",
    "SELECTION_SAMPLES",
    "START_KNOTS",
    "VALIDATION_BLOCKS",
    "Candidate",
    "Selection",
    "Split",
    "batch_errors",
    "beats",
    "design",
    "final_fit",
    "held_part",
    "linear_candidates",
    "select_structure",
    "standard_error",
    "trailing",
    "validation_fit",
]


#: Knot counts tried (2: linear).
KNOT_GRID: tuple[int, ...] = (2, 3, 4, 6, 8, 11, 16, 23, 32, 45, 64, 91, 128)
#: Knots of the first order scan.
START_KNOTS = 8
#: Estimation rows required per parameter of the over-parameterised regression.
ROWS_PER_PARAMETER = 10
#: Parameters of the over-parameterised regression at most (its solution costs their cube).
MAX_PARAMS = 600
#: Orders scanned past the best one before an order scan stops.
PATIENCE = 2
#: Rounds of the coordinate search (orders, then knots) at most.
ROUNDS = 3
#: Batches of the validation part for the standard errors.
BATCHES = 20
#: Estimation rows summed per candidate at most (a systematic subsample beyond).
MAX_ROWS = 2**15
#: Instrumental-variable steps tried per candidate (the final fit tries more).
SELECTION_IV_STEPS = 1
#: Held-out blocks (every ``p``-th of ``VALIDATION_BLOCKS * p`` blocks).
VALIDATION_BLOCKS = 5
#: Records longer than this choose their structure on an excerpt of this many samples.
SELECTION_SAMPLES = 2**16
#: Samples simulated before each window of the excerpt (from rest), not scored.
BURN_IN = 2**12


@dataclass(frozen=True)
class Candidate:
    """One structure tried: order, knots, and its free-run error on held-out data.

    Attributes
    ----------
    order : int
        ``l``.
    n_knots : int
        ``K`` (2: linear).
    n_params : int
        ``l + (l + 1) (K - 1)``.
    validation_mse : float
        Free-run mean square error on the validation part (units of ``y``
        squared); ``inf`` if no stable model came out.
    estimator : str
        ``"least squares"``, ``"instrumental variables"`` or ``"unstable"``.
    """

    order: int
    n_knots: int
    n_params: int
    validation_mse: float
    estimator: str
    batch_mse: F64 = field(repr=False, compare=False)
    fit: StructureFit | None = field(repr=False, compare=False)

    @property
    def linear(self) -> bool:
        """Whether the candidate is a linear model (two knots)."""
        return self.n_knots == 2

    def summary(self) -> dict[str, object]:
        """Plain values (``validation_mse`` None when unstable)."""
        mse = self.validation_mse
        return {
            "order": self.order,
            "n_knots": self.n_knots,
            "n_params": self.n_params,
            "validation_mse": mse if math.isfinite(mse) else None,
            "estimator": self.estimator,
        }


def standard_error(c: Candidate, ref: Candidate, rows: float) -> float:
    """Standard error of ``c.validation_mse - ref.validation_mse`` (module docstring).

    Batch means of the held-out errors, plus the spread of the two models'
    estimation excess, ``mse sqrt(2 (d_c + d_ref)) / rows``.
    """
    d = c.batch_mse - ref.batch_mse
    batch = float(np.std(d, ddof=1) / math.sqrt(d.shape[0])) if d.shape[0] > 1 else 0.0
    excess = ref.validation_mse * math.sqrt(2.0 * (c.n_params + ref.n_params)) / rows
    return batch + excess


def _one_se(cands: list[Candidate], rows: float) -> tuple[Candidate, Candidate]:
    """``(chosen, best)``: the fewest parameters within one standard error of the best."""
    best = min(cands, key=lambda c: (c.validation_mse, c.n_params))
    within = [
        c
        for c in cands
        if c is best or c.validation_mse - best.validation_mse <= standard_error(c, best, rows)
    ]
    return min(within, key=lambda c: (c.n_params, c.validation_mse)), best


def beats(c: Candidate, ref: Candidate, rows: float) -> bool:
    """Whether ``c``'s validation error is below ``ref``'s by more than a standard error."""
    return ref.validation_mse - c.validation_mse > standard_error(c, ref, rows)


@dataclass(frozen=True)
class Selection:
    """The structures tried and the choice (module docstring).

    Attributes
    ----------
    candidates : tuple of Candidate
        Every structure tried, in the order tried.
    chosen : Candidate
        The structure kept (one-standard-error rule; nonlinear only if it beats
        ``best_linear``).
    best : Candidate
        The smallest validation error.
    linear : Candidate
        The linear baseline's structure (the same rule among ``K = 2``).
    best_linear : Candidate
        The linear model of smallest validation error, over every order tried.
    n_estimation, n_validation : int
        Samples of the two parts (interleaved blocks).
    stride : int
        Every ``stride``-th estimation row was summed (1: all).
    rows : float
        Estimation rows summed (the ``N`` of the standard errors).
    part : str
        Which samples validated (in words).
    validation_variance : float
        Mean square of the validation outputs about their mean (units of ``y``
        squared): a validation error as a fit, ``100 (1 - sqrt(mse / variance))`` %.
    """

    candidates: tuple[Candidate, ...]
    chosen: Candidate
    best: Candidate
    linear: Candidate
    best_linear: Candidate
    n_estimation: int
    n_validation: int
    stride: int
    rows: float
    part: str
    validation_variance: float

    @property
    def winner(self) -> str:
        """``"hammerstein"`` if the chosen model is nonlinear and beats the best linear
        model by more than a standard error, else ``"linear"``."""
        won = not self.chosen.linear and beats(self.chosen, self.best_linear, self.rows)
        return "hammerstein" if won else "linear"

    @property
    def nonlinear_helps(self) -> bool:
        """Whether a nonlinear model beat the best linear one by more than a standard error."""
        return self.winner == "hammerstein"

    @property
    def improvement(self) -> tuple[float, float]:
        """``(linear.validation_mse - chosen.validation_mse, its standard error)``."""
        diff = self.linear.validation_mse - self.chosen.validation_mse
        return diff, standard_error(self.linear, self.chosen, self.rows)

    @property
    def margin(self) -> tuple[float, float]:
        """``(best_linear.validation_mse - chosen.validation_mse, its standard error)``:
        positive where the chosen model is the better (units of ``y`` squared)."""
        diff = self.best_linear.validation_mse - self.chosen.validation_mse
        return diff, standard_error(self.chosen, self.best_linear, self.rows)

    def fit_percent(self, c: Candidate) -> float:
        """``c``'s validation error as a free-run fit on the validation part, %."""
        return validation_fit(c.validation_mse, self.validation_variance)

    def summary(self) -> dict[str, object]:
        """Plain values: the choice, the rule, the winner and every candidate."""
        diff, se = self.improvement
        margin, margin_se = self.margin
        return {
            "rule": "one standard error (batch means) on the free-run MSE of held-out blocks",
            "part": self.part,
            "n_estimation": self.n_estimation,
            "n_validation": self.n_validation,
            "chosen": self.chosen.summary(),
            "best": self.best.summary(),
            "linear": self.linear.summary(),
            "best_linear": self.best_linear.summary(),
            "winner": self.winner,
            "nonlinear_helps": self.nonlinear_helps,
            "improvement_over_linear": diff if math.isfinite(diff) else None,
            "improvement_standard_error": se if math.isfinite(se) else None,
            "margin_over_best_linear": margin if math.isfinite(margin) else None,
            "margin_standard_error": margin_se if math.isfinite(margin_se) else None,
            "candidates": [c.summary() for c in self.candidates],
        }


def validation_fit(mse: float, variance: float) -> float:
    """A validation mean square error as a free-run fit, ``100 (1 - sqrt(mse / variance))`` %."""
    if not math.isfinite(mse) or variance <= 0.0:
        return -math.inf
    return 100.0 * (1.0 - math.sqrt(mse / variance))


def batch_errors(err: F64) -> F64:
    """Means of the squared errors ``err`` over :data:`BATCHES` contiguous batches."""
    parts = np.array_split(err, min(BATCHES, err.shape[0]))
    return np.array([float(np.mean(p)) for p in parts])


#: A split of a record: the estimation design, the held-out mask and the samples used.
Split = tuple[Design, NDArray[np.bool_], I64]


def design(n: int, validation_fraction: float) -> Split:
    """The split of an ``n``-sample record, or of its excerpt (module docstring).

    Returns the estimation :class:`~flexarm.ident.hammerstein.correlated.arx.Design`, the
    held-out mask and the indices of the record's samples in the (excerpt) record, shape (n_sub,).
    """
    period = max(2, round(1.0 / validation_fraction))
    n_blocks = VALIDATION_BLOCKS * period
    if n <= SELECTION_SAMPLES:
        index = np.arange(n, dtype=np.int64)
        edges = np.linspace(0, n, n_blocks + 1).round().astype(np.int64)
        starts, stops, burn = edges[:-1], edges[1:], np.zeros(n_blocks, dtype=np.int64)
        runs = np.array([[0, n]], dtype=np.int64)
    else:  # evenly spaced windows, each simulated from rest after its burn-in
        length = SELECTION_SAMPLES // n_blocks
        where = BURN_IN + np.linspace(0, n - length - BURN_IN, n_blocks).round().astype(np.int64)
        index = np.concatenate([np.arange(c - BURN_IN, c + length) for c in where])
        offsets = np.arange(n_blocks, dtype=np.int64) * (BURN_IN + length)
        starts, stops = offsets + BURN_IN, offsets + BURN_IN + length
        burn = np.full(n_blocks, BURN_IN, dtype=np.int64)
        runs = np.column_stack([offsets, stops]).astype(np.int64)
    n_sub = index.shape[0]
    held = np.zeros(n_sub, dtype=bool)
    mask = np.zeros(n_sub, dtype=bool)
    segments: list[list[int]] = []
    for i in range(n_blocks):
        a, b = int(starts[i]), int(stops[i])
        if i % period == period - 1:
            held[a:b] = True
            continue
        mask[a:b] = True
        if segments and segments[-1][1] == a and burn[i] == 0:
            segments[-1][1] = b
        else:
            segments.append([a, b])
    return Design(np.array(segments, dtype=np.int64), runs, mask), held, index


def _ordinal(k: int) -> str:
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


def held_part(n: int, validation_fraction: float) -> str:
    """The held-out part of an ``n``-sample record under :func:`design`, in words."""
    period = max(2, round(1.0 / validation_fraction))
    n_blocks = VALIDATION_BLOCKS * period
    every = f"every {_ordinal(period)} of {n_blocks}"
    if n <= SELECTION_SAMPLES:
        return (
            f"held-out blocks: {every} contiguous blocks of the record (the last one "
            "included), each model simulated from rest over the whole record"
        )
    return (
        f"held-out windows: {every} windows of {SELECTION_SAMPLES // n_blocks} samples spread "
        f"evenly over the record, each simulated from rest over the {BURN_IN} samples before it"
    )


class _Search:
    """Candidates evaluated once each, on one estimation/validation split."""

    def __init__(self, u: F64, y: F64, split: Split, max_rows: int) -> None:
        self.design, self.held, index = split
        self.u, self.y = u[index], y[index]
        est = self.design.mask
        self.u_sorted = np.sort(self.u[est])
        self.distinct = int(np.count_nonzero(np.diff(self.u_sorted))) + 1
        self.rows = int(np.count_nonzero(est))
        self.stride = max(1, math.ceil(self.rows / max_rows))
        self.done: dict[tuple[int, int], Candidate] = {}
        self.order: list[Candidate] = []
        self.located: dict[int, Located] = {}

    def feasible(self, order: int, k: int) -> bool:
        rows = (self.rows - order * self.design.segments.shape[0]) / self.stride
        d = n_params(order, k)
        return k <= self.distinct and d * ROWS_PER_PARAMETER <= rows and d <= MAX_PARAMS

    def __call__(self, order: int, k: int) -> Candidate | None:
        if (order, k) in self.done:
            return self.done[(order, k)]
        if not self.feasible(order, k):
            return None
        if k not in self.located:
            self.located[k] = Located.of(self.u, self.u_sorted, k)
        where = self.located[k]
        fit = fit_structure(
            self.u,
            self.y,
            order,
            k,
            design=self.design,
            stride=self.stride,
            instruments=SELECTION_IV_STEPS,
            located=where,
        )
        batches = np.full(BATCHES, np.inf)
        if fit is not None:
            y_hat = self.design.free_run(fit.b, fit.a, where.segment, where.position, fit.phi)
            batches = batch_errors((self.y[self.held] - fit.offset - y_hat[self.held]) ** 2)
        mse = float(np.mean(batches)) if fit is not None else math.inf
        if fit is not None and not math.isfinite(mse):
            fit, mse = None, math.inf
        cand = Candidate(
            order,
            fit.n_knots if fit is not None else k,
            n_params(order, fit.n_knots if fit is not None else k),
            mse,
            fit.estimator if fit is not None else "unstable",
            batches,
            fit,
        )
        self.done[(order, k)] = cand
        self.order.append(cand)
        return cand

    def scan_orders(self, k: int, orders: list[int], patience: int | None) -> int | None:
        """Evaluate ``orders`` at ``k`` knots; the best order (None if none worked)."""
        best: Candidate | None = None
        since = 0
        for order in orders:
            c = self(order, k)
            if c is None or not math.isfinite(c.validation_mse):
                since += 1
            elif best is None or c.validation_mse < best.validation_mse:
                best, since = c, 0
            else:
                since += 1
            if patience is not None and best is not None and since > patience:
                break
        return None if best is None else best.order

    def scan_knots(self, order: int, grid: list[int]) -> int | None:
        best: Candidate | None = None
        for k in grid:
            c = self(order, k)
            if c is None or not math.isfinite(c.validation_mse):
                continue
            if best is None or c.validation_mse < best.validation_mse:
                best = c
        return None if best is None else best.n_knots


def _search(
    u: F64,
    y: F64,
    max_order: int,
    order: int | None,
    n_knots: int | None,
    validation_fraction: float,
    max_rows: int,
) -> _Search:
    """The candidates tried (module docstring: the linear ones, then by coordinates)."""
    search = _Search(u, y, design(u.shape[0], validation_fraction), max_rows)
    every = list(range(1, max_order + 1))
    orders = [order] if order is not None else every
    search.scan_orders(2, every + [o for o in orders if o not in every], None)
    if n_knots is not None:
        search.scan_orders(n_knots, orders, PATIENCE if order is None else None)
    elif search.distinct > 2:
        grid = [k for k in KNOT_GRID if 2 < k <= search.distinct]
        k_now: int | None = max([k for k in grid if k <= START_KNOTS] or grid[:1])
        seen: set[tuple[int, int]] = set()
        for _ in range(ROUNDS):  # coordinate search: orders at k_now, knots at that order
            assert k_now is not None
            best_order = search.scan_orders(k_now, orders, PATIENCE if order is None else None)
            if best_order is None or (best_order, k_now) in seen:
                break
            seen.add((best_order, k_now))
            k_now = search.scan_knots(best_order, grid)
            if k_now is None:
                break
    return search


def select_structure(
    u: F64,
    y: F64,
    *,
    max_order: int,
    order: int | None = None,
    n_knots: int | None = None,
    validation_fraction: float = 0.25,
    max_rows: int = MAX_ROWS,
) -> Selection | None:
    """Try structures on an estimation/validation split and choose one (module docstring).

    Parameters
    ----------
    u, y : ndarray, shape (n,)
        Input and output, finite.
    max_order : int
        Largest order ``l`` tried (when ``order`` is None).
    order : int, optional
        A fixed order (only the knots are chosen).
    n_knots : int, optional
        A fixed knot count (only the order is chosen); the linear baseline is
        still chosen among ``K = 2``.
    validation_fraction : float
        Share of the record held out, as every ``round(1 / fraction)``-th block.
    max_rows : int
        Estimation rows summed per candidate at most.

    Returns
    -------
    Selection or None
        None if no candidate gave a stable model.
    """
    with one_blas_thread():
        search = _search(u, y, max_order, order, n_knots, validation_fraction, max_rows)
    good = [c for c in search.order if math.isfinite(c.validation_mse)]
    linear = [c for c in good if c.linear and c.order <= max_order]
    eligible = [c for c in good if order is None or c.order == order]
    if not eligible or not linear:
        return None
    rows = search.rows / search.stride
    best = min(good, key=lambda c: (c.validation_mse, c.n_params))
    lin, best_linear = _one_se(linear, rows)
    chosen, _ = _one_se(eligible, rows)
    if not chosen.linear:  # kept only if it beats the best linear model
        winners = [c for c in eligible if not c.linear and beats(c, best_linear, rows)]
        fallback = [c for c in eligible if c.linear]
        if winners:
            chosen = _one_se(winners, rows)[0]
        elif fallback:
            chosen = _one_se(fallback, rows)[0]
    if chosen.linear and order is None:  # no nonlinear model wins: the baseline's structure
        chosen = lin
    held = search.held
    n_est = int(np.count_nonzero(search.design.mask))
    variance = float(np.var(search.y[held]))
    return Selection(
        tuple(search.order),
        chosen,
        best,
        lin,
        best_linear,
        n_est,
        int(np.count_nonzero(held)),
        search.stride,
        rows,
        held_part(u.shape[0], validation_fraction),
        variance,
    )


def trailing(n: int, n_estimation: int) -> Split:
    """Estimate on the samples before ``n_estimation``, validate on the rest: one free run.

    A record of at most :data:`SELECTION_SAMPLES` samples is used whole; a longer
    one through a window of that many samples about ``n_estimation`` (three
    quarters before it, at most), simulated from rest over the :data:`BURN_IN`
    samples before the window.
    """
    if n <= SELECTION_SAMPLES:
        run, start, stop = 0, 0, n
    else:
        start = n_estimation - min(n_estimation, 3 * SELECTION_SAMPLES // 4)
        stop = min(n, start + SELECTION_SAMPLES)
        run = max(0, start - BURN_IN)
    m = stop - run
    index = np.arange(run, stop, dtype=np.int64)
    mask = (index >= start) & (index < n_estimation)
    segments = np.array([[start - run, n_estimation - run]], dtype=np.int64)
    runs = np.array([[0, m]], dtype=np.int64)
    return Design(segments, runs, mask), index >= n_estimation, index


def linear_candidates(
    u: F64, y: F64, max_order: int, split: Split, max_rows: int = MAX_ROWS
) -> tuple[list[Candidate], float]:
    """The linear models of orders 1 to ``max_order`` fitted and validated on ``split``
    (those with a stable fit), and the estimation rows summed."""
    with one_blas_thread():
        search = _Search(u, y, split, max_rows)
        search.scan_orders(2, list(range(1, max_order + 1)), None)
    good = [c for c in search.order if math.isfinite(c.validation_mse)]
    return good, search.rows / search.stride


def final_fit(u: F64, y: F64, cand: Candidate) -> StructureFit:
    """The candidate's structure fitted to the whole record (instrumental variables tried).

    Falls back to the candidate's own fit on the estimation part if the whole
    record gives no stable model.
    """
    with one_blas_thread():
        fit = fit_structure(u, y, cand.order, cand.n_knots)
    if fit is None:
        assert cand.fit is not None  # a chosen candidate always has a stable fit
        return cand.fit
    return fit
