"""Splitting independent compiled work over this machine's cores (threads; the loops release
the GIL).

Only work whose outputs are independent is split — the query points of exact
mode, the grid points of grid mode — so every number is computed by the same
operations in the same order as in one call: the results are the same bit for
bit with any number of threads. Calls from any thread but the main one run
serially (no pools nested in Dask's or a batch's worker threads).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

__all__ = ["MIN_WORK", "cores", "run_split", "workers"]

#: Inner-loop iterations (kernel weights) below which a thread is not worth starting.
MIN_WORK = 2**22


def cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1  # pragma: no cover - not Linux


def workers(work: float, parts: int) -> int:
    """Threads for ``work`` kernel weights split into at most ``parts`` independent pieces."""
    if threading.current_thread() is not threading.main_thread():
        return 1
    return max(1, min(cores(), parts, int(work // MIN_WORK)))


def run_split(n: int, threads: int, fn: Callable[[int, int], None]) -> None:
    """``fn(a, b)`` over ``threads`` contiguous pieces ``[a, b)`` of ``range(n)``."""
    if threads <= 1:
        fn(0, n)
        return
    edges = [n * i // threads for i in range(threads + 1)]
    with ThreadPoolExecutor(max_workers=threads) as pool:
        list(pool.map(lambda i: fn(edges[i], edges[i + 1]), range(threads)))
