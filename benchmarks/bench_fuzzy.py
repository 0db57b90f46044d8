"""Evaluations per second of the paper's fuzzy adaptive law, beside scikit-fuzzy.

Run from the repository root::

    python benchmarks/bench_fuzzy.py                    # table
    python benchmarks/bench_fuzzy.py --json             # machine-readable
    python benchmarks/bench_fuzzy.py --repeat 7 --calls 2000000

The system is :func:`flexarm.fuzzy.paper_system` (inputs δ1, δ2 on [-5, 5], nine
rules, MIN / MIN / MAX, centroid), evaluated at inputs drawn uniformly from
[-5, 5]² with a fixed seed. What is timed:

``evaluate_into, compiled loop``
    :func:`flexarm.fuzzy.evaluate_into` (caller-owned scratch, allocated once)
    called ``--calls`` times from a ``@numba.njit`` driver loop, the way the
    fuzzy adaptive controller calls it in the simulation loop. The driver
    cycles through a table of random inputs (the loop's own cost, an index mask
    and a row view, is included).
``evaluate_many, batch``
    :func:`flexarm.fuzzy.evaluate_many` on ``--batch`` rows, called from Python.
``fls(d1, d2), public call``
    The public vectorised call :meth:`FuzzySystem.__call__` on ``--public-batch``
    points (10**6 by default) with its default backend: the compiled kernel, in
    chunks on every core (input checks, stacking and the threads included).
``fls(d1, d2), NumPy batch``
    The same call with ``backend="numpy"`` (exact integration in NumPy) on
    ``--py-batch`` points (it defuzzifies once per distinct set of rule
    strengths; random inputs make every point distinct).

The peer is scikit-fuzzy's ``skfuzzy.control`` (``ControlSystem`` +
``ControlSystemSimulation``, result cache off) with the same membership
functions (sampled from flexarm's), rules and operators (AND = min, implication
= min, aggregation = max, centroid) on universes of ``--points`` samples; one
evaluation per ``compute()`` call, ``--skfuzzy-calls`` calls per batch. Its
outputs on the timed points are checked against flexarm's exact centroid (the
difference is the discretisation of the output universe).

Every measurement is warmed up first (JIT compilation excluded); each repeat
times a whole batch with ``time.perf_counter_ns``; the table gives the best and
the median of ``--repeat`` batches, per evaluation and as evaluations per second.
"""

from __future__ import annotations

import os

# NumPy's OpenBLAS threads spin for a while after each call into BLAS and take a
# core from the timed loops on a small machine. Set before NumPy is imported; an
# explicit setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np

from _machine import machine_info, print_machine
from flexarm.fuzzy import (
    FuzzySystem,
    evaluate_into,
    evaluate_many,
    paper_system,
    workspace_size,
)

N_INPUTS = 1024  # input rows cycled by the compiled driver (power of two)
SEED = 20261122
LO, HI = -5.0, 5.0  # the inputs' universe (m)
CHECK_TOL_COMPILED = 1e-12  # compiled vs NumPy reference (rounding only)
CHECK_TOL_SKFUZZY = 1e-3  # skfuzzy vs exact centroid (discretisation)
TARGET_NS = 1000.0  # one evaluation in the simulation loop


# -------------------------------------------------------------------- timing
def measure(run_batch: Callable[[], int], repeat: int) -> dict[str, Any]:
    """Call ``run_batch`` (which returns how many evaluations it made) once to warm
    up, then ``repeat`` times under the clock; ns per evaluation, best and median."""
    run_batch()
    per_call = []
    for _ in range(repeat):
        t0 = time.perf_counter_ns()
        n = run_batch()
        per_call.append((time.perf_counter_ns() - t0) / n)
    best, median = min(per_call), statistics.median(per_call)
    return {
        "best_ns": best,
        "median_ns": median,
        "best_evals_per_s": 1e9 / best,
        "median_evals_per_s": 1e9 / median,
        "all_ns": per_call,
        "calls": n,
        "repeat": repeat,
    }


@nb.njit(nogil=True)
def _driver(system, X, n_calls):  # pragma: no cover - compiled
    """``n_calls`` evaluations from compiled code, cycling through the input table."""
    mask = X.shape[0] - 1
    buf = np.empty(workspace_size(system))
    acc = 0.0
    for i in range(n_calls):
        acc += evaluate_into(system, X[i & mask], buf)
    return acc


def bench_compiled_loop(packed: Any, X: np.ndarray, calls: int, repeat: int) -> dict:
    sink = []

    def batch() -> int:
        sink.append(_driver(packed, X, calls))
        return calls

    res = measure(batch, repeat)
    if not np.isfinite(sink[-1]):
        raise RuntimeError("the compiled driver produced a non-finite output")
    return res


