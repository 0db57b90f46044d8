"""``flexarm identify``: nonparametric identification, as three subcommands.

* ``flexarm identify fit DATA`` — the semi-recursive kernel estimate (paper §5,
  eq. 14) of ``E[y | x]`` from two columns of a data file
  (:func:`flexarm.ident.fits.fit_regression`);
* ``flexarm identify study`` — its Monte Carlo convergence rate
  (:func:`flexarm.ident.convergence_study`);
* ``flexarm identify hammerstein [DATA]`` — a Hammerstein model of a data
  file, or the robot-joint experiment (``flexarm.cli._hammerstein``).

The commands parse, call the library and print; the library reads the files
(:mod:`flexarm.ident.data`), holds the defaults and draws the figures. Only
light modules are imported here: the estimators (and Numba) load when a
command runs, so ``flexarm --help`` stays quick.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from ..ident.options import DISTRIBUTIONS, KERNELS, REGRESSION_FUNCTIONS
from . import _hammerstein
from ._common import UsageError, add_figure_options
from ._identify_common import (
    CommandParser,
    given,
    library_errors,
    output_options,
    parse_bandwidth,
    positive_int,
    report,
)

__all__ = ["add_parser"]

PROG = "flexarm identify"


# --------------------------------------------------------------------------- fit


def _cmd_fit(args: argparse.Namespace) -> int:
    from ..ident.data import read_xy
    from ..ident.fits import fit_regression

    prog = f"{PROG} fit"
    fmt = output_options(args, prog)
    t0 = time.perf_counter()
    with library_errors(prog):
        x, y, dropped = read_xy(
            args.data, args.x, args.y, drop_nan=args.drop_nan, delimiter=args.delimiter
        )
        res = fit_regression(
            x,
            y,
            **given(args, "kernel", "bandwidth", "decay", "grid", "binned"),
            series=args.series,
            x_label=str(args.x),
            y_label=str(args.y),
        )
    summary = {
        "status": "ok",
        "mode": "fit",
        "data": str(args.data),
        "columns": {"x": args.x, "y": args.y},
        "dropped_nan_rows": dropped,
        **res.summary(),
        "wall_time_s": time.perf_counter() - t0,
    }
    return report(args, prog, summary, lambda d: res.save(d, figure_format=fmt), _format_fit)


def _format_fit(summary: dict[str, Any]) -> str:
    dropped = summary["dropped_nan_rows"]
    lines = [
        f"{PROG} fit: {summary['n_samples']} samples from {summary['data']} "
        f"(x = column {summary['columns']['x']}, y = column {summary['columns']['y']})"
        + (f", {dropped} NaN row(s) dropped" if dropped else ""),
        f"  {summary['kernel']} kernel, h_1 = {summary['bandwidth']:.6g} "
        f"({summary['bandwidth_rule']}), decay {summary['decay']:g}, "
        f"h_n = {summary['last_bandwidth']:.4g}"
        + (f", binned r = {summary['binned']:g}" if summary["binned"] is not None else ""),
        f"  estimate on {summary['grid']['points']} points in [{summary['grid']['min']:.6g}, "
        f"{summary['grid']['max']:.6g}]; {summary['points_without_estimate']} without data "
        "nearby (NaN)",
    ]
    if summary["error_bound_max"] is not None:
        lines.append(f"  binning error bound (max over the grid): {summary['error_bound_max']:.3g}")
    return "\n".join(lines)


# --------------------------------------------------------------------------- study


def _cmd_study(args: argparse.Namespace) -> int:
    import numpy as np

    from ..ident.regression.convergence import convergence_study, sample_sizes

    prog = f"{PROG} study"
    fmt = output_options(args, prog)
    t0 = time.perf_counter()
    with library_errors(prog):
        sizes = given(args, "n_min", "n_max", steps="n_steps")
        lo, hi = sizes.get("n_min", 250), sizes.get("n_max", 16000)  # sample_sizes' defaults
        if lo >= hi:
            which = "--n-max" if "n_max" in sizes else "--n-min"
            raise UsageError(
                f"{prog}: error: argument {which}: --n-max must be larger than --n-min. "
                f"Got --n-min {lo} and --n-max {hi} instead."
            )
        res = convergence_study(
            args.function,
            n=sample_sizes(**sizes) if sizes else None,
            rng=np.random.default_rng(args.seed),
            **given(args, "repetitions", "noise", "distribution", "kernel", "bandwidth", "decay"),
        )
    summary: dict[str, Any] = {
        "status": "ok",
        "mode": "study",
        **res.summary(),
        "seed": args.seed,
        "wall_time_s": time.perf_counter() - t0,
    }
    summary["settings"]["rng"] = f"default_rng({args.seed})"
    return report(args, prog, summary, lambda d: res.save(d, figure_format=fmt), _format_study)


def _format_study(summary: dict[str, Any]) -> str:
    s = summary["settings"]
    h1 = s["h1"]
    bandwidth = (
        f"h_1 = {s['bandwidth']:g}"
        if not isinstance(s["bandwidth"], str)
        else f"h_1 by {s['bandwidth']} ({min(h1):.3g} to {max(h1):.3g})"
    )
    lines = [
        f"{PROG} study: {s['function']} m, {s['distribution']} inputs, noise {s['noise']:g}, "
        f"{s['kernel']} kernel, {bandwidth}, decay {s['decay']:.4g}, "
        f"{s['repetitions']} repetitions",
        f"  {'n':>8} {'MISE':>12} {'std':>12}",
    ]
    lines += [
        f"  {n:>8d} {m:>12.4e} {sd:>12.4e}"
        for n, m, sd in zip(summary["n"], summary["mise"], summary["std"], strict=True)
    ]
    lines.append(
        f"  fitted log-log slope {summary['slope']:.3f}; theory -2p/(2p+1) = "
        f"{summary['theory_slope']:.3f} (p = {summary['order']:g})"
    )
    return "\n".join(lines)


# --------------------------------------------------------------------------- parsers

_DESCRIPTION = """\
Nonparametric identification (paper section 5): the semi-recursive kernel
estimate of m(x) = E[Y | X = x] from a data file (fit), its convergence rate by
Monte Carlo (study), or a Hammerstein model (hammerstein).
Run 'flexarm identify SUBCOMMAND --help' for a subcommand's options.
"""

_EPILOG = """\
exit status: 0 success; 1 the results could not be written; 2 bad input (one
line on stderr, nothing written).
"""

_FIT_EPILOG = """\
data: .csv (comma-separated), .npz (1-D arrays named by key, or one 2-D table), or
whitespace-separated text ('#' comments); --delimiter ';' (or any one character)
reads a text file separated by it. A first line with a non-numeric cell is
a header. --x and --y take a header name or a 0-based column index. Empty cells
and 'nan' are NaN: rows with NaN in the chosen columns are an error unless
--drop-nan (the count dropped is reported).

