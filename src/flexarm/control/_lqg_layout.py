"""Where each part of the LQG's parameter and state vectors sits, written once.

The packer (:meth:`flexarm.control.lqg.LQG.design`), the compiled step
(:func:`flexarm.control.lqg.lqg_law`) and the readers in Python
(:func:`flexarm.control.lqg.closed_loop_growth`, the tests) all take their offsets
from here. With ``nx`` states, ``nu`` links (torques), ``ny`` measurements and ``G``
grid points:

Parameter vector (float64)
    The header (:data:`HEAD` slots, named by the slot constants): ``nx, ny, G``,
    the point-sensor flag, the feedback gain, ``ks``, ``lambda0``, the offset of
    the fuzzy part, ``G1`` and the absolute-frame flag. Then the grid (``G`` elbow
    angles, rad, increasing), then ``G1`` shoulder angles (rad, increasing; one,
    0, for the design at ``theta_1 = 0`` turned with the reference). Then one
    block per grid point, shoulder-major (block ``i G + j`` at shoulder angle
    ``i`` and elbow angle ``j``): ``Phi`` (nx, nx), ``Gamma`` (nx, nu), ``C``
    (ny, nx), ``K`` (nu, nx), ``M`` (nx, ny), each row-major (:func:`block_parts`).
    Then, for a design about the gravity equilibrium, the operating table: a finer
    grid of elbow angles (``H``), of shoulder angles (``H1``), and per grid point,
    shoulder-major, the holding torques ``tau0`` (nu; N m) and the measurement there
    less what the law subtracts from the reference ``y0`` (ny; the sensed point's
    sag, m) (:func:`operating_parts`; none without gravity). Then,
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
    "ABSOLUTE",
    "FUZZY",
    "GAIN",
    "HEAD",
    "KS",
    "LAMBDA0",
    "NX",
    "NY",
    "N_GRID",
    "N_GRID1",
    "OPS",
    "OPS_N",
    "OPS_N1",
    "POINT",
    "LQGLayout",
    "block_parts",
    "operating_parts",
    "pack_block",
    "pack_parameters",
    "state_parts",
]


NX, NY, N_GRID, POINT, GAIN, KS, LAMBDA0, FUZZY, N_GRID1, ABSOLUTE, OPS, OPS_N, OPS_N1 = range(13)
"""The header's slots: sizes, the point-sensor flag (1.0 or 0.0), the feedback gain,
``ks``, ``lambda0``, the offset of the fuzzy part, the shoulder grid's size, the
absolute-frame flag (1.0: the design is at the grid's shoulder angles, the
measurement is not turned), and the operating table's offset (0: none) and its
grids' sizes ``H``, ``H1``."""
HEAD = 13
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
def operating_parts(start: int, nu: int, ny: int, h: int, h1: int) -> tuple[int, int, int]:
    """Offsets of the operating table's elbow grid, shoulder grid and first row
    (``start``: the table's offset; rows of ``nu + ny``: ``tau0`` then ``y0``)."""
    return start, start + h, start + h + h1


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
    head: Sequence[float],
    grid: F64,
    blocks: Sequence[F64],
    fuzzy: Sequence[F64],
    shoulder: F64 | None = None,
    operating: tuple[F64, F64, F64] | None = None,
) -> F64:
    """The parameter vector from the header's values before the fuzzy offset
    (``nx, ny, G, point, gain, ks, lambda0``), the elbow grid, the blocks, the fuzzy
    part's pieces (empty without adaptation), the shoulder grid (None: one point,
    0, and the measurement turned with the reference; else absolute) and the
    operating table (its elbow grid, shoulder grid and rows (H1 H, nu + ny), or
    None); the offsets, sizes and the frame flag are filled in."""
    g1 = np.zeros(1) if shoulder is None else np.asarray(shoulder, dtype=float)
    header = np.zeros(HEAD)
    header[:FUZZY] = head
    header[N_GRID1] = g1.shape[0]
    header[ABSOLUTE] = 0.0 if shoulder is None else 1.0
    end = HEAD + grid.shape[0] + g1.shape[0] + sum(b.shape[0] for b in blocks)
    table: list[F64] = []
    if operating is not None:
        h, h1, rows = (np.asarray(x, dtype=float) for x in operating)
        header[OPS], header[OPS_N], header[OPS_N1] = end, h.shape[0], h1.shape[0]
        table = [h, h1, rows.ravel()]
        end += h.shape[0] + h1.shape[0] + rows.size
    header[FUZZY] = end
    return np.concatenate([header, grid, g1, *blocks, *table, *fuzzy])


class LQGLayout(NamedTuple):
    """The sizes a parameter vector states, and the views of its parts."""

    nx: int
    nu: int
    ny: int
    n_grid: int
    n_shoulder: int = 1

    @classmethod
    def of(cls, params: F64, nu: int) -> LQGLayout:
        """The layout of ``params`` for an arm with ``nu`` links."""
        sizes = (int(params[NX]), nu, int(params[NY]), int(params[N_GRID]))
        return cls(*sizes, int(params[N_GRID1]))

    def grid(self, params: F64) -> F64:
        """The schedule's elbow angles, shape (G,), rad."""
        return params[HEAD : HEAD + self.n_grid]

    def shoulder_grid(self, params: F64) -> F64:
        """The schedule's shoulder angles, shape (G1,), rad."""
        start = HEAD + self.n_grid
        return params[start : start + self.n_shoulder]

    def _start(self, j: int) -> int:
        blk = block_parts.py_func(self.nx, self.nu, self.ny)[5]
        return HEAD + self.n_grid + self.n_shoulder + j * blk

    def operating(self, params: F64) -> tuple[F64, F64, F64] | None:
        """The operating table: its elbow grid (H,), shoulder grid (H1,), rad, and rows
        (H1, H, nu + ny): ``tau0`` (N m), then ``y0``; None without one."""
        start = int(params[OPS])
        if start == 0:
            return None
        h, h1 = int(params[OPS_N]), int(params[OPS_N1])
        g, g1, r = operating_parts.py_func(start, self.nu, self.ny, h, h1)
        rows = params[r : r + h * h1 * (self.nu + self.ny)].reshape(h1, h, self.nu + self.ny)
        return params[g : g + h], params[g1 : g1 + h1], rows

    def matrices(self, params: F64, j: int) -> tuple[F64, F64, F64, F64, F64]:
        """``Phi, Gamma, C, K, M`` of block ``j`` (views of ``params``; grid point ``j``
        of a schedule on the elbow angle alone)."""
        parts = block_parts.py_func(self.nx, self.nu, self.ny)
        start = self._start(j)
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
