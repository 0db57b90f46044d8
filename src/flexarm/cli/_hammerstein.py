"""``flexarm identify hammerstein``: a Hammerstein model from data, or the robot-joint study.

With DATA, :func:`flexarm.ident.fits.fit_hammerstein` is run on an input column
``u`` and an output column ``y``; without, the nonlinear-joint robot is excited
with a random torque and its stiffness, friction and drive nonlinearity are
identified (:func:`flexarm.studies.joint_identification.identify_joint`).
Which options apply to which case is read from the two option groups of the
parser, not from a table kept by hand.
"""

from __future__ import annotations

import argparse
import inspect
import time
import warnings
from collections.abc import Callable
from typing import Any

from ..ident.options import METHODS, ORDER_RULES
from ._common import UsageError, add_figure_options, figure_format
from ._identify_common import given, library_errors, output_options, positive_int, report

__all__ = ["add_parser", "parse_knots", "parse_known", "parse_order", "word_or_int"]

PROG = "flexarm identify hammerstein"


def word_or_int(words: tuple[str, ...], minimum: int) -> Callable[[str], int | str]:
    """An ``argparse`` type: one of ``words``, or an integer ``>= minimum``."""
    expected = f"{', '.join(repr(w) for w in words)} or an integer >= {minimum}"

    def parse(text: str) -> int | str:
        if text in words:
            return text
        try:
            value = int(text)
        except ValueError:
            value = minimum - 1
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be {expected}. Got {text!r} instead.")
        return value

    return parse


#: ``--order``: "auto", "bic", "aic" or a positive integer.
parse_order = word_or_int(ORDER_RULES, 1)
#: ``--knots``: "auto" or an integer >= 2.
parse_knots = word_or_int(("auto",), 2)


def parse_known(text: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """``--known X1:PHI1,X2:PHI2``: two points where the nonlinearity is known."""
    try:
        pairs = [tuple(float(v) for v in item.split(":")) for item in text.split(",")]
    except ValueError:
        pairs = []
    if len(pairs) != 2 or any(len(p) != 2 for p in pairs):
        raise argparse.ArgumentTypeError(
            f"must be two points X1:PHI1,X2:PHI2 (numbers). Got {text!r} instead."
        )
    (x1, p1), (x2, p2) = pairs
    return (x1, p1), (x2, p2)


def _misplaced(args: argparse.Namespace, actions: list[argparse.Action]) -> str | None:
    """The first option among ``actions`` that the user gave, if any."""
    for action in actions:
        if getattr(args, action.dest) not in (None, False):
            return action.option_strings[0]
    return None


def _run(
    data_options: list[argparse.Action], robot_options: list[argparse.Action]
) -> Callable[[argparse.Namespace], int]:
    """The command: reject the other case's options, then fit DATA or run the robot."""

    def run(args: argparse.Namespace) -> int:
        if args.data is None:
            wrong, case = _misplaced(args, data_options), "applies to DATA"
        else:
            wrong = _misplaced(args, robot_options)
            case = "applies to the robot experiment (hammerstein without DATA)"
        if wrong is not None:
            raise UsageError(f"{PROG}: error: argument {wrong}: {case}")
        output_options(args, PROG)  # before any work
        return _fit_data(args) if args.data is not None else _robot(args)

    return run


def _fit_data(args: argparse.Namespace) -> int:
    from ..ident.data import read_xy
    from ..ident.fits import fit_hammerstein
    from ..ident.hammerstein.whiteness import IdentificationWarning

    t0 = time.perf_counter()
    columns = given(args, "x", "y")
    seed = 0 if args.seed is None else args.seed
    with library_errors(PROG), warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)  # in the summary instead
        u, y, dropped = read_xy(
            args.data, **columns, drop_nan=args.drop_nan, delimiter=args.delimiter
        )
        res = fit_hammerstein(
            u,
            y,
            **given(
                args,
                "order",
                "method",
                "bootstrap",
                n_lags="lags",
                known_points="known",
                n_knots="knots",
            ),
            rng=seed,
            u_label=str(columns.get("x", 0)),
            y_label=str(columns.get("y", 1)),
        )
    summary = {
        "status": "ok",
        "mode": "hammerstein",
        "data": str(args.data),
        "columns": {"u": columns.get("x", 0), "y": columns.get("y", 1)},
        "dropped_nan_rows": dropped,
        "seed": seed if args.bootstrap else None,
        **res.summary(),
        "wall_time_s": time.perf_counter() - t0,
    }
    fmt = figure_format(args, PROG, args.out)
    return report(args, PROG, summary, lambda d: res.save(d, figure_format=fmt), _format)


