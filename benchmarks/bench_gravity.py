"""What gravity costs the closed loop: steps per second with it on and off, same process.

Run from the repository root::

    python benchmarks/bench_gravity.py              # table
    python benchmarks/bench_gravity.py --repeat 9   # more repeats
    python benchmarks/bench_gravity.py --json

The scenario is ``bench_simulate.py``'s case A: the paper's arm
(``FlexibleArm.paper()``, two links, one mode each) under the paper's
Jacobian-transpose PD (``JacobianTransposePD.from_arm(arm)``), joint encoders, the
default 20 s square at ``dt = 2e-4`` s (5 kHz, one RK4 step a period). Three
cases, each the same run but for the arm's gravity and the compensation:

``off``
    A horizontal arm (``gravity=None``): no gravity terms at all.
``on, compensated``
    ``gravity=(0, -9.81)`` with ``gravity_compensation=True`` (the built-in laws'
    default): the kernels add the gravity forces at every RK4 stage and the loop
    the holding torques of the measured posture at every control instant
    (:mod:`flexarm.control.gravity_compensation`: a fixed point on the sag).
``on, uncompensated``
    ``gravity=(0, -9.81)``, ``gravity_compensation=False``: the gravity forces in
    the kernels alone.

What is timed is the compiled loop (``result.info["wall_time_s"]``, the set-up
excluded), reported as simulated control steps per second. Every case is warmed up
first (compilation and cache loading excluded); the repeats are interleaved
(off, on, on, off, ...) so that a change of load falls on all three alike; the
table gives the best and the median and the ratio of each gravity case's best time
to the horizontal arm's (target: within 1.2).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as bench_simulate.py: no spinning BLAS

import argparse
import json
import statistics
from typing import Any

import _machine
from flexarm import FlexibleArm
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.trajectories import Square
from flexarm.sim import SimulationError, simulate

GRAVITY = (0.0, -9.81)
DT = 2e-4
TARGET = 1.2  # with gravity / without, loop time

CASES: dict[str, dict[str, Any]] = {
    "off": {"gravity": None, "gravity_compensation": None},
    "on, compensated": {"gravity": GRAVITY, "gravity_compensation": True},
    "on, uncompensated": {"gravity": GRAVITY, "gravity_compensation": False},
}


def run_once(case: dict[str, Any], duration: float | None = None) -> tuple[float, int, str]:
    """One run: ``(loop wall time s, control steps, status)``."""
    arm = FlexibleArm.paper(gravity=case["gravity"])
    law = JacobianTransposePD.from_arm(arm)
    try:
        res = simulate(
            arm,
            law,
            Square(),
            dt=DT,
            duration=duration,
            gravity_compensation=case["gravity_compensation"],
            record_signals=False,
        )
        status = "ok"
    except SimulationError as exc:  # timed all the same, up to where it stopped
        res, status = exc.result, f"diverged at {exc.time:.3g} s"
    return float(res.info["wall_time_s"]), int(res.t.shape[0] - 1), status


def measure(repeat: int) -> dict[str, dict[str, Any]]:
    for case in CASES.values():
        run_once(case, duration=0.05)  # compile / load the cache, design
    samples: dict[str, list[float]] = {name: [] for name in CASES}
    statuses: dict[str, str] = {}
    for r in range(repeat):
        names = list(CASES) if r % 2 == 0 else list(CASES)[::-1]
        for name in names:
            wall, steps, status = run_once(CASES[name])
            samples[name].append(steps / wall)
            statuses[name] = status
    out: dict[str, dict[str, Any]] = {}
    base = max(samples["off"])
    for name, rates in samples.items():
        out[name] = {
            "best_steps_per_s": max(rates),
            "median_steps_per_s": statistics.median(rates),
            "slowdown_best": base / max(rates),
            "slowdown_median": statistics.median(samples["off"]) / statistics.median(rates),
            "all": rates,
            "status": statuses[name],
        }
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=5, help="timed runs per case (default 5)")
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args()
    machine = _machine.machine_info()
    results = measure(args.repeat)
    machine["loadavg_at_end"] = list(os.getloadavg())
    if args.json:
        print(json.dumps({"machine": machine, "target": TARGET, "cases": results}))
        return
    _machine.print_machine(machine, "numpy")
    print(f"closed loop, the paper's arm, JT-PD, 20 s square at {1 / DT:g} Hz; {args.repeat} runs")
    print(f"  {'gravity':<20}{'best steps/s':>14}{'median':>12}{'x best':>8}{'x med':>8}  run")
    for name, s in results.items():
        print(
            f"  {name:<20}{s['best_steps_per_s']:14.4g}{s['median_steps_per_s']:12.4g}"
            f"{s['slowdown_best']:8.3f}{s['slowdown_median']:8.3f}  {s['status']}"
        )
    worst = max(s["slowdown_best"] for s in results.values())
    verdict = "met" if worst <= TARGET else "missed"
    print(f"target: with gravity within {TARGET}x of without (best figures): {verdict}")


if __name__ == "__main__":
    main()
