"""One run and many: set-up share, batched runs on every core, long runs in bounded memory.

Run from the repository root::

    python benchmarks/bench_scale.py                       # table
    python benchmarks/bench_scale.py --json                # machine-readable
    python benchmarks/bench_scale.py --repeat 7 --runs 16 --reproduce

What is measured (the issue's targets in brackets):

``one run``
    ``simulate(FlexibleArm.paper())``: the paper's 20 s square at its default
    period (0.2 ms, 100 001 control instants), end to end; the compiled loop's own
    time (``info["wall_time_s"]``) and the rest (set-up: reference, sampling check,
    allocation; the result's assembly), as a share of the call [set-up <= 10 %;
    end to end >= 300x real time].
``batch``
    ``--runs`` runs of the same scenario with different noise seeds (joint encoders
    with 1e-4 rad of noise): one after another with :func:`flexarm.simulate`, then
    together with :func:`flexarm.simulate_many` on every core. Parallel efficiency =
    serial time / (cores x batch time), best against best and median against
    median [>= 85 %]. The batch's results are checked
    bit for bit against the serial ones.
``long run``
    ``simulate(arm, duration=600, record_every=10)`` in a fresh interpreter: the
    peak of the memory the run allocates (``tracemalloc``), and the process's
    peak resident set (``VmHWM``; ``ru_maxrss``, which Linux carries over from the
    parent across fork and exec, only where ``/proc`` is missing) beside the same
    interpreter's after importing and warming up (the libraries: NumPy, SciPy,
    Numba and LLVM) [<= 250 MB].
``reproduce`` (``--reproduce``)
    ``flexarm reproduce`` (defaults: matrix, sensitivity, converged arm, beyond; and
    with ``--no-converged``, what the trees before issue 13 ran) in a fresh
    interpreter, wall time; with ``--before PATH`` also the same command from
    another source tree (e.g. a worktree of the commit before the batched
    simulator) for the before/after figure.

Every timing is best and median of ``--repeat`` (the batch and reproduce of
fewer, see the output). Timings carry the machine's load: ``uptime`` is recorded.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Any

import numpy as np

from _machine import machine_info, print_machine
from flexarm import FlexibleArm, simulate, simulate_many
from flexarm.sensing.sensors import JointSensor
from flexarm.sim.batch import default_workers

SERIES = ("t", "q", "dq", "tau", "measurement", "reference", "desired", "tip")


def summarize(samples: list[float]) -> dict[str, float]:
    return {"best": min(samples), "median": statistics.median(samples), "n": len(samples)}


def one_run(repeat: int) -> dict[str, Any]:
    arm = FlexibleArm.paper()
    simulate(arm)  # warm: compilation, caches
    total, loop = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = simulate(arm)
        total.append(time.perf_counter() - t0)
        loop.append(float(res.info["wall_time_s"]))
    setup = [t - lp for t, lp in zip(total, loop, strict=True)]
    duration = float(res.t[-1])
    return {
        "end_to_end_s": summarize(total),
        "loop_s": summarize(loop),
        "setup_s": summarize(setup),
        "setup_share": {
            "best": min(s / t for s, t in zip(setup, total, strict=True)),
            "median": statistics.median(s / t for s, t in zip(setup, total, strict=True)),
        },
        "real_time_factor": {
            "best": duration / min(total),
            "median": duration / statistics.median(total),
        },
    }


def batch(runs: int, repeat: int) -> dict[str, Any]:
    arm = FlexibleArm.paper()
    sensor = JointSensor(noise_std=1e-4)
    specs = [{"arm": arm, "sensor": sensor, "rng": seed} for seed in range(runs)]
    workers = default_workers()
    simulate_many(specs[:workers], workers=workers)  # warm
    serial, together = [], []
    alone: list[Any] = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        alone = [simulate(arm, sensor=sensor, rng=seed) for seed in range(runs)]
        serial.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        out = simulate_many(specs, workers=workers)
        together.append(time.perf_counter() - t0)
    same = all(
        np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True)
        for a, b in zip(alone, out, strict=True)
        for k in SERIES
    )
    # best against best, median against median (a ratio per repeat would pair one
    # repeat's noise with another's)
    eff = {
        "best": min(serial) / (workers * min(together)),
        "median": statistics.median(serial) / (workers * statistics.median(together)),
    }
    return {
        "runs": runs,
        "workers": workers,
        "serial_s": summarize(serial),
        "batch_s": summarize(together),
        "efficiency": eff,
        "bit_for_bit": same,
    }


_LONG_RUN = """
import json, resource, time, tracemalloc
import flexarm

