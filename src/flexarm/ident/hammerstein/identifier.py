r"""Nonparametric identification of Hammerstein systems (paper §5, Fig. 5), for any input.

Model: ``W_n = phi(X_n) + xi_n``, ``Y_n = sum_k lambda_k W_{n-k}`` (a stable ARMA
subsystem, :mod:`flexarm.ident.hammerstein.systems`). :class:`HammersteinIdentifier` has two
paths and tells which it took (``method_``, ``report_``):

* **White input: the paper's correlation approach** (exact for i.i.d. input,
  streaming). For every lag ``k``, ``m_k(x) = E[Y_{n+k} | X_n = x] =
  lambda_k phi(x) + c_k``: the centred lag regressions, each the paper's
  semi-recursive kernel estimate (eq. 14) on a grid, form a rank-one array.
  The impulse response is the covariance with an instrument (``"auto"``: the
  leading singular pair, which also serves an even ``phi`` and a delayed linear
  part; ``"regression"``: ``m_0``, the paper's; ``"input"``: ``x``), the shape
  of ``phi`` their least-squares combination, normalised by two known points
  (the paper's ``d1``, ``alpha``) or else with the impulse response's largest
  entry ``+1`` and ``phi`` of mean zero; the ARMA coefficients come from the
  impulse response (:mod:`~flexarm.ident.hammerstein.white.arma`, order by BIC). Steps:
  :mod:`~flexarm.ident.hammerstein.white.lags`,
  :func:`~flexarm.ident.hammerstein.white.correlation.solve`.
* **Correlated input** (:mod:`flexarm.ident.hammerstein.correlated.solve`): the ARX-Hammerstein
  structure fitted directly — over-parameterised least squares on a
  piecewise-linear basis for ``phi`` with knots at the input's quantiles,
  Bai's rank-one separation, instrumental variables kept when they lower the
  output error (:mod:`flexarm.ident.hammerstein.correlated.arx`); order and knots by the
  one-standard-error rule on held-out free-run error
  (:mod:`flexarm.ident.hammerstein.correlated.selection`). Still nonparametric in ``phi``.

``method="auto"`` (default) takes the white path when the input passes the
whiteness test (:func:`~flexarm.ident.hammerstein.whiteness.whiteness_test`: Ljung–Box and
McLeod–Li) and the record is long enough for it, the correlated path
otherwise. Forcing ``method="white"`` on a coloured input warns
(:class:`~flexarm.ident.hammerstein.whiteness.IdentificationWarning`). Every fit is reported
beside its linear baseline (:class:`~flexarm.ident.LinearARX`, same data); a
model that loses to it is flagged and warned about.

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
its fitted model is saved and loaded too (``flexarm.ident.hammerstein._persist``).
"""

from __future__ import annotations

import os
import warnings
from typing import Any, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._validation import check_array
from ...errors import InvalidValueError
from .._estimator import HyperParameters, NotFittedError
from ..regression.bandwidth import Silverman
from ..regression.estimators import SemiRecursiveKernelRegression
from ._params import check_length, choose_path, correlated_orders, validate
from ._persist import load, save
from .bootstrap import Bands, bootstrap_bands
from .correlated.hatbasis import evaluate, locate
from .correlated.selection import Selection
from .correlated.solve import CorrelatedResult, solve_correlated
from .linear import LinearARX
from .prediction import (
    check_input,
    check_record,
    fit_percent,
    max_lag,
    predict_output,
    r2_score,
)
from .report import IdentificationReport, build_report
from .solution import KnownPoints, Solution
from .systems import ARMA
from .white.lags import LagRegressions, solve_white
from .whiteness import DEFAULT_ALPHA, IdentificationWarning

__all__ = ["DEFAULT_BANDWIDTH", "HammersteinIdentifier"]

F64 = NDArray[np.float64]
_OWNER = "HammersteinIdentifier"

#: The default bandwidth: 0.55 times Silverman's rule on the first ``warmup`` inputs.
DEFAULT_BANDWIDTH = Silverman(0.55)


