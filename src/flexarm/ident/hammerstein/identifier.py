r"""Nonparametric identification of Hammerstein systems (paper §5, Fig. 5), for any input.

Model: ``W_n = phi(X_n) + xi_n``, ``Y_n = sum_k lambda_k W_{n-k}`` (a stable ARMA
subsystem, :mod:`flexarm.ident.hammerstein.systems`). :class:`HammersteinIdentifier` has two
paths and tells which it took (``method_``, ``report_``):

* **White input: the paper's correlation approach** (exact for i.i.d. input,
  streaming): the lag regressions ``m_k(x) = E[Y_{n+k} | X_n = x] = lambda_k
  phi(x) + c_k``, each the paper's semi-recursive kernel estimate (eq. 14) on a
  grid, form a rank-one array; the impulse response, ``phi`` and the ARMA model
  follow from it (:mod:`~flexarm.ident.hammerstein.white`).
* **Correlated input**: the ARX-Hammerstein structure fitted directly, ``phi``
  on a piecewise-linear basis, order and knots chosen on held-out data; still
  nonparametric in ``phi`` (:mod:`~flexarm.ident.hammerstein.correlated`).

``method="auto"`` (default) takes the white path when the input passes the
whiteness test (:func:`~flexarm.ident.hammerstein.whiteness.whiteness_test`: Ljung–Box and
McLeod–Li) and the record is long enough for it, the correlated path
otherwise. Forcing ``method="white"`` on a coloured input warns
(:class:`~flexarm.ident.hammerstein.whiteness.IdentificationWarning`). Every fit is reported
beside its linear baseline (:class:`~flexarm.ident.LinearARX`, same data) and
compared, on a validation part of the record, with the best linear model over
the orders searched (:mod:`~flexarm.ident.hammerstein.comparison`:
``report_.comparison`` says which won and by how much). Where the linear model
wins, the correlated path returns it (its structure is the baseline's); with a
given order, and on the white path, the identifier keeps its model and
recommends the baseline by a warning (:attr:`~HammersteinIdentifier.recommended_`).

Defaults and scale (white path)
-------------------------------
Bandwidth ``Silverman(0.55)``: 0.55 times Silverman's rule on the first
``warmup`` inputs (:mod:`flexarm.ident.regression.bandwidth`), narrow enough for jumps of
``phi``; the grid spans those inputs widened by 10 % per side, and the estimate
is held at its end values beyond it. Nothing depends on the units of ``u`` or ``y``.

Streaming and persistence
-------------------------
The white path's state is the lag regressions' running sums:
:meth:`~HammersteinIdentifier.partial_fit` on chunks equals
:meth:`~HammersteinIdentifier.fit` bit for bit, and
:meth:`~HammersteinIdentifier.save` / :meth:`~HammersteinIdentifier.load`
resume it exactly (the streaming state, :mod:`flexarm.ident.regression.accumulators`).
The correlated path needs the whole record (one :meth:`~HammersteinIdentifier.fit`);
its fitted model is saved and loaded too. Everything a fit leaves is one frozen
value, :attr:`~HammersteinIdentifier.state_` (a :class:`HammersteinState`), and
``partial_fit`` continues only while the hyperparameters keep the values the
first call froze, compared as values (arrays element by element; the kernel
regressions follow the same rule).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import replace
from typing import Any, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._types import F64
from ..._validation import check_array, check_int
from ...errors import InvalidValueError
from .._estimator import NotFittedError, SavedEstimator, frozen_params
from ..regression.bandwidth import Silverman
from ..regression.estimators import SemiRecursiveKernelRegression
from ._attributes import SolutionAttributes
from ._params import check_length, choose_path, correlated_orders, validate
from ._state import HammersteinState, state_arrays, state_from_arrays
from .bootstrap import Bands, bootstrap_bands
from .comparison import Comparison, compare_outputs, correlated_comparison, white_comparison
from .correlated.hatbasis import evaluate, locate
from .correlated.selection import Selection
from .correlated.solve import solve_correlated
from .linear import LinearARX, baseline_fit
from .prediction import Scored, check_input, check_record, fit_percent, predict_output
from .report import IdentificationReport, build_report
from .solution import KnownPoints, Solution
from .white.lags import LagRegressions, solve_white
from .whiteness import DEFAULT_ALPHA, IdentificationWarning, WhitenessReport

__all__ = ["DEFAULT_BANDWIDTH", "HammersteinIdentifier", "HammersteinState"]

_OWNER = "HammersteinIdentifier"

#: The default bandwidth: 0.55 times Silverman's rule on the first ``warmup`` inputs.
DEFAULT_BANDWIDTH = Silverman(0.55)


class HammersteinIdentifier(Scored, SolutionAttributes, SavedEstimator[HammersteinState]):
    """Identify a Hammerstein system from input/output data (module docstring).

    Parameters
    ----------
    n_lags : int, default 40
        Length ``L`` of the impulse response reported (white path: estimated,
        lags ``0 .. L-1``; it should cover the linear part's decay).
    order : int or {"auto", "bic", "aic"}, default "auto"
        ARMA order ``l``, or how to choose it: ``"auto"`` is BIC on the white path
        and the held-out one-standard-error rule on the correlated path;
        ``"bic"``/``"aic"`` apply to the white path only.
    max_order : int, optional
        Largest order tried (default 4 on the white path, 10 on the correlated
        path and for the linear baseline); white path: ``n_lags >= 2 max_order + 2``.
    instrument : {"auto", "regression", "input"}, default "auto"
        Instrument of the correlation approach (white path).
    kernel : str, default "epanechnikov"
        Kernel of the lag regressions (white path; :data:`flexarm.ident.KERNELS`).
    bandwidth : float, "silverman" or Silverman, default Silverman(0.55)
        ``h_1`` in units of ``u``, or a rule on the first ``warmup`` inputs (white path).
    decay : float, default 0.2
        ``h_i = h_1 i**-decay``, ``0 <= decay <= 1`` (white path).
    grid_size : int, default 101
        Grid points of the lag regressions (white path).
    known_points : ((x1, phi1), (x2, phi2)), optional
        Two points where ``phi`` is known (``x1 != x2``, ``phi1 != phi2``): the
        paper's two-point normalisation; without them ``phi`` is identified up
        to an affine map (module docstring).
    warmup : int, default 256
        Samples buffered before the grid and bandwidth are fixed (white path,
        which needs ``n >= max(warmup, 4 n_lags)``).
    method : {"auto", "white", "correlated"}, default "auto"
        The path (module docstring).
    n_knots : int or "auto", default "auto"
        Knots of ``phi`` on the correlated path (``>= 2``; 2 is linear), or chosen.
    validation_fraction : float, default 0.25
        Fraction held out, in (0, 0.5]: as interleaved blocks to choose the
        correlated path's structure and the baseline's order (and to compare the
        model with the best linear one), the trailing part to compare the white
        path's model with it.
    alpha : float, default 0.001
        Level of the whiteness test (:mod:`flexarm.ident.hammerstein.whiteness`).

    Attributes
    ----------
    method_ : {"white", "correlated"}
        The path used; ``report_`` says why.
    report_ : IdentificationReport
        Path, reason, whiteness, structure, fit beside the linear baseline, warnings.
    whiteness_ : WhitenessReport or None
        The input's whiteness (None after :meth:`partial_fit` alone).
    baseline_ : LinearARX
        The linear baseline fitted to the same record.
    recommended_ : HammersteinIdentifier or LinearARX
        The model to use (this one, or the baseline where a linear model won).
    selection_ : Selection
        Correlated path: the structures tried on held-out data.
    n_samples_ : int
        Samples seen.
    grid_, nonlinearity_, shape_ : ndarray, shape (g,)
        Points (units of ``u``; the correlated path's knots), the normalised
        ``phi`` there, and its unnormalised shape.
    input_weights_ : ndarray, shape (g,)
        Share of the inputs at each grid point (sums to 1).
    impulse_response_ : ndarray, shape (n_lags,)
        ``lambda_0 .. lambda_{L-1}`` (normalised with ``phi``).
    arma_ : ARMA
        The linear part; ``order_`` its order ``l``; ``criterion_`` the
        criterion of each order tried (BIC/AIC, or held-out MSE).
    offset_ : float
        Output offset of :meth:`predict` (units of ``y``).
    singular_values_ : ndarray
        Of the rank-one array (lag regressions, or the separated ``b c^T``);
        ``s[1] / s[0]`` small for a Hammerstein system.
    bandwidth_, regressions_ :
        White path: ``h_1`` and the lag regressions (grid mode).
    state_ : HammersteinState
        Everything the fit left, in one frozen value.

    Examples
    --------
    >>> from flexarm.ident import Saturation, simulate_hammerstein
    >>> rng = np.random.default_rng(0)
    >>> u = rng.uniform(-2, 2, 20000)
    >>> y = simulate_hammerstein(Saturation(1.0), [0.5], [1.0, 0.0], u, noise_std=0.1, rng=rng)
    >>> est = HammersteinIdentifier(known_points=((0.0, 0.0), (1.5, 1.0))).fit(u, y)
    >>> est.method_, np.round(est.impulse_response_[:3], 1)
    ('white', array([1. , 0.5, 0.2]))
    >>> np.round(est.nonlinearity([-0.5, 0.5, 1.5]), 1)
    array([-0.5,  0.5,  1. ])
    """

    def __init__(
        self,
        n_lags: int = 40,
        order: int | str = "auto",
        max_order: int | None = None,
        instrument: str = "auto",
        kernel: str = "epanechnikov",
        bandwidth: float | str | Silverman = DEFAULT_BANDWIDTH,
        decay: float = 0.2,
        grid_size: int = 101,
        known_points: KnownPoints | None = None,
        warmup: int = 256,
        method: str = "auto",
        n_knots: int | str = "auto",
        validation_fraction: float = 0.25,
        alpha: float = DEFAULT_ALPHA,
    ) -> None:
        self.n_lags = n_lags
        self.order = order
        self.max_order = max_order
        self.instrument = instrument
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.decay = decay
        self.grid_size = grid_size
        self.known_points = known_points
        self.warmup = warmup
        self.method = method
        self.n_knots = n_knots
        self.validation_fraction = validation_fraction
        self.alpha = alpha

    def _validated(self) -> dict[str, Any]:
        """The hyperparameters, checked (:func:`~flexarm.ident.hammerstein._params.validate`)."""
        return validate(self.get_params())

    # ---------------------------------------------------------------- fitting

    def fit(self, u: ArrayLike, y: ArrayLike) -> Self:
        """Forget any previous state and identify the system from one record.

        Parameters
        ----------
        u : array_like, shape (n,)
            Input ``X_n`` (any unit), finite, not constant; ``n >= 100`` (the
            held-out choices), and ``n >= max(warmup, 4 n_lags)`` for the white path.
        y : array_like, shape (n,)
            Output ``Y_n`` (any unit), finite, not constant.

        Returns
        -------
        self
        """
        ua, ya = check_record(u, y, _OWNER)
        p = self._validated()
        check_length(p, ua.shape[0])
        check_record(ua, ya, _OWNER, varying=True)
        path, reason, white = choose_path(p, ua)
        self._forget()
        notes: list[str] = []
        if path == "white" and not white.white:
            notes.append(f"the white-input path was forced on an input that is not white: {reason}")
        baseline = LinearARX(
            max_order=correlated_orders(p, baseline=True)[1],
            validation_fraction=p["validation_fraction"],
        )
        if path == "white":
            baseline.fit(ua, ya)
            comparison = self._stream_white(p, ua, ya, baseline.order_)
        else:
            self._start_correlated(p, ua, ya)
            result = self._fitted_state().result
            assert result is not None
            fit = baseline_fit(ua, ya, result.selection, p["n_lags"], frozen_params(baseline))
            baseline = LinearARX.from_state(fit)
            comparison = correlated_comparison(result.selection)
        self._set_state(replace(self._fitted_state(), whiteness=white, baseline=baseline))
        report = build_report(
            p,
            path,
            reason,
            white,
            self._solution(),
            self._fitted_state().result,
            fit_percent(ya, self.predict(ua)),
            baseline,
            baseline.fit_percent(ua, ya),
            notes,
            comparison,
        )
        self._set_state(replace(self._fitted_state(), report=report))
        for note in report.warnings:
            warnings.warn(note, IdentificationWarning, stacklevel=2)
        return self

    def _stream_white(self, p: dict[str, Any], u: F64, y: F64, base: int) -> Comparison | None:
        """The white path's fit, streamed in two chunks (bit for bit one fit): the model of
        the leading part is compared on the trailing ``validation_fraction`` with the
        best linear model (None if the leading part is too short for a model)."""
        n = u.shape[0]
        n_est = n - max(1, round(p["validation_fraction"] * n))
        self.partial_fit(u[:n_est], y[:n_est])
        lags = self._fitted_state().lags
        sol = self._solution() if lags is not None and lags.ready else None
        self.partial_fit(u[n_est:], y[n_est:])
        if sol is None:
            return None
        top = correlated_orders(p, baseline=True)[1]
        return white_comparison(u, y, sol, n_est, max_order=top, baseline_order=base)

    def _start_correlated(self, p: dict[str, Any], u: F64, y: F64) -> None:
        order, top = correlated_orders(p)
        result = solve_correlated(
            u,
            y,
            n_lags=p["n_lags"],
            order=order,
            max_order=top,
            n_knots=p["n_knots"],
            known_points=p["known_points"],
            validation_fraction=p["validation_fraction"],
            owner=_OWNER,
        )
        self._set_state(
            HammersteinState(
                self._freeze(),
                p,
                "correlated",
                solution=result.solution,
                n_samples=int(u.shape[0]),
                result=result,
            )
        )

    def partial_fit(self, u: ArrayLike, y: ArrayLike) -> Self:
        """Add a chunk of the record to the white path; chunks give bit for bit what one fit gives.

        The hyperparameters are fixed by the first call; the first ``warmup``
        samples are buffered until the grid and bandwidth can be set. Streaming is
        the white-input path's (the correlated path needs the whole record): it
        keeps no whiteness test, baseline or report.

        Parameters
        ----------
        u : array_like, shape (n,)
            Next inputs.
        y : array_like, shape (n,)
            Next outputs.

        Returns
        -------
        self
        """
        ua, ya = check_record(u, y, _OWNER, 0)
        fitted = self._is_fitted()
        if (fitted and self._fitted_state().path == "correlated") or self.method == "correlated":
            raise InvalidValueError(
                f"The 'method' parameter of {_OWNER} must be 'auto' or 'white' to stream with "
                "partial_fit (the correlated-input path needs the whole record: call fit). "
                "Got a correlated-path identifier instead."
            )
        if not fitted:
            p = self._validated()
            state = HammersteinState(self._freeze(), p, "white", lags=LagRegressions(p, _OWNER))
        else:
            state = self._fitted_state()
            self._check_unchanged(state)
            state = replace(state, solution=None, report=None)  # the next chunk moves the model
        self._set_state(state)
        assert state.lags is not None
        state.lags.add_chunk(ua, ya)
        return self

    # ---------------------------------------------------------------- state

    @property
    def method_(self) -> str:
        """The path used: ``"white"`` or ``"correlated"``."""
        return self._fitted_state().path

    def _after_fit(self, name: str) -> Any:
        """The state's ``name``, which only :meth:`fit` sets."""
        value = getattr(self._fitted_state(), name)
        if value is None:
            raise NotFittedError(
                f"This {_OWNER} instance has no {name}: call 'fit' (partial_fit streams "
                "without one)."
            )
        return value

    @property
    def report_(self) -> IdentificationReport:
        """What the last :meth:`fit` did (path, reason, structure, baseline, warnings)."""
        report: IdentificationReport = self._after_fit("report")
        return report

    @property
    def recommended_(self) -> HammersteinIdentifier | LinearARX:
        """The model to use: this identifier, or its :attr:`baseline_` where a linear model
        beat the Hammerstein model on the validation part and the identifier's own model
        is not that linear model (``report_.comparison.recommended``)."""
        comparison = self.report_.comparison
        if comparison is not None and comparison.recommended == "baseline":
            return self.baseline_
        return self

    def compare(
        self, u: ArrayLike, y: ArrayLike, steps_ahead: int | None = None, skip: int = 0
    ) -> Comparison:
        """This model beside its linear :attr:`baseline_` on the data ``(u, y)``: which wins
        (by more than the batch-means standard error of the mean square errors) and by how
        much; :meth:`score` and :meth:`fit_percent` score this model alone.

        Parameters
        ----------
        u, y : array_like, shape (n,)
            Input and measured output (units of ``u`` and ``y``), e.g. data not fitted.
        steps_ahead : int, optional
            ``k >= 1``: of the k-step predictions; None: of the free runs from rest.
        skip : int, default 0
            Samples at the start run through but not scored (``0 <= skip < n``): a
            record's estimation part, say, so that the free runs start from rest there.

        Returns
        -------
        Comparison
        """
        ua, ya = check_record(u, y, f"{_OWNER}.compare")
        start = check_int(skip, "skip", f"{_OWNER}.compare", minimum=0)
        if start >= ua.shape[0]:
            raise InvalidValueError(
                f"The 'skip' parameter of {_OWNER}.compare must be below the {ua.shape[0]} "
                f"samples given. Got {start} instead."
            )
        base = self.baseline_
        given = ya if steps_ahead else None
        st = self.report_.structure
        label = (
            f"order {st['order']}, {st['n_knots']} knots"
            if self.method_ == "correlated"
            else f"white path, ARMA order {self.order_}"
        )
        return compare_outputs(
            ya,
            self.predict(ua, given, steps_ahead),
            base.predict(ua, given, steps_ahead),
            model=label,
            order=base.order_,
            skip=start,
        )

    @property
    def whiteness_(self) -> WhitenessReport | None:
        """The input's whiteness (None after :meth:`partial_fit` alone)."""
        return self._fitted_state().whiteness

    @property
    def baseline_(self) -> LinearARX:
        """The linear baseline fitted to the same record by :meth:`fit`."""
        baseline: LinearARX = self._after_fit("baseline")
        return baseline

    @property
    def selection_(self) -> Selection:
        """Correlated path: the structures tried on held-out data and the choice."""
        result = self._fitted_state().result
        if result is None:
            raise AttributeError(
                f"{_OWNER}.selection_ exists after a correlated-path fit in this session "
                "(a loaded identifier keeps its summary in report_.structure)."
            )
        return result.selection

    @property
    def n_samples_(self) -> int:
        """Samples seen."""
        state = self._fitted_state()
        return state.n_samples if state.lags is None else state.lags.n_samples

    def _started(self, name: str) -> LagRegressions:
        lags = self._fitted_state().lags
        if lags is None:
            raise AttributeError(f"{_OWNER}.{name} exists on the white-input path only.")
        if lags.regressions is None:
            raise NotFittedError(
                f"This {_OWNER} instance has no {name} yet (fewer than warmup samples seen)."
            )
        return lags

    @property
    def bandwidth_(self) -> float:
        """``h_1`` in use (units of ``u``), fixed after ``warmup`` samples (white path)."""
        return self._started("bandwidth_").bandwidth

    @property
    def regressions_(self) -> list[SemiRecursiveKernelRegression]:
        """The lag regressions ``m_k``, ``k = 0 .. n_lags - 1`` (grid mode; white path)."""
        regs = self._started("regressions_").regressions
        assert regs is not None
        return regs

    def _solution(self) -> Solution:
        state = self._fitted_state() if self._is_fitted() else None
        if state is not None and state.solution is not None:
            return state.solution
        lags = None if state is None else state.lags
        if state is None or lags is None or not lags.ready:
            raise NotFittedError(
                f"This {_OWNER} instance is not fitted yet (or has seen fewer than "
                "warmup + n_lags samples). Call 'fit' or 'partial_fit' with more data "
                "before using this estimator."
            )
        sol = solve_white(state.checked, lags)
        self._set_state(replace(state, solution=sol))
        return sol

    # ---------------------------------------------------------------- model use

    def _phi(self, x: F64) -> F64:
        sol = self._solution()
        if self._fitted_state().path == "correlated":
            return evaluate(*locate(x.ravel(), sol.grid), sol.nonlinearity).reshape(x.shape)
        out: F64 = np.interp(x, sol.grid, sol.nonlinearity)
        return out

    def nonlinearity(self, x: ArrayLike) -> F64:
        """The identified ``phi`` at ``x``.

        White path: linear interpolation on the grid, held at the end values
        beyond it. Correlated path: the piecewise-linear estimate, its end
        segments continued beyond the knots (a linear ``phi`` stays linear).

        Parameters
        ----------
        x : array_like, any shape
            Inputs (units of ``u``).

        Returns
        -------
        ndarray, same shape as ``x``
        """
        self._solution()
        return self._phi(check_array(x, "x", f"{_OWNER}.nonlinearity"))

    def predict(
        self, u: ArrayLike, y: ArrayLike | None = None, steps_ahead: int | None = None
    ) -> F64:
        """Output of the model ``offset_ + ARMA(phi_hat(u))``: free run or from data.

        sysidentpy's convention (:mod:`flexarm.ident.hammerstein.prediction`): without ``y``
        the free run from rest; with ``y`` its first :attr:`max_lag_` samples are
        the initial conditions (returned as given) and, with ``steps_ahead = k``,
        each ``y_n`` is predicted from the outputs measured up to ``n - k``.

        Parameters
        ----------
        u : array_like, shape (n,)
            Input sequence (units of ``u``).
        y : array_like, shape (n,), optional
            Measured output (units of ``y``).
        steps_ahead : int, optional
            ``k >= 1`` (needs ``y``); None: free run.

        Returns
        -------
        ndarray, shape (n,)
            Predicted output (units of ``y``).
        """
        sol = self._solution()
        owner = f"{_OWNER}.predict"
        ua = check_input(u, owner)
        return predict_output(
            sol.arma.model, self._phi(ua), sol.offset, y, steps_ahead, owner=owner
        )

    def bands(
        self,
        u: ArrayLike,
        y: ArrayLike,
        *,
        n_boot: int = 100,
        level: float = 0.9,
        block_length: int | None = None,
        rng: np.random.Generator | int | None = None,
    ) -> Bands:
        """Bootstrap bands of ``phi`` and the impulse response on the record ``(u, y)``
        it was fitted to: :func:`flexarm.ident.hammerstein.bootstrap.bootstrap_bands` (``n_boot``
        circular-block replicates, pointwise ``level``, ``rng`` the resampling)."""
        return bootstrap_bands(
            self, u, y, n_boot=n_boot, level=level, block_length=block_length, rng=rng
        )

    # ---------------------------------------------------------------- persistence

    def to_arrays(self) -> dict[str, NDArray[Any]]:
        """The hyperparameters and the state as plain arrays: what :meth:`save` writes.

        White path: the streaming state, at any point after the first :meth:`fit`
        or :meth:`partial_fit` (also during the warmup), so that ``partial_fit``
        after :meth:`load` gives bit for bit what it would have given without
        stopping. Correlated path: the fitted model. Both keep the report and the
        baseline of a :meth:`fit`.
        """
        return state_arrays(self._fitted_state("Call 'fit' or 'partial_fit' before saving it."))

    @classmethod
    def from_arrays(cls, data: Mapping[str, NDArray[Any]]) -> Self:
        """The identifier :meth:`to_arrays` described (``data``: its output, or the arrays
        of a file :meth:`save` wrote; files of format 1 load too), with the state it had."""
        return cls.from_state(state_from_arrays(data))
