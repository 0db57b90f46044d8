"""A 1000-run Monte Carlo sweep through ``flexarm sweep``, against one run's time.

Run from the repository root::

    python benchmarks/bench_sweep.py                 # 1000 runs, 3 timed sweeps
    python benchmarks/bench_sweep.py --runs 200 --repeat 2 --json

The sweep is the paper's scenario (``examples/paper_square.toml``: two links, one
mode each, the paper's JT-PD gains, joint encoders, the default square, dt = 0.2
ms) cut to 2 s a run, with encoder noise of 1e-4 rad; the Monte Carlo draws the
noise seed (``simulation.seed``, integers) and the damping ratio of the gains
(``controller.zeta``, uniform on [0.6, 0.8]) for each of ``--runs`` runs.

What is timed, in this one process, after a warm-up (JIT compilation and cache
loading excluded):

``one run``
    A run as the sweep does it, alone on one thread:
    ``Scenario.from_dict(scenario)`` then ``simulate(...)`` and ``metrics()``, for
    ``--single`` runs of the sweep (best and median). ``simulate`` alone is given
    beside it, and the share of the compiled loop (``result.info["wall_time_s"]``),
    the only part that releases the GIL: with a share ``s``, threads on ``c`` cores
    cannot do better than a ratio of about ``c (1 - s)``.
``ideal``
    One run's time x runs / cores: the sweep on every core with no overhead.
``flexarm sweep``
    ``flexarm sweep SWEEP.toml --out DIR --json`` run in this process
    (``flexarm.cli.main``), into a new directory each time: reading and checking
    the sweep, the runs on every core (the default: forked processes on Linux), the
    journal, the CSV and Parquet tables and the summary. Timed ``--repeat`` times;
    then the same with ``--threads`` (threads of this process, the default before).

The ratio is ``flexarm sweep`` / ``ideal`` (best against best, median against
median); the target of issue 14 is 1.2 or less. On a shared machine, run it
when the load is low (the load averages are printed).
"""

from __future__ import annotations

import os

# OpenBLAS threads spin after each BLAS call and take a core from the runs; set
# before NumPy is imported (an explicit setting wins).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import contextlib
import io
import json
import pathlib
import statistics
import sys
import tempfile
import time

import flexarm
from _machine import machine_info, print_machine
from flexarm.cli import main
from flexarm.sim.batch import default_workers
from flexarm.sim.scenario import Scenario
from flexarm.sweeps.spec import load_sweep

ROOT = pathlib.Path(__file__).resolve().parents[1]
SWEEP = """\
[base]
file = "{base}"
simulation.duration = 2.0
sensor.noise_std = 1e-4

[monte_carlo]
n = {runs}
seed = 14
"simulation.seed" = {{ distribution = "integers", low = 0, high = 1000000 }}
"controller.zeta" = {{ distribution = "uniform", low = 0.6, high = 0.8 }}
"""


def one_run(scenario: dict) -> tuple[float, float, float]:
    """Wall time of one run as the sweep does it, of its simulate() alone and of the
    compiled loop inside (which releases the GIL), s."""
    t0 = time.perf_counter()
    sc = Scenario.from_dict(scenario)
    t1 = time.perf_counter()
    res = flexarm.simulate(sc.arm, **sc.simulate_kwargs(), progress=False)
    t2 = time.perf_counter()
    res.metrics()
    t3 = time.perf_counter()
    return t3 - t0, t2 - t1, float(res.info["wall_time_s"])


def time_sweep(
    path: pathlib.Path, out: pathlib.Path, extra: tuple[str, ...] = ()
) -> tuple[float, dict]:
    buf = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(buf):
        status = main(["sweep", str(path), "--out", str(out), "--json", *extra])
    wall = time.perf_counter() - t0
    if status != 0:
        sys.exit(f"flexarm sweep failed with status {status}")
    return wall, json.loads(buf.getvalue())


def _warm() -> float:
    """On a worker: import flexarm and load its Numba cache (a 10 ms run)."""
    t0 = time.perf_counter()
    from flexarm.sweeps.records import run_scenario

    run_scenario({"simulation": {"duration": 0.01}})
    return time.perf_counter() - t0