bandwidth: by default (silverman) h_1 is chosen so that the last sample's
bandwidth h_n is Silverman's rule of thumb 0.9 min(sd, IQR/1.34) n^(-1/5) of the
input column (flexarm.ident.regression.bandwidth; with decay 0.2,
h_1 = 0.9 min(sd, IQR/1.34)).

--binned [R]: approximate grid mode with bins R h wide (default R = 0.1; R in
[1e-4, 0.5]; gaussian, epanechnikov or triangular kernel; write --binned=R, or
put DATA first, so that DATA is not taken for R); the summary reports the proven
bound on its error (flexarm.ident.regression.binning). --series (gaussian kernel,
--decay 0): the same sums by a Taylor series (fast Gauss transform), O(n + N) instead of
O(n N) work, equal to the direct sums to rounding.

output: with --out DIR (new or empty), DIR receives estimate.csv (x,m),
estimate.png (data and estimate; .pdf or .svg with --format) and summary.json, all
at once, only if everything succeeded. --json prints the summary on stdout.
"""

_STUDY_EPILOG = """\
MISE against n (geometric from --n-min to --n-max, --n-steps sizes; default 250
to 16000 in 7) for --function, --repetitions data sets drawn from
default_rng(--seed); prints the table and the fitted log-log slope beside the
theoretical -2p/(2p+1). Defaults are flexarm.ident.convergence_study's: gaussian
kernel, Silverman's bandwidth on each data set, decay 1/(2p+1), 20 repetitions.