def bench_evaluate_many(packed: Any, X: np.ndarray, repeat: int) -> dict:
    def batch() -> int:
        evaluate_many(packed, X)
        return X.shape[0]

    return measure(batch, repeat)


def bench_numpy_batch(fls: FuzzySystem, X: np.ndarray, repeat: int, backend: str) -> dict:
    d1, d2 = X[:, 0].copy(), X[:, 1].copy()

    def batch() -> int:
        fls(d1, d2, backend=backend)
        return X.shape[0]

    return measure(batch, repeat)


# ------------------------------------------------------------------ the peer
def skfuzzy_system(fls: FuzzySystem, points: int) -> tuple[Any, Any]:
    """``fls`` rebuilt with ``skfuzzy.control`` on universes of ``points`` samples:
    every term is flexarm's membership function sampled on its universe, the rules
    are the same; skfuzzy's defaults are AND = min, implication = min (clip),
    aggregation = max, centroid. Returns the system and a simulation (cache off)."""
    from skfuzzy import control as ctrl

    def build(var: Any, kind: Callable[..., Any]) -> Any:
        universe = np.linspace(*var.universe, points)
        sk = kind(universe, var.name)
        for name, mf in var.terms.items():
            sk[name] = mf(universe)
        return sk

    if (fls.and_op, fls.implication, fls.aggregation, fls.defuzzifier) != (
        "min",
        "min",
        "max",
        "centroid",
    ):
        raise ValueError("the skfuzzy peer reproduces only MIN / MIN / MAX / centroid")
    ins = [build(v, ctrl.Antecedent) for v in fls.inputs]
    out = build(fls.output, lambda u, n: ctrl.Consequent(u, n, defuzzify_method="centroid"))
    rules = []
    for rule in fls.rules:
        terms = [var[t] for var, t in zip(ins, rule.antecedent, strict=True) if t is not None]
        ante = terms[0]
        for t in terms[1:]:
            ante = ante & t
        rules.append(ctrl.Rule(ante, out[rule.consequent]))
    system = ctrl.ControlSystem(rules)
    sim = ctrl.ControlSystemSimulation(system, cache=False)
    return system, sim


def skfuzzy_outputs(sim: Any, fls: FuzzySystem, X: np.ndarray) -> np.ndarray:
    names = [v.name for v in fls.inputs]
    out_name = fls.output.name
    y = np.empty(X.shape[0])
    for i, row in enumerate(X):
        for name, v in zip(names, row, strict=True):
            sim.input[name] = float(v)
        sim.compute()
        y[i] = sim.output[out_name]
    return y


def bench_skfuzzy(sim: Any, fls: FuzzySystem, X: np.ndarray, repeat: int) -> dict:
    names = [v.name for v in fls.inputs]
    rows = [[float(v) for v in row] for row in X]

    def batch() -> int:
        for row in rows:
            for name, v in zip(names, row, strict=True):
                sim.input[name] = v
            sim.compute()
        return len(rows)

    return measure(batch, repeat)


# -------------------------------------------------------------------- main
def run(args: argparse.Namespace, log: Callable[[str], None]) -> dict[str, Any]:
    try:
        import skfuzzy
    except ImportError as exc:
        skfuzzy = None
        log(f"scikit-fuzzy not importable ({exc}); skipping the peer (pip install scikit-fuzzy)")

    rng = np.random.default_rng(SEED)
    out: dict[str, Any] = {"machine": machine_info(skfuzzy=skfuzzy), "results": {}, "checks": {}}
    out["settings"] = {
        "calls_compiled_loop": args.calls,
        "batch_evaluate_many": args.batch,
        "batch_numpy": args.py_batch,
        "batch_public": args.public_batch,
        "calls_skfuzzy": args.skfuzzy_calls,
        "skfuzzy_universe_points": args.points,
        "repeat": args.repeat,
        "inputs": f"uniform in [{LO}, {HI}]^2, seed {SEED}",
    }
    res = out["results"]
    fls = paper_system()
    packed = fls.compiled()

    X_loop = rng.uniform(LO, HI, (N_INPUTS, 2))
    X_many = rng.uniform(LO, HI, (args.batch, 2))
    X_py = rng.uniform(LO, HI, (args.py_batch, 2))
    X_public = rng.uniform(LO, HI, (args.public_batch, 2))
    X_sk = rng.uniform(LO, HI, (args.skfuzzy_calls, 2))

    # the compiled path agrees with the NumPy reference
    ref = fls(X_loop[:, 0], X_loop[:, 1], backend="numpy")
    err = float(np.max(np.abs(evaluate_many(packed, X_loop) - ref)))
    out["checks"]["evaluate_many vs fls(d1, d2) (max abs diff)"] = (err, CHECK_TOL_COMPILED)

    log("timing evaluate_into from a compiled loop ...")
    res["flexarm evaluate_into, compiled loop"] = bench_compiled_loop(
        packed, X_loop, args.calls, args.repeat
    )
    log("timing evaluate_many ...")
    res["flexarm evaluate_many, batch"] = bench_evaluate_many(packed, X_many, args.repeat)
    log("timing fls(d1, d2) ...")
    res["flexarm fls(d1, d2), public call"] = bench_numpy_batch(fls, X_public, args.repeat, "auto")
    res["flexarm fls(d1, d2), NumPy batch"] = bench_numpy_batch(fls, X_py, args.repeat, "numpy")

    if skfuzzy is not None:
        log(f"building the skfuzzy system ({args.points} points per universe) ...")
        _, sim = skfuzzy_system(fls, args.points)
        y_sk = skfuzzy_outputs(sim, fls, X_sk)
        y_fa = evaluate_many(packed, X_sk)
        err = float(np.max(np.abs(y_sk - y_fa)))
        out["checks"]["skfuzzy vs flexarm exact centroid (max abs diff)"] = (
            err,
            CHECK_TOL_SKFUZZY,
        )
        log("timing skfuzzy ControlSystemSimulation.compute ...")
        res["skfuzzy compute(), one point per call"] = bench_skfuzzy(sim, fls, X_sk, args.repeat)
        anchor = res["skfuzzy compute(), one point per call"]["best_ns"]
        out["ratios_best"] = {
            f"{label} / skfuzzy": anchor / r["best_ns"]
            for label, r in res.items()
            if label.startswith("flexarm")
        }
    out["machine"]["loadavg_at_end"] = list(os.getloadavg())
    return out


