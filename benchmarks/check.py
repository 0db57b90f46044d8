"""The headline figures again, in short versions, beside the recorded ones.

Run from the repository root::

    python benchmarks/check.py                    # every row, a table
    python benchmarks/check.py --only fd_vs_aba   # some rows (keys of recorded.toml)
    python benchmarks/check.py --factor 2 --strict
    python benchmarks/check.py --list

Each row of ``benchmarks/recorded.toml`` (the headline table of BENCHMARKS.md,
which the tests keep in agreement with it) is measured again by the function of
the same key below, in a short version where the full script takes minutes
(fewer repeats, the same sizes, so the figure is comparable; a row that needs
missing data or a missing peer is skipped with the reason). Printed per row: the
recorded best and median, the current best and median, the ratio current /
recorded of the best figures, and a flag where the figure slipped: worse than
recorded by more than the row's own ``factor`` (accuracy rows: a few per cent)
or else ``--factor`` (timings; default 1.5, for a shared 2-core machine whose
load moves timings by tens of per cent). "Worse" is larger for a row with
``better = "lower"``, smaller for ``"higher"``.

With ``--strict`` the exit status is 1 when a row slipped (2 for bad options);
without it, 0: the figures are printed, never asserted, and the test suite never
times anything.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import inspect
import json
import math
import pathlib
import statistics
import subprocess
import sys
import time
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
RECORDED = HERE / "recorded.toml"
DEFAULT_FACTOR = 1.5
BETTER = ("lower", "higher")


# ---------------------------------------------------------------- the table
@dataclass(frozen=True)
class Recorded:
    """One recorded headline figure (a table of ``recorded.toml``).

    Attributes
    ----------
    key : str
        The table's name, also the name of its measurement.
    what : str
        The figure in words.
    unit : str
        Its unit ("s", "ns", "m", "x" for a ratio).
    best, median : float
        The recorded best and median (equal for a figure that is not a timing).
    better : {"lower", "higher"}
        Which way is an improvement.
    command : str
        The command that produced the recorded figure.
    factor : float or None
        The row's own slip factor (accuracy rows); None: the ``--factor`` given.
    load : float or None
        The 1-minute load average when it was recorded (timings), if known.
    """

    key: str
    what: str
    unit: str
    best: float
    median: float
    better: str
    command: str
    factor: float | None = None
    load: float | None = None


def parse_recorded(text: str) -> dict[str, Recorded]:
    """The rows of a ``recorded.toml`` text, in order.

    Raises
    ------
    ValueError
        Naming the row and the field that is missing or wrong.
    """
    data = tomllib.loads(text)
    rows: dict[str, Recorded] = {}
    for key, row in data.items():
        if not isinstance(row, Mapping):
            raise ValueError(f"recorded table: {key!r} must be a table. Got {row!r} instead.")
        for field in ("what", "unit", "best", "median", "better", "command"):
            if field not in row:
                raise ValueError(f"recorded table: {key!r} has no {field!r}.")
        known = {"what", "unit", "best", "median", "better", "command", "factor", "load"}
        unknown = set(row) - known
        if unknown:
            raise ValueError(f"recorded table: {key!r} has unknown fields {sorted(unknown)}.")
        if row["better"] not in BETTER:
            raise ValueError(
                f"recorded table: {key!r}: 'better' must be one of {BETTER}. "
                f"Got {row['better']!r} instead."
            )
        values = {f: row[f] for f in ("best", "median", "factor") if f in row}
        for field, value in values.items():
            if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
                raise ValueError(
                    f"recorded table: {key!r}: {field!r} must be a number > 0. "
                    f"Got {value!r} instead."
                )
        if "factor" in row and not row["factor"] >= 1:
            raise ValueError(f"recorded table: {key!r}: 'factor' must be >= 1.")
        load = row.get("load")
        if load is not None and (isinstance(load, bool) or not isinstance(load, int | float)):
            raise ValueError(f"recorded table: {key!r}: 'load' must be a number.")
        rows[key] = Recorded(
            key,
            str(row["what"]),
            str(row["unit"]),
            float(row["best"]),
            float(row["median"]),
            str(row["better"]),
            str(row["command"]),
            None if "factor" not in row else float(row["factor"]),
            None if load is None else float(load),
        )
    return rows


# ------------------------------------------------------------ the comparison
@dataclass(frozen=True)
class Measured:
    """A figure measured now: best and median (equal for a figure that is not a
    timing), or ``skipped`` with the reason."""

    best: float = math.nan
    median: float = math.nan
    skipped: str | None = None
    note: str = ""


@dataclass(frozen=True)
class Comparison:
    """A measured figure against its recorded one.

    Attributes
    ----------
    ratio, median_ratio : float
        Current / recorded, of the best figures and of the medians.
    slip : float
        How much worse than recorded the best figure is (1 or less: not worse):
        ``ratio`` for a row with ``better = "lower"``, ``1 / ratio`` else.
    factor : float
        The slip allowed.
    slipped : bool
        ``slip > factor``.
    """

    ratio: float
    median_ratio: float
    slip: float
    factor: float
    slipped: bool


def compare(recorded: Recorded, measured: Measured, factor: float) -> Comparison:
    """``measured`` against ``recorded`` (the row's own factor, else ``factor``)."""
    allowed = recorded.factor if recorded.factor is not None else factor
    ratio = measured.best / recorded.best
    slip = ratio if recorded.better == "lower" else 1.0 / ratio
    return Comparison(ratio, measured.median / recorded.median, slip, allowed, slip > allowed)


def _fmt(value: float, unit: str) -> str:
    if math.isnan(value):
        return "-"
    if unit == "x":
        return f"{value:.3g}x"
    return f"{value:.4g} {unit}"


def report(
    rows: Mapping[str, Recorded],
    measured: Mapping[str, Measured],
    factor: float,
) -> tuple[list[str], bool]:
    """The printed lines, and whether any row slipped."""
    lines = [
        f"{'row':<28} {'recorded best / median':>26} {'now best / median':>26} {'now/rec':>8}  flag"
    ]
    any_slip = False
    for key, rec in rows.items():
        if key not in measured:
            continue
        m = measured[key]
        was = f"{_fmt(rec.best, rec.unit)} / {_fmt(rec.median, rec.unit)}"
        if m.skipped is not None:
            lines.append(f"{key:<28} {was:>26} {'skipped: ' + m.skipped}")
            continue
        c = compare(rec, m, factor)
        now = f"{_fmt(m.best, rec.unit)} / {_fmt(m.median, rec.unit)}"
        flag = f"SLIPPED (worse by {c.slip:.2f}x > {c.factor:g}x)" if c.slipped else "ok"
        if rec.load is not None:
            flag += f" (recorded at load {rec.load:g})"
        any_slip = any_slip or c.slipped
        lines.append(f"{key:<28} {was:>26} {now:>26} {c.ratio:>8.3f}  {flag}")
        if m.note:
            lines.append(f"{'':<28} {m.note}")
    return lines, any_slip


# ------------------------------------------------------- the short measurements
def _times(fn: Callable[[], Any], repeat: int) -> list[float]:
    """Wall times of ``repeat`` calls of ``fn`` after a warm-up call, s."""
    fn()
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def _best_median(samples: list[float], scale: float = 1.0) -> Measured:
    return Measured(scale * min(samples), scale * statistics.median(samples))


def _python() -> list[str]:
    return [sys.executable, "-m", "flexarm"]


def measure_lqg_tip_rms(repeat: int) -> Measured:
    """RMS tip tracking error of ``flexarm simulate --controller lqg --sensor tip``."""
    out = subprocess.run(
        [*_python(), "simulate", "--controller", "lqg", "--sensor", "tip", "--json"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    rms = float(json.loads(out.stdout)["rms_error_m"])
    return Measured(rms, rms)


def measure_cli_real_time(repeat: int) -> Measured:
    """``flexarm simulate --duration 200 --json`` against ``--duration 20``."""
    from bench_cli import command

    q = command((20.0, 200.0), max(2, repeat), [None])[0]["wall_s"]["real_time_factor"]
    return Measured(q["best"], q["median"])


def measure_kernel_regression(repeat: int) -> Measured:
    """``NadarayaWatson("gaussian", 0.05)`` (defaults) fit + predict, 10**6 -> 512."""
    from bench_ident_scale import GRID, H, chunk_data
    from flexarm.ident import NadarayaWatson

    X, y = chunk_data(2**31, 10**6)
    return _best_median(
        _times(lambda: NadarayaWatson("gaussian", H).fit(X, y).predict(GRID), repeat)
    )


def measure_kernel_vs_statsmodels(repeat: int) -> Measured:
    """``KernelReg.fit`` time / flexarm's Gaussian (series, exact mode), n = 10**5."""
    try:
        from statsmodels.nonparametric.kernel_regression import KernelReg
    except ImportError:
        return Measured(skipped="statsmodels is not installed")
    import numpy as np

    from bench_ident import BANDWIDTH, SEED, make_data
    from flexarm.ident import NadarayaWatson

    X, y = make_data(10**5, np.random.default_rng(SEED))
    grid = np.linspace(0.0, 1.0, 512)
    ours = _times(lambda: NadarayaWatson("gaussian", BANDWIDTH).fit(X, y).predict(grid), repeat)
    extra = {}  # as bench_ident.py: an explicit generator where KernelReg takes one
    if "rng" in inspect.signature(KernelReg).parameters:
        extra["rng"] = np.random.default_rng(SEED)
    peer = _times(
        lambda: KernelReg(y, X, var_type="c", reg_type="lc", bw=[BANDWIDTH], **extra).fit(grid),
        1,
    )
    return Measured(
        min(peer) / min(ours),
        statistics.median(peer) / statistics.median(ours),
        note=f"flexarm {min(ours) * 1e3:.1f} ms, statsmodels {min(peer):.2f} s (best)",
    )


def _fd_and_aba(repeat: int) -> tuple[list[float], list[float]] | str:
    """ns per call of ``arm.forward_dynamics`` and ``pin.aba`` on the rigid two-link
    arm, batches of 256 calls interleaved."""
    try:
        import pinocchio as pin
    except ImportError:
        return "Pinocchio is not installed (pip install pin)"
    import numpy as np

    from bench_dynamics import (
        N_STATES,
        SEED,
        _py_rows,
        make_arms,
        pinocchio_rigid_arm,
        random_states,
    )

    arm = make_arms()["rigid 2-link (n_dof 2)"]
    rows = _py_rows(random_states(arm, N_STATES, np.random.default_rng(SEED)))
    model, data = pinocchio_rigid_arm(pin)
    fd, aba = arm.forward_dynamics, pin.aba

    def aba_call(q, v, tau, model=model, data=data):  # as bench_dynamics.py calls it
        aba(model, data, q, v, tau)

    def batch(call: Callable[..., Any]) -> float:
        t0 = time.perf_counter_ns()
        for q, dq, tau in rows:
            call(q, dq, tau)
        return (time.perf_counter_ns() - t0) / len(rows)

    batch(fd), batch(aba_call)
    ours, peer = [], []
    for _ in range(40 * repeat):
        ours.append(batch(fd))
        peer.append(batch(aba_call))
    return ours, peer


def measure_fd_vs_aba(repeat: int) -> Measured:
    """``arm.forward_dynamics`` / ``pin.aba`` on the rigid two-link arm, same process."""
    got = _fd_and_aba(repeat)
    if isinstance(got, str):
        return Measured(skipped=got)
    ours, peer = got
    return Measured(
        min(ours) / min(peer),
        statistics.median(ours) / statistics.median(peer),
        note=f"forward_dynamics {min(ours):.0f} / {statistics.median(ours):.0f} ns, "
        f"aba {min(peer):.0f} / {statistics.median(peer):.0f} ns (best / median)",
    )


def measure_hammerstein_vs_arx(repeat: int) -> Measured:
    """Validation mean square error of the best linear ARX / of the Hammerstein model
    (``HammersteinIdentifier().fit``'s comparison), n = 10**5."""
    import numpy as np

    from bench_ident import SEED, hammerstein_data
    from flexarm.ident import HammersteinIdentifier

    u, y = hammerstein_data(10**5, np.random.default_rng(SEED))
    c = HammersteinIdentifier().fit(u, y).report_.comparison
    ratio = c.linear_mse / c.model_mse
    return Measured(
        ratio,
        ratio,
        note=f"fit {c.model_fit_percent:.1f} % against {c.linear_fit_percent:.1f} % "
        f"(ARX order {c.linear_order}); winner {c.winner}",
    )


def measure_calibration(repeat: int) -> Measured:
    """``flexarm.calibrate`` of the Quanser rig's stage 1, one thread."""
    import flexarm
    from flexarm.calibration.config import load_config

    config = load_config(ROOT / "examples" / "quanser_2dsfl" / "stage1_steps.toml")
    if not (config.root / "lqg_step_10deg_run01.mat").is_file():
        return Measured(skipped=f"the Quanser files are not in {config.root}")
    return _best_median(_times(lambda: flexarm.calibrate(config, workers=1), max(1, repeat)))


def measure_loop_step(repeat: int) -> Measured:
    """The compiled loop's time per control step, the paper's 20 s square, 5 kHz."""
    from flexarm import FlexibleArm, simulate

    arm = FlexibleArm.paper()
    simulate(arm, duration=0.1)
    steps = []
    for _ in range(max(3, repeat)):
        res = simulate(arm)
        steps.append(float(res.info["wall_time_s"]) / (res.t.shape[0] - 1))
    return _best_median(steps, 1e9)


MEASURES: dict[str, Callable[[int], Measured]] = {
    "lqg_tip_rms": measure_lqg_tip_rms,
    "cli_real_time_factor": measure_cli_real_time,
    "kernel_regression_1e6": measure_kernel_regression,
    "kernel_vs_statsmodels": measure_kernel_vs_statsmodels,
    "fd_vs_aba": measure_fd_vs_aba,
    "hammerstein_vs_arx": measure_hammerstein_vs_arx,
    "calibration": measure_calibration,
    "loop_step": measure_loop_step,
}


# ---------------------------------------------------------------------- main
def main(
    argv: list[str] | None = None,
    measures: Mapping[str, Callable[[int], Measured]] = MEASURES,
    recorded: pathlib.Path = RECORDED,
    out: Callable[[str], None] = print,
) -> int:
    """The command (module docstring); ``measures`` and ``recorded`` for tests."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", metavar="KEY", help="these rows only")
    p.add_argument("--repeat", type=int, default=3, help="timed repeats per row (default 3)")
    p.add_argument(
        "--factor",
        type=float,
        default=DEFAULT_FACTOR,
        help=f"slip allowed for timings, current/recorded (default {DEFAULT_FACTOR})",
    )
    p.add_argument("--strict", action="store_true", help="exit status 1 if a row slipped")
    p.add_argument("--list", action="store_true", help="list the rows and their commands")
    args = p.parse_args(argv)
    if args.repeat < 1 or not args.factor >= 1:
        p.error("--repeat must be >= 1 and --factor >= 1")
    rows = parse_recorded(recorded.read_text(encoding="utf-8"))
    missing = [k for k in rows if k not in measures]
    if missing:
        p.error(f"rows of {recorded.name} without a measurement: {', '.join(missing)}")
    keys = list(rows) if args.only is None else args.only
    unknown = [k for k in keys if k not in rows]
    if unknown:
        p.error(f"unknown rows {', '.join(unknown)}; the rows: {', '.join(rows)}")
    if args.list:
        for key, rec in rows.items():
            out(f"{key:<28} {rec.what}\n{'':<28} recorded by: {rec.command}")
        return 0
    measured: dict[str, Measured] = {}
    for key in keys:
        print(f"measuring {key} ...", file=sys.stderr, flush=True)
        measured[key] = measures[key](args.repeat)
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    lines, slipped = report({k: rows[k] for k in keys}, measured, args.factor)
    out(f"load average at the end {load} (a shared machine moves timings; best figures compared)")
    for line in lines:
        out(line)
    return 1 if slipped and args.strict else 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE))
    sys.exit(main())
