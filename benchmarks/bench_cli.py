"""The command line end to end: what ``flexarm simulate`` adds per simulated second.

Run from the repository root::

    python benchmarks/bench_cli.py                          # table
    python benchmarks/bench_cli.py --repeat 9 --json        # machine-readable
    python benchmarks/bench_cli.py --before /tmp/old-tree   # the same from another tree

What is measured:

``command``
    ``python -m flexarm simulate --duration D --json`` (the default scenario: the
    paper's arm on the square under the paper's PD, the default period 0.2 ms) in a
    fresh process for a short and a long duration (20 s and 200 s by default), the
    two interleaved, ``--repeat`` times each. A process's start (imports, loading
    the compiled kernels) is the same for both, so the difference of the two wall
    times is what the command spends on the extra simulated time: the real-time
    factor ``(long - short) / (wall(long) - wall(short))``, best against best and
    median against median; and each long run against the short run just before
    it (the same moment's load), best and median of those differences. Beside it:
    the compiled loop's own time (the summary's ``run.wall_time_s``) for the same
    difference, and the child processes' user and system CPU time (the system time
    is the kernel's: the pages of the recorded series).
``python``
    ``flexarm.simulate(FlexibleArm.paper(), duration=D)`` and ``result.metrics()``
    in this process for the same two durations (warm), for comparison.
``breakdown`` (``--breakdown``)
    One long run in a fresh interpreter, the way the command does it, step by
    step: the scenario's run (set-up, loop, assembly) and the metrics, with the
    kernel's share (system CPU time) of each.

With ``--before PATH`` the command is timed from the source tree at ``PATH`` too
(``PYTHONPATH=PATH/src``), interleaved with this tree's runs, for a before/after
figure on the same machine load. Timings carry the machine's load: it is recorded.
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
from typing import Any

from _machine import machine_info, print_machine
from flexarm import FlexibleArm, simulate


def summarize(samples: list[float]) -> dict[str, float]:
    return {"best": min(samples), "median": statistics.median(samples), "n": len(samples)}


def _env(src: str | None) -> dict[str, str]:
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = os.path.join(os.path.abspath(src), "src")
    return env


def command_once(duration: float, src: str | None) -> dict[str, float]:
    """One ``flexarm simulate --duration D --json`` in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-m", "flexarm", "simulate", "--duration", str(duration), "--json"],
        capture_output=True,
        text=True,
        check=True,
        env=_env(src),
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = json.loads(out.stdout)
    return {
        "wall_s": wall,
        "loop_s": float(summary["run"]["wall_time_s"]),
        "user_s": after.ru_utime - before.ru_utime,
        "sys_s": after.ru_stime - before.ru_stime,
        "stdout_bytes": float(len(out.stdout)),
    }


def _difference(short: list[dict[str, float]], long: list[dict[str, float]], extra: float) -> Any:
    """Best against best and median against median of ``long - short`` per quantity."""
    out: dict[str, Any] = {}
    for key in ("wall_s", "loop_s", "user_s", "sys_s"):
        a = [r[key] for r in short]
        b = [r[key] for r in long]
        out[key] = {
            "short": summarize(a),
            "long": summarize(b),
            "difference": {
                "best": min(b) - min(a),
                "median": statistics.median(b) - statistics.median(a),
            },
        }
    for key in ("wall_s", "loop_s"):
        d = out[key]["difference"]
        out[key]["real_time_factor"] = {
            "best": extra / d["best"] if d["best"] > 0 else float("inf"),
            "median": extra / d["median"] if d["median"] > 0 else float("inf"),
        }
        # each long run against the short run just before it (the same moment's load)
        paired = [b[key] - a[key] for a, b in zip(short, long, strict=True)]
        out[key]["paired_real_time_factor"] = {
            "best": extra / min(paired) if min(paired) > 0 else float("inf"),
            "median": extra / statistics.median(paired),
        }
    out["stdout_bytes"] = {"short": short[0]["stdout_bytes"], "long": long[0]["stdout_bytes"]}
    return out


def command(durations: tuple[float, float], repeat: int, trees: list[str | None]) -> Any:
    """The command for both durations and every tree, interleaved."""
    runs: dict[str | None, dict[float, list[dict[str, float]]]] = {
        src: {d: [] for d in durations} for src in trees
    }
    for src in trees:  # warm: the compiled kernels' caches, the OS's file cache
        command_once(durations[0], src)
    for _ in range(repeat):
        for src in trees:
            for d in durations:
                runs[src][d].append(command_once(d, src))
    extra = durations[1] - durations[0]
    return [
        {
            "source": src or "this tree",
            "durations_s": list(durations),
            **_difference(runs[src][durations[0]], runs[src][durations[1]], extra),
        }
        for src in trees
    ]


