"""``flexarm calibrate``: fit an arm's parameters to measured records, judge the fit."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

from ..errors import InvalidTypeError, InvalidValueError
from ._common import (
    EXIT_FAILURE,
    UsageError,
    add_figure_options,
    check_out,
    figure_format,
    number,
    write_failed,
)

__all__ = ["add_parser"]

_PROG = "flexarm calibrate"

_EPILOG = """\
the file: [calibration] settings, the arm ([arm], the scenario file's tables), its
[[drives]] and its instruments ([outputs.NAME]), the [[parameters]] to fit (a dotted
key into those tables, bounds, an initial value, scale = true for a factor) and the
[[records]] (a file and how its columns map to inputs and outputs, with units; role
"training" or "validation"): the user guide's calibration page, or
the files in examples/quanser_2dsfl.

output: the fitted values with 95 % confidence intervals and each record's fit (fit % =
100 (1 - norm(y - yhat) / norm(y - mean y))) per channel, before and after. --json prints
{"parameters": {name: {"value", "ci95", ...}}, "training": [...], "validation":
[{"file", "channels": {name: {"fit_percent", "rms"}}}], ...}. --out DIR (new, or an
empty directory) receives summary.json (what --json prints), calibrated.toml (the
arm's tables with the fitted values), a figure per record (measured and predicted)
and report.html, all at once.

exit status: 0 done; 1 the results could not be written; 2 bad input (one line on
stderr, naming the file and the key).
"""


def add_parser(sub: Any) -> None:
    """Add ``calibrate`` to the subcommands ``sub``."""
    summary = "fit an arm's parameters to measured records"
    description = (
        "Calibrate an arm on measured runs: fit the parameters a calibration file "
        "names by least squares on the free-run prediction of its training records, "
        "and predict its validation records with the fitted arm."
    )
    p = sub.add_parser("calibrate", help=summary, description=description, epilog=_EPILOG)
    p.add_argument("config", metavar="CONFIG.toml", help="the calibration file")
    p.add_argument(
        "--data",
        metavar="DIR",
        help="read the records from DIR (default: the file's [calibration] data)",
    )
    p.add_argument(
        "--validate",
        nargs="+",
        metavar="FILE",
        default=[],
        help="predict further files in the format of the file's first record with the "
        "fitted arm (reported as validation)",
    )
    p.add_argument(
        "--workers",
        type=number(integer=True, minimum=1),
        help="threads for the least squares' Jacobian (default: every core)",
    )
    p.add_argument("--out", metavar="DIR", help="write the results into DIR (see below)")
    add_figure_options(p)
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    p.set_defaults(func=_cmd_calibrate)


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from ..calibration.config import load_config
    from ..calibration.result import calibrate

    out = Path(os.path.abspath(args.out)) if args.out is not None else None
    if out is not None:
        check_out(out, _PROG)
    fmt = figure_format(args, _PROG, out)
    for path in args.validate:
        if not Path(path).is_file():
            raise UsageError(f"{_PROG}: error: argument --validate: no such file: {path!r}")
    try:
        config = load_config(args.config)
        if args.data is not None:
            if not Path(args.data).is_dir():
                raise UsageError(
                    f"{_PROG}: error: argument --data: no such directory: {args.data!r}"
                )
            config = config.with_data(args.data)
        progress = None if args.json else (lambda text: print(f"{_PROG}: {text}", file=sys.stderr))
        result = calibrate(config, workers=args.workers, progress=progress)
        extra = result.validate(args.validate) if args.validate else []
    except (InvalidValueError, InvalidTypeError) as exc:
        raise UsageError(f"{_PROG}: error: {exc}") from None
    result.records.extend(extra)
    if out is not None:
        try:
            result.write(out, figure_format=fmt)
        except OSError as exc:
            print(write_failed(_PROG, out, exc), file=sys.stderr)
            return EXIT_FAILURE
    if args.json:
        print(json.dumps(result.summary(), indent=2))
    else:
        print(result.text())
        if out is not None:
            print(f"results in {out}")
    return 0
