"""Kernel regression estimates of ``m(x) = E[Y | X = x]`` (paper §5, eq. 14).

Three estimators share one implementation:

* :class:`SemiRecursiveKernelRegression` — eq. 14 (Wolverton–Wagner,
  Krzyżak–Pawlak): ``m_n(x) = sum_i Y_i K((x - X_i)/h_i) / sum_i K((x - X_i)/h_i)``
  with ``h_i = bandwidth * i**(-decay)``;
* :class:`NadarayaWatson` — the classical estimate, ``decay = 0`` (one fixed ``h``);
* :class:`RecursiveKernelRegression` — the fully recursive (Devroye–Wagner)
  estimate, weights ``h_i**(-d) K((x - X_i)/h_i)``; with a bandwidth per
  dimension ``h_i**(-d)`` means ``prod_j h_ij**(-1)``.

``i`` is 1-based and counts every sample seen, across :meth:`partial_fit` calls.

Streaming state
---------------
The paper's recursion ``m_n = m_{n-1} + (Y_n - m_{n-1}) K_n / g_n`` holds
**per query point**, so an estimate exact at arbitrary points must keep the
samples. Two modes are offered:

* **exact mode** (``grid=None``): the samples ``(X_i, Y_i, h_i)`` are stored
  (amortised growth, so chunked :meth:`partial_fit` costs O(n) in all);
  :meth:`predict` evaluates eq. 14 at any point in O(n) per query (compiled).
* **grid mode** (``grid`` given): only the running sums
  ``numerator_ = sum_i Y_i w_i(x)`` and ``denominator_ = g_n(x) = sum_i w_i(x)``
  at the grid points are kept and updated sample by sample — O(grid) memory,
  exact on the grid, for streams of any length. :meth:`predict` then accepts
  grid points only. Running sums (rather than the ratio form of the recursion)
  are kept; they are the same quantity, and a ratio taken at the end is what
  the NaN rule needs.

In both modes the sums run over the samples in arrival order, one addition
per sample; every weight is ``scale_i * prod_j k((x_j - X_ij) / h_ij)``
computed with the same floating-point operations
(:func:`flexarm.ident.kernels.kernel_weight`, or its scalar ``d = 1``
specialisations), and ``h_i`` is computed elementwise in a compiled scalar
loop. Hence ``partial_fit`` on chunks equals ``fit`` on all **bit for bit**,
and exact mode equals grid mode bit for bit at the grid points. Zero weights
may be skipped or added (either changes no sum). The tests also hold both
modes to a direct NumPy evaluation of eq. 14 (to ~1e-11, summation order).

:meth:`~SemiRecursiveKernelRegression.save` writes the hyperparameters and this
state (exact mode: the samples and their ``h_i``; grid mode: the grid and the
running sums) to one ``.npz`` file of plain arrays;
:meth:`~SemiRecursiveKernelRegression.load` restores it, and continuing with
``partial_fit`` gives bit for bit what never stopping would have given.

Binned mode (``binned=r``, grid mode, ``d = 1``) trades exactness for speed:
the samples are linearly binned, block by block of nearly equal ``h_i``, onto
bins ``r h`` wide, and the bins are smoothed onto the grid. It is off by
default; :mod:`flexarm.ident.binning` derives its error bound, which
:meth:`~SemiRecursiveKernelRegression.sum_error_bounds` and
:meth:`~SemiRecursiveKernelRegression.error_bound` evaluate. Chunked
``partial_fit`` still equals ``fit`` bit for bit, and ``save``/``load`` resume
exactly (the open block's bins are part of the state).

Series mode (``series=True``: Gaussian kernel, one bandwidth, ``d = 1``)
computes the same sums by a Taylor series about clusters ``h/8`` wide (a fast
Gauss transform; :func:`flexarm.ident.kernels.gauss_series_moments` bounds its
error): ``O(n + m)`` work instead of ``O(n m)``, agreeing with direct summation
to rounding (about 1e-13 relative per weight at worst), though not bit for bit.

Hot loops are compiled with Numba (``cache=True``). Grid mode with ``d = 1``
and a compact kernel touches only the grid points inside each sample's window
(binary search in the sorted grid); the Gaussian likewise within
``|u| <= 38.61``, beyond which ``exp(-u**2/2)`` is exactly zero in float64.
Grid mode in ``d >= 2`` visits every grid point (stopping at the first zero
factor). User callables are evaluated with NumPy in blocks and accumulated by
a compiled loop in the same order.

Hyperparameter bounds
---------------------
``bandwidth > 0`` (a scalar, or one finite value per input dimension).
With ``h_i**d = bandwidth**d i**(-d decay)``, the consistency conditions of
Theorem 1, ``h_i -> 0`` and ``sum h_i**d = inf``, hold iff ``0 < decay <= 1/d``.
``decay = 0`` (fixed ``h``, the classical estimate) is also allowed;
``decay < 0`` or ``decay > 1/d`` is rejected — by :meth:`fit`, since ``d`` is
known only there.
"""

from __future__ import annotations

import copy
import math
import os
from typing import Any, ClassVar, Self

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._io import atomic_path
from .._validation import check_array, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from . import binning
from ._params import HyperParameters, same_value
from .kernels import (
    KERNELS,
    SERIES_REACH,
    SERIES_TERMS,
    SERIES_WIDTH,
    gauss_series_eval,
    gauss_series_moments,
    kernel_profile,
    kernel_weight,
)

__all__ = [
    "NadarayaWatson",
    "NotFittedError",
    "RecursiveKernelRegression",
    "SemiRecursiveKernelRegression",
]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

