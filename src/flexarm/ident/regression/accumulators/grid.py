"""Grid mode: the sums ``N = sum Y_i w_i`` and ``D = sum w_i`` at the grid points, blocked."""

from __future__ import annotations

import numpy as np

from ...._types import F64
from . import _loops
from ._threads import run_split, workers
from .base import CALLABLE, BlockedAccumulator

__all__ = ["GridSums"]


class GridSums(BlockedAccumulator):
    """Exact sums at the grid points, updated sample by sample in the blocked order.

    O(grid) memory for streams of any length. With ``d = 1`` and a named
    kernel each sample visits only the grid points of its window (binary
    search in the sorted grid; the Gaussian within ``|u| <= 38.61``, beyond
    which its float64 value is exactly 0); in ``d >= 2`` every grid point (the
    weight stops at its first zero factor); a user callable is evaluated with
    NumPy in blocks and accumulated in the same order. The order of the
    additions is the blocked one of :mod:`~flexarm.ident.regression.accumulators.blocks`.

    State arrays: ``num`` and ``den`` (complete blocks), ``open_num`` and
    ``open_den`` (the open block), shape (g,) each, in sorted grid order;
    ``block``.
    """

    mode = "grid"

    def _new_arrays(self) -> dict[str, F64]:
        g = self.sorted_grid.shape[0]
        return {"num": np.zeros(g), "den": np.zeros(g)}

    def _add_block(self, X: F64, y: F64, start: int, sums: dict[str, F64]) -> None:
        setup = self.setup
        num, den = sums["num"], sums["den"]
        h, scale = setup.sample_bandwidths(start, X.shape[0])
        if setup.code == CALLABLE:
            setup.callable_sums(self.sorted_grid, X, y, h, scale, num, den)
            return
        grid, g, m = self.sorted_grid, self.sorted_grid.shape[0], X.shape[0]
        if setup.d == 1:  # the grid points are independent: split them over the cores
            radius = _loops.GAUSS_ZERO if setup.code == 0 else 1.0
            gs, x, h1 = grid[:, 0], X[:, 0], h[:, 0]
            span = float(gs[-1] - gs[0])
            reach = 1.0 if span == 0.0 else min(1.0, 2.0 * radius * float(h1.max()) / span)

            def part(a: int, b: int) -> None:
                code = setup.code
                _loops.grid_update_1d(code, gs[a:b], x, y, h1, scale, num[a:b], den[a:b], radius)

            run_split(g, workers(m * g * reach, g), part)
        else:

            def part(a: int, b: int) -> None:
                _loops.grid_update(setup.code, grid[a:b], X, y, h, scale, num[a:b], den[a:b])

            run_split(g, workers(m * g, g), part)

    def sums(self) -> tuple[F64, F64]:
        now = self.current()
        return now["num"], now["den"]
