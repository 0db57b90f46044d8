"""Binned mode: linear binning block by block, with a proven error bound (``d = 1``)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...._types import F64
from .. import binning
from ..kernels import KERNELS
from . import _loops
from .base import GridAccumulator, Smoothing, State

__all__ = ["BIN_MAX_BINS", "BinnedSums"]


#: A block needing more bins than this is added exactly.
BIN_MAX_BINS = 2**24


class BinnedSums(GridAccumulator):
    """Approximate grid sums by linear binning (:mod:`flexarm.ident.regression.binning`).

    Samples go in blocks of nearly equal ``h_i``; a block's samples are binned
    onto bins ``r h_B`` wide, and the bins are smoothed onto the grid when the
    block closes (the open block's bins are added to a copy when the sums are
    read). Blocks whose bins would outnumber their samples are added exactly,
    sample by sample. Chunked :meth:`add_chunk` equals one call bit for bit.

    Binned mode keeps its own blocks (of nearly equal ``h_i``, not the fixed
    blocks of :mod:`~flexarm.ident.regression.accumulators.blocks`): its chunks are taken
    in order, one after another (:meth:`add_partials` receives the samples),
    so a Dask array or an iterator of chunks is fitted sequentially in bounded
    memory, bit for bit as one call.

    State arrays: ``num``, ``den`` (g,) — closed blocks; ``bin_block`` (3,) int
    — start, end and kind (0 none, 1 binned, 2 exact) of the open block;
    ``bin_float`` (3,) — its ``h_B``, bin origin and bin width; ``bin_cw``,
    ``bin_sw``, ``bin_aw`` (bins,) — its bins of ``s_i``, ``s_i Y_i``,
    ``s_i |Y_i|``; ``bin_near`` (2, g) — ``S_near``, ``A_near`` of the closed
    blocks; ``bin_sums`` (2,) — ``S``, ``A`` over all samples.
    """

    mode = "binned"

    def __init__(self, setup: Smoothing) -> None:
        super().__init__(setup)
        assert setup.binned is not None
        self.r = setup.binned
        self.kernel = KERNELS[setup.code]
        g = self.sorted_grid.shape[0]
        self.num = np.zeros(g)
        self.den = np.zeros(g)
        self.block = np.array([1, 1, 0], dtype=np.int64)
        self.floats = np.zeros(3)
        self.cw = np.zeros(0)
        self.sw = np.zeros(0)
        self.aw = np.zeros(0)
        self.near = np.zeros((2, g))
        self.totals = np.zeros(2)

    def _add(self, X: F64, y: F64) -> None:
        x = np.ascontiguousarray(X[:, 0])
        setup = self.setup
        n0 = self.n_samples
        pos = 0
        while pos < x.shape[0]:
            i = n0 + pos + 1  # 1-based index of the next sample
            if self.block[2] == 0 or i >= self.block[1]:
                self._flush(self.num, self.den, self.near)
                self._open(i)
            stop = min(x.shape[0], int(self.block[1]) - n0 - 1)
            xs, ys = x[pos:stop], y[pos:stop]
            if self.block[2] == 2:  # short block: exact, sample by sample
                h, scale = setup.sample_bandwidths(n0 + pos, stop - pos)
                gs = self.sorted_grid[:, 0]
                c = binning.radius(self.kernel)
                _loops.grid_update_1d(setup.code, gs, xs, ys, h[:, 0], scale, self.num, self.den, c)
                _loops.add_totals(scale, ys, self.totals)  # one by one: chunks equal one call
            else:
                binning.bin_samples(
                    xs,
                    ys,
                    n0 + pos,
                    float(setup.bandwidth[0]),
                    setup.decay,
                    setup.recursive,
                    float(self.floats[1]),
                    float(self.floats[2]),
                    self.cw,
                    self.sw,
                    self.aw,
                    self.totals,
                )
            pos = stop

    def _open(self, start: int) -> None:
        setup = self.setup
        end = binning.block_end(start, self.r, setup.decay)
        hb = float(setup.bandwidth[0]) * (float(start) * float(end - 1)) ** (-setup.decay / 2.0)
        delta = self.r * hb
        pad = binning.radius(self.kernel) * hb + delta
        gs = self.sorted_grid[:, 0]
        bins = math.ceil((gs[-1] - gs[0] + 2.0 * pad) / delta) + 1
        binned = bins <= min(end - start, BIN_MAX_BINS)
        self.block[:] = (start, end, 1 if binned else 2)
        self.floats[:] = (hb, gs[0] - pad, delta)
        self.cw = np.zeros(bins if binned else 0)
        self.sw = np.zeros(bins if binned else 0)
        self.aw = np.zeros(bins if binned else 0)

    def _flush(self, num: F64, den: F64, near: F64) -> None:
        """Add the open binned block (if any) to ``num``, ``den``, ``near`` (sorted grid order)."""
        if self.block[2] != 1:
            return
        hb, origin, delta = (float(v) for v in self.floats)
        binning.flush_bins(
            self.setup.code,
            self.sorted_grid[:, 0],
            origin,
            delta,
            hb,
            binning.radius(self.kernel),
            self.cw,
            self.sw,
            self.aw,
            num,
            den,
            near,
        )

    def _all_sums(self) -> tuple[F64, F64, F64]:
        """``num``, ``den`` and ``near`` with the open block added (not stored)."""
        if self.block[2] == 1:
            num, den, near = self.num.copy(), self.den.copy(), self.near.copy()
            self._flush(num, den, near)
            return num, den, near
        return self.num, self.den, self.near

    def sums(self) -> tuple[F64, F64]:
        num, den, _ = self._all_sums()
        return num, den

    @property
    def weight_error(self) -> float:
        """Bound ``E`` on the error of one binned weight (:func:`binning.per_weight_error`)."""
        return binning.per_weight_error(self.kernel, self.r, self.setup.decay)

    def sum_error_bounds(self, where: NDArray[np.int64]) -> tuple[F64, F64]:
        """Bounds ``eN``, ``eD`` on the errors of ``N``, ``D`` at sorted grid positions ``where``.

        ``eN = E A_near + (tau + rho) A``, ``eD = E S_near + (tau + rho) S`` with
        ``rho = 4 (2 n + J + 16) 2**-53`` for the rounding of the sums (``J``
        bins in the open block); see :mod:`flexarm.ident.regression.binning`.
        """
        near = self._all_sums()[2][:, where]
        e = self.weight_error
        tau = binning.far_error(self.kernel, self.r)
        s, a = (float(v) for v in self.totals)
        # rounding: sums of at most n terms into bins and bins (<= n, or this block's) onto the grid
        rnd = 4.0 * (2 * self.n_samples + self.cw.shape[0] + 16) * 2.0**-53
        eN: F64 = e * near[1] + (tau + rnd) * a
        eD: F64 = e * near[0] + (tau + rnd) * s
        return eN, eD

    def _arrays(self) -> State:
        return {
            "num": self.num,
            "den": self.den,
            "bin_block": self.block,
            "bin_float": self.floats,
            "bin_cw": self.cw,
            "bin_sw": self.sw,
            "bin_aw": self.aw,
            "bin_near": self.near,
            "bin_sums": self.totals,
        }

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        def f64(key: str) -> F64:
            return np.array(state[key], dtype=np.float64, order="C")

        self.num, self.den = f64("num"), f64("den")
        self.block = np.array(state["bin_block"], dtype=np.int64, order="C")
        self.floats, self.cw, self.sw, self.aw = (
            f64(k) for k in ("bin_float", "bin_cw", "bin_sw", "bin_aw")
        )
        self.near, self.totals = f64("bin_near"), f64("bin_sums")
