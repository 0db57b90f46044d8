"""Exact mode: the samples are kept, and eq. 14 is evaluated at any point on demand."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...._types import F64
from ..kernels import SERIES_TERMS, SERIES_WIDTH, gauss_series_eval, gauss_series_moments
from . import _loops
from ._threads import run_split, workers
from .base import CALLABLE, Accumulator, Smoothing, State
from .series import far_points

__all__ = ["ExactSamples"]

_KEYS = ("X", "y", "h", "scale")
#: Exact mode sums directly when the series would need more clusters than this.
EXACT_SERIES_MAX_CLUSTERS = 2**18


def _window_work(qs: F64, h: F64, radius: float) -> float:
    """About the number of (sample, point) pairs within the samples' windows of the sorted
    points ``qs`` (points spread evenly; ``h`` the samples' bandwidths)."""
    span = float(qs[-1] - qs[0]) if qs.shape[0] else 0.0
    if span == 0.0:
        return float(h.shape[0] * qs.shape[0])
    return float(qs.shape[0]) * min(float(h.shape[0]), 2.0 * radius * float(h.sum()) / span)


class ExactSamples(Accumulator):
    """The samples ``(X_i, Y_i, h_i, scale_i)``, stored with amortised growth.

    :meth:`evaluate` sums eq. 14 over every sample at each query point
    (compiled) in the blocked order of
    :mod:`~flexarm.ident.regression.accumulators.blocks`; with ``d = 1`` and a named
    kernel, each sample visits only the query points in its window (sorted, as grid
    mode visits its grid: ``O(n log m)`` plus the pairs within the windows, the same
    bits as the loop over every pair), otherwise every pair (``O(n m)``) — or, with
    ``setup.series``, by
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
        self._filled = 0  # rows of _h and _scale computed so far (on first use)

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
        self._fill()
        out: F64 = self._h[: self.n_samples]
        return out

    @property
    def scale(self) -> F64:
        """Per-sample weight factors (``prod_j h_ij**-1`` or 1), shape ``(n,)``."""
        self._fill()
        out: F64 = self._scale[: self.n_samples]
        return out

    def _fill(self) -> None:
        """Compute ``h_i`` and the scales of the samples added since the last use (they
        depend on the index ``i`` only; the Gaussian series needs neither)."""
        n0, n = self._filled, self.n_samples
        if n > n0:
            self._h[n0:n], self._scale[n0:n] = self.setup.sample_bandwidths(n0, n - n0)
            self._filled = n

    def _add(self, X: F64, y: F64) -> None:
        n0, m = self.n_samples, X.shape[0]
        need = n0 + m
        if need > self._y.shape[0]:
            cap = max(need, 2 * self._y.shape[0])
            for name, rows in (
                ("_X", n0),
                ("_y", n0),
                ("_h", self._filled),
                ("_scale", self._filled),
            ):
                old = getattr(self, name)
                new = np.empty((cap, *old.shape[1:]))
                new[:rows] = old[:rows]
                setattr(self, name, new)
        self._X[n0:need] = X
        self._y[n0:need] = y

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
        if setup.code == CALLABLE:
            num, den = setup.blocked_callable_sums(Q, X, y, h, s)
            r: F64 = _loops.ratio(num, den)
            return r
        out = np.empty(Q.shape[0])
        if setup.d == 1:  # each sample's window of the sorted points, as grid mode sums
            order = np.argsort(Q[:, 0], kind="stable")
            qs, x0, h0 = np.ascontiguousarray(Q[order, 0]), X[:, 0], h[:, 0]
            radius = _loops.GAUSS_ZERO if setup.code == 0 else 1.0
            sorted_out = np.empty(Q.shape[0])

            def window(i: int, j: int) -> None:
                num, den = _loops.exact_sums_1d(setup.code, qs[i:j], x0, y, h0, s, b, radius)
                sorted_out[i:j] = _loops.ratio(num, den)

            run_split(Q.shape[0], workers(_window_work(qs, h0, radius), Q.shape[0]), window)
            out[order] = sorted_out
            return out

        def part(i: int, j: int) -> None:  # the query points are independent: split them
            out[i:j] = _loops.exact_predict(setup.code, Q[i:j], X, y, h, s, b)

        run_split(Q.shape[0], workers(Q.shape[0] * X.shape[0], Q.shape[0]), part)
        return out

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
        order = np.argsort(Q[:, 0], kind="stable")
        num, den, shift = gauss_series_eval(np.ascontiguousarray(Q[order, 0]), origin, hs, mn, md)
        out = np.empty(Q.shape[0])
        out[order] = _loops.ratio(num, den)
        far = np.empty(Q.shape[0], dtype=np.bool_)
        far[order] = far_points(den, shift)
        if far.any():
            out[far] = self._direct(np.ascontiguousarray(Q[far]))
        return out

    def _arrays(self) -> State:
        return {"X": self.X, "y": self.y, "h": self.h, "scale": self.scale}

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        self._X, self._y, self._h, self._scale = (
            np.array(state[k], dtype=np.float64, order="C") for k in _KEYS
        )
        self._filled = self._y.shape[0]