class HammersteinIdentifier(HyperParameters):
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
        Trailing fraction held out to choose the correlated path's structure and
        the baseline's order, in (0, 0.5].
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
        return validate(self)

    # ---------------------------------------------------------------- fitting

    def _reset(self) -> None:
        for name in ("_params", "_frozen", "_lags", "_cache", "_path", "_result", "_report",
                     "whiteness_", "baseline_", "_n_seen"):  # fmt: skip
            self.__dict__.pop(name, None)

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
        self._reset()
        notes: list[str] = []
        if path == "white" and not white.white:
            notes.append(f"the white-input path was forced on an input that is not white: {reason}")
        baseline = LinearARX(
            max_order=correlated_orders(p, baseline=True)[1],
            validation_fraction=p["validation_fraction"],
        )
        if path == "white":
            self.partial_fit(ua, ya)
            baseline.fit(ua, ya)
        else:
            self._start_correlated(p, ua, ya)
            baseline._fit(ua, ya, self._result.selection, p["n_lags"])
        self.whiteness_ = white
        self.baseline_ = baseline
        self._report = build_report(
            p,
            path,
            reason,
            white,
            self._solution(),
            self.__dict__.get("_result"),
            fit_percent(ya, self.predict(ua)),
            baseline,
            baseline.fit_percent(ua, ya),
            notes,
        )
        for note in self._report.warnings:
            warnings.warn(note, IdentificationWarning, stacklevel=2)
        return self

    def _start_correlated(self, p: dict[str, Any], u: F64, y: F64) -> None:
        order, top = correlated_orders(p)
        self._params, self._frozen, self._path = p, self.get_params(), "correlated"
        self._n_seen = int(u.shape[0])
        self._result = solve_correlated(
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
        self._cache = self._result.solution

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
        if self.__dict__.get("_path") == "correlated" or self.method == "correlated":
            raise InvalidValueError(
                f"The 'method' parameter of {_OWNER} must be 'auto' or 'white' to stream with "
                "partial_fit (the correlated-input path needs the whole record: call fit). "
                "Got a correlated-path identifier instead."
            )
        if "_params" not in self.__dict__:
            self._params = self._validated()
            self._frozen = self.get_params()
            self._lags = LagRegressions(self._params, _OWNER)
            self._path = "white"
        else:
            now = self.get_params()
            changed = sorted(k for k in now if repr(now[k]) != repr(self._frozen[k]))
            if changed:
                raise InvalidValueError(
                    f"The {changed} parameter(s) of {_OWNER} changed since the first "
                    "partial_fit. Got new values instead; call fit to start again."
                )
        self.__dict__.pop("_cache", None)
        self.__dict__.pop("_report", None)
        self._lags.add_chunk(ua, ya)
        return self

    # ---------------------------------------------------------------- state

    @property
    def method_(self) -> str:
        """The path used: ``"white"`` or ``"correlated"``."""
        path: str | None = self.__dict__.get("_path")
        if path is None:
            raise NotFittedError(f"This {_OWNER} instance is not fitted yet.")
        return path

    @property
    def report_(self) -> IdentificationReport:
        """What the last :meth:`fit` did (path, reason, structure, baseline, warnings)."""
        report: IdentificationReport | None = self.__dict__.get("_report")
        if report is None:
            raise NotFittedError(
                f"This {_OWNER} instance has no report: call 'fit' (partial_fit streams "
                "without one)."
            )
        return report

    @property
    def selection_(self) -> Selection:
        """Correlated path: the structures tried on held-out data and the choice."""
        result: CorrelatedResult | None = self.__dict__.get("_result")
        if result is None:
            raise AttributeError(
                f"{_OWNER}.selection_ exists after a correlated-path fit in this session "
                "(a loaded identifier keeps its summary in report_.structure)."
            )
        return result.selection

    @property
    def n_samples_(self) -> int:
        """Samples seen."""
        if self.__dict__.get("_path") == "correlated":
            return int(self._n_seen)
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None:
            raise NotFittedError(f"This {_OWNER} instance is not fitted yet.")
        return lags.n_samples

    def _started(self, name: str) -> LagRegressions:
        if self.__dict__.get("_path") == "correlated":
            raise AttributeError(f"{_OWNER}.{name} exists on the white-input path only.")
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None or lags.regressions is None:
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
        cached: Solution | None = self.__dict__.get("_cache")
        if cached is not None:
            return cached
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None or not lags.ready:
            raise NotFittedError(
                f"This {_OWNER} instance is not fitted yet (or has seen fewer than "
                "warmup + n_lags samples). Call 'fit' or 'partial_fit' with more data "
                "before using this estimator."
            )
        sol = solve_white(self._params, lags)
        self._cache = sol
        return sol

    @property
    def impulse_response_(self) -> F64:
        """``lambda_0 .. lambda_{L-1}``, shape (n_lags,)."""
        return self._solution().impulse.copy()

    @property
    def nonlinearity_(self) -> F64:
        """The identified ``phi`` on :attr:`grid_`, shape (g,)."""
        return self._solution().nonlinearity.copy()

    @property
    def shape_(self) -> F64:
        """The unnormalised shape of ``phi`` on :attr:`grid_`, shape (g,)."""
        return self._solution().shape.copy()

    @property
    def grid_(self) -> F64:
        """Points (units of ``u``) where ``phi`` is estimated, shape (g,)."""
        return self._solution().grid.copy()

    @property
    def input_weights_(self) -> F64:
        """Share of the inputs at each point of :attr:`grid_` (sums to 1), shape (g,)."""
        return self._solution().weights.copy()

    @property
    def arma_(self) -> ARMA:
        """The ARMA model of the linear part."""
        return self._solution().arma.model

    @property
    def order_(self) -> int:
        """The ARMA order ``l`` in use."""
        return self._solution().arma.order

    @property
    def max_lag_(self) -> int:
        """``max(p, q)``: the initial conditions :meth:`predict` takes from ``y``."""
        return max_lag(self._solution().arma.model)

    @property
    def criterion_(self) -> dict[int, float]:
        """Criterion of each order tried (BIC/AIC, or the held-out MSE at the chosen knots)."""
        return dict(self._solution().arma.criterion)

    @property
    def offset_(self) -> float:
        """Output offset added by :meth:`predict`, units of ``y``."""
        return self._solution().offset

    @property
    def singular_values_(self) -> F64:
        """Singular values of the rank-one array (rank one if Hammerstein)."""
        return self._solution().singular_values.copy()

    # ---------------------------------------------------------------- model use

    def _phi(self, x: F64) -> F64:
        sol = self._solution()
        if self.__dict__.get("_path") == "correlated":
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

    def score(self, u: ArrayLike, y: ArrayLike, steps_ahead: int | None = None) -> float:
        """R² of :meth:`predict` on ``(u, y)`` (scikit-learn's ``score``; 1 is perfect).

        With ``steps_ahead``, of the k-step prediction; otherwise of the free run from rest.
        """
        ua, ya = check_record(u, y, f"{_OWNER}.score")
        return r2_score(ya, self.predict(ua, ya if steps_ahead else None, steps_ahead))

    def fit_percent(self, u: ArrayLike, y: ArrayLike, steps_ahead: int | None = None) -> float:
        """Fit in percent, ``100 (1 - ||y - y_hat|| / ||y - mean y||)``, of :meth:`predict`.

        With ``steps_ahead``, of the k-step prediction; otherwise of the free run from rest.
        """
        ua, ya = check_record(u, y, f"{_OWNER}.fit_percent")
        return fit_percent(ya, self.predict(ua, ya if steps_ahead else None, steps_ahead))

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

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the identifier to ``path`` (NumPy ``.npz``, plain arrays, atomically).

        White path: the hyperparameters and the streaming state, at any point
        after the first :meth:`fit` or :meth:`partial_fit` (also during the
        warmup); :meth:`load` resumes exactly, so ``partial_fit`` after ``load``
        gives bit for bit what it would have given without stopping. Correlated
        path: the fitted model. Both keep the report and the baseline of a
        :meth:`fit`.

        Parameters
        ----------
        path : str or os.PathLike
            Destination file (no suffix added).
        """
        save(self, path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Self:
        """Read an identifier written by :meth:`save`.

        Parameters
        ----------
        path : str or os.PathLike
            File written by :meth:`save`.

        Returns
        -------
        HammersteinIdentifier
            With the state it had when saved.
        """
        return load(cls, path)
