"""The accumulator interface and the constant description it works from.

:class:`Smoothing` is the validated, frozen description of one estimate
(kernel, bandwidth, decay, the estimate's weights, the grid and the mode's
options) — the model. An :class:`Accumulator` is the run state built on it:
it takes chunks of samples (:meth:`~Accumulator.add_chunk`), evaluates the
estimate (:meth:`~Accumulator.evaluate`), and exports and imports its state
as a dict of plain arrays (:meth:`~Accumulator.state`,
:meth:`~Accumulator.from_state`), the one description that ``save`` writes
and ``load`` reads.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, ClassVar, Self

import numpy as np
from numpy.typing import NDArray

from ...._types import F64, I64
from ....errors import InvalidValueError
from ..._estimator import callable_output
from ..kernels import KernelFunction
from . import _loops
from .blocks import BLOCK, ChunkPartials, segments, zeros_like

__all__ = [
    "CALLABLE",
    "Accumulator",
    "BlockedAccumulator",
    "GridAccumulator",
    "Smoothing",
    "State",
]

#: An accumulator's state: plain arrays by name (``.npz``-ready, no pickle).
State = dict[str, NDArray[Any]]

#: Kernel code of a user callable (evaluated with NumPy).
CALLABLE = -1


@dataclass(frozen=True, eq=False)
class Smoothing:
    """The validated constant description of one kernel estimate.

    Attributes
    ----------
    owner : str
        The estimator's class name (named in error messages).
    kernel : str or callable
        A kernel name, or ``K(u)`` mapping shape ``(m, d)`` to ``(m,)``.
    code : int
        Compiled kernel code (index in :data:`~flexarm.ident.KERNELS`), or
        :data:`CALLABLE`.
    bandwidth : ndarray, shape (d,)
        ``h_1`` per input dimension (units of the regressor).
    decay : float
        ``h_i = bandwidth * i**(-decay)``.
    recursive : bool
        Weights ``h_i**(-d) K`` (Devroye–Wagner) rather than ``K`` (eq. 14).
    grid : ndarray of shape (g, d), or None
        Evaluation points of the grid modes; ``None`` in exact mode.
    binned : float or None
        Relative bin width ``r`` of binned mode.
    series : bool
        Gaussian series sums (resolved: ``series="auto"`` is decided before).
    block : int
        Samples per block of the blocked sums
        (:mod:`~flexarm.ident.regression.accumulators.blocks`).
    """

    owner: str
    kernel: str | KernelFunction
    code: int
    bandwidth: F64
    decay: float
    recursive: bool
    grid: F64 | None = None
    binned: float | None = None
    series: bool = False
    block: int = BLOCK

    @property
    def d(self) -> int:
        """Input dimension."""
        return int(self.bandwidth.shape[0])

    def fail(self, name: str, expected: str, got: str) -> InvalidValueError:
        """The error for parameter ``name`` of the estimator, in the one message format."""
        return InvalidValueError(
            f"The '{name}' parameter of {self.owner} must be {expected}. Got {got} instead."
        )

    def sample_bandwidths(self, start: int, n: int) -> tuple[F64, F64]:
        """``h_i`` (shape ``(n, d)``) and weight scales (``(n,)``) of samples ``start + 1 ..``."""
        h, scale = _loops.sample_bandwidths(self.bandwidth, self.decay, start, n, self.recursive)
        return h, scale

    def series_scale(self) -> float:
        """The constant weight factor of the series: ``1/h`` for the recursive estimate, else 1."""
        return 1.0 / float(self.bandwidth[0]) if self.recursive else 1.0

    def callable_weights(self, Q: F64, X: F64, h: F64, scale: F64) -> F64:
        """Weights ``W[i, q] = scale_i K((Q_q - X_i) / h_i)`` from the user callable."""
        kernel = self.kernel
        assert callable(kernel)
        u = (Q[None, :, :] - X[:, None, :]) / h[:, None, :]
        flat = u.reshape(-1, Q.shape[1])
        expected = f"shape ({flat.shape[0]},) for u of shape {flat.shape}"
        w = callable_output(kernel(flat), "kernel", self.owner, (flat.shape[0],), expected)
        W: F64 = np.ascontiguousarray(w.reshape(X.shape[0], Q.shape[0]) * scale[:, None])
        return W

    def callable_sums(self, Q: F64, X: F64, y: F64, h: F64, scale: F64, num: F64, den: F64) -> None:
        """Add the callable kernel's ``sum W y`` and ``sum W`` at ``Q`` to ``num``, ``den``.

        One addition per sample, in sample order (the caller cuts the blocks).
        """
        step = max(1, 2**20 // Q.shape[0])
        for s in range(0, X.shape[0], step):
            W = self.callable_weights(Q, X[s : s + step], h[s : s + step], scale[s : s + step])
            _loops.accumulate_rows(W, y[s : s + step], num, den)

    def blocked_callable_sums(self, Q: F64, X: F64, y: F64, h: F64, scale: F64) -> tuple[F64, F64]:
        """``N`` and ``D`` at ``Q`` over samples ``1 .. n`` in the blocked order (callable)."""
        num, den = np.zeros(Q.shape[0]), np.zeros(Q.shape[0])
        for a, b, closes in segments(0, X.shape[0], self.block):
            pn, pd = np.zeros(Q.shape[0]), np.zeros(Q.shape[0])
            self.callable_sums(Q, X[a:b], y[a:b], h[a:b], scale[a:b], pn, pd)
            if not closes:  # the open block: added last, as the grid modes do
                return num + pn, den + pd
            num += pn
            den += pd
        return num + 0.0, den + 0.0


class Accumulator(ABC):
    """Streaming sums of one kernel estimate: one subclass per mode.

    Parameters
    ----------
    setup : Smoothing
        The estimate's constant description.
    """

    #: The mode's name: "exact", "grid", "binned" or "series".
    mode: ClassVar[str]

    def __init__(self, setup: Smoothing) -> None:
        self.setup = setup
        self.n_samples = 0

    @abstractmethod
    def _add(self, X: F64, y: F64) -> None:
        """Add the samples ``n_samples + 1 ..`` (``n_samples`` not yet advanced)."""

    def add_chunk(self, X: F64, y: F64) -> None:
        """Add samples in arrival order.

        Parameters
        ----------
        X : ndarray, shape (m, d)
            Inputs (units of the regressor), C-contiguous float64.
        y : ndarray, shape (m,)
            Outputs (units of the response).
        """
        self._add(X, y)
        self.n_samples += X.shape[0]

    @classmethod
    def chunk_partials(cls, setup: Smoothing, X: F64, y: F64, start: int) -> ChunkPartials:
        """The partials of samples ``start + 1 .. start + m`` (a pure function, picklable).

        Exact and binned modes take their samples in order: their "partials"
        are the samples themselves. Blocked modes override this.

        Parameters
        ----------
        setup : Smoothing
            The estimate.
        X : ndarray, shape (m, d)
            Checked inputs (units of the regressor), C-contiguous float64.
        y : ndarray, shape (m,)
            Checked outputs (units of the response).
        start : int
            Global 0-based index of the chunk's first sample.
        """
        return ChunkPartials(start, X.shape[0], ({"X": X, "y": y},))

    def add_partials(self, partials: ChunkPartials) -> None:
        """Combine a chunk's partials (from :meth:`chunk_partials`), in sample order.

        ``partials.start`` must equal ``n_samples``.
        """
        self._check_start(partials)
        for blk in partials.blocks:
            self.add_chunk(blk["X"], blk["y"])

    def _check_start(self, partials: ChunkPartials) -> None:
        if partials.start != self.n_samples:
            raise self.setup.fail(
                "partials",
                f"the next chunk in order (starting at sample {self.n_samples})",
                f"a chunk starting at sample {partials.start}",
            )

    @abstractmethod
    def evaluate(self, Q: F64) -> F64:
        """The estimate ``m_n`` at the rows of ``Q`` (shape ``(m, d)``); NaN where no weight.

        Grid modes accept grid points only.
        """

    @abstractmethod
    def _arrays(self) -> State:
        """The mode's own arrays."""

    @abstractmethod
    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        """Set the mode's own arrays from :meth:`state` output."""

    def state(self) -> State:
        """Everything needed to resume: ``n_samples`` and the mode's arrays (copies)."""
        out: State = {"n_samples": np.array(self.n_samples, dtype=np.int64)}
        out.update({k: np.array(v, copy=True) for k, v in self._arrays().items()})
        return out

    @classmethod
    def from_state(cls, setup: Smoothing, state: Mapping[str, NDArray[Any]]) -> Self:
        """An accumulator resuming exactly from ``state`` (written by :meth:`state`)."""
        if "block" in state:  # the block size the sums were written with
            setup = replace(setup, block=int(state["block"]))
        acc = cls(setup)
        acc._restore(state)
        acc.n_samples = int(state["n_samples"])
        return acc


