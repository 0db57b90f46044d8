"""Wall time of a calibration: the Quanser rig's stage 1 on its two step runs.

Run from the repository root::

    python benchmarks/bench_calibrate.py                       # table
    python benchmarks/bench_calibrate.py --repeat 5 --json
    python benchmarks/bench_calibrate.py --data DIR            # the rig's files elsewhere

What is timed: ``flexarm.calibrate(examples/quanser_2dsfl/stage1_steps.toml)``
end to end (reading the records, estimating the strain channel's delay, the
identifiability check, the least squares with its forward-difference Jacobians,
the predictions of every record before and after, the confidence intervals): four
parameters (flexural rigidity, tip inertia, damping ratio, the delay) on two
records of 2000 samples each, plus two validation windows. With ``--workers 1``
and with every core (the Jacobian's columns on threads). The target: 10 s or less.
The first run compiles nothing new (the simulator is cached) and is left out.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import flexarm  # noqa: E402
from _machine import machine_info  # noqa: E402
from flexarm.calibration.config import load_config  # noqa: E402

CONFIG = ROOT / "examples" / "quanser_2dsfl" / "stage1_steps.toml"
TARGET_S = 10.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--data", help="directory of the rig's files")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    config = load_config(CONFIG)
    if args.data:
        config = config.with_data(args.data)
    if not (config.root / "lqg_step_10deg_run01.mat").is_file():
        print(f"skipped: the Quanser files are not in {config.root} (--data DIR)")
        return
    flexarm.calibrate(config)  # warm: compile and cache
    rows = {}
    for workers in (1, None):
        times, evaluations = [], 0
        for _ in range(args.repeat):
            start = time.perf_counter()
            cal = flexarm.calibrate(config, workers=workers)
            times.append(time.perf_counter() - start)
            evaluations = cal.fit.evaluations
        label = "1 thread" if workers == 1 else "every core"
        rows[label] = {
            "best_s": min(times),
            "median_s": statistics.median(times),
            "evaluations": evaluations,
            "target_met": min(times) <= TARGET_S and statistics.median(times) <= TARGET_S,
        }
    if args.json:
        print(json.dumps({"machine": machine_info(), "rows": rows}, indent=2, default=str))
        return
    print(f"calibration of {CONFIG.name}: 4 parameters, 2 x 2000 samples (target <= {TARGET_S} s)")
    for label, r in rows.items():
        print(
            f"  {label:>10}: best {r['best_s']:.2f} s, median {r['median_s']:.2f} s, "
            f"{r['evaluations']} evaluations of the residual, target met: {r['target_met']}"
        )


if __name__ == "__main__":
    main()
