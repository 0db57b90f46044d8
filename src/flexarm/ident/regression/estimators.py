"""Kernel regression estimates of ``m(x) = E[Y | X = x]`` (paper §5, eq. 14).

Three estimators share one implementation:

* :class:`SemiRecursiveKernelRegression` — eq. 14 (Wolverton–Wagner,
  Krzyżak–Pawlak): ``m_n(x) = sum_i Y_i K((x - X_i)/h_i) / sum_i K((x - X_i)/h_i)``
  with ``h_i = bandwidth * i**(-decay)``;
* :class:`NadarayaWatson` — the classical estimate, ``decay = 0`` (one fixed ``h``);
* :class:`RecursiveKernelRegression` — the fully recursive (Devroye–Wagner)
  estimate, weights ``h_i**(-d) K((x - X_i)/h_i)``; with a bandwidth per
  dimension ``h_i**(-d)`` means ``prod_j h_ij**(-1)``.

``i`` is 1-based and counts every sample seen, across
:meth:`~SemiRecursiveKernelRegression.partial_fit` calls.

Modes
-----
The estimator validates its hyperparameters into a constant
:class:`~flexarm.ident.regression.accumulators.Smoothing` and chooses the accumulator that
keeps the streaming state (:mod:`flexarm.ident.regression.accumulators`, one per mode):

* **exact** (``grid=None``): the samples are stored;
  :meth:`~SemiRecursiveKernelRegression.predict` evaluates eq. 14 at any point (by the
  Gaussian series where ``series`` selects it);
* **grid** (``grid`` given): running sums ``numerator_`` and ``denominator_``
  at the grid points; :meth:`~SemiRecursiveKernelRegression.predict` accepts grid points
  only;
* **binned** (``grid`` and ``binned=r``, ``d = 1``): linear binning, with the
  error bound of :mod:`flexarm.ident.regression.binning`
  (:meth:`~SemiRecursiveKernelRegression.error_bound`);
* **series** (``grid``, Gaussian, one bandwidth, ``d = 1``; chosen by the
  default ``series="auto"``, or ``series=True``): cluster moments of a fast
  Gauss transform, ``O(n + m)`` work, equal to direct summation to rounding
  (to ``2e-13`` of the weighted mean ``|Y|``; bit for bit far from the data).

Chunked ``partial_fit`` equals ``fit`` bit for bit in every mode, and exact
mode equals grid mode bit for bit at the grid points with ``series=False``
(the tests also hold both to a direct NumPy evaluation of eq. 14, to ~1e-11):
the sums run in the blocked order of :mod:`flexarm.ident.regression.accumulators.blocks`.

At scale
--------
:meth:`~SemiRecursiveKernelRegression.fit_chunks` fits from any iterator of
``(X, y)`` chunks, and :meth:`~SemiRecursiveKernelRegression.fit` /
:meth:`~SemiRecursiveKernelRegression.partial_fit` accept Dask arrays (summed
per block on Dask's workers, combined in order on the client); both equal the
in-memory fit bit for bit, in memory bounded by a few chunks outside exact
mode (:mod:`flexarm.ident.regression.chunked`).

State and persistence
---------------------
A fit leaves one frozen value, :attr:`~SemiRecursiveKernelRegression.state_`
(a :class:`RegressionState`: the hyperparameters the first fit froze and the
mode's accumulator); ``partial_fit`` continues only while the hyperparameters
keep those values, compared as values (arrays element by element, so that a
change in place counts; the Hammerstein identifier follows the same rule).
:meth:`~SemiRecursiveKernelRegression.to_arrays` describes it as plain arrays —
the hyperparameters, then the accumulator's
:meth:`~flexarm.ident.regression.accumulators.Accumulator.state` — and
:meth:`~SemiRecursiveKernelRegression.save` writes them to one ``.npz`` file;
:meth:`~SemiRecursiveKernelRegression.load` rebuilds the estimator and its
accumulator from it
(:meth:`~flexarm.ident.regression.accumulators.Accumulator.from_state`), and
continuing with ``partial_fit`` gives bit for bit what never stopping would
have given.

Hyperparameter bounds
---------------------
``bandwidth > 0`` (a scalar, or one finite value per input dimension), or
``"silverman"`` (:mod:`flexarm.ident.regression.bandwidth`: Silverman's rule of thumb,
evaluated on the samples of the first ``fit`` or ``partial_fit`` call). With
``h_i**d = bandwidth**d i**(-d decay)``, the consistency conditions of
Theorem 1, ``h_i -> 0`` and ``sum h_i**d = inf``, hold iff ``0 < decay <= 1/d``.
``decay = 0`` (fixed ``h``, the classical estimate) is also allowed;
``decay < 0`` or ``decay > 1/d`` is rejected — by
:meth:`~SemiRecursiveKernelRegression.fit`, since ``d`` is known only there.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any, ClassVar, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._types import F64
from ...errors import InvalidValueError
from .._estimator import SavedEstimator
from ._setup import check_X, check_Xy, smoothing
from ._state import RegressionState, hyperparameters, state_arrays
from .accumulators import Accumulator, BinnedSums, ExactSamples, GridAccumulator, State, choose
from .bandwidth import Silverman
from .chunked import fit_dask, fit_iterable, is_dask
from .kernels import KernelFunction

__all__ = [
    "NadarayaWatson",
    "RecursiveKernelRegression",
    "RegressionState",
    "SemiRecursiveKernelRegression",
]

#: A bandwidth: ``h_1`` (one value, or one per input dimension), a rule name or a rule.
Bandwidth = float | ArrayLike | str | Silverman


class _KernelRegression(SavedEstimator[RegressionState]):
    """Shared implementation; see the module docstring for the design."""

    _recursive: ClassVar[bool] = False
    _fixed_decay: ClassVar[float | None] = None

    kernel: str | KernelFunction
    bandwidth: Bandwidth
    grid: ArrayLike | None

    def __init__(
        self,
        kernel: str | KernelFunction = "gaussian",
        bandwidth: Bandwidth = 1.0,
        decay: float = 0.2,
        grid: ArrayLike | None = None,
        binned: float | None = None,
        series: bool | str = "auto",
    ) -> None:
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.decay = decay
        self.grid = grid
        self.binned = binned
        self.series = series

    # ---------------------------------------------------------------- fitting

    def _start(
        self,
        X: F64 | None = None,
        d: int | None = None,
        bandwidth: F64 | None = None,
        state: Mapping[str, NDArray[Any]] | None = None,
        source: str | None = None,
    ) -> Accumulator:
        """Validate the hyperparameters (on the first samples ``X``) and set up the state.

        To restore a saved estimator give ``d``, the resolved ``bandwidth`` and
        the accumulator's ``state`` instead of ``X``; to fit from chunks or a
        Dask array, ``d`` and the ``source`` (no bandwidth rule then).
        """
        setup = smoothing(
            self.get_params(),
            self._owner,
            recursive=self._recursive,
            fixed_decay=self._fixed_decay,
            X=X,
            d=d,
            bandwidth=bandwidth,
            source=source,
        )
        kind = choose(setup)
        acc: Accumulator = kind(setup) if state is None else kind.from_state(setup, state)
        self._set_state(RegressionState(params=self._freeze(), accumulator=acc))
        return acc

    def _check_fitted(self) -> Accumulator:
        return self._fitted_state().accumulator

    def fit(self, X: ArrayLike, y: ArrayLike) -> Self:
        """Forget any previous state and fit to the samples.

        ``X`` and ``y`` may be Dask arrays (:mod:`flexarm.ident.regression.chunked`): the
        chunks are summed on Dask's workers and combined in order, bit for bit
        as the in-memory fit, in bounded memory outside exact mode. A bandwidth
        rule is refused then (it needs every sample at once).

        Parameters
        ----------
        X : array_like or dask array, shape (n,) or (n, d)
            Inputs ``X_i`` (units of the regressor); shape ``(n,)`` means ``d = 1``.
        y : array_like or dask array, shape (n,)
            Outputs ``Y_i`` (units of the response).

        Returns
        -------
        self
        """
        self._forget()
        if is_dask(X) or is_dask(y):
            return self._guarded(lambda: fit_dask(self._begin, X, y, self._owner))
        Xa, ya = check_Xy(X, y, self._owner)
        self._start(Xa).add_chunk(Xa, ya)
        return self

    def fit_chunks(self, chunks: Iterable[tuple[ArrayLike, ArrayLike]]) -> Self:
        """Forget any previous state and fit to the samples of an iterator of chunks.

        The same estimate, bit for bit, as :meth:`fit` on the concatenated
        samples (and as :meth:`partial_fit` on each chunk in turn), holding one
        chunk at a time: bounded memory in the grid, binned and series modes.
        A bandwidth rule is refused (it needs every sample at once).

        Parameters
        ----------
        chunks : iterable of (X, y)
            ``X`` of shape ``(m,)`` or ``(m, d)`` (units of the regressor), ``y``
            of shape ``(m,)`` (units of the response); ``m`` may vary from chunk
            to chunk. A generator is consumed once.

        Returns
        -------
        self
        """
        self._forget()
        return self._guarded(lambda: fit_iterable(self._begin, chunks, self._owner))

    def _begin(self, d: int, source: str) -> Accumulator:
        """The accumulator to continue (``partial_fit``), or a new one for ``d`` inputs."""
        if self._is_fitted():
            return self._continued(d)
        return self._start(d=d, source=source)

    def _guarded(self, run: Callable[[], Accumulator]) -> Self:
        """Run a chunked fit; on an error the estimator is left unfitted."""
        try:
            run()
        except BaseException:
            self._forget()
            raise
        return self

    def partial_fit(self, X: ArrayLike, y: ArrayLike) -> Self:
        """Add samples to the estimate; chunks give the same result as one :meth:`fit`.

        The hyperparameters are fixed by the first call (a bandwidth rule is
        evaluated on its samples); changing them before a later call raises
        ``ValueError`` (call :meth:`fit` to start again).

        ``X`` and ``y`` may be Dask arrays (as in :meth:`fit`); if a chunk turns
        out bad (e.g. NaN), the chunks combined before it stay added.

        Parameters
        ----------
        X : array_like or dask array, shape (n,) or (n, d)
            Inputs ``X_i`` (units of the regressor).
        y : array_like or dask array, shape (n,)
            Outputs ``Y_i`` (units of the response).

        Returns
        -------
        self
        """
        if is_dask(X) or is_dask(y):
            fit_dask(self._begin, X, y, self._owner)
            return self
        Xa, ya = check_Xy(X, y, self._owner)
        acc = self._continued(Xa.shape[1]) if self._is_fitted() else self._start(Xa)
        acc.add_chunk(Xa, ya)
        return self

    def _continued(self, d_new: int) -> Accumulator:
        """The accumulator ``partial_fit`` continues: same ``d``, unchanged hyperparameters."""
        state = self._fitted_state()
        d = state.accumulator.setup.d
        if d_new != d:
            raise InvalidValueError(
                f"The 'X' parameter of {self._owner} must be of {d} column(s) as before. "
                f"Got {d_new} instead."
            )
        self._check_unchanged(state)
        return state.accumulator

    # ---------------------------------------------------------------- fitted state

    @property
    def n_samples_(self) -> int:
        """Samples seen so far."""
        return self._check_fitted().n_samples

    @property
    def n_features_in_(self) -> int:
        """Input dimension ``d``."""
        return self._check_fitted().setup.d

    @property
    def bandwidth_(self) -> F64:
        """``h_1`` in use, shape ``(d,)`` (the validated ``bandwidth``, or its rule's value)."""
        return self._check_fitted().setup.bandwidth

    @property
    def kernel_(self) -> str | KernelFunction:
        """The kernel in use."""
        return self._check_fitted().setup.kernel

    def _mode(self, name: str, kind: type, where: str) -> Any:
        acc = self._check_fitted()
        if not isinstance(acc, kind):
            raise AttributeError(f"{name} is {where}")
        return acc

    def _exact(self, name: str) -> ExactSamples:
        acc: ExactSamples = self._mode(
            name, ExactSamples, "not kept in grid mode (grid is not None)"
        )
        return acc

    def _grid(self, name: str) -> GridAccumulator:
        acc: GridAccumulator = self._mode(
            name, GridAccumulator, "kept in grid mode only (grid is None)"
        )
        return acc

    def _binned(self, name: str) -> BinnedSums:
        acc: BinnedSums = self._mode(name, BinnedSums, "kept in binned mode only (binned is None)")
        return acc

    @property
    def X_(self) -> F64:
        """Stored inputs, shape ``(n_samples_, d)`` (exact mode only)."""
        return self._exact("X_").X

    @property
    def y_(self) -> F64:
        """Stored outputs, shape ``(n_samples_,)`` (exact mode only)."""
        return self._exact("y_").y

    @property
    def bandwidths_(self) -> F64:
        """Per-sample bandwidths ``h_i``, shape ``(n_samples_, d)`` (exact mode only)."""
        return self._exact("bandwidths_").h

    @property
    def grid_(self) -> F64:
        """The grid, shape ``(g, d)`` (grid modes only)."""
        return self._grid("grid_").grid

    @property
    def numerator_(self) -> F64:
        """Running ``sum_i Y_i w_i`` at the grid points, shape ``(g,)`` (grid mode only)."""
        return self._grid("numerator_").grid_sums()[0]

    @property
    def denominator_(self) -> F64:
        """Running ``g_n = sum_i w_i`` at the grid points, shape ``(g,)`` (grid mode only)."""
        return self._grid("denominator_").grid_sums()[1]

    @property
    def bin_error_(self) -> float:
        """Bound ``E`` on the error of one binned kernel weight (binned mode only).

        See :mod:`flexarm.ident.regression.binning` and :meth:`sum_error_bounds`.
        """
        return self._binned("bin_error_").weight_error

    def sum_error_bounds(self, X: ArrayLike) -> tuple[F64, F64]:
        """Bounds on the errors of the binned sums at grid points (binned mode only).

        ``eN >= |N_binned(x) - N(x)|`` and ``eD >= |D_binned(x) - D(x)|`` with
        ``N``, ``D`` the exact ``numerator_`` and ``denominator_``:
        ``eN = E A_near(x) + (tau + rho) A``, ``eD = E S_near(x) + (tau + rho) S``
        with ``rho = 4 (2 n + J + 16) 2**-53`` for the rounding of the sums
        (``J`` bins in the open block); see :mod:`flexarm.ident.regression.binning`.

        Parameters
        ----------
        X : array_like, shape (m,) or (m, 1)
            Grid points (units of the regressor).

        Returns
        -------
        eN, eD : ndarray, shape (m,)
            Bounds (units of the response times weight; weight).
        """
        acc = self._binned("sum_error_bounds")
        Q = self._query(X)
        return acc.sum_error_bounds(acc.index(Q))

    def error_bound(self, X: ArrayLike) -> F64:
        """Bound on ``|m_binned(x) - m(x)|`` at grid points, ``m`` the exact estimate.

        ``(eN + |m_binned| eD) / (D_binned - eD)`` where ``D_binned > eD``
        (:meth:`sum_error_bounds`), ``inf`` elsewhere, NaN where ``m_binned``
        is NaN; see :mod:`flexarm.ident.regression.binning`. Binned mode only.

        Parameters
        ----------
        X : array_like, shape (m,) or (m, 1)
            Grid points (units of the regressor).

        Returns
        -------
        ndarray, shape (m,)
            Bounds (units of the response).
        """
        eN, eD = self.sum_error_bounds(X)
        acc = self._binned("error_bound")
        Q = self._query(X)
        m = acc.evaluate(Q)
        den = acc.sums()[1][acc.index(Q)]
        with np.errstate(divide="ignore", invalid="ignore"):
            out: F64 = np.where(den > eD, (eN + np.abs(m) * eD) / (den - eD), np.inf)
        out[np.isnan(m)] = np.nan
        return out

    # ---------------------------------------------------------------- prediction

    def _query(self, X: ArrayLike) -> F64:
        d = self._check_fitted().setup.d
        Q = check_X(X, self._owner)
        if Q.shape[1] != d:
            raise InvalidValueError(
                f"The 'X' parameter of {self._owner} must be of {d} column(s) like the "
                f"training X. Got {Q.shape[1]} instead."
            )
        return Q

    def predict(self, X: ArrayLike) -> F64:
        """Return the estimate ``m_n(x)`` at the query points; NaN where no sample has weight.

        Parameters
        ----------
        X : array_like, shape (m,) or (m, d)
            Query points (units of the regressor). In grid mode they must be
            points of ``grid``.

        Returns
        -------
        ndarray, shape (m,)
            Estimates (units of the response).
        """
        acc = self._check_fitted()
        return acc.evaluate(self._query(X))

    # ---------------------------------------------------------------- persistence

    def to_arrays(self) -> State:
        """The hyperparameters, then the accumulator's state
        (:mod:`flexarm.ident.regression.accumulators`), as plain arrays: what :meth:`save`
        writes. A user-callable ``kernel`` cannot be written."""
        return state_arrays(self._fitted_state(), self._owner)

    @classmethod
    def from_arrays(cls, data: Mapping[str, NDArray[Any]]) -> Self:
        """The estimator :meth:`to_arrays` described (``data``: its output, or the arrays of
        a file :meth:`save` wrote), its accumulator resumed: continuing with
        ``partial_fit`` gives bit for bit what never stopping would have given."""
        kwargs, d, h1 = hyperparameters(data, cls.__name__, cls._get_param_names())
        est = cls(**kwargs)
        est._start(d=d, bandwidth=h1, state=data)
        return est


class SemiRecursiveKernelRegression(_KernelRegression):
    """Semi-recursive kernel regression estimate, eq. 14 of the paper.

    ``m_n(x) = sum_{i<=n} Y_i K((x - X_i)/h_i) / sum_{i<=n} K((x - X_i)/h_i)``,
    ``h_i = bandwidth * i**(-decay)``; see the module docstring for the
    modes (exact, grid, binned, series) and the bounds on ``decay``.

    Parameters
    ----------
    kernel : str or callable, default "gaussian"
        One of ``"gaussian"``, ``"epanechnikov"``, ``"uniform"``,
        ``"triangular"`` (product kernels in ``d`` dimensions), or ``K(u)``
        mapping ``u`` of shape ``(m, d)`` to weights of shape ``(m,)``.
    bandwidth : float, array_like of shape (d,), "silverman" or Silverman, default 1.0
        ``h_1`` (units of ``X``), one value or one per input dimension; > 0.
        ``"silverman"``: Silverman's rule of thumb for the last sample of the
        first ``fit``/``partial_fit`` call (:mod:`flexarm.ident.regression.bandwidth`);
        a :class:`~flexarm.ident.regression.bandwidth.Silverman` gives a multiple of it.
    decay : float, default 0.2
        ``h_i = bandwidth * i**(-decay)``; ``0 <= decay <= 1/d``.
    grid : array_like of shape (g,) or (g, d), optional
        Evaluation points for grid mode; ``None`` (default) for exact mode.
    binned : float, optional
        ``None`` (default): exact sums. A number ``r`` in ``[1e-4, 0.5]``:
        approximate grid mode (``d = 1``, continuous kernels) by linear binning
        with bins ``r h`` wide, with a proven error bound; see
        :mod:`flexarm.ident.regression.binning`, :attr:`bin_error_` and :meth:`error_bound`.
    series : bool or "auto", default "auto"
        Gaussian kernel with one bandwidth (``decay = 0``), ``d = 1``, not
        binned: compute the kernel sums by a Taylor series about clusters
        ``h/8`` wide (a fast Gauss transform,
        :func:`flexarm.ident.regression.kernels.gauss_series_moments`), ``O(n + m)``
        instead of ``O(n m)``. At every point with a sample within 36.6 h the
        estimate agrees with direct summation to ``2e-13 A / D`` (``A / D`` the
        kernel-weighted mean of ``|Y_i|``; not bit for bit); farther out, where
        the direct weights are subnormal or zero, it *is* the direct sum, bit
        for bit (NaN past 38.61 h); see :mod:`flexarm.ident.regression.accumulators.series`.
        ``"auto"``: the series wherever it applies (exact mode: unless its
        clusters outnumber the samples; grid mode: unless the grid spans more
        than ~2000 bandwidths or a sample's window holds fewer than 8 grid
        points), direct sums elsewhere. ``True`` insists (an error where it
        does not apply); ``False``: direct sums (exact mode then equals grid
        mode bit for bit). Grid mode keeps the cluster moments as its state
        (chunked ``partial_fit`` equals ``fit`` bit for bit).

    Attributes
    ----------
    n_samples_ : int
        Samples seen so far.
    n_features_in_ : int
        Input dimension ``d``.
    bandwidth_ : ndarray, shape (d,)
        ``h_1`` in use: the validated ``bandwidth``, or its rule's value.
    kernel_ : str or callable
        The kernel in use.
    X_, y_, bandwidths_ : ndarray
        Exact mode: stored samples and their ``h_i``.
    grid_, numerator_, denominator_ : ndarray, shape (g, d), (g,), (g,)
        Grid mode: the grid and the running sums ``sum Y_i K_i``, ``g_n = sum K_i``.
    bin_error_ : float
        Binned mode: the bound ``E`` on the error of one weight (see
        :meth:`sum_error_bounds` and :meth:`error_bound`).
    state_ : RegressionState
        The fitted state: the frozen hyperparameters and the mode's accumulator.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.uniform(0, 1, 2000)
    >>> y = np.sin(2 * np.pi * X) + 0.1 * rng.standard_normal(2000)
    >>> est = SemiRecursiveKernelRegression(kernel="epanechnikov", bandwidth=0.3).fit(X, y)
    >>> m = est.predict([0.25, 5.0])  # 5.0 is far from every sample
    >>> round(float(m[0]), 1), bool(np.isnan(m[1]))
    (1.0, True)
    """


class RecursiveKernelRegression(_KernelRegression):
    """Fully recursive (Devroye–Wagner) kernel regression estimate.

    ``m_n(x) = sum_i Y_i h_i**(-d) K((x - X_i)/h_i) / sum_i h_i**(-d) K((x - X_i)/h_i)``
    (``h_i**(-d)`` is ``prod_j h_ij**(-1)`` for a per-dimension bandwidth).
    Parameters and attributes as :class:`SemiRecursiveKernelRegression`.
    """

    _recursive = True


class NadarayaWatson(_KernelRegression):
    """Classical Nadaraya–Watson estimate: eq. 14 with one fixed bandwidth (``decay = 0``).

    Parameters and attributes as :class:`SemiRecursiveKernelRegression`, without ``decay``.
    """

    _fixed_decay = 0.0

    def __init__(
        self,
        kernel: str | KernelFunction = "gaussian",
        bandwidth: Bandwidth = 1.0,
        grid: ArrayLike | None = None,
        binned: float | None = None,
        series: bool | str = "auto",
    ) -> None:
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.grid = grid
        self.binned = binned
        self.series = series