class GridAccumulator(Accumulator):
    """Sums kept at the points of a grid (grid, binned and series modes).

    Internally the grid is sorted for ``d = 1`` (binary-searched windows) and
    kept as given otherwise.
    """

    def __init__(self, setup: Smoothing) -> None:
        super().__init__(setup)
        grid = setup.grid
        assert grid is not None
        self.grid = grid
        order = np.argsort(grid[:, 0], kind="stable") if setup.d == 1 else np.arange(len(grid))
        self.inv: I64 = np.argsort(order).astype(np.int64)
        self.sorted_grid: F64 = np.ascontiguousarray(grid[order])

    @abstractmethod
    def sums(self) -> tuple[F64, F64]:
        """``N = sum Y_i w_i`` and ``D = sum w_i`` at the sorted grid points, shape (g,) each."""

    def ratio(self) -> F64:
        """``N / D`` at the sorted grid points (NaN where ``D = 0``)."""
        out: F64 = _loops.ratio(*self.sums())
        return out

    def index(self, Q: F64) -> I64:
        """Positions in the sorted grid of the rows of ``Q``; they must be grid points."""
        lookup = {tuple(row): j for j, row in enumerate(self.grid.tolist())}
        index = np.empty(Q.shape[0], dtype=np.int64)
        missing = 0
        for q, row in enumerate(Q.tolist()):
            j = lookup.get(tuple(row), -1)
            missing += j < 0
            index[q] = j
        if missing:
            raise self.setup.fail(
                "X", "points of the grid in grid mode", f"{missing} point(s) off it"
            )
        out: I64 = self.inv[index]
        return out

    def evaluate(self, Q: F64) -> F64:
        out: F64 = self.ratio()[self.index(Q)]
        return out

    def grid_sums(self) -> tuple[F64, F64]:
        """``N`` and ``D`` at the grid points in the order given, shape (g,) each."""
        num, den = self.sums()
        return num[self.inv], den[self.inv]


