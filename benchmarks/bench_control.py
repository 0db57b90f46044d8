"""Controllers for a distant sensor: the issue's targets, and what the observer costs per step.

Run from the repository root::

    python benchmarks/bench_control.py            # targets table and per-step costs
    python benchmarks/bench_control.py --json

Two measurements:

``targets``
    :func:`flexarm.studies.reproduction.beyond.run_beyond` on the full 20 s square
    (the same runs ``flexarm reproduce`` makes beyond the paper): the chosen LQG per
    physical sensor, its robustness rows, and each target met or not, with the
    linear growth rates of the rows with their own plant.
``per step``
    The compiled loop's wall time per control step (best and median of
    ``--repeat`` runs of 20 s at 5 kHz) for the paper's arm under the paper's
    Jacobian-transpose PD (joint sensor) and under the LQG (tip sensor), side by
    side in one process: what the observer and the gain schedule cost inside the
    loop.
"""

from __future__ import annotations

import argparse
import json
import statistics

import _machine
import flexarm as fa
from flexarm.control.lqg import LQG
from flexarm.sensing.sensors import JointSensor, TipSensor
from flexarm.studies.reproduction.beyond import run_beyond


def per_step(repeat: int) -> dict[str, dict[str, float]]:
    arm = fa.FlexibleArm.paper()
    cases = {"JT-PD, joint sensor": (None, JointSensor()), "LQG, tip sensor": (LQG(), TipSensor())}
    out = {}
    for name, (law, sensor) in cases.items():
        fa.simulate(arm, law, sensor=sensor, smoothing=0.1, duration=0.1)  # warm-up, design
        walls = []
        for _ in range(repeat):
            res = fa.simulate(arm, law, sensor=sensor, smoothing=0.1)
            walls.append(float(res.info["wall_time_s"]) / (res.t.shape[0] - 1))  # type: ignore[arg-type]
        out[name] = {"best_ns": 1e9 * min(walls), "median_ns": 1e9 * statistics.median(walls)}
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=5, help="timed runs per law (default 5)")
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args()
    machine = _machine.machine_info()
    beyond = run_beyond(None, 2e-4, workers=2)
    steps = per_step(args.repeat)
    if args.json:
        print(json.dumps({"machine": machine, "beyond": beyond.summary(), "per_step": steps}))
        return
    _machine.print_machine(machine, "numpy")
    for line in beyond.text_lines():
        print(line)
    print("per control step (compiled loop, 5 kHz, the paper's arm):")
    for name, s in steps.items():
        print(f"  {name:<22}{s['best_ns']:8.0f} ns best {s['median_ns']:8.0f} ns median")


if __name__ == "__main__":
    main()
