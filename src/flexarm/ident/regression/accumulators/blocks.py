"""Blocked summation: the order of every kernel sum, fixed by the global sample index.

Floating-point addition is not associative, so sums of chunks computed apart
and added afterwards differ from one running sum in the last bits. The grid,
series and exact modes therefore sum in a **fixed blocked order** that does
not depend on how the samples arrive:

* the samples are cut into blocks of ``B`` (:data:`BLOCK` ``= 2**16``)
  consecutive indices, aligned to the global sample index ``i`` (0-based:
  block ``b`` holds ``i`` in ``[b B, (b + 1) B)``);
* within a block, a *partial sum* starts from ``0.0`` and adds the block's
  samples in index order, one addition per sample;
* the *total* adds the partials of the complete blocks in block order
  (``T = ((0 + P_0) + P_1) + ...``), and the sums an estimate uses are
  ``T + P_open``, the open (incomplete) block's partial added last.

The open partial is part of the streaming state. Hence ``partial_fit`` with
any chunking, ``fit``, and chunk partials computed anywhere (on Dask workers,
in other processes) from chunks that start at multiples of ``B`` and are
combined in order (:meth:`~flexarm.ident.regression.accumulators.Accumulator.add_partials`)
all give the same sums bit for bit; so does exact mode's prediction, which
sums its stored samples in the same order.

:class:`ChunkPartials` carries one chunk's partials: a pure function of the
estimate's :class:`~flexarm.ident.regression.accumulators.Smoothing`, the chunk and its
global offset (:meth:`~flexarm.ident.regression.accumulators.Accumulator.chunk_partials`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["BLOCK", "ChunkPartials", "segments", "zeros_like"]

#: Samples per block of the blocked sums (aligned to the global sample index).
BLOCK = 2**16


def segments(start: int, m: int, block: int) -> Iterator[tuple[int, int, bool]]:
    """The pieces of samples ``start, …, start + m - 1`` (0-based) that lie in one block each.

    Yields ``(a, b, closes)``: offsets into the chunk (``0 <= a < b <= m``) and
    whether sample ``start + b - 1`` is the last of its block.

    >>> list(segments(5, 10, 8))
    [(0, 3, True), (3, 10, False)]
    """
    a = 0
    while a < m:
        end_of_block = (start + a) // block * block + block
        b = min(m, end_of_block - start)
        yield a, b, start + b == end_of_block
        a = b


@dataclass(frozen=True)
class ChunkPartials:
    """The partial sums of one chunk of samples, per block, ready to be combined in order.

    Attributes
    ----------
    start : int
        Global index (0-based) of the chunk's first sample; a multiple of the
        block size for the blocked modes.
    n : int
        Samples in the chunk.
    blocks : tuple of dict
        One dict of arrays per block the chunk touches, in block order: the
        block's partial sums (blocked modes), or the checked samples
        themselves (``{"X": ..., "y": ...}``: exact and binned modes, which
        take them in order).
    """

    start: int
    n: int
    blocks: tuple[dict[str, NDArray[Any]], ...]

    @property
    def nbytes(self) -> int:
        """Memory held by the partials, bytes."""
        return int(sum(a.nbytes for b in self.blocks for a in b.values()))


def zeros_like(arrays: dict[str, NDArray[np.float64]]) -> dict[str, NDArray[np.float64]]:
    """Fresh zero arrays of the same shapes (an empty open block)."""
    return {k: np.zeros_like(v) for k, v in arrays.items()}