def _robot(args: argparse.Namespace) -> int:
    from ..studies.joint_identification import (
        JointExcitation,
        design_dead_band_excitation,
        identify_joint,
    )

    if args.design and args.duration is not None:
        raise UsageError(f"{PROG}: error: argument --duration: not with --design (it sets it)")
    t0 = time.perf_counter()
    measurement = "sensor" if args.torque_sensor else "motor-balance"
    seed = args.seed
    if seed is None:
        seed = inspect.signature(identify_joint).parameters["rng"].default
    design = None
    with library_errors(PROG):
        if args.design:  # the pilot and the experiment: independent streams of one seed
            import numpy as np

            pilot_rng, main_rng = np.random.default_rng(seed).spawn(2)
            design = design_dead_band_excitation(rng=pilot_rng)
            excitation = design.excitation
        else:
            excitation = JointExcitation(**given(args, "duration"))
        res = identify_joint(
            excitation=excitation,
            torque_measurement=measurement,
            method="correlated" if args.design else "auto",
            **given(args, n_lags="lags"),
            rng=main_rng if args.design else seed,
        )
    summary = {
        "status": "ok",
        "mode": "hammerstein-robot",
        "duration_s": excitation.duration,
        "torque_measurement": measurement,
        "seed": seed,
        "design": None if design is None else design.summary(),
        **res.summary(),
        "wall_time_s": time.perf_counter() - t0,
    }
    fmt = figure_format(args, PROG, args.out)
    return report(args, PROG, summary, lambda d: res.save(d, figure_format=fmt), _format)


def _format_data(summary: dict[str, Any]) -> str:
    """The human-readable summary of a fit to DATA."""
    base = summary["baseline"]
    if summary["method"] == "white":
        structure = f"{summary['n_lags']} lags by correlation, ARMA order {summary['arma_order']}"
    else:
        st = summary["structure"]
        structure = (
            f"ARX-Hammerstein order {st['order']}, {st['n_knots']} knots ({st['chosen_by']}), "
            f"{st['estimator']}"
        )
    helps = "helps" if summary["nonlinear_helps"] else "does not help"
    lines = [
        f"{PROG}: {summary['n_samples']} samples from {summary['data']} "
        f"(u = column {summary['columns']['u']}, y = column {summary['columns']['y']})",
        f"  path: {summary['method']} input -- {summary['reason']}",
        f"  model: {structure}; nonlinearity {summary['normalisation']}",
        f"  free-run fit on the data: {summary['fit_percent']:.2f} % "
        f"(linear ARX baseline, order {base['order']}: {base['fit_percent']:.2f} %); "
        f"the nonlinearity {helps}",
    ]
    comparison = summary["comparison"]
    if comparison is not None:
        lines.append(f"  validation: {comparison['statement']}")
    if summary["bands"] is not None:
        b = summary["bands"]
        lines.append(
            f"  bootstrap: {b['n_boot']} replicates, blocks of {b['block_length']} samples, "
            f"{100 * b['level']:g} % bands (seed {summary['seed']})"
        )
    said = None if comparison is None else comparison["statement"]
    lines += [f"  warning: {w}" for w in summary["warnings"] if w != said]
    return "\n".join(lines)


def _format(summary: dict[str, Any]) -> str:
    """The human-readable summary."""
    if summary["mode"] == "hammerstein":
        return _format_data(summary)
    s, f, d, h = summary["stiffness"], summary["friction"], summary["drive"], summary["hammerstein"]
    db, design = summary["dead_band"], summary["design"]
    lines = [
        f"{PROG}: random-torque experiment on the nonlinear joint "
        f"({summary['duration_s']:g} s, tau_s by {summary['torque_measurement']})",
    ]
    if design is not None:
        lines.append(
            f"  designed for the dead band: {100 * design['dead_band_fraction']:g} % of the "
            f"commands within +-{design['dead_band_span_Nm']:g} N m, {design['n_knots']} knots, "
            f"{design['n_holds']} estimation holds (pilot {design['pilot']['duration_s']:g} s)"
        )
    lines += [
        f"  stiffness curve: RMS error {s['rms_error']:.4g} {s['y_unit']}",
        f"  friction curve:  RMS error {f['rms_error']:.4g} {f['y_unit']}",
        f"  drive nonlinearity (Hammerstein, {h['method']} path): RMS error "
        f"{d['rms_error']:.4g} {d['y_unit']}",
        f"  dead band: half-width {db['half_width_negative_Nm']:.2f} / "
        f"{db['half_width_positive_Nm']:.2f} N m (true {db['true_half_width_Nm']:g}); RMS error "
        f"{db['rms_error_Nm']:.3g} N m within +-{db['span_Nm']:g} N m",
        f"  Hammerstein free-run fit on held-out data: {h['fit_percent']:.2f} % "
        f"(reference {h['reference_fit_percent']:.2f} %)",
    ]
    return "\n".join(lines)


