"""Where each part of the LQG's parameter and state vectors sits, written once.

The packer (:meth:`flexarm.control.lqg.LQG.design`), the compiled step
(:func:`flexarm.control.lqg.lqg_law`) and the readers in Python
(:func:`flexarm.control.lqg.closed_loop_growth`, the tests) all take their offsets
from here. With ``nx`` states, ``nu`` links (torques), ``ny`` measurements and ``G``
grid points:

Parameter vector (float64)
    The header (:data:`HEAD` slots, named by the slot constants): ``nx, ny, G``,
    the point-sensor flag, the feedback gain, ``ks``, ``lambda0`` and the offset of
    the fuzzy part. Then the grid (``G`` elbow angles, rad, increasing). Then one
    block per grid point: ``Phi`` (nx, nx), ``Gamma`` (nx, nu), ``C`` (ny, nx),
    ``K`` (nu, nx), ``M`` (nx, ny), each row-major (:func:`block_parts`). Then,
    with fuzzy adaptation only, the fuzzy part: each link's tip deflection as a row
    over the ``nx / 2`` coordinates (nu, nx / 2), then the packed fuzzy system
    (:func:`flexarm.fuzzy.compiled.pack_system`).
State vector
    The estimate ``xh`` (nx), the last feedback ``du`` (nu), the prediction (nx)
    and the innovation (ny); with fuzzy adaptation, the fuzzy inputs (nu), the
    last gain (1) and the fuzzy system's workspace (:func:`state_parts`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numba as nb
import numpy as np

from .._types import F64

__all__ = [
    "FUZZY",
    "GAIN",
    "HEAD",
    "KS",
    "LAMBDA0",
    "NX",
    "NY",
    "N_GRID",
    "POINT",
    "LQGLayout",
    "block_parts",
    "pack_block",
    "pack_parameters",
    "state_parts",
]


NX, NY, N_GRID, POINT, GAIN, KS, LAMBDA0, FUZZY = range(8)
"""The header's slots: sizes, the point-sensor flag (1.0 or 0.0), the feedback gain,
``ks``, ``lambda0`` and the offset of the fuzzy part."""
HEAD = 8
"""The header's length."""


@nb.njit(cache=True, nogil=True, inline="always")
def block_parts(nx: int, nu: int, ny: int) -> tuple[int, int, int, int, int, int]:
    """Offsets of ``Phi, Gamma, C, K, M`` inside a grid point's block, and its length."""
    gamma = nx * nx
    c = gamma + nx * nu
    k = c + ny * nx
    m = k + nu * nx
    return 0, gamma, c, k, m, m + nx * ny


@nb.njit(cache=True, nogil=True, inline="always")
def state_parts(nx: int, nu: int, ny: int) -> tuple[int, int, int, int, int, int]:
    """Offsets in the state of ``du``, the prediction, the innovation, the fuzzy
    inputs, the last gain and the fuzzy workspace (the estimate starts at 0)."""
    du = nx
    prediction = du + nu
    innovation = prediction + nx
    fuzzy_inputs = innovation + ny
    gain = fuzzy_inputs + nu
    return du, prediction, innovation, fuzzy_inputs, gain, gain + 1


def pack_block(phi: F64, gamma: F64, c: F64, k: F64, m: F64) -> F64:
    """One grid point's block, its matrices in layout order."""
    return np.concatenate([a.ravel() for a in (phi, gamma, c, k, m)])


def pack_parameters(
    head: Sequence[float], grid: F64, blocks: Sequence[F64], fuzzy: Sequence[F64]
) -> F64:
    """The parameter vector from the header's values before the fuzzy offset
    (``nx, ny, G, point, gain, ks, lambda0``), the grid, the blocks and the fuzzy
    part's pieces (empty without adaptation); the fuzzy offset is filled in."""
    header = np.array([*head, 0.0])
    header[FUZZY] = HEAD + grid.shape[0] + sum(b.shape[0] for b in blocks)
    return np.concatenate([header, grid, *blocks, *fuzzy])


class LQGLayout(NamedTuple):
    """The sizes a parameter vector states, and the views of its parts."""

    nx: int
    nu: int
    ny: int
    n_grid: int

    @classmethod
    def of(cls, params: F64, nu: int) -> LQGLayout:
        """The layout of ``params`` for an arm with ``nu`` links."""
        return cls(int(params[NX]), nu, int(params[NY]), int(params[N_GRID]))

    def grid(self, params: F64) -> F64:
        """The schedule's elbow angles, shape (G,), rad."""
        return params[HEAD : HEAD + self.n_grid]

    def matrices(self, params: F64, j: int) -> tuple[F64, F64, F64, F64, F64]:
        """``Phi, Gamma, C, K, M`` of grid point ``j`` (views of ``params``)."""
        parts = block_parts.py_func(self.nx, self.nu, self.ny)
        start = HEAD + self.n_grid + j * parts[5]
        shapes = [
            (self.nx, self.nx),
            (self.nx, self.nu),
            (self.ny, self.nx),
            (self.nu, self.nx),
            (self.nx, self.ny),
        ]
        phi, gamma, c, k, m = (
            params[start + o : start + o + a * b].reshape(a, b)
            for o, (a, b) in zip(parts[:5], shapes, strict=True)
        )
        return phi, gamma, c, k, m

    def state(self, state: F64) -> tuple[F64, F64]:
        """The estimate ``xh`` (nx) and the last feedback ``du`` (nu) in ``state``."""
        du = state_parts.py_func(self.nx, self.nu, self.ny)[0]
        return state[:du], state[du : du + self.nu]