_FORMAT = 1  # version of the save() file layout
_BIN_MIN, _BIN_MAX = 1e-4, 0.5  # allowed relative bin widths r = delta / h
_BIN_MAX_BINS = 2**24  # a block needing more bins than this is added exactly
_SERIES_MAX_CLUSTERS = 2**22  # grid mode: (grid span + 2 reach) / (h/2) at most this
_CALLABLE = -1  # kernel code of a user callable (evaluated with NumPy)
_GAUSS_ZERO = 38.61  # exp(-u**2 / 2) == 0.0 exactly in float64 for |u| > 38.61 (u**2/2 > 745.2)


class NotFittedError(ValueError, AttributeError):
    """Raised when an estimator is used before :meth:`fit` (as in scikit-learn)."""


# --------------------------------------------------------------------------- compiled loops


@nb.njit(cache=True)
def _sample_bandwidths(
    bw: F64, decay: float, start: int, n: int, recursive: bool
) -> tuple[F64, F64]:  # pragma: no cover - compiled
    """``h[k] = bw * i**(-decay)`` with ``i = start + k + 1``; scale ``prod(h)**-1`` or 1."""
    d = bw.shape[0]
    h = np.empty((n, d))
    scale = np.ones(n)
    for k in range(n):
        f = float(start + k + 1) ** (-decay)
        p = 1.0
        for j in range(d):
            h[k, j] = bw[j] * f
            p *= h[k, j]
        if recursive:
            scale[k] = 1.0 / p
    return h, scale


@nb.njit(cache=True)
def _grid_update_1d(
    code: int, gs: F64, x: F64, y: F64, h: F64, scale: F64, num: F64, den: F64, radius: float
) -> None:  # pragma: no cover - compiled
    """``d = 1``: ``gs`` is the sorted grid and ``num``/``den`` follow its order.

    Each sample visits only the grid points in its window (``|u| <= 1``, or
    ``38.61`` for the Gaussian, where its float64 value becomes exactly 0; the
    caller passes this ``radius``, smaller in binned mode), found by binary
    search (padded; the kernel itself decides the edge). The weight is
    ``scale * k(u)``, the same floating-point operations as :func:`kernel_weight`
    (adding a zero weight, which that path skips, changes no sum).
    """
    for i in range(x.shape[0]):
        xi = x[i]
        hi = h[i]
        si = scale[i]
        yi = y[i]
        # Window half-width in units of h: 1 for compact kernels; for the Gaussian
        # exp(-u**2/2) is exactly 0.0 in float64 beyond |u| = 38.61, so it is exact too.
        r = radius * hi * (1.0 + 1e-9) + 1e-12 * abs(xi)
        lo = np.searchsorted(gs, xi - r, side="left")
        up = np.searchsorted(gs, xi + r, side="right")
        if code == 0:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * math.exp(-0.5 * u * u)
                num[k] += w * yi
                den[k] += w
        elif code == 1:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * (0.75 * (1.0 - u * u)) if abs(u) <= 1.0 else 0.0
                num[k] += w * yi
                den[k] += w
        elif code == 2:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * 0.5 if abs(u) <= 1.0 else 0.0
                num[k] += w * yi
                den[k] += w
        else:
            for k in range(lo, up):
                u = (gs[k] - xi) / hi
                w = si * (1.0 - abs(u)) if abs(u) <= 1.0 else 0.0
                num[k] += w * yi
                den[k] += w


@nb.njit(cache=True)
def _grid_update(
    code: int, grid: F64, X: F64, y: F64, h: F64, scale: F64, num: F64, den: F64
) -> None:  # pragma: no cover - compiled
    """Add samples to the running sums at every grid point, in sample order (any ``d``)."""
    g = grid.shape[0]
    for i in range(X.shape[0]):
        xi = X[i]
        hi = h[i]
        for j in range(g):
            w = kernel_weight(code, grid[j], xi, hi, scale[i])
            if w != 0.0:
                num[j] += w * y[i]
                den[j] += w


@nb.njit(cache=True)
def _exact_predict(
    code: int, Q: F64, X: F64, y: F64, h: F64, scale: F64
) -> F64:  # pragma: no cover - compiled
    out = np.empty(Q.shape[0])
    for q in range(Q.shape[0]):
        num = 0.0
        den = 0.0
        for i in range(X.shape[0]):
            w = kernel_weight(code, Q[q], X[i], h[i], scale[i])
            if w != 0.0:
                num += w * y[i]
                den += w
        out[q] = num / den if den != 0.0 else np.nan
    return out


@nb.njit(cache=True)
def _exact_predict_1d(
    code: int, q: F64, x: F64, y: F64, h: F64, scale: F64
) -> F64:  # pragma: no cover - compiled
    """``d = 1`` version of :func:`_exact_predict` on scalars (same operations, faster)."""
    out = np.empty(q.shape[0])
    for m in range(q.shape[0]):
        num = 0.0
        den = 0.0
        qm = q[m]
        for i in range(x.shape[0]):
            w = scale[i] * kernel_profile(code, (qm - x[i]) / h[i])
            if w != 0.0:
                num += w * y[i]
                den += w
        out[m] = num / den if den != 0.0 else np.nan
    return out


@nb.njit(cache=True)
def _accumulate_rows(W: F64, y: F64, num: F64, den: F64) -> None:  # pragma: no cover
    """``num += sum_i W[i] y[i]``, ``den += sum_i W[i]`` row by row (callable kernels)."""
    for i in range(W.shape[0]):
        for j in range(W.shape[1]):
            w = W[i, j]
            if w != 0.0:
                num[j] += w * y[i]
                den[j] += w


@nb.njit(cache=True)
def _ratio(num: F64, den: F64) -> F64:  # pragma: no cover - compiled
    out = np.empty(num.shape[0])
    for j in range(num.shape[0]):
        out[j] = num[j] / den[j] if den[j] != 0.0 else np.nan
    return out


# --------------------------------------------------------------------------- estimators


