"""flexarm against Exudyn's geometrically exact ANCF cables: the longer studies.

Run from the repository root (needs ``pip install exudyn``, in the ``test`` extra)::

    python benchmarks/exudyn_study.py              # all studies, tables on stdout
    python benchmarks/exudyn_study.py --only square deflection
    python benchmarks/exudyn_study.py --refine     # the reference's own error
    python benchmarks/exudyn_study.py --json

Studies (``tests/exudyn_models.py`` builds the references, 8 ANCF elements per
link unless ``--refine``):

``square``
    The paper's arm on the default square (quintic timing), joint angles
    prescribed, 20 s: the largest link tip deflection errors (mm) and tip
    position error of every basis — clamped-free and clamped-mass modes, 1, 2, 3
    and 5 per link, geometric stiffening off and on — and the paper's model.
``pulses``
    The paper's arm under torque pulses on both joints (8 and -3 N m), 3 s.
``deflection``
    One link of the paper's arm under torque pulses of growing amplitude: the
    error of flexarm (5 clamped-mass modes, stiffening) as the peak deflection
    grows from 1 % to 30 % of the length — where small-deflection kinematics end.
``spin``
    Kane's spin-up at final rates of 2, 4, 6 and 8 rad/s, stiffening on and off.
``--refine``
    Each test case of ``tests/test_exudyn_oracle.py`` with 8 elements against 16
    elements and a quarter of the step: the reference's discretisation error
    that the tests' tolerances are built on.

Each table gives the wall time of the Exudyn run beside flexarm's (the peer
measured in the same process).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time
import warnings
from typing import Any

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))

import flexarm as fa
from exudyn_models import EXUDYN_MISSING, TorquePulses, run_exudyn
from flexarm.control.trajectories import Square
from flexarm.sim import SimulationError, joint_reference
from flexarm.sim.prescribed import simulate_prescribed
from flexarm.studies.spin_up import KANE_LINK, kane_motion

PAPER = fa.Link(4.5, 1676.0, 0.335)


def _run(arm: fa.FlexibleArm, drive: Any, t: np.ndarray) -> tuple[Any, float]:
    start = time.perf_counter()
    try:
        if isinstance(drive, TorquePulses):
            res = fa.simulate_open_loop(arm, t, drive, substeps=10)
        else:
            res = simulate_prescribed(arm, t, drive, substeps=10)
    except SimulationError:
        return None, time.perf_counter() - start
    return res, time.perf_counter() - start


def _errors(res: Any, ref: Any) -> dict[str, Any]:
    if res is None:
        return {"diverged": True}
    return {
        "deflection_m": np.abs(res.link_deflections - ref.deflection).max(axis=0).tolist(),
        "tip_m": float(np.linalg.norm(res.tip - ref.tip, axis=1).max()),
    }


def square(log: Any) -> dict[str, Any]:
    paper = fa.FlexibleArm.paper()
    sq = Square(timing="quintic")

    def motion(t: np.ndarray) -> Any:
        return joint_reference(paper, sq, np.atleast_1d(t))

    log("square: Exudyn, 20 s ...")
    ref = run_exudyn(paper, motion, t_end=20.0, dt_out=0.01, n_elements=8, step=1e-3)
    out: dict[str, Any] = {
        "exudyn_wall_s": ref.wall_s,
        "peak_deflection_m": np.abs(ref.deflection).max(axis=0).tolist(),
        "cases": [],
    }
    for boundary in ("clamped-free", "clamped-mass"):
        for stiff in (False, True):
            for k in (1, 2, 3, 5):
                arm = paper.with_modes(k, boundary=boundary, geometric_stiffening=stiff)
                res, wall = _run(arm, motion, ref.t)
                row = {"boundary": boundary, "stiffening": stiff, "n_modes": k, "wall_s": wall}
                out["cases"].append(row | _errors(res, ref))
    return out


def pulses(log: Any) -> dict[str, Any]:
    arm = fa.FlexibleArm([PAPER, PAPER])
    drive = TorquePulses((8.0, -3.0), (1.0, 0.7))
    log("pulses: Exudyn, 3 s ...")
    ref = run_exudyn(arm, drive, t_end=3.0, dt_out=0.01, n_elements=8, step=2.5e-4)
    out: dict[str, Any] = {
        "exudyn_wall_s": ref.wall_s,
        "peak_deflection_m": np.abs(ref.deflection).max(axis=0).tolist(),
        "cases": [],
    }
    for boundary in ("clamped-free", "clamped-mass"):
        for stiff in (False, True):
            for k in (1, 2, 3, 5):
                variant = arm.with_modes(k, boundary=boundary, geometric_stiffening=stiff)
                res, wall = _run(variant, drive, ref.t)
                row = {"boundary": boundary, "stiffening": stiff, "n_modes": k, "wall_s": wall}
                out["cases"].append(row | _errors(res, ref))
    return out


def deflection(log: Any) -> dict[str, Any]:
    arm = fa.FlexibleArm([PAPER])
    out: dict[str, Any] = {"cases": []}
    # a 1 s pulse of 5 N m deflects the tip by 17 mm (0.37 % of L); scale the amplitude
    for target in (0.01, 0.05, 0.10, 0.20, 0.30):
        amp = 5.0 * target / 0.0037
        drive = TorquePulses((amp,), (1.0,))
        log(f"deflection: Exudyn, peak about {target:.0%} of L ...")
        ref = run_exudyn(arm, drive, t_end=3.0, dt_out=0.01, n_elements=16, step=2.5e-4)
        peak = float(np.abs(ref.deflection).max())
        row: dict[str, Any] = {"torque_Nm": amp, "peak_over_L": peak / PAPER.length}
        for stiff in (False, True):
            res, _ = _run(arm.with_modes(5, geometric_stiffening=stiff), drive, ref.t)
            err = _errors(res, ref)
            if "deflection_m" in err:
                err["relative"] = err["deflection_m"][0] / peak
            row["stiffening" if stiff else "linear"] = err
        out["cases"].append(row)
    return out


def spin(log: Any) -> dict[str, Any]:
    base = fa.FlexibleArm([KANE_LINK])
    out: dict[str, Any] = {"cases": []}
    for omega in (2.0, 4.0, 6.0, 8.0):
        log(f"spin: Exudyn, Omega = {omega} rad/s ...")
        motion = kane_motion(omega)
        ref = run_exudyn(
            base, motion, t_end=20.0, dt_out=0.02, n_elements=8, step=1e-3, axial_stiffness=(2.8e7,)
        )
        peak = float(np.abs(ref.deflection).max())
        row: dict[str, Any] = {"omega": omega, "peak_m": peak, "exudyn_wall_s": ref.wall_s}
        for stiff in (False, True):
            res, wall = _run(base.with_modes(3, geometric_stiffening=stiff), motion, ref.t)
            err = _errors(res, ref)
            if "deflection_m" in err:
                err["relative"] = err["deflection_m"][0] / peak
            row["stiffening" if stiff else "linear"] = err | {"wall_s": wall}
        out["cases"].append(row)
    return out


def refine(log: Any) -> dict[str, Any]:
    paper = fa.FlexibleArm.paper()
    sq = Square(timing="quintic")

    def square_motion(t: np.ndarray) -> Any:
        return joint_reference(paper, sq, np.atleast_1d(t))

    cases = {
        "one-link": (fa.FlexibleArm([PAPER]), TorquePulses((5.0,), (1.0,)), 3.0, 2.5e-4, {}),
        "one-link-hub": (
            fa.FlexibleArm([fa.Link(4.5, 1676.0, 0.335, hub_inertia=2.0)]),
            TorquePulses((12.0,), (1.0,)),
            3.0,
            2.5e-4,
            {},
        ),
        "two-link": (
            fa.FlexibleArm([PAPER, PAPER]),
            TorquePulses((8.0, -3.0), (1.0, 0.7)),
            3.0,
            2.5e-4,
            {},
        ),
        "spin-slow": (
            fa.FlexibleArm([KANE_LINK]),
            kane_motion(2.0),
            20.0,
            1e-3,
            {"axial_stiffness": (2.8e7,)},
        ),
        "spin-fast": (
            fa.FlexibleArm([KANE_LINK]),
            kane_motion(6.0),
            20.0,
            1e-3,
            {"axial_stiffness": (2.8e7,)},
        ),
        "square": (paper, square_motion, 6.0, 1e-3, {}),
    }
    out: dict[str, Any] = {}
    for name, (arm, drive, t_end, step, kw) in cases.items():
        log(f"refine: {name} ...")
        coarse = run_exudyn(arm, drive, t_end=t_end, dt_out=0.01, n_elements=8, step=step, **kw)
        fine = run_exudyn(arm, drive, t_end=t_end, dt_out=0.01, n_elements=16, step=step / 4, **kw)
        peak = np.abs(fine.deflection).max(axis=0)
        defl = np.abs(coarse.deflection - fine.deflection).max(axis=0) / peak
        tip = np.linalg.norm(coarse.tip - fine.tip, axis=1).max() / peak[-1]
        out[name] = {
            "relative_deflection_error": defl.tolist(),
            "relative_tip_error": float(tip),
            "max": float(max(defl.max(), tip)),
            "wall_s": [coarse.wall_s, fine.wall_s],
        }
    return out


STUDIES = {"square": square, "pulses": pulses, "deflection": deflection, "spin": spin}


def _mm(x: float) -> str:
    return f"{1000 * x:8.2f}"


def print_report(out: dict[str, Any]) -> None:
    for name in ("square", "pulses"):
        if name not in out:
            continue
        r = out[name]
        pk = r["peak_deflection_m"]
        print(
            f"\n{name}: Exudyn peak tip deflections {[round(1000 * p, 1) for p in pk]} mm "
            f"(Exudyn {r['exudyn_wall_s']:.1f} s)"
        )
        print(
            f"{'boundary':<13} {'stiff':<6} {'modes':>5} {'link1 mm':>9} {'link2 mm':>9} "
            f"{'tip mm':>8} {'flexarm s':>10}"
        )
        for c in r["cases"]:
            if c.get("diverged"):
                print(f"{c['boundary']:<13} {c['stiffening']!s:<6} {c['n_modes']:>5}  diverged")
                continue
            d = c["deflection_m"]
            print(
                f"{c['boundary']:<13} {c['stiffening']!s:<6} {c['n_modes']:>5} {_mm(d[0]):>9} "
                f"{_mm(d[1]):>9} {_mm(c['tip_m']):>8} {c['wall_s']:>10.2f}"
            )
    if "deflection" in out:
        print("\ndeflection: one link, 5 clamped-mass modes; error over the peak deflection")
        print(f"{'peak / L':>9} {'stiffening':>11} {'linear':>9}")
        for c in out["deflection"]["cases"]:
            on = c["stiffening"].get("relative", float("nan"))
            off = c["linear"].get("relative", float("nan"))
            print(f"{c['peak_over_L']:>9.1%} {on:>11.2%} {off:>9.2%}")
    if "spin" in out:
        print("\nspin: Kane's beam, 3 modes; error over the peak deflection")
        print(f"{'Omega':>6} {'peak m':>8} {'stiffening':>11} {'linear':>10}")
        for c in out["spin"]["cases"]:
            on = c["stiffening"].get("relative")
            off = c["linear"].get("relative")
            off_s = "diverged" if off is None else f"{off:.2%}"
            print(f"{c['omega']:>6} {c['peak_m']:>8.3f} {on:>11.2%} {off_s:>10}")
    if "refine" in out:
        print("\nreference error: 8 elements against 16 and a quarter step, over the peak")
        for k, v in out["refine"].items():
            print(f"  {k:<14} {v['max']:.1e}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", choices=sorted(STUDIES), help="studies to run")
    p.add_argument("--refine", action="store_true", help="the reference's discretisation error")
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args(argv)
    if EXUDYN_MISSING:
        print(EXUDYN_MISSING, file=sys.stderr)
        return 1
    warnings.simplefilter("ignore", DeprecationWarning)

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    out: dict[str, Any] = {}
    if args.refine:
        out["refine"] = refine(log)
    else:
        for name in args.only or sorted(STUDIES):
            out[name] = STUDIES[name](log)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print_report(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