def _fmt(ns: float) -> str:
    if ns >= 1e6:
        return f"{ns / 1e6:.3f} ms"
    return f"{ns / 1000:.3f} µs" if ns >= 1000 else f"{ns:.0f} ns"


def _rate(per_s: float) -> str:
    return f"{per_s:,.0f}"


def print_report(out: dict[str, Any]) -> None:
    m = out["machine"]
    print_machine(m, "skfuzzy", "scikit-fuzzy")
    s = out["settings"]
    print(
        f"evaluations per batch: compiled loop {s['calls_compiled_loop']}, evaluate_many "
        f"{s['batch_evaluate_many']}, NumPy {s['batch_numpy']}, skfuzzy {s['calls_skfuzzy']} "
        f"({s['skfuzzy_universe_points']} points per universe); {s['repeat']} batches"
    )
    print()
    w = 40
    print(f"{'what':<{w}} {'best / eval':>12} {'median / eval':>14} {'best eval/s':>14}")
    print("-" * (w + 43))
    for label, t in out["results"].items():
        print(
            f"{label:<{w}} {_fmt(t['best_ns']):>12} {_fmt(t['median_ns']):>14} "
            f"{_rate(t['best_evals_per_s']):>14}"
        )
    print()
    if "ratios_best" in out:
        print("speed-up over skfuzzy (evaluations/s, best / best):")
        for k, v in out["ratios_best"].items():
            print(f"  {k:<55} {v:10,.0f}x")
    else:
        print("scikit-fuzzy not installed: no ratios")
    print()
    print("checks:")
    for k, (v, tol) in out["checks"].items():
        print(f"  {k:<55} {v:.2e}  {'ok' if v <= tol else 'MISMATCH'} (tol {tol:.0e})")
    print()
    best = out["results"]["flexarm evaluate_into, compiled loop"]["best_ns"]
    print(
        f"target <= 1 µs per evaluation (compiled loop, best): {_fmt(best)}  "
        f"{'met' if best <= TARGET_NS else 'NOT met'}"
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7, help="timed batches per measurement (>= 1)")
    p.add_argument(
        "--calls",
        type=int,
        default=1_000_000,
        help="evaluations per batch in the compiled loop",
    )
    p.add_argument("--batch", type=int, default=100_000, help="rows per evaluate_many call")
    p.add_argument(
        "--public-batch", type=int, default=1_000_000, help="points per public fls(d1, d2) call"
    )
    p.add_argument(
        "--py-batch", type=int, default=10_000, help="points per fls(d1, d2, backend='numpy')"
    )
    p.add_argument(
        "--skfuzzy-calls", type=int, default=500, help="compute() calls per skfuzzy batch"
    )
    p.add_argument(
        "--points", type=int, default=1001, help="samples per universe in the skfuzzy system"
    )
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args(argv)
    if (
        min(
            args.repeat,
            args.calls,
            args.batch,
            args.py_batch,
            args.public_batch,
            args.skfuzzy_calls,
        )
        < 1
    ):
        p.error("--repeat, --calls, --batch, --py-batch and --skfuzzy-calls must be >= 1")
    if args.points < 2:
        p.error("--points must be >= 2")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    out = run(args, log)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print_report(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