output: with --out DIR, study.csv (n,mise,std), study.png (.pdf or .svg with
--format) and summary.json.
"""


def _add_estimator_options(p: argparse.ArgumentParser, decay: str) -> None:
    p.add_argument("--kernel", choices=KERNELS, help="kernel (default gaussian)")
    p.add_argument(
        "--bandwidth",
        type=parse_bandwidth,
        metavar="H|silverman",
        help="h_1 in units of x, or a rule (default silverman)",
    )
    p.add_argument("--decay", type=float, metavar="D", help=f"h_i = h_1 i^-D (default {decay})")


def _add_output_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", metavar="DIR", help="write the results into DIR (new or empty)")
    add_figure_options(p)
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")


def add_parser(sub: Any) -> None:
    """Add ``identify`` and its subcommands to the subcommands ``sub``."""
    summary = "nonparametric identification: fit, study, hammerstein"
    p = sub.add_parser("identify", help=summary, description=_DESCRIPTION, epilog=_EPILOG)
    isub = p.add_subparsers(
        dest="identify_command",
        metavar="{fit,study,hammerstein}",
        parser_class=CommandParser,
        required=True,
    )

    summary = "m(x) = E[y | x] by eq. 14 from two columns of a data file"
    description = (
        "Estimate m(x) = E[Y | X = x] (eq. 14, h_i = h_1 i^-decay) on a grid spanning the inputs."
    )
    fit = isub.add_parser("fit", help=summary, description=description, epilog=_FIT_EPILOG)
    fit.add_argument("data", metavar="DATA", help="data file (.csv, .npz or text)")
    fit.add_argument("--x", metavar="COL", default="0", help="input column (default 0)")
    fit.add_argument("--y", metavar="COL", default="1", help="output column (default 1)")
    _add_estimator_options(fit, "0.2")
    fit.add_argument("--grid", type=positive_int(2), metavar="N", help="grid points (512)")
    fit.add_argument(
        "--binned",
        type=float,
        nargs="?",
        const=0.1,
        metavar="R",
        help="approximate binned mode, bins R h wide (R 0.1 if omitted)",
    )
    fit.add_argument(
        "--series",
        action="store_true",
        help="gaussian with --decay 0: fast series sums (same estimate to rounding)",
    )
    fit.add_argument("--drop-nan", action="store_true", help="drop rows with NaN (else an error)")
    fit.add_argument(
        "--delimiter",
        metavar="C",
        help="column separator of a text file (default: ',' for .csv, else whitespace)",
    )
    _add_output_options(fit)
    fit.set_defaults(func=_cmd_fit)

    summary = "convergence rate of eq. 14 by Monte Carlo"
    description = (
        "Monte Carlo MISE of the semi-recursive estimate against n "
        "(flexarm.ident.convergence_study)."
    )
    study = isub.add_parser("study", help=summary, description=description, epilog=_STUDY_EPILOG)
    study.add_argument(
        "--function", choices=REGRESSION_FUNCTIONS, default="smooth", help="m (default smooth)"
    )
    study.add_argument("--n-min", type=positive_int(1), metavar="N", help="smallest n")
    study.add_argument("--n-max", type=positive_int(1), metavar="N", help="largest n")
    study.add_argument("--n-steps", type=positive_int(2), metavar="K", help="sample sizes")
    study.add_argument("--repetitions", type=positive_int(2), metavar="R", help="data sets")
    study.add_argument(
        "--seed", type=positive_int(0), default=0, metavar="S", help="seed (default 0)"
    )
    study.add_argument("--noise", type=float, metavar="SIGMA", help="noise std (default 0.1)")
    study.add_argument("--distribution", choices=DISTRIBUTIONS, help="inputs (default uniform)")
    _add_estimator_options(study, "1/(2p+1)")
    _add_output_options(study)
    study.set_defaults(func=_cmd_study)

    _hammerstein.add_parser(isub)
