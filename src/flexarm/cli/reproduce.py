"""``flexarm reproduce``: the paper's experiments, a report and a verdict on each claim."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

from ..errors import InvalidTypeError, InvalidValueError
from ..studies.reproduction.cases import (
    ADAPTATION_LAWS,
    DEFAULT_DT,
    DEFAULT_KS,
    DEFAULT_KS_RANGE,
    DEFAULT_LAW,
    DEFAULT_TOLERANCE,
)
from ._common import (
    EXIT_FAILURE,
    UsageError,
    add_figure_options,
    check_out,
    figure_format,
    write_failed,
)

__all__ = ["add_parser"]

_PROG = "flexarm reproduce"


def _ks_list(text: str) -> tuple[float, ...]:
    fail = argparse.ArgumentTypeError(
        f"must be comma-separated finite numbers >= 0. Got {text!r} instead."
    )
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise fail from None
    if not values or not all(math.isfinite(v) and v >= 0 for v in values):
        raise fail
    return values


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from ..studies.reproduction import reproduce  # the simulator: loaded only to run

    out = Path(os.path.abspath(args.out))
    check_out(out, _PROG)
    fmt = figure_format(args, _PROG)
    try:
        rep = reproduce(
            duration=args.duration,
            dt=args.dt,
            ks=args.ks,
            law=args.law,
            ks_range=args.ks_range,
            sensitivity=args.sensitivity,
            beyond=args.beyond,
            converged=args.converged,
            tolerance=args.tolerance,
            workers=args.workers,
            progress=None if not args.json else False,
        )
    except (InvalidTypeError, InvalidValueError) as exc:
        raise UsageError(f"{_PROG}: error: {exc}") from None
    try:
        files = rep.write(out, figure_format=fmt)
    except OSError as exc:
        print(write_failed(_PROG, out, exc), file=sys.stderr)
        return EXIT_FAILURE
    if args.json:
        print(json.dumps({**rep.summary(), "out": str(out), "files": files}, indent=2))
    else:
        print(f"{_PROG}: {rep.text()}\n  report in {out / 'report.html'}")
    return 0


_DESCRIPTION = """\
Run the paper's experiments: {pd (nonadaptive JT-PD), fuzzy (adaptive)} x {joint sensor,
end-effector sensor, sensor 0.5 m from the elbow} on the default square, with the
paper's sensor model (rigid kinematics of the joint angles through a 2nd-order Pade
delay, as the paper simulated it) and with the physical one (the deflected point); a
sensitivity study (the paper's model under each delay model: none, the seed's wave
speed, the dispersive bending-wave speed; the fuzzy law over a range of ks and both
adaptation laws); and, beyond the paper, flexarm's LQG and reflected-tip laws on the
physical distant sensors with their robustness rows, and the square in a vertical
plane (the arm on its shoulder under gravity). Writes a table, figures, a
self-contained HTML report and a JSON summary, and states for each of the paper's
claims whether the model supports it.
"""

_EPILOG = """\
the fuzzy law (flexarm.control.adaptive.FuzzyAdaptiveJTPD): the FLS reads ks times the
links' tip deflections (m); its output lambda scales the whole JT-PD law (--law
scaled, the paper's printed form) or only its damping (--law damping) by
lambda / lambda(0, 0), so both laws equal the nonadaptive law with straight links.
ks = 1 is the paper's +-5 m universe; ks = 0 switches the adaptation off.

output: --out DIR (default ./results) must be new or empty; it receives
summary.json (what --json prints), table.csv, report.html (figures embedded as PNG),
tracking.png, deflections.png, fuzzy_surface.png and sensitivity.png (or .pdf,
.svg with --format), all at once.

exit status: 0 success (runs that diverge are results, reported as such);
1 the results could not be written; 2 bad input (one line on stderr).
"""


def add_parser(sub: Any) -> None:
    """Add ``reproduce`` to the subcommands ``sub``."""
    summary = "the paper's experiments: matrix, sensitivity study, report and claims"
    p = sub.add_parser("reproduce", help=summary, description=_DESCRIPTION, epilog=_EPILOG)
    p.add_argument("--out", metavar="DIR", default="results", help="default ./results")
    p.add_argument("--json", action="store_true", help="print the JSON summary on stdout")
    p.add_argument(
        "--duration", type=float, metavar="SECONDS", help="per run (default: the square, 20 s)"
    )
    p.add_argument(
        "--dt",
        type=float,
        default=DEFAULT_DT,
        metavar="SECONDS",
        help=f"control period (default {DEFAULT_DT:g})",
    )
    p.add_argument(
        "--ks",
        type=float,
        default=DEFAULT_KS,
        help=f"membership-width gain of the fuzzy law (default {DEFAULT_KS:g})",
    )
    p.add_argument(
        "--law", choices=ADAPTATION_LAWS, default=DEFAULT_LAW, help=f"default {DEFAULT_LAW}"
    )
    p.add_argument(
        "--ks-range",
        type=_ks_list,
        default=DEFAULT_KS_RANGE,
        metavar="K1,K2,...",
        help="ks values of the sensitivity study (default "
        + ",".join(f"{k:g}" for k in DEFAULT_KS_RANGE)
        + ")",
    )
    p.add_argument(
        "--sensitivity",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="run the sensitivity study (default on)",
    )
    p.add_argument(
        "--beyond",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="run the study beyond the paper: LQG and the reflected tip on the physical "
        "distant sensors, with robustness rows, and the square in a vertical plane "
        "(default on)",
    )
    p.add_argument(
        "--converged",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="rerun the matrix on a converged arm (3 clamped-mass modes per link, geometric "
        "stiffening) and judge the claims there too (default on)",
    )
    p.add_argument(
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE,
        help="'tracks well' = RMS error <= TOLERANCE x the square's side "
        f"(default {DEFAULT_TOLERANCE:g})",
    )
    p.add_argument("--workers", type=int, help="parallel runs (default: every core)")
    add_figure_options(p, "into --out")
    p.set_defaults(func=_cmd_reproduce)