class _KernelRegression(HyperParameters):
    """Shared implementation; see the module docstring for the design."""

    _recursive: ClassVar[bool] = False
    _fixed_decay: ClassVar[float | None] = None

    kernel: Any
    bandwidth: Any
    grid: Any

    # ---------------------------------------------------------------- validation

    @property
    def _owner(self) -> str:
        return type(self).__name__

    def _fail(self, name: str, expected: str, got: str) -> ValueError:
        return ValueError(
            f"The '{name}' parameter of {self._owner} must be {expected}. Got {got} instead."
        )

    def _check_kernel(self) -> int:
        k = self.kernel
        if callable(k):
            return _CALLABLE
        return KERNELS.index(check_option(k, "kernel", self._owner, KERNELS))

    def _check_bandwidth(self, d: int) -> F64:
        bw = self.bandwidth
        if np.ndim(bw) == 0:
            value = check_real(bw, "bandwidth", self._owner, positive=True)
            return np.full(d, value)
        arr = check_array(bw, "bandwidth", self._owner, shape=(-1,))
        if arr.dtype.kind == "c":
            raise InvalidTypeError(
                f"The 'bandwidth' parameter of {self._owner} must be real. Got complex instead."
            )
        if arr.shape[0] != d:
            raise self._fail(
                "bandwidth",
                f"a scalar or of shape ({d},) for {d}-dimensional X",
                f"shape {arr.shape}",
            )
        if not np.all(arr > 0.0):
            raise self._fail("bandwidth", "> 0", repr(arr))
        return np.ascontiguousarray(arr, dtype=np.float64)

    def _check_decay(self, d: int) -> float:
        if self._fixed_decay is not None:
            return self._fixed_decay
        decay = check_real(getattr(self, "decay", 0.0), "decay", self._owner, nonnegative=True)
        if decay * d > 1.0 + 1e-12:
            raise self._fail(
                "decay",
                f"<= 1/d = {1.0 / d:.6g} for d = {d} (sum of h_i**d must diverge)",
                repr(decay),
            )
        return decay

    def _check_binned(self, code: int, d: int, has_grid: bool) -> float | None:
        value = getattr(self, "binned", None)
        if value is None:
            return None
        r = check_real(value, "binned", self._owner, positive=True)
        if not _BIN_MIN <= r <= _BIN_MAX:
            raise self._fail(
                "binned", f"None or a relative bin width in [{_BIN_MIN:g}, {_BIN_MAX:g}]", repr(r)
            )
        if not has_grid:
            raise self._fail("binned", "None in exact mode (binning needs a grid)", repr(r))
        if d != 1:
            raise self._fail("binned", f"None for d = {d} (binning is one-dimensional)", repr(r))
        name = "a callable" if code == _CALLABLE else repr(KERNELS[code])
        if code == _CALLABLE or KERNELS[code] not in binning.BINNABLE:
            raise self._fail(
                "binned",
                f"None with kernel {name} (binnable kernels: {binning.BINNABLE})",
                repr(r),
            )
        return r

    def _check_series(self, code: int, d: int, decay: float, binned: float | None) -> bool:
        value = getattr(self, "series", False)
        if not isinstance(value, bool | np.bool_):
            raise InvalidTypeError(
                f"The 'series' parameter of {self._owner} must be a bool. Got {value!r} instead."
            )
        if not value:
            return False
        if code != 0:
            raise self._fail("series", "False unless kernel='gaussian'", "True")
        if d != 1:
            raise self._fail("series", f"False for d = {d} (the series is one-dimensional)", "True")
        if decay != 0.0:
            raise self._fail("series", "False unless decay = 0 (one bandwidth)", "True")
        if binned is not None:
            raise self._fail("series", "False in binned mode (choose one)", "True")
        return True

    def _series_scale(self) -> float:
        """The constant weight factor ``s``: ``1/h`` for the recursive estimate, else 1."""
        return 1.0 / float(self.bandwidth_[0]) if self._recursive else 1.0

    def _check_X(self, X: ArrayLike, name: str = "X") -> F64:
        arr = check_array(X, name, self._owner)
        if arr.dtype.kind == "c":
            raise InvalidTypeError(
                f"The '{name}' parameter of {self._owner} must be real. Got complex instead."
            )
        if arr.ndim == 1:
            arr = arr[:, None]
        if arr.ndim != 2:
            raise self._fail(name, "of shape (n,) or (n, d)", f"shape {arr.shape}")
        if arr.shape[1] < 1:
            raise self._fail(name, "of at least one column", f"shape {arr.shape}")
        return np.ascontiguousarray(arr, dtype=np.float64)

    def _check_Xy(self, X: ArrayLike, y: ArrayLike) -> tuple[F64, F64]:
        Xa = self._check_X(X)
        ya = check_array(y, "y", self._owner)
        if ya.dtype.kind == "c":
            raise InvalidTypeError(
                f"The 'y' parameter of {self._owner} must be real. Got complex instead."
            )
        if ya.ndim != 1:
            raise self._fail("y", "of shape (n,)", f"shape {ya.shape}")
        if ya.shape[0] != Xa.shape[0]:
            raise self._fail(
                "y", f"of length {Xa.shape[0]} (the rows of X)", f"length {ya.shape[0]}"
            )
        if Xa.shape[0] == 0:
            raise self._fail("X", "at least one sample", "0 samples")
        return Xa, np.ascontiguousarray(ya, dtype=np.float64)

    def _check_fitted(self) -> None:
        if not hasattr(self, "n_samples_"):
            raise NotFittedError(
                f"This {self._owner} instance is not fitted yet. Call 'fit' or "
                "'partial_fit' with appropriate arguments before using this estimator."
            )

    # ---------------------------------------------------------------- fitting

    def _reset(self) -> None:
        for name in [k for k in vars(self) if k.endswith("_") and not k.startswith("__")]:
            delattr(self, name)
        for name in (
            "_X",
            "_y",
            "_h",
            "_scale",
            "_frozen",
            "_code",
            "_decay",
            "_inv",
            "_grid_sorted",
            "_num",
            "_den",
            "_bin",
            "_blk",
            "_bfl",
            "_bcw",
            "_bsw",
            "_baw",
            "_near",
            "_bsums",
            "_series",
            "_smn",
            "_smd",
            "_sorigin",
        ):
            self.__dict__.pop(name, None)

    def _start(self, d: int) -> None:
        """Validate the hyperparameters for ``d``-dimensional input and set up the state."""
        code = self._check_kernel()
        bw = self._check_bandwidth(d)
        decay = self._check_decay(d)
        grid = None
        if self.grid is not None:
            grid = self._check_X(self.grid, "grid")
            if grid.shape[1] != d:
                raise self._fail("grid", f"of {d} column(s) like X", f"{grid.shape[1]} column(s)")
            if grid.shape[0] == 0:
                raise self._fail("grid", "non-empty", "0 points")
        r = self._check_binned(code, d, grid is not None)
        series = self._check_series(code, d, decay, r)
        if code == _CALLABLE:
            probe = np.zeros((3, d))
            probe[1:] = [[0.5], [-2.0]]
            self.kernel_ = self.kernel
            self._callable_weights(probe[:1], probe, np.ones((3, d)), np.ones(3))
        self._code = code
        self._decay = decay
        self._series = series
        self._frozen = {
            k: copy.deepcopy(v) if isinstance(v, np.ndarray | list | tuple) else v
            for k, v in self.get_params().items()
        }
        self.kernel_ = self.kernel
        self.bandwidth_ = bw
        self.n_features_in_ = d
        self.n_samples_ = 0
        if grid is None:
            self._X = np.empty((16, d))
            self._y = np.empty(16)
            self._h = np.empty((16, d))
            self._scale = np.empty(16)
        else:
            self.grid_ = grid.copy()
            # Internal order: sorted for d = 1 (binary-searched windows), as given otherwise.
            order = np.argsort(grid[:, 0], kind="stable") if d == 1 else np.arange(len(grid))
            self._inv = np.argsort(order).astype(np.int64)
            self._grid_sorted = np.ascontiguousarray(grid[order])
            self._num = np.zeros(grid.shape[0])
            self._den = np.zeros(grid.shape[0])
            if series:
                h = float(bw[0])
                gs = self._grid_sorted[:, 0]
                clusters = (
                    math.ceil((gs[-1] - gs[0] + 2.0 * SERIES_REACH * h) / (SERIES_WIDTH * h)) + 2
                )
                if clusters > _SERIES_MAX_CLUSTERS:
                    raise self._fail(
                        "series",
                        f"False when the grid spans more than {_SERIES_MAX_CLUSTERS // 2} "
                        "bandwidths (too many clusters)",
                        "True",
                    )
                self._sorigin = float(gs[0] - SERIES_REACH * h - SERIES_WIDTH * h)
                self._smn = np.zeros((clusters, SERIES_TERMS))
                self._smd = np.zeros((clusters, SERIES_TERMS))
            if r is not None:
                self._bin = r
                self._blk = np.array([1, 1, 0], dtype=np.int64)  # start, end, mode (0/1/2)
                self._bfl = np.zeros(3)  # h_B, origin, delta of the open block
                self._bcw = np.zeros(0)  # bins of the open block: sum s_i, s_i Y_i, s_i |Y_i|
                self._bsw = np.zeros(0)
                self._baw = np.zeros(0)
                self._near = np.zeros((2, grid.shape[0]))  # S_near, A_near (closed blocks)
                self._bsums = np.zeros(2)  # S = sum s_i, A = sum s_i |Y_i| (all samples)

    def fit(self, X: ArrayLike, y: ArrayLike) -> Self:
        """Forget any previous state and fit to the samples.

        Parameters
        ----------
        X : array_like, shape (n,) or (n, d)
            Inputs ``X_i`` (units of the regressor); shape ``(n,)`` means ``d = 1``.
        y : array_like, shape (n,)
            Outputs ``Y_i`` (units of the response).

        Returns
        -------
        self
        """
        Xa, ya = self._check_Xy(X, y)
        self._reset()
        self._start(Xa.shape[1])
        self._add(Xa, ya)
        return self

    def partial_fit(self, X: ArrayLike, y: ArrayLike) -> Self:
        """Add samples to the estimate; chunks give the same result as one :meth:`fit`.

        The hyperparameters are fixed by the first call; changing them before a
        later call raises ``ValueError`` (call :meth:`fit` to start again).

        Parameters
        ----------
        X : array_like, shape (n,) or (n, d)
            Inputs ``X_i`` (units of the regressor).
        y : array_like, shape (n,)
            Outputs ``Y_i`` (units of the response).

        Returns
        -------
        self
        """
        Xa, ya = self._check_Xy(X, y)
        if not hasattr(self, "n_samples_"):
            self._start(Xa.shape[1])
        else:
            if Xa.shape[1] != self.n_features_in_:
                raise self._fail(
                    "X", f"of {self.n_features_in_} column(s) as before", f"{Xa.shape[1]}"
                )
            now = self.get_params()
            changed = sorted(k for k in now if not same_value(now[k], self._frozen[k]))
            if changed:
                raise InvalidValueError(
                    f"The {changed} parameter(s) of {self._owner} changed since the first "
                    "partial_fit. Got new values instead; call fit to start again."
                )
        self._add(Xa, ya)
        return self

    def _add(self, X: F64, y: F64) -> None:
        n0 = self.n_samples_
        m = X.shape[0]
        if hasattr(self, "_bin") or (self._series and hasattr(self, "grid_")):
            h = scale = np.empty((0, 1))  # binned/series modes compute what they need
        else:
            h, scale = _sample_bandwidths(self.bandwidth_, self._decay, n0, m, self._recursive)
        if hasattr(self, "_bin"):
            self._add_binned(np.ascontiguousarray(X[:, 0]), y)
        elif self._series and hasattr(self, "grid_"):
            gauss_series_moments(
                np.ascontiguousarray(X[:, 0]),
                y,
                self._series_scale(),
                self._sorigin,
                float(self.bandwidth_[0]),
                self._smn,
                self._smd,
            )
        elif hasattr(self, "grid_"):
            if self._code == _CALLABLE:
                self._grid_update_callable(X, y, h, scale)
            elif self.n_features_in_ == 1:
                _grid_update_1d(
                    self._code,
                    self._grid_sorted[:, 0],
                    X[:, 0],
                    y,
                    h[:, 0],
                    scale,
                    self._num,
                    self._den,
                    _GAUSS_ZERO if self._code == 0 else 1.0,
                )
            else:
                _grid_update(
                    self._code,
                    self._grid_sorted,
                    X,
                    y,
                    h,
                    scale,
                    self._num,
                    self._den,
                )
        else:
            need = n0 + m
            if need > self._y.shape[0]:
                cap = max(need, 2 * self._y.shape[0])
                for name in ("_X", "_y", "_h", "_scale"):
                    old = getattr(self, name)
                    new = np.empty((cap, *old.shape[1:]))
                    new[:n0] = old[:n0]
                    setattr(self, name, new)
            self._X[n0:need] = X
            self._y[n0:need] = y
            self._h[n0:need] = h
            self._scale[n0:need] = scale
        self.n_samples_ = n0 + m

    # ---------------------------------------------------------------- binned mode

    def _add_binned(self, x: F64, y: F64) -> None:
        """Binned grid mode (:mod:`flexarm.ident.binning`): samples go block by block."""
        n0 = self.n_samples_
        pos = 0
        while pos < x.shape[0]:
            i = n0 + pos + 1  # 1-based index of the next sample
            if self._blk[2] == 0 or i >= self._blk[1]:
                self._flush_block(self._num, self._den)
                self._open_block(i)
            stop = min(x.shape[0], int(self._blk[1]) - n0 - 1)
            xs, ys = x[pos:stop], y[pos:stop]
            if self._blk[2] == 2:  # short block: exact, sample by sample
                h, scale = _sample_bandwidths(
                    self.bandwidth_, self._decay, n0 + pos, stop - pos, self._recursive
                )
                gs = self._grid_sorted[:, 0]
                c = binning.radius(KERNELS[self._code])
                _grid_update_1d(self._code, gs, xs, ys, h[:, 0], scale, self._num, self._den, c)
                self._bsums += (scale.sum(), (scale * np.abs(ys)).sum())
            else:
                binning.bin_samples(
                    xs,
                    ys,
                    n0 + pos,
                    float(self.bandwidth_[0]),
                    self._decay,
                    self._recursive,
                    float(self._bfl[1]),
                    float(self._bfl[2]),
                    self._bcw,
                    self._bsw,
                    self._baw,
                    self._bsums,
                )
            pos = stop

    def _open_block(self, start: int) -> None:
        r = self._bin
        end = binning.block_end(start, r, self._decay)
        hb = float(self.bandwidth_[0]) * (float(start) * float(end - 1)) ** (-self._decay / 2.0)
        delta = r * hb
        pad = binning.radius(KERNELS[self._code]) * hb + delta
        gs = self._grid_sorted[:, 0]
        bins = math.ceil((gs[-1] - gs[0] + 2.0 * pad) / delta) + 1
        binned = bins <= min(end - start, _BIN_MAX_BINS)
        self._blk[:] = (start, end, 1 if binned else 2)
        self._bfl[:] = (hb, gs[0] - pad, delta)
        self._bcw = np.zeros(bins if binned else 0)
        self._bsw = np.zeros(bins if binned else 0)
        self._baw = np.zeros(bins if binned else 0)

    def _flush_block(self, num: F64, den: F64, near: F64 | None = None) -> None:
        """Add the open binned block (if any) to ``num``, ``den``, ``near`` (sorted grid order)."""
        if self._blk[2] != 1:
            return
        hb, origin, delta = (float(v) for v in self._bfl)
        binning.flush_bins(
            self._code,
            self._grid_sorted[:, 0],
            origin,
            delta,
            hb,
            binning.radius(KERNELS[self._code]),
            self._bcw,
            self._bsw,
            self._baw,
            num,
            den,
            self._near if near is None else near,
        )

    def _grid_sums(self) -> tuple[F64, F64]:
        """Running sums in sorted grid order, with the open binned block added (not stored)."""
        if self._series:
            num, den, shift = self._series_grid()
            scale = np.exp(-shift)
            return num * scale, den * scale
        return self._binned_sums()[:2]

    def _series_grid(self) -> tuple[F64, F64, F64]:
        """Series mode: scaled sums and their shift at the sorted grid (see the kernels)."""
        return gauss_series_eval(
            np.ascontiguousarray(self._grid_sorted[:, 0]),
            self._sorigin,
            float(self.bandwidth_[0]),
            self._smn,
            self._smd,
        )

    def _grid_ratio(self) -> F64:
        """``m`` at the sorted grid (series mode: from the scaled sums)."""
        if self._series:
            num, den, _ = self._series_grid()
            return _ratio(num, den)
        return _ratio(*self._grid_sums())

    def _binned_sums(self) -> tuple[F64, F64, F64]:
        """``num``, ``den`` and (binned mode) ``near``, with the open block added."""
        if hasattr(self, "_bin"):
            if self._blk[2] == 1:
                num, den, near = self._num.copy(), self._den.copy(), self._near.copy()
                self._flush_block(num, den, near)
                return num, den, near
            return self._num, self._den, self._near
        return self._num, self._den, np.zeros((2, 0))

    def _check_binned_fitted(self, name: str) -> None:
        self._check_fitted()
        if not hasattr(self, "_bin"):
            raise AttributeError(f"{name} is kept in binned mode only (binned is None)")

    @property
    def bin_error_(self) -> float:
        """Bound ``E`` on the error of one binned kernel weight (binned mode only).

        See :mod:`flexarm.ident.binning` and :meth:`sum_error_bounds`.
        """
        self._check_binned_fitted("bin_error_")
        return binning.per_weight_error(KERNELS[self._code], self._bin, self._decay)

    def sum_error_bounds(self, X: ArrayLike) -> tuple[F64, F64]:
        """Bounds on the errors of the binned sums at grid points (binned mode only).

        ``eN >= |N_binned(x) - N(x)|`` and ``eD >= |D_binned(x) - D(x)|`` with
        ``N``, ``D`` the exact ``numerator_`` and ``denominator_``:
        ``eN = E A_near(x) + (tau + rho) A``, ``eD = E S_near(x) + (tau + rho) S``
        with ``rho = 4 (2 n + J + 16) 2**-53`` for the rounding of the sums
        (``J`` bins in the open block); see :mod:`flexarm.ident.binning`.

        Parameters
        ----------
        X : array_like, shape (m,) or (m, 1)
            Grid points (units of the regressor).

        Returns
        -------
        eN, eD : ndarray, shape (m,)
            Bounds (units of the response times weight; weight).
        """
        self._check_binned_fitted("sum_error_bounds")
        Q = self._check_X(X)
        if Q.shape[1] != 1:
            raise self._fail("X", "of 1 column like the training X", f"{Q.shape[1]}")
        where = self._inv[self._grid_index(Q)]
        near = self._binned_sums()[2][:, where]
        e = self.bin_error_
        tau = binning.far_error(KERNELS[self._code], self._bin)
        s, a = (float(v) for v in self._bsums)
        # rounding: sums of at most n terms into bins and bins (<= n, or this block's) onto the grid
        rnd = 4.0 * (2 * self.n_samples_ + self._bcw.shape[0] + 16) * 2.0**-53
        eN: F64 = e * near[1] + (tau + rnd) * a
        eD: F64 = e * near[0] + (tau + rnd) * s
        return eN, eD

    def error_bound(self, X: ArrayLike) -> F64:
        """Bound on ``|m_binned(x) - m(x)|`` at grid points, ``m`` the exact estimate.

        ``(eN + |m_binned| eD) / (D_binned - eD)`` where ``D_binned > eD``
        (:meth:`sum_error_bounds`), ``inf`` elsewhere, NaN where ``m_binned``
        is NaN; see :mod:`flexarm.ident.binning`. Binned mode only.

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
        m = self.predict(X)
        where = self._inv[self._grid_index(self._check_X(X))]
        den = self._grid_sums()[1][where]
        with np.errstate(divide="ignore", invalid="ignore"):
            out: F64 = np.where(den > eD, (eN + np.abs(m) * eD) / (den - eD), np.inf)
        out[np.isnan(m)] = np.nan
        return out

    def _callable_weights(self, Q: F64, X: F64, h: F64, scale: F64) -> F64:
        """Weights ``W[i, q] = scale_i K((Q_q - X_i) / h_i)`` from the user callable."""
        u = (Q[None, :, :] - X[:, None, :]) / h[:, None, :]
        flat = u.reshape(-1, Q.shape[1])
        w = np.asarray(self.kernel_(flat), dtype=np.float64)
        if w.shape != (flat.shape[0],):
            raise InvalidValueError(
                f"The 'kernel' parameter of {self._owner} must return shape "
                f"({flat.shape[0]},) for u of shape {flat.shape}. Got shape {w.shape} instead."
            )
        if not np.all(np.isfinite(w)):
            raise InvalidValueError(
                f"The 'kernel' parameter of {self._owner} must return finite values. "
                "Got non-finite values instead."
            )
        W: F64 = np.ascontiguousarray(w.reshape(X.shape[0], Q.shape[0]) * scale[:, None])
        return W

    def _grid_update_callable(self, X: F64, y: F64, h: F64, scale: F64) -> None:
        g = self.grid_.shape[0]
        step = max(1, 2**20 // g)
        for s in range(0, X.shape[0], step):
            W = self._callable_weights(
                self._grid_sorted, X[s : s + step], h[s : s + step], scale[s : s + step]
            )
            _accumulate_rows(W, y[s : s + step], self._num, self._den)

    # ---------------------------------------------------------------- fitted state

    @property
    def X_(self) -> F64:
        """Stored inputs, shape ``(n_samples_, d)`` (exact mode only)."""
        self._check_fitted()
        if hasattr(self, "grid_"):
            raise AttributeError("X_ is not kept in grid mode (grid is not None)")
        out: F64 = self._X[: self.n_samples_]
        return out

    @property
    def y_(self) -> F64:
        """Stored outputs, shape ``(n_samples_,)`` (exact mode only)."""
        self._check_fitted()
        if hasattr(self, "grid_"):
            raise AttributeError("y_ is not kept in grid mode (grid is not None)")
        out: F64 = self._y[: self.n_samples_]
        return out

    @property
    def bandwidths_(self) -> F64:
        """Per-sample bandwidths ``h_i``, shape ``(n_samples_, d)`` (exact mode only)."""
        self._check_fitted()
        if hasattr(self, "grid_"):
            raise AttributeError("bandwidths_ is not kept in grid mode (grid is not None)")
        out: F64 = self._h[: self.n_samples_]
        return out

    @property
    def numerator_(self) -> F64:
        """Running ``sum_i Y_i w_i`` at the grid points, shape ``(g,)`` (grid mode only)."""
        self._check_fitted()
        if not hasattr(self, "grid_"):
            raise AttributeError("numerator_ is kept in grid mode only (grid is None)")
        out: F64 = self._grid_sums()[0][self._inv]
        return out

    @property
    def denominator_(self) -> F64:
        """Running ``g_n = sum_i w_i`` at the grid points, shape ``(g,)`` (grid mode only)."""
        self._check_fitted()
        if not hasattr(self, "grid_"):
            raise AttributeError("denominator_ is kept in grid mode only (grid is None)")
        out: F64 = self._grid_sums()[1][self._inv]
        return out

    # ---------------------------------------------------------------- persistence

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the hyperparameters and the streaming state to ``path`` (NumPy ``.npz``).

        :meth:`load` then resumes exactly: ``partial_fit`` after ``load`` gives,
        bit for bit, what it would have given without stopping. The file holds
        plain arrays only (no pickle); a user-callable ``kernel`` cannot be saved.

        Parameters
        ----------
        path : str or os.PathLike
            Destination file, written as given (no suffix is added), atomically:
            a temporary file beside it is renamed into place once complete.
        """
        self._check_fitted()
        if not isinstance(self.kernel_, str):
            raise InvalidTypeError(
                f"The 'kernel' parameter of {self._owner} must be a kernel name to save the "
                f"estimator. Got {self.kernel_!r} instead."
            )
        params = self._frozen
        arrays: dict[str, Any] = {
            "format": np.array(_FORMAT),
            "estimator": np.array(self._owner),
            "kernel": np.array(self.kernel_),
            "bandwidth": np.asarray(params["bandwidth"], dtype=np.float64),
            "decay": np.array(self._decay),
            "n_samples": np.array(self.n_samples_),
            "n_features_in": np.array(self.n_features_in_),
            "series": np.array(self._series),
        }
        if hasattr(self, "grid_"):
            arrays.update(grid=self.grid_, num=self._num, den=self._den)
            if self._series:
                arrays.update(series_mn=self._smn, series_md=self._smd)
        else:
            n = self.n_samples_
            arrays.update(X=self._X[:n], y=self._y[:n], h=self._h[:n], scale=self._scale[:n])
        if hasattr(self, "_bin"):
            arrays.update(
                binned=np.array(self._bin),
                bin_block=self._blk,
                bin_float=self._bfl,
                bin_cw=self._bcw,
                bin_sw=self._bsw,
                bin_aw=self._baw,
                bin_near=self._near,
                bin_sums=self._bsums,
            )
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Self:
        """Read an estimator written by :meth:`save` (of this same class).

        Parameters
        ----------
        path : str or os.PathLike
            File written by :meth:`save`.

        Returns
        -------
        estimator
            Fitted, with the state it had when saved.
        """
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        if int(data.get("format", -1)) != _FORMAT or str(data.get("estimator")) != cls.__name__:
            raise InvalidValueError(
                f"The 'path' parameter of {cls.__name__}.load must name a file saved by "
                f"{cls.__name__}.save. Got {data.get('estimator', 'another file')!s} instead."
            )
        bw = data["bandwidth"]
        names = cls._get_param_names()
        kwargs: dict[str, Any] = {
            "kernel": str(data["kernel"]),
            "bandwidth": float(bw) if bw.ndim == 0 else bw,
            "grid": data.get("grid"),
        }
        if "decay" in names:
            kwargs["decay"] = float(data["decay"])
        if "binned" in data:
            kwargs["binned"] = float(data["binned"])
        if bool(data.get("series", False)):
            kwargs["series"] = True
        est = cls(**kwargs)
        est._start(int(data["n_features_in"]))
        if "grid" in data:
            est._num[:] = data["num"]
            est._den[:] = data["den"]
            if "series_mn" in data:
                est._smn = np.ascontiguousarray(data["series_mn"])
                est._smd = np.ascontiguousarray(data["series_md"])
        else:
            est._X = np.ascontiguousarray(data["X"])
            est._y = np.ascontiguousarray(data["y"])
            est._h = np.ascontiguousarray(data["h"])
            est._scale = np.ascontiguousarray(data["scale"])
        if "binned" in data:
            est._blk = np.ascontiguousarray(data["bin_block"], dtype=np.int64)
            est._bfl = np.ascontiguousarray(data["bin_float"])
            est._bcw = np.ascontiguousarray(data["bin_cw"])
            est._bsw = np.ascontiguousarray(data["bin_sw"])
            est._baw = np.ascontiguousarray(data["bin_aw"])
            est._near = np.ascontiguousarray(data["bin_near"])
            est._bsums = np.ascontiguousarray(data["bin_sums"])
        est.n_samples_ = int(data["n_samples"])
        return est

    # ---------------------------------------------------------------- prediction

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
        self._check_fitted()
        Q = self._check_X(X)
        d = self.n_features_in_
        if Q.shape[1] != d:
            raise self._fail("X", f"of {d} column(s) like the training X", f"{Q.shape[1]}")
        if hasattr(self, "grid_"):
            index = self._grid_index(Q)
            out: F64 = self._grid_ratio()[self._inv[index]]
            return out
        n = self.n_samples_
        X_, y_, h_, s_ = self._X[:n], self._y[:n], self._h[:n], self._scale[:n]
        if self._series:
            hs = float(self.bandwidth_[0])
            x0 = np.ascontiguousarray(X_[:, 0])
            origin = float(x0.min()) - 0.5 * SERIES_WIDTH * hs
            clusters = int((float(x0.max()) - origin) / (SERIES_WIDTH * hs)) + 2
            if clusters <= max(64, 4 * n):  # else the series gains nothing: sum directly
                mn = np.zeros((clusters, SERIES_TERMS))
                md = np.zeros((clusters, SERIES_TERMS))
                gauss_series_moments(x0, y_, self._series_scale(), origin, hs, mn, md)
                num, den, _ = gauss_series_eval(np.ascontiguousarray(Q[:, 0]), origin, hs, mn, md)
                rs: F64 = _ratio(num, den)
                return rs
        if self._code != _CALLABLE:
            if d == 1:
                r1: F64 = _exact_predict_1d(self._code, Q[:, 0], X_[:, 0], y_, h_[:, 0], s_)
                return r1
            res: F64 = _exact_predict(self._code, Q, X_, y_, h_, s_)
            return res
        num = np.zeros(Q.shape[0])
        den = np.zeros(Q.shape[0])
        step = max(1, 2**20 // Q.shape[0])
        for s in range(0, n, step):
            W = self._callable_weights(Q, X_[s : s + step], h_[s : s + step], s_[s : s + step])
            _accumulate_rows(W, y_[s : s + step], num, den)
        r: F64 = _ratio(num, den)
        return r

    def _grid_index(self, Q: F64) -> I64:
        lookup = {tuple(row): j for j, row in enumerate(self.grid_.tolist())}
        index = np.empty(Q.shape[0], dtype=np.int64)
        missing = 0
        for q, row in enumerate(Q.tolist()):
            j = lookup.get(tuple(row), -1)
            missing += j < 0
            index[q] = j
        if missing:
            raise self._fail("X", "points of the grid in grid mode", f"{missing} point(s) off it")
        return index


class SemiRecursiveKernelRegression(_KernelRegression):
    """Semi-recursive kernel regression estimate, eq. 14 of the paper.

    ``m_n(x) = sum_{i<=n} Y_i K((x - X_i)/h_i) / sum_{i<=n} K((x - X_i)/h_i)``,
    ``h_i = bandwidth * i**(-decay)``; see the module docstring for the
    streaming state (exact and grid modes) and the bounds on ``decay``.

    Parameters
    ----------
    kernel : str or callable, default "gaussian"
        One of ``"gaussian"``, ``"epanechnikov"``, ``"uniform"``,
        ``"triangular"`` (product kernels in ``d`` dimensions), or ``K(u)``
        mapping ``u`` of shape ``(m, d)`` to weights of shape ``(m,)``.
    bandwidth : float or array_like of shape (d,), default 1.0
        ``h_1`` (units of ``X``), one value or one per input dimension; > 0.
    decay : float, default 0.2
        ``h_i = bandwidth * i**(-decay)``; ``0 <= decay <= 1/d``.
    grid : array_like of shape (g,) or (g, d), optional
        Evaluation points for grid mode; ``None`` (default) for exact mode.
    binned : float, optional
        ``None`` (default): exact sums. A number ``r`` in ``[1e-4, 0.5]``:
        approximate grid mode (``d = 1``, continuous kernels) by linear binning
        with bins ``r h`` wide, with a proven error bound; see
        :mod:`flexarm.ident.binning`, :attr:`bin_error_` and :meth:`error_bound`.
    series : bool, default False
        Gaussian kernel with one bandwidth (``decay = 0``), ``d = 1``: compute
        the kernel sums by a Taylor series about clusters ``h/8`` wide (a fast
        Gauss transform, :func:`flexarm.ident.kernels.gauss_series_moments`),
        ``O(n + m)`` instead of ``O(n m)``. Each weight keeps a relative error
        of at most ~1e-13 (truncation 2.7e-17, cancellation), so the result
        agrees with direct summation to rounding, but not bit for bit. Where
        every direct weight is subnormal (``x`` farther than ~37.6 h from all
        samples) the series, which rescales them, is the more accurate; it
        gives NaN only beyond 38.67 h from every sample (direct: 38.61 h).
        Grid mode keeps the cluster moments as its state (chunked
        ``partial_fit`` equals ``fit`` bit for bit).

    Attributes
    ----------
    n_samples_ : int
        Samples seen so far.
    n_features_in_ : int
        Input dimension ``d``.
    bandwidth_ : ndarray, shape (d,)
        The validated ``bandwidth``.
    kernel_ : str or callable
        The kernel in use.
    X_, y_, bandwidths_ : ndarray
        Exact mode: stored samples and their ``h_i``.
    grid_, numerator_, denominator_ : ndarray, shape (g, d), (g,), (g,)
        Grid mode: the grid and the running sums ``sum Y_i K_i``, ``g_n = sum K_i``.
    bin_error_ : float
        Binned mode: the bound ``E`` on the error of one weight (see
        :meth:`sum_error_bounds` and :meth:`error_bound`).

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

    def __init__(
        self,
        kernel: Any = "gaussian",
        bandwidth: Any = 1.0,
        decay: float = 0.2,
        grid: ArrayLike | None = None,
        binned: float | None = None,
        series: bool = False,
    ) -> None:
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.decay = decay
        self.grid = grid
        self.binned = binned
        self.series = series


class RecursiveKernelRegression(_KernelRegression):
    """Fully recursive (Devroye–Wagner) kernel regression estimate.

    ``m_n(x) = sum_i Y_i h_i**(-d) K((x - X_i)/h_i) / sum_i h_i**(-d) K((x - X_i)/h_i)``
    (``h_i**(-d)`` is ``prod_j h_ij**(-1)`` for a per-dimension bandwidth).
    Parameters and attributes as :class:`SemiRecursiveKernelRegression`.
    """

    _recursive = True

    def __init__(
        self,
        kernel: Any = "gaussian",
        bandwidth: Any = 1.0,
        decay: float = 0.2,
        grid: ArrayLike | None = None,
        binned: float | None = None,
        series: bool = False,
    ) -> None:
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.decay = decay
        self.grid = grid
        self.binned = binned
        self.series = series


class NadarayaWatson(_KernelRegression):
    """Classical Nadaraya–Watson estimate: eq. 14 with one fixed bandwidth (``decay = 0``).

    Parameters and attributes as :class:`SemiRecursiveKernelRegression`, without ``decay``.
    """

    _fixed_decay = 0.0

    def __init__(
        self,
        kernel: Any = "gaussian",
        bandwidth: Any = 1.0,
        grid: ArrayLike | None = None,
        binned: float | None = None,
        series: bool = False,
    ) -> None:
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.grid = grid
        self.binned = binned
        self.series = series
