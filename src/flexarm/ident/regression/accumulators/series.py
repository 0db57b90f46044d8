"""Series mode: cluster moments of the Gaussian series (a fast Gauss transform) on a grid.

Where it is used, and how well it agrees with direct summation
---------------------------------------------------------------
The series applies to the Gaussian kernel with one bandwidth ``h``
(``decay = 0``) in one dimension, outside binned mode; ``series="auto"`` (the
estimators' default) takes it there when it is the faster path
(:func:`auto_series`). Each series weight has a relative error below ~1e-13
(:func:`~flexarm.ident.regression.kernels.gauss_series_moments`), so at a point ``x``
with a sample within :data:`SERIES_NEAR` ``h`` the sums agree with direct
summation to ``|N_s - N| <= 1e-13 A``, ``|D_s - D| <= 1e-13 D`` (``A = sum w_i
|Y_i|``) and the estimates to ``|m_s - m| <= 2e-13 A / D`` (the tests measure
1e-12 against a long-double oracle over adversarial inputs). Farther from
every sample the direct weights are subnormal numbers or zero (direct
summation itself loses its precision there, and gives NaN past 38.61 h): at
those points the estimate takes the direct sums, kept alongside for them
(grid mode: the *band* sums of ``flexarm.ident.regression.accumulators._loops.band_update_1d``;
exact mode: the stored samples), so it equals direct summation **bit for
bit** there, NaN included.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...._types import F64
from ..kernels import (
    SERIES_REACH,
    SERIES_TERMS,
    SERIES_WIDTH,
    gauss_series_eval,
    gauss_series_moments,
)
from . import _loops
from .base import BlockedAccumulator, Smoothing

__all__ = [
    "SERIES_AUTO_CLUSTERS",
    "SERIES_BAND",
    "SERIES_MAX_CLUSTERS",
    "SERIES_NEAR",
    "SeriesMoments",
    "auto_series",
    "far_points",
    "series_clusters",
]


#: Grid mode: (grid span + 2 reach) / (h/8) clusters at most.
SERIES_MAX_CLUSTERS = 2**22
#: ``series="auto"`` in grid mode takes the series up to this many clusters (state
#: ``2 x 2 x 28 x 8`` bytes a cluster) and when a sample's window holds this many grid
#: points or more (``SERIES_AUTO_POINTS``); otherwise the direct grid sums.
SERIES_AUTO_CLUSTERS = 2**14
SERIES_AUTO_POINTS = 8
#: The series is used where a non-empty cluster's centre lies within this many ``h``
#: (so some sample within ``SERIES_NEAR + 1/16``, where its weight is a normal float
#: above 1e-292); elsewhere the direct sums.
SERIES_NEAR = 36.6
#: Band sums: the direct Gaussian terms of samples at least this many ``h`` away.
SERIES_BAND = 36.5


def series_clusters(lo: float, hi: float, h: float) -> int:
    """Clusters ``h/8`` wide covering ``[lo, hi]`` widened by the series' reach."""
    return math.ceil((hi - lo + 2.0 * SERIES_REACH * h) / (SERIES_WIDTH * h)) + 2


def auto_series(grid: F64 | None, h: float) -> bool:
    """Whether ``series="auto"`` takes the series (where it applies): exact mode always,
    grid mode when its clusters and the direct window's grid points favour it."""
    if grid is None:
        return True
    gs = grid[:, 0]
    lo, hi = float(gs.min()), float(gs.max())
    if series_clusters(lo, hi, h) > SERIES_AUTO_CLUSTERS:
        return False
    span = hi - lo
    window = gs.shape[0] if span == 0.0 else gs.shape[0] * min(1.0, 2 * 38.61 * h / span)
    return bool(window >= SERIES_AUTO_POINTS)


def far_points(den: F64, shift: F64) -> NDArray[np.bool_]:
    """Points without a non-empty cluster within :data:`SERIES_NEAR` ``h`` (direct sums there).

    ``den`` and ``shift`` come from :func:`~flexarm.ident.regression.kernels.gauss_series_eval`.
    """
    out: NDArray[np.bool_] = (den == 0.0) | (2.0 * shift > SERIES_NEAR**2)
    return out


