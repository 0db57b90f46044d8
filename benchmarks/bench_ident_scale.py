"""Kernel regression at scale: 10**8 samples in bounded memory, and the default fast path.

Run from the repository root (also ``python benchmarks/bench_ident.py --section scale``)::

    python benchmarks/bench_ident_scale.py                  # table
    python benchmarks/bench_ident_scale.py --json           # machine-readable
    python benchmarks/bench_ident_scale.py --n 100000000 --repeat 1 --cluster

What is timed:

Default estimator, exact mode (``--n-default`` = 10**6 samples onto 512 points; target <= 0.2 s)
    ``SemiRecursiveKernelRegression(kernel, bandwidth=0.2, decay=0.2).fit(X, y).predict(grid)``
    with no grid given (the samples are stored; any point can be asked), for the compact
    kernels (epanechnikov, the one named in the target, then uniform and triangular): the
    ``fit`` and the ``predict`` of each run timed apart, best and median of
    ``--repeat-default`` runs after a warm-up (the total's best and median are of the same
    runs). The estimate must equal grid mode's (``grid`` given) bit for bit at every point
    (checked).

Default path (``--n-default`` = 10**6 samples onto 512 points)
    ``X ~ U[0, 1]``, ``y = sin(2 pi X) + 0.1 e``; Gaussian, ``h = 0.05``, one bandwidth:
    ``NadarayaWatson`` and ``SemiRecursiveKernelRegression(decay=0)`` ``fit`` plus
    ``predict`` at 512 points, in exact mode (no grid) and in grid mode, with the
    default ``series="auto"`` (the series) beside ``series=False`` (direct sums, the
    default before). Best and median of ``--repeat-default`` runs after a warm-up;
    the largest difference between the two, relative to ``max |m|``, is printed.

At scale (``--n`` = 10**8 samples, chunks of ``--chunk`` = 2**20)
    Chunk ``k`` is generated from ``default_rng([SEED, k])`` (same formula), so every path
    sees the same samples without holding them. Estimates, on a 512-point grid:
    ``NadarayaWatson("gaussian", 0.05)`` (series mode, by default) and
    ``SemiRecursiveKernelRegression("epanechnikov", 0.05, decay=0.2)`` (grid mode, direct
    sums). Paths: ``fit_chunks`` of a generator; ``fit`` of a Dask array built from the same
    chunks (``da.from_delayed``), threaded scheduler; with ``--cluster``, the same on a
    ``LocalCluster`` (2 worker processes, 1 thread each). Each (estimate, path) runs in a
    fresh process: wall time of the fit (generation included: it is part of streaming 10**8
    samples; the generation alone is timed too), the process's CPU time (this process's
    threads; a cluster's workers are other processes), its peak RSS during the fit
    (``VmHWM``, reset by ``/proc/self/clear_refs`` after the imports and the warm-up) beside
    its RSS before the fit (imports, compiled code), and the peak of ``tracemalloc``
    (allocations made through Python and NumPy; Numba's own are not traced). The estimates
    of every path must equal the generator's bit for bit (checked: the grid sums are
    compared).

The machine has 2 cores shared with other work: the load average is printed.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time
import tracemalloc
from typing import Any

import numpy as np

SEED = 20261122
N_GRID = 512
H = 0.05
NOISE = 0.1
GRID = np.linspace(0.0, 1.0, N_GRID)
ESTIMATES = ("nw-gaussian-series", "semi-epanechnikov-grid")
PATHS = ("generator", "dask-threads", "dask-cluster")


def chunk_data(k: int, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Chunk ``k``: ``X ~ U[0, 1]``, ``y = sin(2 pi X) + NOISE N(0, 1)`` from ``[SEED, k]``."""
    rng = np.random.default_rng([SEED, k])
    X = rng.uniform(0.0, 1.0, size)
    return X, np.sin(2.0 * np.pi * X) + NOISE * rng.standard_normal(size)


