"""Doing a sweep's runs on this machine: the batched simulator on every core.

:func:`iter_records` hands the runs to :func:`flexarm.sim.batch.iter_simulations`
(a pool of threads; the compiled loop releases the GIL, so the loops of
different runs share the cores) and yields each run's
:class:`~flexarm.sweeps.records.Record` as it finishes. Each run builds its own
scenario in its thread (:func:`~flexarm.sweeps.records.run_scenario`), so a bad
combination of parameters is that run's ``"error"``; at most twice as many
runs as threads are in flight, and each keeps its metrics only.

:func:`run_chunk` is the same for a list of runs at once: what a Dask worker
does with the chunk it is sent (:mod:`flexarm.sweeps.cluster`), and what each
process does with its chunks in :func:`iter_process_records`.

Threads or processes: a run's compiled loop releases the GIL, but its set-up
(building the scenario, the sampled-data check, the metrics) is Python and holds
it. For short runs the set-up is a large share (about 60 % of a 2 s run of the
paper's scenario), and threads then share one GIL much of the time;
:func:`iter_process_records` runs chunks in worker processes forked from this
one instead (each inherits the loaded simulator; no GIL is shared). Sweeps take
processes by default where they can be forked (:func:`prefer_processes`). The
numbers are the same bit for bit either way.
"""

from __future__ import annotations

import functools
import math
import multiprocessing
import signal
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait

from ..sim.batch import default_workers, iter_simulations
from ..sim.results import SimulationResult
from .reader import Value
from .records import Record, record_of, run_scenario

__all__ = [
    "Item",
    "default_chunk_size",
    "iter_process_records",
    "iter_records",
    "prefer_processes",
    "run_chunk",
]

Item = tuple[str, Mapping[str, Value]]
"""One run to do: its id and its full scenario mapping (plain data: it pickles)."""


def iter_records(items: Iterable[Item], *, workers: int | None = None) -> Iterator[Record]:
    """Do the runs ``items`` on ``workers`` threads; yield each record as it finishes.

    Parameters
    ----------
    items : iterable of (str, mapping)
        Run ids and scenario mappings, consumed lazily.
    workers : int, optional
        Threads (default: every core this process may use).

    Yields
    ------
    Record
        In the order the runs finish (``Record.run_id`` says which).
    """
    ids: list[str] = []

    def calls() -> Iterator[Callable[[], SimulationResult]]:
        for run_id, scenario in items:
            ids.append(run_id)
            yield functools.partial(run_scenario, scenario)

    for index, outcome in iter_simulations(
        calls(), workers=workers, errors="return", progress=False
    ):
        yield record_of(ids[index], outcome)


def run_chunk(items: Sequence[Item], workers: int = 1) -> list[Record]:
    """Do the runs ``items`` (on ``workers`` threads) and return their records in order.

    What each Dask task runs: the chunk arrives as plain data (ids and scenario
    mappings), the worker builds and simulates each run with its own copy of
    flexarm and its Numba cache, and only the records travel back.
    """
    if workers == 1:  # in this thread, one after another: no pool to hand runs to
        from threadpoolctl import threadpool_limits

        records = []
        with threadpool_limits(limits=1, user_api="blas"):  # as the batched simulator
            for run_id, scenario in items:
                try:
                    outcome: SimulationResult | Exception = run_scenario(scenario)
                except Exception as exc:  # the run's failure is its record
                    outcome = exc
                records.append(record_of(run_id, outcome))
        return records
    order = {run_id: k for k, (run_id, _) in enumerate(items)}
    records = list(iter_records(items, workers=workers))
    return sorted(records, key=lambda rec: order[rec["run_id"]])


def default_chunk_size(n_runs: int, workers: int, at_most: int | None = None) -> int:
    """About four chunks per worker, at least one run each (and ``at_most``).

    Examples
    --------
    >>> default_chunk_size(1000, 2), default_chunk_size(3, 8), default_chunk_size(1000, 2, 16)
    (125, 1, 16)
    """
    size = max(1, math.ceil(n_runs / (4 * max(1, workers))))
    return size if at_most is None else min(size, at_most)


def prefer_processes(n_runs: int, workers: int) -> bool:
    """Whether a local sweep of ``n_runs`` runs on ``workers`` workers runs in processes
    by default: where processes can be forked from this one (Linux: they start with
    the simulator loaded, in milliseconds) and there is more than one run and one
    worker to share. Elsewhere processes would be spawned (a fresh interpreter
    that imports and loads everything, and a script needs the ``__main__`` guard),
    so threads are the default there."""
    return sys.platform.startswith("linux") and n_runs > 1 and workers > 1


def _ignore_sigint() -> None:
    """In a worker process: Ctrl-C is for the parent, which stops the sweep."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def iter_process_records(
    items: Sequence[Item], *, workers: int | None = None, chunk_size: int | None = None
) -> Iterator[Record]:
    """Do the runs ``items`` in ``workers`` processes; yield records as chunks finish.

    The processes are forked from this one where the platform allows it (Linux),
    so each starts with flexarm and its compiled functions loaded; elsewhere they
    are spawned (then the script that calls this needs the
    ``if __name__ == "__main__":`` guard). At most two chunks per process are in
    flight; on Ctrl-C the chunks under way finish and no other starts.

    Parameters
    ----------
    items : sequence of (str, mapping)
        Run ids and scenario mappings.
    workers : int, optional
        Processes (default: every core this process may use).
    chunk_size : int, optional
        Runs per chunk (default: about four chunks per process, at most 16 runs,
        so that the journal and the progress bar advance often).
    """
    n = default_workers() if workers is None else workers
    size = chunk_size or default_chunk_size(len(items), n, at_most=16)
    method = "fork" if sys.platform.startswith("linux") else "spawn"
    context = multiprocessing.get_context(method)
    chunks = iter([list(items[i : i + size]) for i in range(0, len(items), size)])
    pool = ProcessPoolExecutor(max_workers=n, mp_context=context, initializer=_ignore_sigint)
    pending: set[Future[list[Record]]] = set()
    try:
        while True:
            while len(pending) < 2 * n:
                chunk = next(chunks, None)
                if chunk is None:
                    break
                pending.add(pool.submit(run_chunk, chunk))
            if not pending:
                break
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                yield from future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
