"""Driving a compiled loop from Python in chunks, with a progress bar and a stop flag.

:func:`run_in_chunks` calls a compiled loop over consecutive ranges of control
instants (one range, or fifty with a progress bar on stderr), checks a stop flag
between them and stops at the first divergence. The closed loop, the open loop
and prescribed motion all run this way.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Protocol

import numpy as np

from ..errors import Cancelled

__all__ = ["DIVERGED", "OK", "Chunk", "StopFlag", "run_in_chunks"]

OK, DIVERGED = 0, 1
"""Status of a chunk: done, or the state diverged (a loop may have codes of its own)."""

Chunk = Callable[[int, int], tuple[int, int]]
"""``chunk(k0, k1) -> (status, k)``: advance a compiled loop over ``k0 <= k < k1``."""


class StopFlag(Protocol):
    """What stops a run between chunks: a :class:`threading.Event` or alike."""

    def is_set(self) -> bool: ...


def run_in_chunks(
    chunk: Chunk,
    n_rows: int,
    work: float,
    progress: bool | None,
    *,
    block: int | None = None,
    stop: StopFlag | None = None,
) -> tuple[int, int]:
    """Run ``chunk`` over ``0 <= k < n_rows``; return ``(status, last row written)``.

    Parameters
    ----------
    chunk : callable
        ``chunk(k0, k1) -> (status, k)`` (status 0: done; else diverged at ``k``).
    n_rows : int
        Rows (control instants) in all.
    work : float
        A size of the run (rows x substeps x coordinates) for the default of
        ``progress``.
    progress : bool or None
        Show a progress bar on stderr; default: when stderr is a terminal and the
        run is long (``work > 5e6``).
    block : int, optional
        Run in chunks of ``block`` rows starting at its multiples (the progress
        bar then moves once a chunk). Default: one chunk, or fifty with a
        progress bar.
    stop : threading.Event or alike, optional
        Checked before every chunk: once set, the run ends with
        :class:`~flexarm.errors.Cancelled`.

    Raises
    ------
    Cancelled
        If ``stop`` was set.
    """
    show = sys.stderr.isatty() and work > 5e6 if progress is None else bool(progress)
    if block is not None:
        bounds = np.r_[np.arange(0, n_rows, block), n_rows]
    else:
        bounds = np.linspace(0, n_rows, (50 if show else 1) + 1).astype(int)
    n_chunks = bounds.shape[0] - 1
    status, k = OK, 0
    for c in range(n_chunks):
        k0, k1 = int(bounds[c]), int(bounds[c + 1])
        if k1 <= k0:
            continue
        if stop is not None and stop.is_set():
            if show:
                sys.stderr.write("\n")
            raise Cancelled("the run was stopped before its end (its stop flag was set)")
        status, k = chunk(k0, k1)
        if show:
            _progress_bar((c + 1) / n_chunks)
        if status != OK:
            break
    if show:
        sys.stderr.write("\n")
    return int(status), min(int(k), n_rows - 1)


def _progress_bar(fraction: float) -> None:
    width = 40
    filled = round(width * fraction)
    sys.stderr.write(f"\rsimulating [{'#' * filled}{'.' * (width - filled)}] {fraction:5.1%}")
    sys.stderr.flush()