def make_estimator(name: str) -> Any:
    from flexarm.ident import NadarayaWatson, SemiRecursiveKernelRegression

    if name == "nw-gaussian-series":
        return NadarayaWatson("gaussian", H, grid=GRID)
    return SemiRecursiveKernelRegression("epanechnikov", H, 0.2, grid=GRID)


def _status_mb(field: str) -> float:
    """``VmRSS`` (now) or ``VmHWM`` (peak since the last reset) of this process, MB."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return float(line.split()[1]) / 1024.0
    except OSError:  # pragma: no cover - not Linux
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _reset_peak() -> None:
    """Reset the peak RSS (``VmHWM``) to the current RSS (Linux: ``clear_refs`` 5)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:  # pragma: no cover - not Linux, or not allowed
        pass


def run_case(estimate: str, path: str, n: int, chunk: int) -> dict[str, Any]:
    """One fit of ``n`` samples (in this process); times, memory and the grid sums."""
    import flexarm.ident.regression.estimators  # noqa: F401 - imports before the baseline RSS

    sizes = [chunk] * (n // chunk) + ([n % chunk] if n % chunk else [])
    warm = make_estimator(estimate).fit_chunks([chunk_data(0, 1000)])  # compile / load caches
    del warm
    client = cluster = None
    if path != "generator":
        import dask
        import dask.array as da

        if path == "dask-cluster":
            import distributed

            cluster = distributed.LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
            )
            client = distributed.Client(cluster)
            client.run(lambda: make_estimator(estimate).fit_chunks([chunk_data(0, 1000)]) and None)
        else:
            dask.config.set(scheduler="threads")
    base_rss = _status_mb("VmRSS")
    _reset_peak()
    tracemalloc.start()
    t0, c0 = time.perf_counter(), time.process_time()
    est = make_estimator(estimate)
    if path == "generator":
        est.fit_chunks(chunk_data(k, s) for k, s in enumerate(sizes))
    else:
        parts = [dask.delayed(chunk_data, pure=True)(k, s) for k, s in enumerate(sizes)]
        X = da.concatenate(
            [da.from_delayed(p[0], (s,), float) for p, s in zip(parts, sizes, strict=True)]
        )
        y = da.concatenate(
            [da.from_delayed(p[1], (s,), float) for p, s in zip(parts, sizes, strict=True)]
        )
        est.fit(X, y)
    m = est.predict(GRID)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    peak_rss = _status_mb("VmHWM")
    _, traced = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    if client is not None:
        client.close()
        cluster.close()
    t0 = time.perf_counter()
    for k, s in enumerate(sizes):
        chunk_data(k, s)
    gen = time.perf_counter() - t0
    return {
        "estimate": estimate,
        "path": path,
        "n": est.n_samples_,
        "wall_s": wall,
        "cpu_s": cpu,
        "generation_only_s": gen,
        "peak_rss_mb": peak_rss,
        "rss_before_fit_mb": base_rss,
        "tracemalloc_peak_mb": traced / 2**20,
        "max_err_vs_sin": float(np.nanmax(np.abs(m - np.sin(2 * np.pi * GRID)))),
        "numerator": est.numerator_.tolist(),
        "denominator": est.denominator_.tolist(),
    }


