"""Start-up cost: ``import flexarm`` and ``flexarm --help``, beside Python and NumPy.

Run from the repository root::

    python benchmarks/bench_import.py            # table
    python benchmarks/bench_import.py --repeat 20 --json

Each figure is the wall time of a fresh interpreter running one statement
(``python -c ...``), so it includes the interpreter's own start-up; the anchors
``pass`` and ``import numpy`` are measured the same way in the same run.

``warm``  bytecode of flexarm already compiled (``__pycache__`` present): what a
          user sees from the second run on. Best and median of ``--repeat`` runs.
``cold``  flexarm's ``__pycache__`` directories removed before each run, so its
          modules are compiled from source (NumPy's own bytecode stays cached):
          what the first run after installing or editing costs.

It also reports which of Numba, SciPy and Matplotlib each statement loaded
(none should: they load on first use).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import statistics
import subprocess
import sys
import time

import _machine

SRC = pathlib.Path(__file__).resolve().parents[1] / "src" / "flexarm"
STATEMENTS = {
    "python -c pass": "pass",
    "import numpy": "import numpy",
    "import flexarm": "import flexarm",
    "flexarm --help": (
        "import sys; sys.argv = ['flexarm', '--help']\n"
        "from flexarm.cli import main\n"
        "try:\n    main()\nexcept SystemExit:\n    pass"
    ),
}
PROBE = (
    "\nimport sys as _s\n"
    "print(sorted(m for m in ('numba', 'scipy', 'matplotlib') if m in _s.modules), file=_s.stderr)"
)


def _clear_bytecode() -> None:
    for cache in SRC.rglob("__pycache__"):
        for f in cache.glob("*.pyc"):
            f.unlink()


def _run(code: str) -> tuple[float, str]:
    start = time.perf_counter()
    res = subprocess.run(
        [sys.executable, "-c", code + PROBE], capture_output=True, text=True, check=True
    )
    return time.perf_counter() - start, res.stderr.strip().splitlines()[-1]


def measure(repeat: int) -> dict[str, dict[str, object]]:
    out: dict[str, dict[str, object]] = {}
    for name, code in STATEMENTS.items():
        _run(code)  # warm-up: bytecode and OS caches
        warm = [_run(code)[0] for _ in range(repeat)]
        cold = []
        for _ in range(max(3, repeat // 4)):
            _clear_bytecode()
            cold.append(_run(code)[0])
        loaded = _run(code)[1]
        out[name] = {
            "warm_best_ms": 1e3 * min(warm),
            "warm_median_ms": 1e3 * statistics.median(warm),
            "cold_best_ms": 1e3 * min(cold),
            "cold_median_ms": 1e3 * statistics.median(cold),
            "heavy_modules_loaded": loaded,
        }
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=12, help="warm runs per statement (default 12)")
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args()
    if shutil.which(sys.executable) is None:  # pragma: no cover
        raise SystemExit("cannot find the interpreter")
    machine = _machine.machine_info()
    res = measure(args.repeat)
    machine["loadavg_at_end"] = list(__import__("os").getloadavg())
    if args.json:
        print(json.dumps({"machine": machine, "results": res}, indent=2))
        return
    _machine.print_machine(machine, "numpy")
    base = res["python -c pass"]
    print(f"{'statement':<18}{'warm best':>11}{'median':>9}{'cold best':>11}{'median':>9}"
          f"{'over python':>13}  loaded")  # fmt: skip
    for name, r in res.items():
        over = float(r["warm_median_ms"]) - float(base["warm_median_ms"])  # type: ignore[arg-type]
        print(
            f"{name:<18}{r['warm_best_ms']:>9.1f}ms{r['warm_median_ms']:>7.1f}ms"
            f"{r['cold_best_ms']:>9.1f}ms{r['cold_median_ms']:>7.1f}ms{over:>11.1f}ms"
            f"  {r['heavy_modules_loaded']}"
        )


if __name__ == "__main__":
    main()
