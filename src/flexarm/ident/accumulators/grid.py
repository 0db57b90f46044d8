"""Grid mode: the running sums ``N = sum Y_i w_i`` and ``D = sum w_i`` at the grid points."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _loops
from .base import CALLABLE, GridAccumulator, State

__all__ = ["GridSums"]

F64 = NDArray[np.float64]


class GridSums(GridAccumulator):
    """Exact running sums at the grid points, updated sample by sample.

    O(grid) memory for streams of any length. With ``d = 1`` and a named
    kernel each sample visits only the grid points of its window (binary
    search in the sorted grid; the Gaussian within ``|u| <= 38.61``, beyond
    which its float64 value is exactly 0); in ``d >= 2`` every grid point (the
    weight stops at its first zero factor); a user callable is evaluated with
    NumPy in blocks and accumulated in the same order.

    State arrays: ``num`` and ``den``, shape (g,) each, in sorted grid order.
    """

    mode = "grid"

    def _add(self, X: F64, y: F64) -> None:
        setup = self.setup
        h, scale = setup.sample_bandwidths(self.n_samples, X.shape[0])
        if setup.code == CALLABLE:
            setup.callable_sums(self.sorted_grid, X, y, h, scale, self.num, self.den)
        elif setup.d == 1:
            radius = _loops.GAUSS_ZERO if setup.code == 0 else 1.0
            _loops.grid_update_1d(
                setup.code,
                self.sorted_grid[:, 0],
                X[:, 0],
                y,
                h[:, 0],
                scale,
                self.num,
                self.den,
                radius,
            )
        else:
            _loops.grid_update(setup.code, self.sorted_grid, X, y, h, scale, self.num, self.den)

    def sums(self) -> tuple[F64, F64]:
        return self.num, self.den

    def _arrays(self) -> State:
        return {"num": self.num, "den": self.den}

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        self.num = np.array(state["num"], dtype=np.float64, order="C")
        self.den = np.array(state["den"], dtype=np.float64, order="C")