def in_subprocess(estimate: str, path: str, n: int, chunk: int) -> dict[str, Any]:
    args = [sys.executable, __file__, "--case", estimate, path, "--n", str(n)]
    done = subprocess.run([*args, "--chunk", str(chunk)], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{estimate} / {path} failed:\n{done.stderr[-3000:]}")
    out: dict[str, Any] = json.loads(done.stdout)
    return out


EXACT_H = 0.2  # the default estimator's row: h_1 = 0.2, h_i = 0.2 i**-0.2
EXACT_DECAY = 0.2
EXACT_KERNELS = ("epanechnikov", "uniform", "triangular")
EXACT_TARGET_S = 0.2


def bench_exact(n: int, repeat: int, log) -> dict[str, Any]:
    """The default estimator in exact mode onto 512 points; fit and predict timed apart."""
    from flexarm.ident import SemiRecursiveKernelRegression

    X, y = chunk_data(2**31, n)
    res: dict[str, Any] = {}
    for kernel in EXACT_KERNELS:
        log(f"exact mode: {kernel}, h = {EXACT_H}, decay = {EXACT_DECAY}, n = {n} ...")

        def once(kernel=kernel) -> tuple[float, float, np.ndarray]:
            t0 = time.perf_counter()
            est = SemiRecursiveKernelRegression(kernel, EXACT_H, EXACT_DECAY).fit(X, y)
            t1 = time.perf_counter()
            m = est.predict(GRID)
            return t1 - t0, time.perf_counter() - t1, m

        once()
        runs = [once() for _ in range(repeat)]
        on_grid = SemiRecursiveKernelRegression(kernel, EXACT_H, EXACT_DECAY, grid=GRID)
        m_grid = on_grid.fit(X, y).predict(GRID)
        m = runs[-1][2]
        row: dict[str, Any] = {
            "equal_to_grid_mode_bitwise": bool(np.array_equal(m, m_grid, equal_nan=True)),
            "max_err_vs_sin": float(np.nanmax(np.abs(m - np.sin(2 * np.pi * GRID)))),
        }
        for i, what in enumerate(("fit", "predict")):
            times = [r[i] for r in runs]
            row[what] = {"best_s": min(times), "median_s": statistics.median(times)}
        totals = [r[0] + r[1] for r in runs]
        row["total"] = {"best_s": min(totals), "median_s": statistics.median(totals)}
        res[kernel] = row
    return res


def bench_default(n: int, repeat: int, log) -> dict[str, Any]:
    """10**6 samples onto 512 points: the default (series) beside direct sums."""
    from flexarm.ident import NadarayaWatson, SemiRecursiveKernelRegression

    X, y = chunk_data(2**31, n)
    res: dict[str, Any] = {}
    for label, cls, kw in (
        ("NadarayaWatson", NadarayaWatson, {}),
        ("SemiRecursive decay=0", SemiRecursiveKernelRegression, {"decay": 0.0}),
    ):
        for mode, grid in (("exact", None), ("grid", GRID)):
            out = {}
            for series in ("auto", False):
                log(f"default path: {label}, {mode} mode, series={series!r} ...")

                def once(cls=cls, kw=kw, grid=grid, series=series) -> np.ndarray:
                    est = cls("gaussian", H, grid=grid, series=series, **kw)
                    return est.fit(X, y).predict(GRID)

                once()
                times, m = [], None
                for _ in range(repeat):
                    t0 = time.perf_counter()
                    m = once()
                    times.append(time.perf_counter() - t0)
                out[str(series)] = {
                    "best_s": min(times),
                    "median_s": statistics.median(times),
                    "m": m,
                }
            a, b = out["auto"].pop("m"), out["False"].pop("m")
            out["max_diff_rel"] = float(np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b)))
            out["speedup_best"] = out["False"]["best_s"] / out["auto"]["best_s"]
            res[f"{label}, {mode} mode"] = out
    return res


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=10**8, help="samples of the scale runs")
    p.add_argument("--chunk", type=int, default=2**20, help="samples per generated chunk")
    p.add_argument("--repeat", type=int, default=1, help="runs of each scale case (fresh process)")
    p.add_argument("--n-default", type=int, default=10**6, help="samples of the default path")
    p.add_argument("--repeat-default", type=int, default=5, help="runs of the default path")
    p.add_argument("--cluster", action="store_true", help="also a 2-process LocalCluster")
    p.add_argument("--no-scale", action="store_true", help="only the default path")
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    p.add_argument("--case", nargs=2, metavar=("ESTIMATE", "PATH"), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.case:  # the child process of one scale run
        print(json.dumps(run_case(*args.case, args.n, args.chunk)))
        return 0

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    out: dict[str, Any] = {"loadavg_at_start": list(os.getloadavg()), "settings": vars(args)}
    out["exact_mode"] = bench_exact(args.n_default, args.repeat_default, log)
    out["default_path"] = bench_default(args.n_default, args.repeat_default, log)
    scale: dict[str, Any] = {}
    paths = PATHS if args.cluster else PATHS[:2]
    for estimate in () if args.no_scale else ESTIMATES:
        ref = None
        for path in paths:
            runs = []
            for r in range(args.repeat):
                log(f"scale: {estimate}, {path}, n = {args.n} (run {r + 1}/{args.repeat}) ...")
                runs.append(in_subprocess(estimate, path, args.n, args.chunk))
            sums = (runs[0].pop("numerator"), runs[0].pop("denominator"))
            for extra in runs[1:]:
                extra.pop("numerator"), extra.pop("denominator")
            ref = ref or sums
            walls = [x["wall_s"] for x in runs]
            scale[f"{estimate} / {path}"] = {
                **runs[0],
                "best_s": min(walls),
                "median_s": statistics.median(walls),
                "runs": len(runs),
                "peak_rss_mb": max(x["peak_rss_mb"] for x in runs),
                "equal_to_generator_bitwise": sums == ref,
            }
    out["scale"] = scale
    out["loadavg_at_end"] = list(os.getloadavg())
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(f"load average at start {out['loadavg_at_start']}, at end {out['loadavg_at_end']}")
    print(
        f"\nDefault estimator, exact mode: SemiRecursiveKernelRegression(kernel, {EXACT_H}, "
        f"decay={EXACT_DECAY}).fit(X, y).predict(grid), {args.n_default} samples onto "
        f"{N_GRID} points (best / median of {args.repeat_default}):"
    )
    print(f"{'kernel':<14} {'fit':>17} {'predict':>17} {'total':>17}  target   = grid mode")
    for k, v in out["exact_mode"].items():
        cells = [
            f"{v[w]['best_s'] * 1e3:7.1f} /{v[w]['median_s'] * 1e3:6.1f} ms"
            for w in ("fit", "predict", "total")
        ]
        verdict = "met" if v["total"]["best_s"] <= EXACT_TARGET_S else "NOT met"
        print(
            f"{k:<14} {cells[0]:>17} {cells[1]:>17} {cells[2]:>17}  {verdict:<8} "
            f"{v['equal_to_grid_mode_bitwise']}"
        )
    print(f"\nDefault path: {args.n_default} samples onto {N_GRID} points, Gaussian h = {H}:")
    print(f"{'estimate':<40} {'auto best':>10} {'median':>9} {'direct best':>12} {'median':>9}")
    for k, v in out["default_path"].items():
        a, d = v["auto"], v["False"]
        print(
            f"{k:<40} {a['best_s']:>9.3f}s {a['median_s']:>8.3f}s {d['best_s']:>11.3f}s "
            f"{d['median_s']:>8.3f}s  x{v['speedup_best']:.1f}  diff {v['max_diff_rel']:.1e}"
        )
    if scale:
        print(f"\nAt scale: {args.n} samples in chunks of {args.chunk} onto {N_GRID} points:")
        print(
            f"{'estimate / path':<44} {'best':>8} {'median':>8} {'cpu':>7} {'gen.':>7} "
            f"{'peak RSS':>9} {'before':>8} {'traced':>8}  bitwise"
        )
        for k, v in scale.items():
            print(
                f"{k:<44} {v['best_s']:>7.1f}s {v['median_s']:>7.1f}s {v['cpu_s']:>6.1f}s "
                f"{v['generation_only_s']:>6.1f}s {v['peak_rss_mb']:>6.0f} MB "
                f"{v['rss_before_fit_mb']:>5.0f} MB {v['tracemalloc_peak_mb']:>5.1f} MB  "
                f"{v['equal_to_generator_bitwise']}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