def python_call(durations: tuple[float, float], repeat: int) -> Any:
    """``simulate`` and ``metrics`` in this process, warm, for both durations."""
    arm = FlexibleArm.paper()
    simulate(arm, duration=1.0).metrics()
    walls: dict[float, list[float]] = {d: [] for d in durations}
    for _ in range(repeat):
        for d in durations:
            t0 = time.perf_counter()
            simulate(arm, duration=d).metrics()
            walls[d].append(time.perf_counter() - t0)
    a, b = walls[durations[0]], walls[durations[1]]
    extra = durations[1] - durations[0]
    return {
        "short_s": summarize(a),
        "long_s": summarize(b),
        "real_time_factor": {
            "best": extra / (min(b) - min(a)),
            "median": extra / (statistics.median(b) - statistics.median(a)),
        },
    }


_BREAKDOWN = """
import json, resource, sys, time
from flexarm.sim.scenario import Scenario

def clock():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return time.perf_counter(), r.ru_stime

scenario = Scenario.from_dict({"simulation": {"duration": 1.0}}, source="warm")
scenario.simulate(progress=None).metrics()  # the kernels loaded
scenario = Scenario.from_dict({"simulation": {"duration": float(sys.argv[1])}}, source="x")
w0, s0 = clock()
try:  # as the command runs it: the series it does not print are not recorded
    result = scenario.simulate(progress=None, record_signals=False)
except TypeError:  # (a tree without the setting)
    result = scenario.simulate(progress=None)
w1, s1 = clock()
metrics = result.metrics()
w2, s2 = clock()
text = json.dumps({**metrics, "run": result.info, "settings": scenario.description})
w3, s3 = clock()
loop = float(result.info["wall_time_s"])
print(json.dumps({
    "simulate_s": w1 - w0, "loop_s": loop, "set_up_and_assembly_s": w1 - w0 - loop,
    "simulate_sys_s": s1 - s0, "metrics_s": w2 - w1, "metrics_sys_s": s2 - s1,
    "json_s": w3 - w2,
}))
"""


def breakdown(duration: float, repeat: int, src: str | None) -> Any:
    samples: list[dict[str, float]] = []
    for _ in range(repeat):
        out = subprocess.run(
            [sys.executable, "-c", _BREAKDOWN, str(duration)],
            capture_output=True,
            text=True,
            check=True,
            env=_env(src),
        )
        samples.append(json.loads(out.stdout.strip().splitlines()[-1]))
    return {k: summarize([s[k] for s in samples]) for k in samples[0]}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7)
    p.add_argument("--short", type=float, default=20.0, help="short duration, s (default 20)")
    p.add_argument("--long", type=float, default=200.0, help="long duration, s (default 200)")
    p.add_argument("--before", metavar="PATH", help="a source tree to time the command from too")
    p.add_argument("--breakdown", action="store_true", help="also time the steps of a long run")
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    durations = (args.short, args.long)
    trees: list[str | None] = [None] if args.before is None else [None, args.before]
    out: dict[str, Any] = {"machine": machine_info()}
    out["command"] = command(durations, args.repeat, trees)
    out["python"] = python_call(durations, args.repeat)
    if args.breakdown:
        out["breakdown"] = [
            {"source": src or "this tree", **breakdown(args.long, args.repeat, src)}
            for src in trees
        ]
    out["machine"]["loadavg_at_end"] = list(os.getloadavg())
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_machine(out["machine"], "numpy")
    extra = args.long - args.short
    for c in out["command"]:
        print(
            f"\nflexarm simulate --duration {args.long:g} --json against --duration "
            f"{args.short:g} ({c['source']}; best / median of {args.repeat})"
        )
        for key, label in (("wall_s", "process"), ("loop_s", "loop")):
            q = c[key]
            print(
                f"  {label:<9}{q['short']['best']:7.3f} / {q['short']['median']:.3f} s and "
                f"{q['long']['best']:.3f} / {q['long']['median']:.3f} s: {extra:g} s more in "
                f"{q['difference']['best']:.3f} / {q['difference']['median']:.3f} s, real time "
                f"x{q['real_time_factor']['best']:.0f} / x{q['real_time_factor']['median']:.0f}"
            )
            pq = q["paired_real_time_factor"]
            print(
                f"  {'':<9}each long run against the short run before it: real time "
                f"x{pq['best']:.0f} / x{pq['median']:.0f}"
            )
        for key, label in (("user_s", "user CPU"), ("sys_s", "sys CPU")):
            d = c[key]["difference"]
            print(f"  {label:<9}{d['best']:7.3f} / {d['median']:.3f} s more for the long run")
        b = c["stdout_bytes"]
        print(f"  stdout   {b['short']:.0f} and {b['long']:.0f} bytes")
    py = out["python"]
    print(
        f"\nsimulate() + metrics() in one process, warm: {py['short_s']['best']:.3f} / "
        f"{py['short_s']['median']:.3f} s and {py['long_s']['best']:.3f} / "
        f"{py['long_s']['median']:.3f} s: real time x{py['real_time_factor']['best']:.0f} / "
        f"x{py['real_time_factor']['median']:.0f}"
    )
    for b in out.get("breakdown", []):
        print(f"\none {args.long:g} s run step by step ({b['source']}; best / median, s)")
        for key in b:
            if key != "source":
                print(f"  {key:<24}{b[key]['best']:8.3f} / {b[key]['median']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
