"""Streaming state of the kernel regression estimates: one accumulator per mode.

The paper's recursion ``m_n = m_{n-1} + (Y_n - m_{n-1}) K_n / g_n`` holds
**per query point**, so an estimate exact at arbitrary points must keep the
samples. Each mode keeps a different state behind one interface
(:class:`~flexarm.ident.accumulators.base.Accumulator`: ``add_chunk``,
``evaluate``, ``state``, ``from_state``):

========== =========================== ==================================== ===========
mode       class                       state                                exactness
========== =========================== ==================================== ===========
exact      :class:`ExactSamples`       the samples ``(X_i, Y_i, h_i)``      exact at any point
grid       :class:`GridSums`           ``N = sum Y_i w_i``, ``D = sum w_i``  exact on the grid
                                       at the grid points
binned     :class:`BinnedSums`         binned blocks + closed-block sums    proven bound
series     :class:`SeriesMoments`      Gaussian cluster moments             to rounding
========== =========================== ==================================== ===========

:func:`choose` picks the class from the estimate's :class:`Smoothing` (the
estimators call it; a user never needs to).

Bit for bit
-----------
In the exact and grid modes the sums run over the samples in arrival order,
one addition per sample; every weight is ``scale_i * prod_j k((x_j - X_ij) /
h_ij)`` computed with the same floating-point operations
(:func:`flexarm.ident.kernels.kernel_weight`, or its scalar ``d = 1``
specialisations), and ``h_i`` is computed elementwise in a compiled scalar
loop. Hence adding chunks equals adding everything at once **bit for bit**,
and exact mode equals grid mode bit for bit at the grid points. Zero weights
may be skipped or added (either changes no sum). Binned and series modes keep
their own state in arrival order too, so chunks equal one call bit for bit
there as well; their values differ from the exact sums within their bounds.
``state`` then ``from_state`` resumes exactly: continuing gives bit for bit
what never stopping would have given.
"""

from __future__ import annotations

from .base import Accumulator, GridAccumulator, Smoothing, State
from .binned import BinnedSums
from .exact import ExactSamples
from .grid import GridSums
from .series import SeriesMoments

__all__ = [
    "Accumulator",
    "BinnedSums",
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
