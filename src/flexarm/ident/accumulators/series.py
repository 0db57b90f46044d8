"""Series mode: cluster moments of the Gaussian series (a fast Gauss transform) on a grid."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..kernels import (
    SERIES_REACH,
    SERIES_TERMS,
    SERIES_WIDTH,
    gauss_series_eval,
    gauss_series_moments,
)
from . import _loops
from .base import GridAccumulator, Smoothing, State

__all__ = ["SERIES_MAX_CLUSTERS", "SeriesMoments"]

F64 = NDArray[np.float64]

#: Grid mode: (grid span + 2 reach) / (h/8) clusters at most.
SERIES_MAX_CLUSTERS = 2**22


class SeriesMoments(GridAccumulator):
    """Gaussian kernel, one bandwidth, ``d = 1``: moments of clusters ``h/8`` wide.

    The clusters cover the grid widened by :data:`~flexarm.ident.kernels.SERIES_REACH`
    bandwidths (every sample with a nonzero weight at a grid point). Each
    sample adds to its cluster's ``SERIES_TERMS`` moments in arrival order, so
    chunks give what one call gives bit for bit; the sums at the grid agree
    with direct summation to rounding (:func:`~flexarm.ident.kernels.gauss_series_moments`).

    State arrays: ``series_mn`` and ``series_md``, shape (clusters, terms) each.
    """

    mode = "series"

    def __init__(self, setup: Smoothing) -> None:
        super().__init__(setup)
        h = float(setup.bandwidth[0])
        gs = self.sorted_grid[:, 0]
        clusters = math.ceil((gs[-1] - gs[0] + 2.0 * SERIES_REACH * h) / (SERIES_WIDTH * h)) + 2
        if clusters > SERIES_MAX_CLUSTERS:
            raise setup.fail(
                "series",
                f"False when the grid spans more than {SERIES_MAX_CLUSTERS // 2} "
                "bandwidths (too many clusters)",
                "True",
            )
        self.origin = float(gs[0] - SERIES_REACH * h - SERIES_WIDTH * h)
        self.mn = np.zeros((clusters, SERIES_TERMS))
        self.md = np.zeros((clusters, SERIES_TERMS))

    def _add(self, X: F64, y: F64) -> None:
        setup = self.setup
        x = np.ascontiguousarray(X[:, 0])
        h = float(setup.bandwidth[0])
        gauss_series_moments(x, y, setup.series_scale(), self.origin, h, self.mn, self.md)

    def _scaled(self) -> tuple[F64, F64, F64]:
        """Scaled sums and their shift at the sorted grid (see the kernels module)."""
        return gauss_series_eval(
            np.ascontiguousarray(self.sorted_grid[:, 0]),
            self.origin,
            float(self.setup.bandwidth[0]),
            self.mn,
            self.md,
        )

    def sums(self) -> tuple[F64, F64]:
        num, den, shift = self._scaled()
        scale = np.exp(-shift)
        return num * scale, den * scale

    def ratio(self) -> F64:
        """``N / D`` from the scaled sums (free of underflow far from the data)."""
        num, den, _ = self._scaled()
        out: F64 = _loops.ratio(num, den)
        return out

    def _arrays(self) -> State:
        return {"series_mn": self.mn, "series_md": self.md}

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        self.mn = np.array(state["series_mn"], dtype=np.float64, order="C")
        self.md = np.array(state["series_md"], dtype=np.float64, order="C")
