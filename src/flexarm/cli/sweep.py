"""``flexarm sweep``: a grid or Monte Carlo over scenario parameters, one table of runs."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InvalidTypeError, InvalidValueError
from ._common import EXIT_FAILURE, UsageError

if TYPE_CHECKING:
    from ..sweeps.spec import SweepSpec
    from ..sweeps.table import SweepTable

__all__ = ["EXIT_INTERRUPTED", "add_parser"]

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports Ctrl-C
_PROG = "flexarm sweep"


def _positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be an integer >= 1. Got {text!r} instead."
        ) from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1. Got {text!r} instead.")
    return value


def _shape(spec: SweepSpec) -> str:
    """``grid 2 x 3, monte_carlo n = 100``."""
    parts = [
        ("grid " if len(spec.grids) == 1 else f"grid[{k}] ")
        + " x ".join(str(len(values)) for _, values in grid.axes)
        for k, grid in enumerate(spec.grids)
    ]
    if spec.monte_carlo is not None:
        parts.append(f"monte_carlo n = {spec.monte_carlo.n}")
    return ", ".join(parts)


def _format_row(row: dict[str, Any], table: SweepTable, metric: str) -> str:
    params = ", ".join(
        f"{k} = {row[k]:.6g}" if isinstance(row[k], float) else f"{k} = {row[k]}"
        for k in table.parameters
    )
    return f"{metric} {row[metric]:.6g}: run {row['run']} ({params})"


def _format_summary(summary: dict[str, Any], spec: SweepSpec, table: SweepTable) -> str:
    s = summary
    kind = "process(es)" if s["processes"] else "thread(s)"
    where = f"on {s['scheduler']}" if s["scheduler"] else f"on {s['workers']} {kind}"
    lines = [
        f"{_PROG}: {s['runs']} runs of {spec.source} ({_shape(spec)}) in "
        f"{s['wall_time_s']:.3g} s {where}",
        f"  ok {s['ok']}, diverged {s['diverged']}, error {s['error']}; "
        f"{s['resumed']} done before (from the journal)",
    ]
    metric = s["ranked_by"]
    for label, key in (("best ", "best"), ("worst", "worst")):
        row = table.best(metric, largest=key == "worst") if metric else None
        if row is not None:
            lines.append(f"  {label} {_format_row(row, table, metric)}")
    files = s["files"]
    lines.append(f"  table in {s['out']}: {', '.join(f for f in files if f.startswith('runs'))}")
    return "\n".join(lines)


def _cmd_sweep(args: argparse.Namespace) -> int:
    try:
        return _run(args)
    except KeyboardInterrupt as exc:  # before or after the runs (during them: below)
        from ..errors import SweepInterrupted

        if isinstance(exc, SweepInterrupted) and exc.journal is not None:
            print(
                f"{_PROG}: interrupted: {exc.finished} of {exc.total} runs done, kept in "
                f"{exc.journal}; run the same command again to resume",
                file=sys.stderr,
            )
        else:
            print(f"{_PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _run(args: argparse.Namespace) -> int:
    from ..errors import ClusterError, OutputDirectoryError
    from ..sweeps.cluster import connect
    from ..sweeps.driver import summary, sweep
    from ..sweeps.journal import check_output_directory
    from ..sweeps.spec import load_sweep
    from ..sweeps.table import PARQUET_EXTRA, have_pyarrow

    try:
        spec = load_sweep(args.sweep)
    except (InvalidValueError, InvalidTypeError) as exc:
        raise UsageError(f"{_PROG}: error: {exc}") from None
    stem = Path(args.sweep).stem
    out = Path(os.path.abspath(args.out if args.out is not None else f"sweep_{stem}"))
    try:
        check_output_directory(out)
    except OutputDirectoryError as exc:
        raise UsageError(f"{_PROG}: error: argument --out: {exc}") from None
    parquet = {None: None, "csv": False, "parquet": True}[args.format]
    if parquet and not have_pyarrow():
        raise UsageError(
            f"{_PROG}: error: argument --format: parquet needs pyarrow, which is not "
            f"installed: {PARQUET_EXTRA}"
        )
    if args.processes and args.scheduler is not None:
        raise UsageError(
            f"{_PROG}: error: argument --processes: not with --scheduler (a Dask cluster "
            "has its own processes)"
        )
    client = None
    if args.scheduler is not None:
        try:
            client = connect(args.scheduler)
        except InvalidValueError as exc:
            raise UsageError(f"{_PROG}: error: argument --scheduler: {exc}") from None
    try:
        table = sweep(
            spec,
            out=out,
            workers=args.workers,
            client=client,
            chunk_size=args.chunk_size,
            processes=args.processes,
            parquet=parquet,
            progress=None if not args.json else False,
        )
    except (InvalidValueError, InvalidTypeError) as exc:  # checked before anything is written
        raise UsageError(f"{_PROG}: error: {exc}") from None
    except ClusterError as exc:
        print(f"{_PROG}: error: {exc}; the runs done are kept in {out}", file=sys.stderr)
        return EXIT_FAILURE
    except OSError as exc:
        print(f"{_PROG}: error: cannot write {str(out)!r}: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    finally:
        if client is not None:
            client.close()
    result = summary(table)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(_format_summary(result, spec, table))
    return 0


_DESCRIPTION = """\
Run a grid or Monte Carlo sweep over any scenario parameter and write one table of
runs (one row per run: its parameters, status and metrics). SWEEP.toml gives the
base scenario (base = "file.toml", or [base] with the scenario's sections), a [grid]
(key = [values]: every combination; [[grid]] for several) and/or a [monte_carlo]
(n, seed, key = { distribution = "uniform" | "loguniform" | "normal" | "integers" |
"choice", ... }), and optionally [sweep] metrics = [...]. Keys are dotted keys into
the scenario ("sensor.noise_std", "controller.zeta", "arm.links[1].length"). Example:
examples/sweep_noise.toml; schema in flexarm.sweeps.spec.
"""

_EPILOG = """\
runs: on every core of this machine by default, in worker processes forked from this
one on Linux (a run's Python set-up holds the GIL; --threads keeps them in threads,
whose compiled loops release it; same numbers); --scheduler tcp://HOST:8786 sends
chunks of runs to a Dask cluster (pip install 'flexarm[dask]'; see
flexarm.sweeps.cluster for SLURM and the pitfalls).
A run that diverges or cannot be built is recorded (status diverged or error, with
the message) and the sweep goes on.

output: DIR (default ./sweep_NAME for SWEEP NAME.toml) must be new, empty, or the
directory of an earlier sweep: then the runs its journal holds are not done again
(resume after Ctrl-C, or grow a sweep). It receives sweep.json (the runs) at once,
journal.jsonl as runs finish, and at the end runs.csv, runs.parquet (with pyarrow;
--format csv: CSV only, --format parquet: required) and summary.json (what --json
prints).

exit status: 0 the sweep ran (whatever its runs' statuses); 1 the results could not
be written or a Dask task failed; 2 bad input (one line on stderr, nothing written);
130 interrupted (the journal keeps the runs done; run the same command to resume).
"""


def add_parser(sub: Any) -> None:
    """Add ``sweep`` to the subcommands ``sub``."""
    summary = "a grid or Monte Carlo over scenario parameters: one table of runs"
    p = sub.add_parser("sweep", help=summary, description=_DESCRIPTION, epilog=_EPILOG)
    p.add_argument("sweep", metavar="SWEEP.toml", help="the sweep file (TOML)")
    p.add_argument("--out", metavar="DIR", help="output directory (default ./sweep_NAME)")
    p.add_argument(
        "--workers",
        type=_positive,
        metavar="N",
        help="processes or threads on this machine (default: every core); with "
        "--scheduler, threads per task on its worker (default 1)",
    )
    mode = p.add_mutually_exclusive_group()
    mode.add_argument(
        "--processes",
        action="store_const",
        const=True,
        dest="processes",
        help="run in worker processes forked from this one (the default on Linux for "
        "more than one run and worker: a run's Python set-up holds the GIL)",
    )
    mode.add_argument(
        "--threads",
        action="store_const",
        const=False,
        dest="processes",
        help="run in threads of this process (the default where processes cannot be "
        "forked; same numbers)",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on the Dask cluster of this scheduler (tcp://HOST:8786)",
    )
    p.add_argument(
        "--chunk-size",
        type=_positive,
        metavar="N",
        help="runs per Dask task (default: about four tasks per worker thread)",
    )
    p.add_argument(
        "--format",
        choices=("csv", "parquet"),
        help="csv: runs.csv only; parquet: runs.csv and runs.parquet (needs pyarrow); "
        "default: both when pyarrow is installed",
    )
    p.add_argument("--json", action="store_true", help="print the JSON summary on stdout")
    p.set_defaults(func=_cmd_sweep)
