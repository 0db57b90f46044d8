"""``flexarm reproduce``: the paper's experiments, a report and a verdict on each claim."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

from ..control.adaptive import ADAPTATION_LAWS
from ..studies.reproduction import DEFAULT_KS_RANGE, OUTPUT_FILES, Reproduction, reproduce
from ._common import EXIT_FAILURE, UsageError, check_out

__all__ = ["add_parser"]

_PROG = "flexarm reproduce"


def _ks_list(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be comma-separated numbers >= 0. Got {text!r} instead."
        ) from None
    if not values or any(not (v >= 0) for v in values):
        raise argparse.ArgumentTypeError(
            f"must be comma-separated numbers >= 0. Got {text!r} instead."
        )
    return values


def _format(rep: Reproduction, out: Path) -> str:
    s = rep.settings
    lines = [
        f"{_PROG}: {s['runs']} runs in {s['wall_time_s']:.1f} s "
        f"(control period {s['dt_s']:g} s; 'tracks well' = RMS <= {s['tolerance_m']:g} m)",
        f"  {'controller':<16}{'sensor':<14}{'status':<22}{'rms (m)':>10}{'max (m)':>10}",
    ]
    for c in rep.cases:
        row = c.row()
        status = "ok" if c.status == "ok" else f"diverged at {c.diverged_at_s:.3g} s"
        rms = "" if row["rms_error_m"] is None else f"{row['rms_error_m']:.4g}"
        mx = "" if row["max_error_m"] is None else f"{row['max_error_m']:.4g}"
        name = "nonadaptive" if c.case.controller == "pd" else "fuzzy adaptive"
        lines.append(f"  {name:<16}{c.case.sensor:<14}{status:<22}{rms:>10}{mx:>10}")
    lines.append("claims:")
    for claim in rep.claims:
        lines.append(f"  - {claim['claim']}: {claim['verdict'].upper()}")
        lines.append(f"      {claim['evidence']}")
    lines.append(f"  report in {out / 'report.html'}")
    return "\n".join(lines)


def _cmd_reproduce(args: argparse.Namespace) -> int:
    out = Path(os.path.abspath(args.out))
    check_out(out, _PROG)
    try:
        rep = reproduce(
            duration=args.duration,
            dt=args.dt,
            ks=args.ks,
            law=args.law,
            ks_range=args.ks_range,
            sensitivity=args.sensitivity,
            tolerance=args.tolerance,
            workers=args.workers,
            progress=None if not args.json else False,
        )
    except (TypeError, ValueError) as exc:
        raise UsageError(f"{_PROG}: error: {exc}") from None
    try:
        rep.write(out)
    except OSError as exc:
        print(f"{_PROG}: error: cannot write {str(out)!r}: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    if args.json:
        summary: dict[str, Any] = rep.summary()
        summary["out"] = str(out)
        summary["files"] = list(OUTPUT_FILES)
        print(json.dumps(summary, indent=2))
    else:
        print(_format(rep, out))
    return 0


_DESCRIPTION = """\
Run the paper's experiments: {nonadaptive JT-PD, fuzzy adaptive} x {joint sensor,
end-effector sensor, sensor 0.5 m from the elbow} on the default square, and a
sensitivity study (the same matrix under each delay model: none, the seed's wave
speed, the dispersive bending-wave speed; the fuzzy law over a range of ks and both
adaptation laws). Writes a table, figures, a self-contained HTML report and a JSON
summary, and states for each of the paper's claims whether the model supports it.
"""

_EPILOG = """\
the fuzzy law (flexarm.control.adaptive.FuzzyAdaptiveJTPD): the FLS reads ks times the
links' tip deflections (m); its output lambda scales the whole JT-PD law (--law
scaled, the paper's printed form) or only its damping (--law damping) by
lambda / lambda(0, 0), so both laws equal the nonadaptive law with straight links.
ks = 1 is the paper's +-5 m universe; ks = 0 switches the adaptation off.

output: --out DIR (default ./results) must be new or empty; it receives
summary.json (what --json prints), table.csv, report.html (figures embedded),
tracking.png, deflections.png, fuzzy_surface.png and sensitivity.png, all at once.

exit status: 0 success (runs that diverge are results, reported as such);
1 the results could not be written; 2 bad input (one line on stderr).
"""


def add_parser(sub: Any) -> None:
    """Add ``reproduce`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "reproduce",
        help="the paper's experiments: matrix, sensitivity study, report and claims",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", metavar="DIR", default="results", help="default ./results")
    p.add_argument("--json", action="store_true", help="print the JSON summary on stdout")
    p.add_argument(
        "--duration", type=float, metavar="SECONDS", help="per run (default: the square, 20 s)"
    )
    p.add_argument(
        "--dt", type=float, default=2e-4, metavar="SECONDS", help="control period (default 2e-4)"
    )
    p.add_argument(
        "--ks", type=float, default=1.0, help="membership-width gain of the fuzzy law (default 1)"
    )
    p.add_argument("--law", choices=ADAPTATION_LAWS, default="scaled", help="default scaled")
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
        "--tolerance",
        type=float,
        default=0.05,
        help="'tracks well' = RMS error <= TOLERANCE x the square's side (default 0.05)",
    )
    p.add_argument("--workers", type=int, help="parallel runs (default: CPUs, at most 4)")
    p.set_defaults(func=_cmd_reproduce)