def time_cluster(
    path: pathlib.Path, workdir: pathlib.Path, args: argparse.Namespace, cores: int
) -> list[float] | None:
    """Wall times of the sweep on a warmed LocalCluster of ``cores`` processes."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        print("dask.distributed is not installed: no LocalCluster row", file=sys.stderr)
        return None
    print(f"timing {args.repeat} sweeps on a LocalCluster ...", file=sys.stderr)
    with (
        LocalCluster(
            n_workers=cores, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0"
        ) as cluster,
        Client(cluster) as client,
    ):
        client.run(_warm)
        extra = ("--scheduler", cluster.scheduler_address)
        return [time_sweep(path, workdir / f"c{k}", extra)[0] for k in range(args.repeat)]


def main_(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=1000, help="runs in the sweep (default 1000)")
    p.add_argument("--repeat", type=int, default=3, help="timed sweeps (default 3)")
    p.add_argument("--single", type=int, default=20, help="runs timed alone (default 20)")
    p.add_argument("--no-cluster", action="store_true", help="skip the LocalCluster row")
    p.add_argument("--json", action="store_true", help="print a JSON dict")
    args = p.parse_args(argv)

    machine = machine_info()
    cores = default_workers()
    with tempfile.TemporaryDirectory() as tmp:
        workdir = pathlib.Path(tmp)
        path = workdir / "sweep.toml"
        base = (ROOT / "examples" / "paper_square.toml").as_posix()
        path.write_text(SWEEP.format(base=base, runs=args.runs))
        spec = load_sweep(path)
        scenarios = [spec.scenario(r.params) for r in spec.runs[: args.single]]
        for sc in scenarios[:3]:  # warm-up: compile or load the cache
            one_run(sc)
        print("timing one run ...", file=sys.stderr)
        singles = [one_run(sc) for sc in scenarios]
        run_times = [s[0] for s in singles]
        sim_times = [s[1] for s in singles]
        loop_share = statistics.median(s[2] / s[0] for s in singles)
        print(f"timing {args.repeat} sweeps of {args.runs} runs ...", file=sys.stderr)
        sweeps = [time_sweep(path, workdir / f"out{k}") for k in range(args.repeat)]
        print(f"timing {args.repeat} sweeps with --threads ...", file=sys.stderr)
        thread_walls = [
            time_sweep(path, workdir / f"p{k}", ("--threads",))[0] for k in range(args.repeat)
        ]
        cluster_walls = None if args.no_cluster else time_cluster(path, workdir, args, cores)
    machine["loadavg_at_end"] = list(os.getloadavg())
    walls = [w for w, _ in sweeps]
    best_run, median_run = min(run_times), statistics.median(run_times)
    ideal_best = best_run * args.runs / cores
    ideal_median = median_run * args.runs / cores
    result = {
        "machine": machine,
        "cores": cores,
        "runs": args.runs,
        "simulated_s_per_run": 2.0,
        "one_run_s": {"best": best_run, "median": median_run},
        "simulate_only_s": {"best": min(sim_times), "median": statistics.median(sim_times)},
        "loop_share": loop_share,
        "ideal_s": {"best": ideal_best, "median": ideal_median},
        "sweep_s": {"best": min(walls), "median": statistics.median(walls), "all": walls},
        "ratio": {
            "best": min(walls) / ideal_best,
            "median": statistics.median(walls) / ideal_median,
        },
        "statuses": {k: sweeps[0][1][k] for k in ("ok", "diverged", "error")},
    }
    result["threads_sweep_s"] = {
        "best": min(thread_walls),
        "median": statistics.median(thread_walls),
        "all": thread_walls,
    }
    result["threads_ratio"] = {
        "best": min(thread_walls) / ideal_best,
        "median": statistics.median(thread_walls) / ideal_median,
    }
    if cluster_walls:
        result["cluster_sweep_s"] = {
            "best": min(cluster_walls),
            "median": statistics.median(cluster_walls),
            "all": cluster_walls,
        }
        result["cluster_ratio"] = {
            "best": min(cluster_walls) / ideal_best,
            "median": statistics.median(cluster_walls) / ideal_median,
        }
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print_machine(machine, "flexarm")
    print(f"\n{args.runs}-run Monte Carlo of the paper's scenario, 2 s a run, on {cores} cores")
    print(f"{'':32}{'best':>10}{'median':>10}")
    rows = [
        ("one run (build + simulate), s", best_run, median_run),
        ("  of which simulate(), s", min(sim_times), statistics.median(sim_times)),
        (f"ideal: run x {args.runs} / {cores}, s", ideal_best, ideal_median),
        ("flexarm sweep, s", min(walls), statistics.median(walls)),
        ("ratio sweep / ideal", result["ratio"]["best"], result["ratio"]["median"]),
    ]
    rows += [
        ("flexarm sweep --threads, s", min(thread_walls), statistics.median(thread_walls)),
        ("ratio --threads / ideal", *result["threads_ratio"].values()),
    ]
    if cluster_walls:
        c = result["cluster_sweep_s"]
        rows += [
            (f"sweep --scheduler ({cores} procs), s", c["best"], c["median"]),
            ("ratio cluster sweep / ideal", *result["cluster_ratio"].values()),
        ]
    for name, best, med in rows:
        print(f"{name:32}{best:>10.3f}{med:>10.3f}")
    print(f"statuses: {result['statuses']}  (target: ratio <= 1.2)")
    print(
        f"the compiled loop (no GIL) is {100 * loop_share:.0f} % of a run (median); the rest "
        f"holds the GIL, so {cores} threads cannot beat a ratio of about "
        f"{max(1.0, cores * (1 - loop_share)):.2f} (processes can)"
    )


if __name__ == "__main__":
    main_()
