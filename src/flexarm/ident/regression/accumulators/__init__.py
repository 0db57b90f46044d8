"""Streaming state of the kernel regression estimates: one accumulator per mode.

The paper's recursion ``m_n = m_{n-1} + (Y_n - m_{n-1}) K_n / g_n`` holds
**per query point**, so an estimate exact at arbitrary points must keep the
samples. Each mode keeps a different state behind one interface
(:class:`~flexarm.ident.regression.accumulators.base.Accumulator`: ``add_chunk``,
``evaluate``, ``state``, ``from_state``):

========== =========================== ==================================== ==================
mode       class                       state                                exactness
========== =========================== ==================================== ==================
exact      :class:`ExactSamples`       the samples ``(X_i, Y_i, h_i)``      exact at any point
grid       :class:`GridSums`           ``N = sum Y_i w_i``, ``D = sum w_i`` exact on the grid
                                       at the grid points (blocked)
binned     :class:`BinnedSums`         binned blocks + closed-block sums    proven bound
series     :class:`SeriesMoments`      Gaussian cluster moments, band sums  to rounding; direct
                                       (blocked)                            far from the data
========== =========================== ==================================== ==================

The interface also has :meth:`Accumulator.chunk_partials` (a chunk's partial
sums, computed anywhere) and :meth:`Accumulator.add_partials` (combined in
order). Compiled work over independent outputs (exact mode's query points,
grid mode's grid points) is split over the cores from the main thread
(``flexarm.ident.regression.accumulators._threads``; the same numbers bit for bit).

:func:`choose` picks the class from the estimate's :class:`Smoothing` (the
estimators call it; a user never needs to).

Bit for bit
-----------
In the exact, grid and series modes the sums run in the **blocked order** of
:mod:`~flexarm.ident.regression.accumulators.blocks`: blocks of ``B = 2**16`` samples
aligned to the global sample index, each summed from 0 in sample order, the
complete blocks added in block order, the open block's partial last (it is
part of the state). Every weight is ``scale_i * prod_j k((x_j - X_ij) /
h_ij)`` computed with the same floating-point operations
(:func:`flexarm.ident.regression.kernels.kernel_weight`, or its scalar ``d = 1``
specialisations), and ``h_i`` is computed elementwise in a compiled scalar
loop. Hence adding chunks equals adding everything at once **bit for bit**,
per-block partials computed anywhere (:meth:`Accumulator.chunk_partials`,
e.g. on Dask workers) and combined in order (:meth:`Accumulator.add_partials`)
equal both, and exact mode equals grid mode bit for bit at the grid points
(series off). Zero weights may be skipped or added (either changes no sum).
Binned mode keeps its own blocks (of nearly equal ``h_i``) and takes chunks in
arrival order, so chunks equal one call bit for bit there as well; binned and
series values differ from the direct sums within their bounds (series: see
:mod:`~flexarm.ident.regression.accumulators.series`). ``state`` then ``from_state``
resumes exactly: continuing gives bit for bit what never stopping would have
given. (A grid or series state written before the blocked order, without
``open_*`` arrays, resumes with its sums as the total of complete blocks: the
result then agrees with an uninterrupted fit to rounding, not bit for bit.)
"""

from __future__ import annotations

from .base import Accumulator, BlockedAccumulator, GridAccumulator, Smoothing, State
from .binned import BinnedSums
from .blocks import BLOCK, ChunkPartials
from .exact import ExactSamples
from .grid import GridSums
from .series import SeriesMoments

__all__ = [
    "BLOCK",
    "Accumulator",
    "BinnedSums",
    "BlockedAccumulator",
    "ChunkPartials",
    "ExactSamples",
    "GridAccumulator",
    "GridSums",
    "SeriesMoments",
    "Smoothing",
    "State",
    "choose",
]


def choose(setup: Smoothing) -> type[Accumulator]:
    """The accumulator class for ``setup``: exact, grid, binned or series mode.

    Exact mode without a grid (series evaluation, if asked for, happens at
    :meth:`~Accumulator.evaluate`); with a grid, binned mode if ``binned`` is
    set, series mode if ``series``, plain grid sums otherwise.
    """
    if setup.grid is None:
        return ExactSamples
    if setup.binned is not None:
        return BinnedSums
    if setup.series:
        return SeriesMoments
    return GridSums