class BlockedAccumulator(GridAccumulator):
    """Grid accumulators whose sums run in the blocked order (grid and series modes).

    The state is two sets of arrays of the same shapes: ``total`` (the
    complete blocks, added in block order) and ``open`` (the partial of the
    open block, from 0 in sample order); see
    :mod:`~flexarm.ident.regression.accumulators.blocks`. State keys: each array under its
    name (total) and under ``"open_" + name``; ``block`` (the block size).
    """

    def __init__(self, setup: Smoothing) -> None:
        super().__init__(setup)
        self.total: dict[str, F64] = self._new_arrays()
        self.open: dict[str, F64] = zeros_like(self.total)

    @abstractmethod
    def _new_arrays(self) -> dict[str, F64]:
        """Fresh zero sums by state key."""

    @abstractmethod
    def _add_block(self, X: F64, y: F64, start: int, sums: dict[str, F64]) -> None:
        """Add samples ``start + 1 ..`` (all in one block) to ``sums``, in sample order."""

    def _add(self, X: F64, y: F64) -> None:
        for a, b, closes in segments(self.n_samples, X.shape[0], self.setup.block):
            self._add_block(X[a:b], y[a:b], self.n_samples + a, self.open)
            if closes:
                self._close()

    def _close(self) -> None:
        """The open block is complete: add it to the total, start a new one."""
        for k, v in self.open.items():
            self.total[k] += v
            v[...] = 0.0

    def current(self) -> dict[str, F64]:
        """``total + open`` by key: the sums over every sample seen."""
        return {k: v + self.open[k] for k, v in self.total.items()}

    @classmethod
    def chunk_partials(cls, setup: Smoothing, X: F64, y: F64, start: int) -> ChunkPartials:
        acc = cls(setup)
        blocks = []
        for a, b, _ in segments(start, X.shape[0], setup.block):
            part = zeros_like(acc.open)
            acc._add_block(X[a:b], y[a:b], start + a, part)
            blocks.append(part)
        return ChunkPartials(start, X.shape[0], tuple(blocks))

    def add_partials(self, partials: ChunkPartials) -> None:
        """Combine a chunk's per-block partials in order (or add its samples, if it sent them).

        Partial sums need the open block empty (``n_samples`` a multiple of the
        block size) and ``partials.start == n_samples``.
        """
        if partials.blocks and "X" in partials.blocks[0]:
            super().add_partials(partials)
            return
        self._check_start(partials)
        if self.n_samples % self.setup.block:
            raise self.setup.fail(
                "partials",
                f"added when the open block is empty (after a multiple of {self.setup.block} "
                "samples)",
                f"{self.n_samples % self.setup.block} sample(s) in the open block",
            )
        pieces = list(segments(partials.start, partials.n, self.setup.block))
        if len(pieces) != len(partials.blocks):
            raise self.setup.fail(
                "partials", f"{len(pieces)} block(s) for the chunk", f"{len(partials.blocks)}"
            )
        for (_, _, closes), blk in zip(pieces, partials.blocks, strict=True):
            for k, v in self.open.items():
                v[...] = blk[k]
            if closes:
                self._close()
        self.n_samples += partials.n

    def _arrays(self) -> State:
        out: State = {"block": np.array(self.setup.block, dtype=np.int64)}
        out.update(self.total)
        out.update({"open_" + k: v for k, v in self.open.items()})
        return out

    def _restore(self, state: Mapping[str, NDArray[Any]]) -> None:
        """Files without ``open_*`` keys (format 1) resume with their sums as the total."""
        for k, v in self.total.items():
            if k in state:
                v[...] = state[k]
            if "open_" + k in state:
                self.open[k][...] = state["open_" + k]
