"""``flexarm identify``: the static kernel regression estimate from a data file, or a study.

``flexarm identify DATA`` fits ``m(x) = E[Y | X = x]`` (paper §5, eq. 14) to two
columns of a data file and evaluates it on a grid; ``flexarm identify --study``
runs :func:`flexarm.ident.convergence_study`. Reading the data is
:func:`load_columns`, reusable by other identification commands.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..ident import KERNELS, SemiRecursiveKernelRegression
from ..ident.convergence import DISTRIBUTIONS, FUNCTIONS, ConvergenceResult, convergence_study
from . import _hammerstein
from ._common import EXIT_FAILURE, UsageError, check_out, json_ready, output_directory

__all__ = [
    "FIT_FILES",
    "STUDY_FILES",
    "DataError",
    "add_parser",
    "default_bandwidth",
    "load_columns",
]

F64 = NDArray[np.float64]
PROG = "flexarm identify"
FIT_FILES = ("estimate.csv", "estimate.png", "summary.json")
STUDY_FILES = ("study.csv", "study.png", "summary.json")
_PLOT_POINTS = 5000  # data points drawn at most (every k-th)


class DataError(ValueError):
    """A data file that cannot give the requested columns (one-line message)."""


# --------------------------------------------------------------------------- reading data


def _rows(path: Path) -> list[tuple[int, list[str]]]:
    """``(line number, cells)`` of the non-blank lines: CSV for ``.csv``, else whitespace."""
    try:
        with open(path, newline="") as f:
            text = f.read()
    except UnicodeDecodeError:
        raise DataError(f"{str(path)!r} is not a text file (nor .npz)") from None
    lines = text.splitlines()
    if path.suffix.lower() == ".csv":
        try:
            parsed = list(csv.reader(lines, strict=True))
        except csv.Error as exc:
            raise DataError(f"{str(path)!r} is not valid CSV: {exc}") from None
        return [(k + 1, [c.strip() for c in row]) for k, row in enumerate(parsed) if row]
    out = []
    for k, line in enumerate(lines):
        body = line.split("#", 1)[0].split()
        if body:
            out.append((k + 1, body))
    return out


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _pick(spec: str | int, names: list[str] | None, width: int) -> int:
    """Column index of ``spec``: a header name, else a 0-based index."""
    if isinstance(spec, str) and names is not None and spec in names:
        return names.index(spec)
    try:
        index = int(spec)
    except ValueError:
        known = f"columns: {', '.join(names)}" if names else "the file has no header"
        raise DataError(f"no column named {spec!r} ({known})") from None
    if not 0 <= index < width:
        raise DataError(f"column index {index} is out of range ({width} column(s))")
    return index


def _load_npz(path: Path, columns: Sequence[str | int]) -> tuple[F64, ...]:
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as exc:  # zipfile/OSError/ValueError: all mean "not a readable .npz"
        raise DataError(f"{str(path)!r} is not a readable .npz file ({exc})") from None
    if len(arrays) == 1 and next(iter(arrays.values())).ndim == 2:
        table = next(iter(arrays.values()))
        names: list[str] | None = None
        cols = [table[:, j] for j in range(table.shape[1])]
    else:
        names = list(arrays)
        cols = list(arrays.values())
        bad = [k for k, a in arrays.items() if a.ndim != 1]
        if bad:
            raise DataError(
                f"{str(path)!r}: array {bad[0]!r} is not one-dimensional (an .npz holds 1-D "
                "columns, or one 2-D table)"
            )
        lengths = {a.shape[0] for a in cols}
        if len(lengths) > 1:
            raise DataError(f"{str(path)!r}: the arrays have different lengths {sorted(lengths)}")
    out = []
    for spec in columns:
        j = _pick(spec, names, len(cols))
        col = cols[j]
        label = names[j] if names else str(j)
        if col.dtype.kind not in "biuf":
            raise DataError(f"{str(path)!r}: column {label!r} is not numeric (dtype {col.dtype})")
        out.append(np.asarray(col, dtype=np.float64))
    return tuple(out)


def load_columns(path: str | os.PathLike[str], columns: Sequence[str | int]) -> tuple[F64, ...]:
    """Read the named or numbered columns of a data file as float arrays.

    Formats: ``.npz`` (1-D arrays named by their keys, or a single 2-D table
    whose columns are numbered); ``.csv`` (comma-separated); anything else,
    whitespace-separated text (``#`` starts a comment). A text file has a
    header when its first line has a non-numeric cell. Empty cells and
    ``nan`` read as NaN (the caller decides what to do with them); only the
    chosen columns must be numeric.

    Parameters
    ----------
    path : str or os.PathLike
        The data file.
    columns : sequence of str or int
        Each a header name or a 0-based column index (a string of digits that
        is not a header name counts as an index).

    Returns
    -------
    tuple of ndarray, each of shape (n,)
        The columns, in the order asked for.

    Raises
    ------
    DataError
        Missing or unreadable file, ragged rows, an unknown column, a
        non-numeric cell or no data rows; the message is one line.
    """
    p = Path(path)
    if not p.exists():
        raise DataError(f"{str(p)!r} does not exist")
    if not p.is_file():
        raise DataError(f"{str(p)!r} is not a file")
    if p.suffix.lower() == ".npz":
        return _load_npz(p, columns)
    rows = _rows(p)
    if not rows:
        raise DataError(f"{str(p)!r} holds no data")
    names: list[str] | None = None
    if not all(_is_number(c) or c == "" for c in rows[0][1]):
        names = rows[0][1]
        rows = rows[1:]
    width = len(names) if names is not None else len(rows[0][1]) if rows else 0
    if not rows:
        raise DataError(f"{str(p)!r} has a header but no data rows")
    picked = [_pick(spec, names, width) for spec in columns]
    out = [np.empty(len(rows)) for _ in picked]
    for r, (line, cells) in enumerate(rows):
        if len(cells) != width:
            raise DataError(
                f"{str(p)!r} line {line}: {len(cells)} field(s), expected {width} like the "
                f"{'header' if names is not None else 'first line'}"
            )
        for col, j in zip(out, picked, strict=True):
            cell = cells[j]
            if cell == "":
                col[r] = math.nan
                continue
            try:
                col[r] = float(cell)
            except ValueError:
                label = names[j] if names is not None else str(j)
                raise DataError(
                    f"{str(p)!r} line {line}, column {label!r}: {cell!r} is not a number"
                ) from None
    return tuple(out)


def default_bandwidth(x: F64, decay: float) -> float:
    """``h_1`` such that the last sample's ``h_n`` is Silverman's rule of thumb.

    ``h_n = 0.9 min(sd, IQR / 1.34) n**(-1/5)`` (Silverman 1986, eq. 3.31),
    so ``h_1 = h_n n**decay``; for ``decay = 0.2`` that is
    ``0.9 min(sd, IQR / 1.34)``, a fixed fraction of the input spread. If the
    spread is 0 (a constant input) ``1.0`` is used for it.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Inputs (units of X).
    decay : float
        Bandwidth decay of the estimator.

    Returns
    -------
    float
        ``h_1`` (units of X).
    """
    n = x.shape[0]
    q75, q25 = np.percentile(x, [75.0, 25.0])
    spread = min(float(np.std(x, ddof=1)) if n > 1 else 0.0, float(q75 - q25) / 1.34)
    if not spread > 0.0:
        spread = float(np.std(x)) if np.std(x) > 0 else 1.0
    return 0.9 * spread * float(float(n) ** (decay - 0.2))


# --------------------------------------------------------------------------- fitting


def _fail(message: str) -> UsageError:
    return UsageError(f"{PROG}: error: {message}")


def _read_xy(args: argparse.Namespace) -> tuple[F64, F64, int]:
    """The chosen columns with NaN rows dropped (``--drop-nan``) or refused."""
    try:
        x, y = load_columns(args.data, [args.x, args.y])
    except DataError as exc:
        raise _fail(str(exc)) from None
    bad = np.isnan(x) | np.isnan(y)
    dropped = int(bad.sum())
    if dropped and not args.drop_nan:
        first = int(np.argmax(bad))
        raise _fail(
            f"{dropped} row(s) have NaN or empty cells in the chosen columns (the first is "
            f"data row {first + 1}); pass --drop-nan to drop them"
        )
    x, y = x[~bad], y[~bad]
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise _fail("the chosen columns hold infinite values")
    if x.shape[0] < 2:
        raise _fail(f"need at least 2 data rows, got {x.shape[0]}")
    return x, y, dropped


def _fit(args: argparse.Namespace, out: Path | None) -> dict[str, Any]:
    t0 = time.perf_counter()
    x, y, dropped = _read_xy(args)
    decay = 0.2 if args.decay is None else args.decay
    rule = "given" if args.bandwidth is not None else "silverman"
    bandwidth = args.bandwidth if args.bandwidth is not None else default_bandwidth(x, decay)
    grid = np.linspace(float(x.min()), float(x.max()), args.grid)
    if grid[0] == grid[-1]:
        raise _fail("the input column is constant: no grid to estimate on")
    est = SemiRecursiveKernelRegression(
        kernel=args.kernel,
        bandwidth=bandwidth,
        decay=decay,
        grid=grid,
        binned=args.binned,
        series=args.series,
    )
    try:
        est.fit(x, y)
    except (TypeError, ValueError) as exc:
        raise _fail(str(exc)) from None
    m = est.predict(grid)
    summary: dict[str, Any] = {
        "status": "ok",
        "mode": "fit",
        "data": str(args.data),
        "columns": {"x": args.x, "y": args.y},
        "n_samples": int(x.shape[0]),
        "dropped_nan_rows": dropped,
        "estimator": "SemiRecursiveKernelRegression",
        "kernel": args.kernel,
        "bandwidth": float(bandwidth),
        "bandwidth_rule": rule,
        "decay": decay,
        "last_bandwidth": float(bandwidth) * float(x.shape[0]) ** (-decay),
        "binned": args.binned,
        "series": args.series,
        "error_bound_max": (
            float(np.nanmax(est.error_bound(grid))) if args.binned is not None else None
        ),
        "grid": {"points": int(grid.shape[0]), "min": float(grid[0]), "max": float(grid[-1])},
        "points_without_estimate": int(np.isnan(m).sum()),
        "wall_time_s": time.perf_counter() - t0,
        "out": None if out is None else str(out),
        "files": [] if out is None else list(FIT_FILES),
        "estimate": {"x": grid, "m": m},
    }
    summary = json_ready(summary)
    if out is not None:
        _write_fit(out, x, y, grid, m, summary)
    return summary


def _write_fit(out: Path, x: F64, y: F64, grid: F64, m: F64, summary: dict[str, Any]) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with output_directory(out) as tmp:
        np.savetxt(
            tmp / "estimate.csv",
            np.column_stack([grid, m]),
            fmt="%.12g",
            delimiter=",",
            header="x,m",
            comments="",
        )
        fig = Figure(figsize=(7, 4.5), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        step = max(1, x.shape[0] // _PLOT_POINTS)
        ax.plot(x[::step], y[::step], ".", ms=2, alpha=0.4, color="0.5", label="data")
        ax.plot(grid, m, "-", lw=2, label="estimate m_n(x)")
        ax.set_xlabel(f"x (column {summary['columns']['x']})")
        ax.set_ylabel(f"y (column {summary['columns']['y']})")
        ax.set_title(
            f"{summary['kernel']} kernel, h_1 = {summary['bandwidth']:.4g}, "
            f"decay {summary['decay']:g}, n = {summary['n_samples']}"
        )
        ax.legend()
        fig.savefig(tmp / "estimate.png", dpi=100)
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


# --------------------------------------------------------------------------- study


def _study(args: argparse.Namespace, out: Path | None) -> dict[str, Any]:
    t0 = time.perf_counter()
    if not 1 <= args.n_min < args.n_max:
        raise _fail(f"need 1 <= --n-min < --n-max, got {args.n_min} and {args.n_max}")
    if args.n_steps < 2:
        raise _fail(f"argument --n-steps: must be >= 2, got {args.n_steps}")
    ns = np.unique(np.round(np.geomspace(args.n_min, args.n_max, args.n_steps)).astype(int))
    if ns.shape[0] < 2:  # pragma: no cover - n_min < n_max gives two distinct sizes
        raise _fail("the n range gives fewer than 2 distinct sample sizes")
    kw: dict[str, Any] = {}
    if args.bandwidth is not None:
        kw["bandwidth"] = args.bandwidth
    try:
        res = convergence_study(
            args.function,
            n=ns,
            repetitions=args.repetitions,
            noise=args.noise,
            distribution=args.distribution,
            kernel=args.kernel,
            decay=args.decay,
            rng=np.random.default_rng(args.seed),
            **kw,
        )
    except (TypeError, ValueError) as exc:
        raise _fail(str(exc)) from None
    summary: dict[str, Any] = json_ready(
        {
            "status": "ok",
            "mode": "study",
            **res.summary(),
            "seed": args.seed,
            "wall_time_s": time.perf_counter() - t0,
            "out": None if out is None else str(out),
            "files": [] if out is None else list(STUDY_FILES),
        }
    )
    summary["settings"]["rng"] = f"default_rng({args.seed})"
    if out is not None:
        _write_study(out, res, summary)
    return summary


def _write_study(out: Path, res: ConvergenceResult, summary: dict[str, Any]) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with output_directory(out) as tmp:
        header, table = res.table()
        np.savetxt(
            tmp / "study.csv",
            table,
            fmt="%.10g",
            delimiter=",",
            header=",".join(header),
            comments="",
        )
        fig = Figure(figsize=(6, 4.5), layout="constrained")
        FigureCanvasAgg(fig)
        res.plot(ax=fig.add_subplot())
        fig.savefig(tmp / "study.png", dpi=100)
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


# --------------------------------------------------------------------------- command


_FIT_ONLY = ("x", "y", "grid", "binned", "series", "drop_nan")
_STUDY_ONLY = (
    "function",
    "n_min",
    "n_max",
    "n_steps",
    "repetitions",
    "seed",
    "noise",
    "distribution",
)


_HAMMERSTEIN_ONLY = ("lags", "order", "known", "duration", "torque_sensor")
_STATIC_ONLY = ("kernel", "bandwidth", "decay", "grid", "binned", "series")


def _hammerstein_mode(args: argparse.Namespace) -> tuple[Path | None, Any]:
    """Check the options of ``--hammerstein``; return ``(out, job)``."""
    if args.study:
        raise _fail("give either --hammerstein or --study, not both")
    given = [o for o in (*_STATIC_ONLY, *_STUDY_ONLY) if getattr(args, o) not in (None, False)]
    given = [o for o in given if not (o == "kernel" and args.kernel == "gaussian")]
    given = [o for o in given if not (o == "seed" and args.data is None)]
    if given:
        raise _fail(f"argument --{given[0].replace('_', '-')}: does not apply to --hammerstein")
    if args.data is not None:
        robot = [o for o in ("duration", "torque_sensor") if getattr(args, o) not in (None, False)]
        if robot:
            raise _fail(
                f"argument --{robot[0].replace('_', '-')}: applies to the robot experiment "
                "(--hammerstein without DATA)"
            )
        args.x = "0" if args.x is None else args.x
        args.y = "1" if args.y is None else args.y
    else:
        fit = [o for o in ("x", "y", "drop_nan", "known") if getattr(args, o) not in (None, False)]
        if fit:
            raise _fail(f"argument --{fit[0].replace('_', '-')}: applies to DATA")
    if args.lags is not None and args.lags < 2:
        raise _fail(f"argument --lags: must be >= 2, got {args.lags}")
    out = Path(os.path.abspath(args.out)) if args.out is not None else None
    if out is not None:
        check_out(out, PROG)

    def job() -> Any:
        if args.data is None:
            return _hammerstein.run_robot(args, out)
        x, y, dropped = _read_xy(args)
        return _hammerstein.fit_data(x, y, dropped, args, out)

    return out, job


def _cmd_identify(args: argparse.Namespace) -> int:
    if args.hammerstein:
        out, job = _hammerstein_mode(args)
        try:
            summary = job()
        except OSError as exc:
            print(f"{PROG}: error: cannot write {str(out)!r}: {exc}", file=sys.stderr)
            return EXIT_FAILURE
        if args.json:
            print(json.dumps(summary, indent=2))
        else:
            print(_hammerstein.format_summary(summary))
            if out is not None:
                print(f"  results in {out}: {', '.join(summary['files'])}")
        return 0
    given = [o for o in _HAMMERSTEIN_ONLY if getattr(args, o) not in (None, False)]
    if given:
        raise _fail(f"argument --{given[0].replace('_', '-')}: applies to --hammerstein only")
    if args.study:
        if args.data is not None:
            raise _fail("give either DATA or --study, not both")
        given = [o for o in _FIT_ONLY if getattr(args, o) not in (None, False)]
        if given:
            raise _fail(f"argument --{given[0].replace('_', '-')}: applies to DATA, not --study")
        _study_defaults(args)
    else:
        if args.data is None:
            raise _fail("the following arguments are required: DATA (or --study)")
        given = [o for o in _STUDY_ONLY if getattr(args, o) is not None]
        if given:
            raise _fail(f"argument --{given[0].replace('_', '-')}: applies to --study only")
        args.x = "0" if args.x is None else args.x
        args.y = "1" if args.y is None else args.y
        args.grid = 512 if args.grid is None else args.grid
        if args.grid < 2:
            raise _fail(f"argument --grid: must be >= 2, got {args.grid}")
    out = Path(os.path.abspath(args.out)) if args.out is not None else None
    if out is not None:
        check_out(out, PROG)
    try:
        summary = _study(args, out) if args.study else _fit(args, out)
    except OSError as exc:
        print(f"{PROG}: error: cannot write {str(out)!r}: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(_format(summary))
        if out is not None:
            print(f"  results in {out}: {', '.join(summary['files'])}")
    return 0


def _study_defaults(args: argparse.Namespace) -> None:
    defaults = {
        "function": "smooth",
        "n_min": 250,
        "n_max": 16000,
        "n_steps": 7,
        "repetitions": 20,
        "seed": 0,
        "noise": 0.1,
        "distribution": "uniform",
    }
    for name, value in defaults.items():
        if getattr(args, name) is None:
            setattr(args, name, value)


def _format(summary: dict[str, Any]) -> str:
    if summary["mode"] == "study":
        s = summary["settings"]
        lines = [
            f"{PROG} --study: {s['function']} m, {s['distribution']} inputs, noise {s['noise']:g}, "
            f"{s['kernel']} kernel, h_1 = {s['bandwidth']:g}, decay {s['decay']:.4g}, "
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
    dropped = summary["dropped_nan_rows"]
    lines = [
        f"{PROG}: {summary['n_samples']} samples from {summary['data']} "
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


_DESCRIPTION = """\
Estimate m(x) = E[Y | X = x] nonparametrically (paper section 5, eq. 14: the
semi-recursive kernel estimate with h_i = h_1 i^-decay) from two columns of DATA,
on a grid spanning the inputs; or, with --study, measure its convergence rate by
Monte Carlo (flexarm.ident.convergence_study).
"""

_EPILOG = """\
data: .csv (comma-separated), .npz (1-D arrays named by key, or one 2-D table), or
whitespace-separated text ('#' comments). A first line with a non-numeric cell is
a header. --x and --y take a header name or a 0-based column index (default
columns 0 and 1). Empty cells and 'nan' are NaN: rows with NaN in the chosen
columns are an error unless --drop-nan (the count dropped is reported).

bandwidth: by default h_1 is chosen so that the last sample's bandwidth h_n is
Silverman's rule of thumb 0.9 min(sd, IQR/1.34) n^(-1/5) of the input column
(with the default decay 0.2, h_1 = 0.9 min(sd, IQR/1.34)).

--binned [R]: approximate grid mode with bins R h wide (default R = 0.1; R in
[1e-4, 0.5]; gaussian, epanechnikov or triangular kernel; write --binned=R, or
put DATA first, so that DATA is not taken for R); the summary reports
the proven bound on its error (flexarm.ident.binning). --series (gaussian kernel,
--decay 0): the same sums by a Taylor series (fast Gauss transform), O(n + N)
instead of O(n N) work, equal to the direct sums to rounding.

--study: MISE against n (geometric from --n-min to --n-max) for --function
(smooth, deadzone, saturation, quantizer), --repetitions data sets drawn from
default_rng(--seed); prints the table and the fitted log-log slope beside the
theoretical -2p/(2p+1). --bandwidth, --decay and --kernel apply (defaults 0.3,
1/(2p+1), gaussian).

--hammerstein DATA: HammersteinIdentifier (flexarm.ident) on u = --x, y = --y: the
linear part by the correlation approach (--lags, ARMA --order by BIC by default),
the nonlinearity by eq. 14 -- up to an affine map unless --known gives two points
where it is known (the paper's two-point normalisation). Writes nonlinearity.csv,
impulse_response.csv, hammerstein.png and summary.json; reports the free-run fit.
The correlation approach assumes a white (i.i.d.) input.
--hammerstein without DATA: the robot experiment (paper section IX): a nonlinear
flexible joint driven by a random torque for --duration s (--seed), its stiffness,
friction and drive curves identified and compared with the truth
(flexarm.studies.joint_identification); writes summary.json, curves.npz and
identify_joint.png.

output: with --out DIR (new or empty), DIR receives estimate.csv (x,m),
estimate.png (data and estimate) and summary.json -- or study.csv (n,mise,std),
study.png and summary.json -- all at once, only if everything succeeded.
--json prints the summary on stdout.

exit status: 0 success; 1 the results could not be written; 2 bad input (one
line on stderr, nothing written).
"""


def add_parser(sub: Any) -> None:
    """Add ``identify`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "identify",
        help="nonparametric identification: a static nonlinearity from data, a "
        "Hammerstein model (--hammerstein), or a convergence study (--study)",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("data", nargs="?", metavar="DATA", help="data file (.csv, .npz or text)")
    p.add_argument("--x", metavar="COL", help="input column: name or 0-based index (default 0)")
    p.add_argument("--y", metavar="COL", help="output column: name or index (default 1)")
    p.add_argument("--kernel", choices=KERNELS, default="gaussian", help="default gaussian")
    p.add_argument(
        "--bandwidth", type=float, metavar="H", help="h_1 (units of x; default: see below)"
    )
    p.add_argument(
        "--decay", type=float, metavar="D", help="h_i = h_1 i^-D (default 0.2; study: 1/(2p+1))"
    )
    p.add_argument("--grid", type=int, metavar="N", help="grid points (default 512)")
    p.add_argument(
        "--binned",
        type=float,
        nargs="?",
        const=0.1,
        metavar="R",
        help="approximate binned mode, bins R h wide (default R 0.1)",
    )
    p.add_argument(
        "--series",
        action="store_true",
        help="gaussian with --decay 0: fast series sums (same estimate to rounding)",
    )
    p.add_argument("--drop-nan", action="store_true", help="drop rows with NaN (else an error)")
    p.add_argument("--study", action="store_true", help="run the convergence study instead")
    p.add_argument("--function", choices=tuple(FUNCTIONS), help="study: m (default smooth)")
    p.add_argument("--n-min", type=int, metavar="N", help="study: smallest n (default 250)")
    p.add_argument("--n-max", type=int, metavar="N", help="study: largest n (default 16000)")
    p.add_argument("--n-steps", type=int, metavar="K", help="study: sample sizes (default 7)")
    p.add_argument("--repetitions", type=int, metavar="R", help="study: data sets (default 20)")
    p.add_argument("--seed", type=int, metavar="S", help="study, robot experiment: seed (0)")
    p.add_argument("--noise", type=float, metavar="SIGMA", help="study: noise std (default 0.1)")
    p.add_argument("--distribution", choices=DISTRIBUTIONS, help="study: inputs (default uniform)")
    p.add_argument(
        "--hammerstein",
        action="store_true",
        help="a Hammerstein model of DATA (u = --x, y = --y), or without DATA the "
        "nonlinear-joint robot experiment (see below)",
    )
    p.add_argument("--lags", type=int, metavar="N", help="hammerstein: impulse response (40)")
    p.add_argument(
        "--order",
        type=_hammerstein.parse_order,
        metavar="bic|aic|N",
        help="hammerstein: ARMA order or criterion (default bic)",
    )
    p.add_argument(
        "--known",
        type=_hammerstein.parse_known,
        metavar="X1:PHI1,X2:PHI2",
        help="hammerstein: two points of the nonlinearity (two-point normalisation)",
    )
    p.add_argument(
        "--duration", type=float, metavar="SECONDS", help="robot experiment: record (default 60)"
    )
    p.add_argument(
        "--torque-sensor",
        action="store_true",
        help="robot experiment: a joint torque sensor measures tau_s (default: motor balance)",
    )
    p.add_argument("--out", metavar="DIR", help="write the results into DIR (see below)")
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    p.set_defaults(func=_cmd_identify)