class SeriesMoments(BlockedAccumulator):
    """Gaussian kernel, one bandwidth, ``d = 1``: moments of clusters ``h/8`` wide.

    The clusters cover the grid widened by :data:`~flexarm.ident.regression.kernels.SERIES_REACH`
    bandwidths (every sample with a nonzero weight at a grid point). Each
    sample adds to its cluster's ``SERIES_TERMS`` moments and to the band sums
    (its direct terms at the grid points :data:`SERIES_BAND` ``h`` or farther),
    in the blocked order of :mod:`~flexarm.ident.regression.accumulators.blocks`; the
    estimate takes the series near the data and the band sums far from it
    (see the module docstring).

    State arrays: ``series_mn`` and ``series_md``, shape (clusters, terms)
    each, and ``series_band`` (2, g) (numerator, denominator), for the
    complete blocks; the same with ``open_`` for the open block; ``block``.
    A file without ``series_band`` (format 1) evaluates by the series everywhere.
    """

    mode = "series"

    def __init__(self, setup: Smoothing) -> None:
        h = float(setup.bandwidth[0])
        assert setup.grid is not None
        g0, g1 = float(setup.grid[:, 0].min()), float(setup.grid[:, 0].max())
        self.clusters = series_clusters(g0, g1, h)
        if self.clusters > SERIES_MAX_CLUSTERS:
            raise setup.fail(
                "series",
                f"False when the grid spans more than {SERIES_MAX_CLUSTERS // 2} "
                "bandwidths (too many clusters)",
                "True",
            )
        self.origin = float(g0 - SERIES_REACH * h - SERIES_WIDTH * h)
        self.band_ok = True
        super().__init__(setup)

    def _new_arrays(self) -> dict[str, F64]:
        g = self.sorted_grid.shape[0]
        return {
            "series_mn": np.zeros((self.clusters, SERIES_TERMS)),
            "series_md": np.zeros((self.clusters, SERIES_TERMS)),
            "series_band": np.zeros((2, g)),
        }

    def _add_block(self, X: F64, y: F64, start: int, sums: dict[str, F64]) -> None:
        setup = self.setup
        x = np.ascontiguousarray(X[:, 0])
        h = float(setup.bandwidth[0])
        s = setup.series_scale()
        gauss_series_moments(x, y, s, self.origin, h, sums["series_mn"], sums["series_md"])
        gs = self.sorted_grid[:, 0]
        reach = SERIES_BAND * h  # one bandwidth (decay = 0): skip the band if no sample has one
        if float(x.max()) - reach < gs[0] and gs[-1] < float(x.min()) + reach:
            return
        hs, scale = setup.sample_bandwidths(start, x.shape[0])
        band = sums["series_band"]
        _loops.band_update_1d(gs, x, y, hs[:, 0], scale, band[0], band[1], SERIES_BAND)

    def _scaled(self) -> tuple[F64, F64, F64, dict[str, F64]]:
        """Scaled sums, their shift at the sorted grid (see the kernels module), and the sums."""
        now = self.current()
        num, den, shift = gauss_series_eval(
            np.ascontiguousarray(self.sorted_grid[:, 0]),
            self.origin,
            float(self.setup.bandwidth[0]),
            now["series_mn"],
            now["series_md"],
        )
        return num, den, shift, now

    def sums(self) -> tuple[F64, F64]:
        num, den, shift, now = self._scaled()
        scale = np.exp(-shift)
        num, den = num * scale, den * scale
        if self.band_ok:
            far = far_points(den, shift)
            num[far], den[far] = now["series_band"][0][far], now["series_band"][1][far]
        return num, den

    def ratio(self) -> F64:
        """``N / D`` from the scaled sums (free of underflow), direct sums far from the data."""
        num, den, shift, now = self._scaled()
        if self.band_ok:
            far = far_points(den, shift)
            num[far], den[far] = now["series_band"][0][far], now["series_band"][1][far]
        out: F64 = _loops.ratio(num, den)
        return out

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        super()._restore(state)
        self.band_ok = "series_band" in state
