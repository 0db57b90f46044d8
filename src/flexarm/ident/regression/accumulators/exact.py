"""Exact mode: the samples are kept, and eq. 14 is evaluated at any point on demand."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..kernels import SERIES_TERMS, SERIES_WIDTH, gauss_series_eval, gauss_series_moments
from . import _loops
from ._threads import run_split, workers
from .base import CALLABLE, Accumulator, Smoothing, State
from .series import far_points

__all__ = ["ExactSamples"]

F64 = NDArray[np.float64]
_KEYS = ("X", "y", "h", "scale")
#: Exact mode sums directly when the series would need more clusters than this.
EXACT_SERIES_MAX_CLUSTERS = 2**18


class ExactSamples(Accumulator):
    """The samples ``(X_i, Y_i, h_i, scale_i)``, stored with amortised growth.

    :meth:`evaluate` sums eq. 14 over every sample at each query point
    (compiled, O(n) per point) in the blocked order of
    :mod:`~flexarm.ident.regression.accumulators.blocks` — or, with ``setup.series``, by
    the Gaussian series (:func:`flexarm.ident.regression.kernels.gauss_series_moments`)
    when the clusters do not outnumber the samples (nor exceed
    ``EXACT_SERIES_MAX_CLUSTERS``), directly at the points far from every
    sample (:mod:`~flexarm.ident.regression.accumulators.series`). Chunked
    :meth:`add_chunk` stores exactly what one call would (``h_i`` depends on
    the index ``i`` only).

    State arrays: ``X`` (n, d), ``y`` (n,), ``h`` (n, d), ``scale`` (n,).
    """

    mode = "exact"

    def __init__(self, setup: Smoothing) -> None:
        super().__init__(setup)
        d = setup.d
        self._X = np.empty((16, d))
        self._y = np.empty(16)
        self._h = np.empty((16, d))
        self._scale = np.empty(16)

    @property
    def X(self) -> F64:
        """Stored inputs, shape ``(n, d)``."""
        out: F64 = self._X[: self.n_samples]
        return out

    @property
    def y(self) -> F64:
        """Stored outputs, shape ``(n,)``."""
        out: F64 = self._y[: self.n_samples]
        return out

    @property
    def h(self) -> F64:
        """Per-sample bandwidths ``h_i``, shape ``(n, d)``."""
        out: F64 = self._h[: self.n_samples]
        return out

    @property
    def scale(self) -> F64:
        """Per-sample weight factors (``prod_j h_ij**-1`` or 1), shape ``(n,)``."""
        out: F64 = self._scale[: self.n_samples]
        return out

    def _add(self, X: F64, y: F64) -> None:
        n0, m = self.n_samples, X.shape[0]
        h, scale = self.setup.sample_bandwidths(n0, m)
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

    def evaluate(self, Q: F64) -> F64:
        if self.setup.series:
            out = self._series(Q, self.X, self.y)
            if out is not None:
                return out
        return self._direct(Q)

    def _direct(self, Q: F64) -> F64:
        """Eq. 14 at ``Q`` by direct summation over the stored samples (blocked order)."""
        setup = self.setup
        X, y, h, s = self.X, self.y, self.h, self.scale
        b = setup.block
        if setup.code != CALLABLE:  # the query points are independent: split them over the cores
            out = np.empty(Q.shape[0])
            q0, x0, h0 = np.ascontiguousarray(Q[:, 0]), X[:, 0], h[:, 0]

            def part(i: int, j: int) -> None:
                if setup.d == 1:
                    out[i:j] = _loops.exact_predict_1d(setup.code, q0[i:j], x0, y, h0, s, b)
                else:
                    out[i:j] = _loops.exact_predict(setup.code, Q[i:j], X, y, h, s, b)

            run_split(Q.shape[0], workers(Q.shape[0] * X.shape[0], Q.shape[0]), part)
            return out
        num, den = setup.blocked_callable_sums(Q, X, y, h, s)
        r: F64 = _loops.ratio(num, den)
        return r

    def _series(self, Q: F64, X: F64, y: F64) -> F64 | None:
        """Series sums at ``Q`` (direct ones far from the data), or ``None`` where the
        clusters would outnumber the samples."""
        hs = float(self.setup.bandwidth[0])
        x0 = np.ascontiguousarray(X[:, 0])
        origin = float(x0.min()) - 0.5 * SERIES_WIDTH * hs
        clusters = int((float(x0.max()) - origin) / (SERIES_WIDTH * hs)) + 2
        if clusters > min(max(64, 4 * x0.shape[0]), EXACT_SERIES_MAX_CLUSTERS):
            return None  # the series gains nothing: sum directly
        mn = np.zeros((clusters, SERIES_TERMS))
        md = np.zeros((clusters, SERIES_TERMS))
        gauss_series_moments(x0, y, self.setup.series_scale(), origin, hs, mn, md)
        num, den, shift = gauss_series_eval(np.ascontiguousarray(Q[:, 0]), origin, hs, mn, md)
        out: F64 = _loops.ratio(num, den)
        far = far_points(den, shift)
        if far.any():
            out[far] = self._direct(np.ascontiguousarray(Q[far]))
        return out

    def _arrays(self) -> State:
        return {"X": self.X, "y": self.y, "h": self.h, "scale": self.scale}

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        self._X, self._y, self._h, self._scale = (
            np.array(state[k], dtype=np.float64, order="C") for k in _KEYS
        )