_DESCRIPTION = """\
A Hammerstein model of DATA (input u = --x, output y = --y), reported beside the
best linear ARX model of the same data (flexarm.ident.HammersteinIdentifier): on a
validation part (the held-out blocks; the white path: the last quarter) the model
is compared with the best linear ARX over orders 1-10, and the summary says which
won and by how much (the linear model is returned, or recommended by a warning,
when the nonlinear one does not beat it).
--method auto (default) tests the input for whiteness (Ljung-Box, McLeod-Li):
a white input takes the paper's path (the linear part by the correlation
approach, the nonlinearity by eq. 14); any other input the correlated-input
path (over-parameterised ARX on a piecewise-linear basis for the nonlinearity,
rank-one separation, instrumental variables; order and knots chosen on held-out
blocks, every fourth of twenty). The nonlinearity is up to an affine map unless --known
gives two points where it is known (the paper's two-point normalisation).

Without DATA: the robot experiment (paper section IX): a nonlinear flexible joint
driven by a random torque for --duration s (--seed), its stiffness, friction and
drive curves identified and compared with the truth
(flexarm.studies.joint_identification). --design sizes the experiment to resolve
the drive's dead band (commands concentrated near it, the duration from a pilot
run; the pilot and the experiment draw from default_rng(S).spawn(2)) and
identifies it on the correlated-input path.
"""

_EPILOG = """\
output: with --out DIR (new or empty), all at once: for DATA nonlinearity.csv
(u,phi; with --bootstrap also phi_low,phi_high), impulse_response.csv
(lag,impulse_response[,low,high]), hammerstein.png and summary.json (path and
why, whiteness, structure, baseline, warnings); for the robot experiment
summary.json, curves.npz and identify_joint.png (figures as .pdf or .svg with
--format). --json prints the summary on
stdout.
"""


def add_parser(isub: Any) -> None:
    """Add ``hammerstein`` to the ``identify`` subcommands ``isub``."""
    summary = "a Hammerstein model of DATA, or (without DATA) the robot-joint experiment"
    p = isub.add_parser("hammerstein", help=summary, description=_DESCRIPTION, epilog=_EPILOG)
    p.add_argument("data", nargs="?", metavar="DATA", help="data file (.csv, .npz or text)")
    p.add_argument("--lags", type=positive_int(2), metavar="N", help="impulse response length (40)")
    p.add_argument(
        "--seed", type=positive_int(0), metavar="S", help="seed: bootstrap, or robot (default 0)"
    )
    p.add_argument("--out", metavar="DIR", help="write the results into DIR (new or empty)")
    add_figure_options(p)
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    d = p.add_argument_group("with DATA")
    data_options = [
        d.add_argument("--x", metavar="COL", help="input column: name or 0-based index (0)"),
        d.add_argument("--y", metavar="COL", help="output column: name or index (1)"),
        d.add_argument("--drop-nan", action="store_true", help="drop rows with NaN"),
        d.add_argument(
            "--delimiter",
            metavar="C",
            help="column separator of a text file (default: ',' for .csv, else whitespace)",
        ),
        d.add_argument(
            "--method",
            choices=METHODS,
            help="path: auto (by the whiteness test), white, correlated (default auto)",
        ),
        d.add_argument(
            "--order",
            type=parse_order,
            metavar="auto|bic|aic|N",
            help="ARMA order (auto: BIC on the white path, held-out on the correlated)",
        ),
        d.add_argument(
            "--knots", type=parse_knots, metavar="auto|N", help="correlated path: knots of phi"
        ),
        d.add_argument(
            "--bootstrap", type=positive_int(10), metavar="B", help="bootstrap bands, B replicates"
        ),
        d.add_argument(
            "--known",
            type=parse_known,
            metavar="X1:PHI1,X2:PHI2",
            help="two points of the nonlinearity (two-point normalisation)",
        ),
    ]
    r = p.add_argument_group("robot experiment (without DATA)")
    robot_options = [
        r.add_argument("--duration", type=float, metavar="SECONDS", help="record (default 60)"),
        r.add_argument(
            "--design",
            action="store_true",
            help="design the excitation to resolve the drive's dead band (sets the duration)",
        ),
        r.add_argument(
            "--torque-sensor",
            action="store_true",
            help="a joint torque sensor measures tau_s (default: motor balance)",
        ),
    ]
    p.set_defaults(func=_run(data_options, robot_options))
