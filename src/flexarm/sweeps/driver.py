"""``flexarm.sweep``: a sweep from its file to its table, on this machine or a cluster.

:func:`sweep` reads and checks the sweep (:mod:`~flexarm.sweeps.spec`), builds
the base scenario and the first run of each grid to refuse a mistyped key
before anything runs, skips the runs its output directory's journal already
holds (:mod:`~flexarm.sweeps.journal`), does the others on every core
(:mod:`~flexarm.sweeps.execute`) or on a Dask cluster
(:mod:`~flexarm.sweeps.cluster`), appending each to the journal as it finishes,
and returns the table (:class:`~flexarm.sweeps.table.SweepTable`), written as
``runs.csv`` (and ``runs.parquet``) with ``summary.json`` beside the journal.

Examples
--------
>>> table = sweep({"base": {"simulation": {"duration": 0.02}},
...                "grid": {"controller.zeta": [0.5, 0.7]}}, workers=2, progress=False)
>>> table["controller.zeta"].tolist(), table["status"].tolist()
([0.5, 0.7], ['ok', 'ok'])
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from .._io import JSONValue, json_ready
from .._validation import check_bool, check_int
from .._version import __version__
from ..errors import InvalidValueError, SweepError, SweepInterrupted
from ..sim.batch import default_workers
from .cluster import iter_cluster_records
from .execute import Item, iter_process_records, iter_records, prefer_processes
from .journal import (
    JOURNAL_FILE,
    SWEEP_FILE,
    Journal,
    check_output_directory,
    write_json,
)
from .records import RUN_SOURCE, Record
from .spec import SweepSpec, load_sweep
from .table import PARQUET_EXTRA, SweepTable, have_pyarrow

if TYPE_CHECKING:
    from distributed import Client

__all__ = [
    "CSV_FILE",
    "PARQUET_FILE",
    "SUMMARY_FILE",
    "SweepInterrupted",
    "check_runs",
    "summary",
    "sweep",
]

CSV_FILE = "runs.csv"
PARQUET_FILE = "runs.parquet"
SUMMARY_FILE = "summary.json"
_OWNER = "sweep"


def sweep(
    spec: SweepSpec | Mapping[str, object] | str | os.PathLike[str],
    *,
    out: str | os.PathLike[str] | None = None,
    workers: int | None = None,
    client: Client | None = None,
    chunk_size: int | None = None,
    processes: bool | None = None,
    parquet: bool | None = None,
    progress: bool | None = None,
) -> SweepTable:
    """Run a grid or Monte Carlo sweep over scenario parameters; return its table.

    Parameters
    ----------
    spec : SweepSpec, mapping or path
        The sweep: a :class:`~flexarm.sweeps.spec.SweepSpec`, a mapping with the
        schema of a sweep file, or a sweep file (TOML; module docstring of
        :mod:`flexarm.sweeps.spec`).
    out : path, optional
        Output directory: new, empty, or one an earlier sweep wrote (its
        journal's runs are not done again). It receives ``sweep.json`` at once,
        ``journal.jsonl`` as runs finish, and ``runs.csv``, ``runs.parquet`` and
        ``summary.json`` at the end. None: nothing is written and an
        interrupted sweep cannot resume.
    workers : int, optional
        Threads (or processes) on this machine (default: every core this process
        may use). With ``client``: the threads each task uses on its worker
        (default 1).
    client : distributed.Client, optional
        Run on this Dask cluster instead of this machine
        (:mod:`flexarm.sweeps.cluster`).
    chunk_size : int, optional
        Runs per Dask task (default: about four tasks per worker thread) or per
        chunk of a process (default: the same, at most 16).
    processes : bool, optional
        Run in worker processes forked from this one
        (:func:`~flexarm.sweeps.execute.iter_process_records`) rather than in
        threads (:func:`~flexarm.sweeps.execute.iter_records`). Default (None):
        processes where the platform forks (Linux) and the sweep has more than one
        run and one worker, threads otherwise
        (:func:`~flexarm.sweeps.execute.prefer_processes`). A run's set-up holds
        the GIL, so threads share one interpreter for that part; processes do not.
        The numbers are the same either way.
    parquet : bool, optional
        Also write ``runs.parquet``: None (default) when pyarrow is installed,
        True always (an error without pyarrow), False never.
    progress : bool, optional
        A progress bar on stderr (default: when stderr is a terminal).

    Returns
    -------
    SweepTable
        One row per run in sweep order; ``SweepTable.info`` says how it ran.

    Raises
    ------
    SweepError, SweepTypeError
        A sweep file or mapping that cannot be run (nothing is written).
    InvalidValueError
        A bad argument, an ``out`` that cannot take the results, Parquet asked
        for without pyarrow (nothing is written).
    SweepInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``): the journal holds the finished runs.
    ClusterError
        If a Dask task fails.
    """
    if not isinstance(spec, SweepSpec):
        spec = (
            load_sweep(spec) if isinstance(spec, str | os.PathLike) else SweepSpec.from_dict(spec)
        )
    if workers is not None:
        check_int(workers, "workers", _OWNER, minimum=1)
    if chunk_size is not None:
        check_int(chunk_size, "chunk_size", _OWNER, minimum=1)
    check_bool(processes, "processes", _OWNER, optional=True)
    if processes and client is not None:
        raise InvalidValueError(
            "The 'processes' parameter of sweep must be False with a 'client' (a Dask "
            "cluster has its own processes). Got True instead."
        )
    if parquet is None:
        parquet = have_pyarrow()
    elif parquet and not have_pyarrow():
        raise InvalidValueError(
            f"Parquet files need pyarrow, which is not installed: {PARQUET_EXTRA}"
        )
    runs = spec.runs
    check_runs(spec)
    out_dir = Path(os.path.abspath(out)) if out is not None else None
    if out_dir is not None:
        check_output_directory(out_dir)
    start = time.perf_counter()
    unique = list({run.run_id: run for run in runs}.values())
    records: dict[str, Record] = {}
    journal = None
    if out_dir is not None:
        out_dir.mkdir(exist_ok=True)
        write_json(out_dir / SWEEP_FILE, _description(spec))
        journal = Journal(out_dir / JOURNAL_FILE)
        known = journal.read()
        records = {run.run_id: known[run.run_id] for run in unique if run.run_id in known}
    resumed = len(records)
    todo = [r for r in unique if r.run_id not in records]
    bar = _Progress(len(unique), resumed, sys.stderr.isatty() if progress is None else progress)
    items: Iterator[Item] = ((r.run_id, spec.scenario(r.params)) for r in todo)
    if processes is None:
        processes = client is None and prefer_processes(len(todo), workers or default_workers())
    if client is not None:
        stream: Iterator[Record] = iter_cluster_records(
            list(items), client, chunk_size=chunk_size, workers=workers or 1
        )
    elif processes:
        stream = iter_process_records(list(items), workers=workers, chunk_size=chunk_size)
    else:
        stream = iter_records(items, workers=workers)
    try:
        for record in stream:
            if journal is not None:
                journal.append(record)
            records[record["run_id"]] = record
            bar.update(record["status"])
    except KeyboardInterrupt:
        path = None if out_dir is None else out_dir / JOURNAL_FILE
        raise SweepInterrupted(len(records), len(unique), path) from None
    finally:
        try:
            close = getattr(stream, "close", None)
            if close is not None:
                close()  # the runs in flight finish; their results are dropped
        finally:
            bar.close()
            if journal is not None:
                journal.close()
    info: dict[str, JSONValue] = {
        "source": spec.source,
        "runs": len(runs),
        "distinct_runs": len(unique),
        "resumed": resumed,
        "wall_time_s": time.perf_counter() - start,
        "workers": (workers or 1) if client is not None else (workers or default_workers()),
        "processes": processes,
        "scheduler": None if client is None else _address(client),
        "out": None if out_dir is None else str(out_dir),
        "files": [],
        "flexarm": __version__,
    }
    table = SweepTable.from_records(runs, records, spec.parameters, spec.metrics, info)
    if out_dir is not None:
        files = [
            SWEEP_FILE,
            JOURNAL_FILE,
            CSV_FILE,
            *([PARQUET_FILE] if parquet else []),
            SUMMARY_FILE,
        ]
        table.info["files"] = list(files)
        table.write_csv(out_dir / CSV_FILE)
        if parquet:
            table.write_parquet(out_dir / PARQUET_FILE)
        write_json(out_dir / SUMMARY_FILE, summary(table))
    return table


def check_runs(spec: SweepSpec) -> None:
    """Refuse a sweep whose base scenario cannot be built, or that sets a key the
    scenario does not know, before any run.

    Builds the base scenario and the first run of each grid (of the draws,
    without a grid). A rejected *value* in those runs is not an error of the
    sweep: that run is recorded as ``"error"`` like any other bad combination.

    Raises
    ------
    SweepError
        ``base: ...`` for a base scenario that cannot be built; ``grid: unknown
        key ...`` (or ``monte_carlo: ...``) for a swept key the scenario does not
        take (a key that only some kinds take: sweep it in a ``[[grid]]`` of its
        own with those kinds).
    """
    from ..errors import ScenarioError
    from ..sim.scenario import Scenario

    def reason(exc: ScenarioError) -> str:
        text = str(exc)
        return text[len(exc.source) + 2 :] if text.startswith(f"{exc.source}: ") else text

    try:
        Scenario.from_dict(spec.base, source=RUN_SOURCE)
    except ScenarioError as exc:
        raise SweepError(spec.source, "base", reason(exc)) from None
    for index in spec.first_runs:
        params = spec.runs[index].params
        try:
            Scenario.from_dict(spec.scenario(params), source=RUN_SOURCE)
        except ScenarioError as exc:
            if not exc.reason.startswith("unknown") or exc.key is None:
                continue  # a value: that run's error, recorded with it
            for key in params:
                if exc.key == key or exc.key.startswith((f"{key}.", f"{key}[")):
                    raise SweepError(spec.source, spec.axis(key), reason(exc)) from None
        except Exception:  # any other failure is the run's, recorded with it
            continue


def summary(table: SweepTable) -> dict[str, JSONValue]:
    """What ``flexarm sweep --json`` prints and ``summary.json`` holds: counts, wall
    time, the best and worst ``ok`` runs by RMS error, the files."""

    def pick(row: Mapping[str, object] | None) -> JSONValue:
        if row is None:
            return None
        keep = ("run", "run_id", *table.parameters, "rms_error_m", "max_error_m")
        ready: JSONValue = json_ready({k: row[k] for k in keep if k in row})
        return ready

    rank = "rms_error_m" if "rms_error_m" in table.metrics else (table.metrics or (None,))[0]
    best = table.best(rank) if rank else None
    worst = table.best(rank, largest=True) if rank else None
    result: dict[str, JSONValue] = {
        **{k: v for k, v in table.info.items()},
        "rows": len(table),
        **{k: v for k, v in table.counts().items()},
        "parameters": list(table.parameters),
        "metrics": list(table.metrics),
        "ranked_by": rank,
        "best": pick(best),
        "worst": pick(worst),
    }
    ready: dict[str, JSONValue] = json_ready(result)
    return ready


def _address(client: Client) -> str | None:
    address = getattr(getattr(client, "scheduler", None), "address", None)
    return None if address is None else str(address)


def _description(spec: SweepSpec) -> dict[str, JSONValue]:
    """``sweep.json``: enough to redo any row (the base scenario and each run's values)."""
    runs: list[JSONValue] = [
        {"run": r.index, "run_id": r.run_id, "params": r.params}  # type: ignore[dict-item]
        for r in spec.runs
    ]
    return {
        "flexarm": __version__,
        "source": spec.source,
        "base": spec.base,  # type: ignore[dict-item]
        "parameters": list(spec.parameters),
        "metrics": list(spec.metrics),
        "runs": runs,
    }


class _Progress:
    """``sweep [#####.....] 37/100  ok 35  diverged 1  error 1`` on stderr."""

    def __init__(self, total: int, done: int, show: bool):
        self.total, self.done, self.show = total, done, show
        self.counts = {"ok": 0, "diverged": 0, "error": 0}
        self.last = 0.0
        if show:
            self._draw()

    def update(self, status: str) -> None:
        self.done += 1
        self.counts[status] = self.counts.get(status, 0) + 1
        now = time.monotonic()
        if self.show and (now - self.last > 0.1 or self.done == self.total):
            self.last = now
            self._draw()

    def _draw(self) -> None:
        width = 30
        filled = round(width * self.done / self.total) if self.total else width
        counts = "  ".join(f"{k} {v}" for k, v in self.counts.items())
        sys.stderr.write(
            f"\rsweep [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total}  {counts}"
        )
        sys.stderr.flush()

    def close(self) -> None:
        if self.show:
            self._draw()
            sys.stderr.write("\n")
            sys.stderr.flush()