def peak_rss():  # this process's own peak (ru_maxrss carries the parent's over fork and exec)
    try:
        with open("/proc/self/status") as f:
            return next(int(l.split()[1]) * 1024 for l in f if l.startswith("VmHWM:"))
    except (OSError, StopIteration):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024

arm = flexarm.FlexibleArm.paper()
flexarm.simulate(arm, duration=0.1)
before = peak_rss()
tracemalloc.start()
t0 = time.perf_counter()
r = flexarm.simulate(arm, duration=600.0, record_every=10)
wall = time.perf_counter() - t0
_, peak = tracemalloc.get_traced_memory()
tracemalloc.stop()
after = peak_rss()
print(json.dumps({"rows": int(r.t.shape[0]), "wall_s": wall, "traced_peak_bytes": peak,
                  "rss_before_run_bytes": before, "rss_peak_bytes": after}))
"""


def long_run() -> dict[str, Any]:
    out = subprocess.run(
        [sys.executable, "-c", _LONG_RUN], capture_output=True, text=True, check=True
    )
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


def reproduce(src: str | None, *options: str) -> dict[str, Any]:
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = os.path.join(src, "src")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run(
            [
                sys.executable,
                "-m",
                "flexarm",
                "reproduce",
                "--out",
                os.path.join(tmp, "r"),
                *options,
            ],
            check=True,
            capture_output=True,
            env=env,
        )
        wall = time.perf_counter() - t0
        return {"wall_s": wall, "source": src or "this tree", "options": " ".join(options)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7)
    p.add_argument("--runs", type=int, default=16, help="runs in the batch")
    p.add_argument("--batch-repeat", type=int, default=7)
    p.add_argument("--reproduce", action="store_true", help="also time flexarm reproduce")
    p.add_argument("--before", metavar="PATH", help="a source tree to time reproduce from too")
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    out: dict[str, Any] = {"machine": machine_info()}
    out["one_run"] = one_run(args.repeat)
    out["batch"] = batch(args.runs, args.batch_repeat)
    out["long_run"] = long_run()
    if args.reproduce:
        # the converged arm (issue 13) came after the batched simulator: without it,
        # this tree runs what the tree before did
        out["reproduce"] = [reproduce(None), reproduce(None, "--no-converged")]
        if args.before:
            out["reproduce"].append(reproduce(args.before))
    out["machine"]["loadavg_at_end"] = list(os.getloadavg())
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_machine(out["machine"], "numpy")
    o = out["one_run"]
    print("\none run: the paper's 20 s square, dt 0.2 ms (best / median)")
    print(
        f"  end to end   {o['end_to_end_s']['best'] * 1e3:8.1f} / "
        f"{o['end_to_end_s']['median'] * 1e3:.1f} ms   "
        f"real time x{o['real_time_factor']['best']:.0f} / x{o['real_time_factor']['median']:.0f}"
    )
    print(f"  loop         {o['loop_s']['best'] * 1e3:8.1f} / {o['loop_s']['median'] * 1e3:.1f} ms")
    print(
        f"  set-up       {o['setup_s']['best'] * 1e3:8.1f} / {o['setup_s']['median'] * 1e3:.1f} ms"
        f"   share {o['setup_share']['best']:.1%} / {o['setup_share']['median']:.1%}"
    )
    b = out["batch"]
    print(f"\nbatch: {b['runs']} runs on {b['workers']} workers (best / median)")
    print(f"  serial       {b['serial_s']['best']:8.3f} / {b['serial_s']['median']:.3f} s")
    print(f"  together     {b['batch_s']['best']:8.3f} / {b['batch_s']['median']:.3f} s")
    print(
        f"  efficiency   {b['efficiency']['best']:8.1%} / {b['efficiency']['median']:.1%}"
        f"   bit for bit: {b['bit_for_bit']}"
    )
    lr = out["long_run"]
    mb = 2**20
    print(f"\nlong run: 600 s, record_every=10: {lr['rows']} rows in {lr['wall_s']:.2f} s")
    print(f"  allocated by the run (tracemalloc peak) {lr['traced_peak_bytes'] / mb:8.1f} MB")
    print(
        f"  resident: {lr['rss_before_run_bytes'] / mb:.1f} MB before the run, "
        f"{lr['rss_peak_bytes'] / mb:.1f} MB peak"
    )
    for r in out.get("reproduce", []):
        print(f"\nflexarm reproduce {r['options']} ({r['source']}): {r['wall_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
