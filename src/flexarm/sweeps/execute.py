"""Doing a sweep's runs on this machine: the batched simulator on every core.

:func:`iter_records` hands the runs to :func:`flexarm.sim.batch.iter_simulations`
(a pool of threads; the compiled loop releases the GIL, so the loops of
different runs share the cores) and yields each run's
:class:`~flexarm.sweeps.records.Record` as it finishes. Each run builds its own
scenario in its thread (:func:`~flexarm.sweeps.records.run_scenario`), so a bad
combination of parameters is that run's ``"error"``; at most twice as many
runs as threads are in flight, and each keeps its metrics only.

:func:`run_chunk` is the same for a list of runs at once: what a Dask worker
does with the chunk it is sent (:mod:`flexarm.sweeps.cluster`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence

from ..sim.batch import iter_simulations
from ..sim.results import SimulationResult
from .reader import Value
from .records import Record, record_of, run_scenario

__all__ = ["Item", "iter_records", "run_chunk"]

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
        In the order the runs finish (:attr:`Record.run_id` says which).
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
    order = {run_id: k for k, (run_id, _) in enumerate(items)}
    records = list(iter_records(items, workers=workers))
    return sorted(records, key=lambda rec: order[rec["run_id"]])
