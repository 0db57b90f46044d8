"""Wall-clock cost of flexarm's closed-loop simulation, beside SciPy and MuJoCo.

Run from the repository root::

    python benchmarks/bench_simulate.py                  # table
    python benchmarks/bench_simulate.py --json           # machine-readable
    python benchmarks/bench_simulate.py --repeat 7 --scipy-repeat 3 --scipy-horizon 1

The scenario is the paper's: two links with one mode each, Jacobian-transpose PD
with the paper's gains (``JacobianTransposePD.from_arm(arm)``), joint sensor, the
default 20 s square (:class:`flexarm.control.trajectories.Square`), zero-order hold,
one RK4 step per control period (``substeps=1``). Two cases:

``A``  ``simulate(FlexibleArm.paper())`` as the library runs it by default, with
       ``dt = 2e-4`` s (5 kHz control). The paper's arm has no hub inertia; the
       fastest pole of its linearised closed loop is about -1700 rad/s at the
       square's first corner and -4500 rad/s at the two corners farther out, so at
       ``dt = 1e-3`` (1 kHz) the zero-order-hold loop is unstable: it diverges
       after about 2 s (the script checks this and reports it).
``B``  1 kHz control (``dt = 1e-3``) on a variant that is stable there: the paper's
       links with a hub inertia of 3 kg m**2 at both joints (a motor-like assumption
       the paper does not make; fastest pole about -500 rad/s). The gains are the
       same: ``from_arm`` takes them from the clamped-free first mode, which the
       hubs do not change.

What is timed:

``flexarm, simulate() end to end``
    The whole ``simulate(arm, dt=dt)`` call (reference, inverse kinematics,
    allocation, the compiled loop, the result object). Real-time factor =
    simulated time / this wall time.
``flexarm, compiled loop only``
    ``result.info["wall_time_s"]``: the compiled loop inside that call.
``flexarm, loop with a zero-torque controller`` (1 and 2 RK4 substeps)
    The same call with the controller replaced by a trivial zero-torque
    :class:`flexarm.control.controllers.CompiledController` (the arm then stays at rest),
    loop time only, with ``substeps=1`` and ``substeps=2``. The difference of the
    two is one more RK4 step of the plant (four dynamics calls and the divergence
    check) per control period: the plant's share of a step, measured inside the
    library's own loop. The rest of a step (sensing, recording, calling the
    controller through its function pointer) is what is left; the JT-PD law's
    own cost is the JT-PD loop minus the zero-torque loop. These are differences
    of best figures and carry their noise.
``SciPy solve_ivp loop``
    A straightforward SciPy implementation of the same closed loop: a Python loop
    over control instants evaluates the same control law in NumPy
    (``tau = J(theta)' [Kp (x_r - x) + Kd (v_r - v)]``, ``x, v`` from the rigid
    kinematics of the joint angles, zero-order hold) and integrates each control
    period with ``solve_ivp(..., method="RK45")`` (default tolerances), its
    right-hand side calling ``arm.forward_dynamics(q, dq, tau, backend="numpy")``.
    Run over ``--scipy-horizon`` seconds only (it is slow); figures are per
    simulated second. Its RMS tracking error over that horizon is checked against
    flexarm's over the same horizon, so both run the same loop.
``MuJoCo mj_step``
    The per-step anchor: ``mujoco.mj_step(model, data)`` from a Python loop on a
    rigid planar two-link arm (hinges about z, capsule links of 4.5 m with the
    inertia of a uniform rod of 0.335 * 4.5 kg, gravity off, timestep 1e-3), with
    the default (Euler) and the RK4 integrator; also ``mj_step(..., nstep=N)``
    (the loop in C). ``pip install mujoco``; skipped with a note if it is not
    importable.

``first compilation`` (``--compile-time`` only)
    A fresh interpreter with an empty Numba cache (``NUMBA_CACHE_DIR`` set to a
    new temporary directory) imports flexarm and runs a 10 ms ``simulate`` of
    case B: the import, then the first call, which JIT-compiles the simulation
    loop and everything it calls. Timed once.

Every flexarm measurement is warmed up first (JIT compilation and disk-cache
loading excluded) and timed ``--repeat`` times; the table gives the best and the
median. The SciPy loop is timed ``--scipy-repeat`` times after a short warm-up.
"""

from __future__ import annotations

import os

# NumPy's OpenBLAS threads spin for a while after each call into BLAS and take a
# core from the timed loops on a small machine; none of the matrices here is big
# enough to use them. Set before NumPy is imported; an explicit setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np
from scipy.integrate import solve_ivp

from _machine import machine_info, print_machine
from flexarm import FlexibleArm, Link
from flexarm.control.controllers import CompiledController, JacobianTransposePD
from flexarm.control.trajectories import Square
from flexarm.sim import SimulationError, simulate

LENGTH, EI, RHO = 4.5, 1676.0, 0.335  # the paper's links (Sasiadek et al. 2014)
HUB_INERTIA = 3.0  # kg m**2 at both joints in case B (not in the paper)
DT_A, DT_B = 2e-4, 1e-3  # control periods of cases A (library default) and B (1 kHz)
MJ_TIMESTEP = 1e-3
MJ_STEPS = 20_000  # mj_step calls per batch
ERR_TOL = 0.03  # relative agreement required of the SciPy loop's RMS error
CHECK_TOL = 1e-9  # q̈ agreement required of the MuJoCo model with flexarm's rigid arm
TARGET_RTF, TARGET_SCIPY = 1000.0, 100.0  # the targets
SEED = 20261122


# ----------------------------------------------------------------------- arms
def arm_a() -> FlexibleArm:
    """The paper's arm (no hubs)."""
    return FlexibleArm.paper()


def arm_b() -> FlexibleArm:
    """The paper's links with a 3 kg m**2 hub at both joints: stable at 1 kHz. The
    paper's model otherwise (clamped-free modes, no geometric stiffening), as
    ``FlexibleArm.paper()``; an arm built from links defaults to the converged model
    since issue 13, which would time another model."""
    links = [Link(LENGTH, EI, RHO, n_modes=1, hub_inertia=HUB_INERTIA)] * 2
    return FlexibleArm(links, boundary="clamped-free", geometric_stiffening=False)


CASES: dict[str, dict[str, Any]] = {
    "A": {
        "label": "A: paper arm, dt 2e-4 s (5 kHz, library default)",
        "arm": arm_a,
        "dt": DT_A,
    },
    "B": {
        "label": "B: paper links + 3 kg m² hubs, dt 1e-3 s (1 kHz)",
        "arm": arm_b,
        "dt": DT_B,
    },
}


# -------------------------------------------------------------------- timing
def summarize(samples: list[float]) -> dict[str, Any]:
    return {
        "best": min(samples),
        "median": statistics.median(samples),
        "all": samples,
        "repeat": len(samples),
    }


def time_simulate(
    arm: FlexibleArm, dt: float, repeat: int, configs: dict[str, dict[str, Any]]
) -> dict[str, dict[str, Any]]:
    """``simulate(arm, dt=dt, **kwargs)`` for each ``kwargs`` in ``configs``: each once to
    warm up, then ``repeat`` rounds that run every configuration in turn (so a change
    of machine load hits all alike). End-to-end wall time (s) and the compiled loop's
    own (``info["wall_time_s"]``), best and median."""
    for kwargs in configs.values():
        simulate(arm, dt=dt, progress=False, **kwargs)
    total: dict[str, list[float]] = {key: [] for key in configs}
    loop: dict[str, list[float]] = {key: [] for key in configs}
    last = {}
    for _ in range(repeat):
        for key, kwargs in configs.items():
            t0 = time.perf_counter()
            result = simulate(arm, dt=dt, progress=False, **kwargs)
            total[key].append(time.perf_counter() - t0)
            loop[key].append(float(result.info["wall_time_s"]))
            last[key] = result
    return {
        key: {
            "end_to_end_s": summarize(total[key]),
            "loop_s": summarize(loop[key]),
            "sim_time_s": float(res.t[-1]),
            "n_steps": int(res.t.shape[0] - 1),
            "rms_error_m": float(np.sqrt(np.mean(res.error**2))),
            "status": res.info["status"],
        }
        for key, res in last.items()
    }


@nb.njit(nogil=True)
def _zero_torque(t, y, r, params, state, tau):  # pragma: no cover - compiled
    for i in range(tau.shape[0]):
        tau[i] = 0.0


_COMPILE_SCRIPT = f"""
import time
t0 = time.perf_counter()
from flexarm import FlexibleArm, Link
from flexarm.sim import simulate
arm = FlexibleArm([Link({LENGTH}, {EI}, {RHO}, n_modes=1, hub_inertia={HUB_INERTIA})] * 2,
                  boundary="clamped-free", geometric_stiffening=False)
t1 = time.perf_counter()
simulate(arm, dt={DT_B}, duration=0.01, progress=False)
print(t1 - t0, time.perf_counter() - t1)
"""


def time_first_compile() -> dict[str, float]:
    """Import time and first ``simulate`` call (JIT compilation of the loop) of case B's
    arm in a fresh interpreter whose Numba cache is empty, in seconds."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        res = subprocess.run(
            [sys.executable, "-c", _COMPILE_SCRIPT],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
    t_import, t_first = (float(x) for x in res.stdout.split()[-2:])
    return {"import_s": t_import, "first_simulate_s": t_first}


# ------------------------------------------------------------ the SciPy peer
def scipy_closed_loop(arm: FlexibleArm, dt: float, horizon: float) -> dict[str, Any]:
    """The paper's closed loop written straightforwardly with NumPy and ``solve_ivp``:
    JT-PD on the joint angles' rigid kinematics, zero-order hold, RK45 (default
    tolerances) over each control period, the NumPy dynamics in the right-hand side.
    Starts, like :func:`flexarm.simulate`, at rest and undeflected on the
    square's first point (positive elbow)."""
    ctrl = JacobianTransposePD.from_arm(arm)
    kp = float(ctrl.kp) * np.eye(2)
    kd = float(ctrl.kd) * np.eye(2)
    l1, l2 = arm.links[0].length, arm.links[1].length
    n = arm.n_dof
    n_steps = round(horizon / dt)
    t = np.arange(n_steps + 1) * dt
    pos, vel, _ = Square().evaluate(t)
    x = np.zeros(2 * n)
    x[:2] = arm.inverse_kinematics(pos[0], elbow="positive")
    tip = np.empty((n_steps + 1, 2))
    nfev = 0
    t0 = time.perf_counter()
    for k in range(n_steps + 1):
        q, dq = x[:n], x[n:]
        tip[k] = arm.tip_position(q)
        if k == n_steps:
            break
        c1, s1 = math.cos(q[0]), math.sin(q[0])
        c12, s12 = math.cos(q[0] + q[1]), math.sin(q[0] + q[1])
        jac = np.array([[-l1 * s1 - l2 * s12, -l2 * s12], [l1 * c1 + l2 * c12, l2 * c12]])
        p = np.array([l1 * c1 + l2 * c12, l1 * s1 + l2 * s12])
        v = jac @ dq[:2]
        tau = jac.T @ (kp @ (pos[k] - p) + kd @ (vel[k] - v))

        def rhs(_t: float, x: np.ndarray, tau: np.ndarray = tau) -> np.ndarray:
            ddq = arm.forward_dynamics(x[:n], x[n:], tau, backend="numpy")
            return np.concatenate([x[n:], ddq])

        sol = solve_ivp(rhs, (t[k], t[k + 1]), x, method="RK45")
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed at t = {t[k]:.4f} s: {sol.message}")
        x = sol.y[:, -1]
        nfev += sol.nfev
    wall = time.perf_counter() - t0
    err = np.linalg.norm(tip - pos, axis=1)
    return {
        "wall_s": wall,
        "tip": tip,
        "rms_error_m": float(np.sqrt(np.mean(err**2))),
        "nfev_per_period": nfev / n_steps,
        "n_steps": n_steps,
    }


def time_scipy(arm: FlexibleArm, dt: float, horizon: float, repeat: int) -> dict[str, Any]:
    """The SciPy loop over ``horizon`` s, ``repeat`` times after a 10-period warm-up,
    and its agreement with flexarm's ``simulate`` over the same horizon."""
    scipy_closed_loop(arm, dt, 10 * dt)
    walls, run = [], {}
    for _ in range(repeat):
        run = scipy_closed_loop(arm, dt, horizon)
        walls.append(run["wall_s"])
    ref = simulate(arm, dt=dt, duration=horizon, progress=False)
    fa_rms = float(np.sqrt(np.mean(ref.error**2)))
    sim_time = run["n_steps"] * dt
    return {
        "horizon_s": sim_time,
        "wall_s": summarize(walls),
        "wall_per_sim_s": summarize([w / sim_time for w in walls]),
        "nfev_per_period": run["nfev_per_period"],
        "rms_error_m": run["rms_error_m"],
        "flexarm_rms_error_m": fa_rms,
        "rms_rel_diff": abs(run["rms_error_m"] - fa_rms) / fa_rms,
        "max_tip_diff_m": float(np.max(np.abs(run["tip"] - ref.tip))),
    }


# ------------------------------------------------------------- the MuJoCo anchor
def mujoco_xml(integrator: str) -> str:
    """A rigid planar two-link arm: hinges about z, each link a capsule of length
    ``LENGTH`` along its x axis with the inertia of a uniform rod of mass
    ``RHO * LENGTH`` (explicit ``<inertial>``), no gravity, timestep 1 ms."""
    m = RHO * LENGTH
    i_c = m * LENGTH**2 / 12.0
    inertial = f'<inertial pos="{LENGTH / 2} 0 0" mass="{m}" diaginertia="1e-9 {i_c} {i_c}"/>'
    geom = f'<geom type="capsule" fromto="0 0 0 {LENGTH} 0 0" size="0.02"/>'
    return f"""<mujoco model="rigid two-link arm">
  <option timestep="{MJ_TIMESTEP}" gravity="0 0 0" integrator="{integrator}"/>
  <worldbody>
    <body name="link1">
      <joint name="joint1" type="hinge" axis="0 0 1"/>
      {inertial}
      {geom}
      <body name="link2" pos="{LENGTH} 0 0">
        <joint name="joint2" type="hinge" axis="0 0 1"/>
        {inertial}
        {geom}
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="joint1"/>
    <motor joint="joint2"/>
  </actuator>
</mujoco>"""


def check_mujoco(mujoco: Any, model: Any, rng: np.random.Generator) -> float:
    """Largest |q̈_mujoco - q̈_flexarm| (rigid arm, numpy backend) over random states."""
    rigid = FlexibleArm([Link(LENGTH, EI, RHO, n_modes=0)] * 2)
    data = mujoco.MjData(model)
    err = 0.0
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, 2)
        v = rng.uniform(-2.0, 2.0, 2)
        tau = rng.uniform(-5.0, 5.0, 2)
        data.qpos[:], data.qvel[:], data.ctrl[:] = q, v, tau
        mujoco.mj_forward(model, data)
        ref = rigid.forward_dynamics(q, v, tau, backend="numpy")
        err = max(err, float(np.max(np.abs(np.asarray(data.qacc) - ref))))
    return err


def time_mujoco(mujoco: Any, model: Any, repeat: int) -> dict[str, Any]:
    """ns per ``mj_step``: from a Python loop, and with ``nstep`` (loop in C)."""
    data = mujoco.MjData(model)
    data.qvel[:] = [0.3, -0.2]
    data.ctrl[:] = [0.5, -0.5]
    step = mujoco.mj_step

    def py_batch() -> float:
        t0 = time.perf_counter_ns()
        for _ in range(MJ_STEPS):
            step(model, data)
        return (time.perf_counter_ns() - t0) / MJ_STEPS

    def c_batch() -> float:
        t0 = time.perf_counter_ns()
        step(model, data, nstep=MJ_STEPS)
        return (time.perf_counter_ns() - t0) / MJ_STEPS

    py_batch()
    out = {"python_loop_ns": summarize([py_batch() for _ in range(repeat)])}
    try:
        c_batch()
        out["nstep_ns"] = summarize([c_batch() for _ in range(repeat)])
    except TypeError:  # an old binding without nstep
        pass
    if not np.all(np.isfinite(data.qpos)):
        raise RuntimeError("MuJoCo produced a non-finite state")
    return out


# ----------------------------------------------------------------- machine
# -------------------------------------------------------------------- main
def run(
    repeat: int,
    scipy_repeat: int,
    horizon: float,
    log: Callable[[str], None],
    compile_time: bool = False,
) -> dict[str, Any]:
    try:
        import mujoco
    except ImportError as exc:
        mujoco = None
        log(f"mujoco not importable ({exc}); skipping the anchor (pip install mujoco)")

    out: dict[str, Any] = {"machine": machine_info(mujoco=mujoco), "results": {}, "checks": {}}
    out["settings"] = {
        "repeat": repeat,
        "scipy_repeat": scipy_repeat,
        "scipy_horizon_s": horizon,
        "trajectory": "Square() (default: 20 s)",
        "controller": "JacobianTransposePD.from_arm(arm)",
        "sensor": "JointSensor()",
        "substeps": 1,
        "mj_steps_per_batch": MJ_STEPS,
    }

    if compile_time:
        log("timing the first compilation (fresh interpreter, empty Numba cache) ...")
        out["first_compilation"] = time_first_compile()

    # 1 kHz on the paper's arm is unstable: show it rather than assume it
    try:
        simulate(arm_a(), dt=DT_B, progress=False)
        out["paper_arm_at_1kHz"] = "ran to the end"
    except SimulationError as exc:
        out["paper_arm_at_1kHz"] = f"SimulationError at t = {exc.time:.3f} s"
    log(f"paper arm at dt = 1e-3 s: {out['paper_arm_at_1kHz']}")

    for key, case in CASES.items():
        arm, dt = case["arm"](), case["dt"]
        ctrl = JacobianTransposePD.from_arm(arm)
        log(f"timing {case['label']}: flexarm ...")
        r: dict[str, Any] = {
            "label": case["label"],
            "dt_s": dt,
            "gains": {"kp": float(ctrl.kp), "kd": float(ctrl.kd)},
        }
        trivial = CompiledController(_zero_torque, name="zero torque")
        r.update(
            time_simulate(
                arm,
                dt,
                repeat,
                {
                    "flexarm": {},
                    "flexarm_trivial_controller": {"controller": trivial},
                    "flexarm_trivial_controller_2_substeps": {
                        "controller": trivial,
                        "substeps": 2,
                    },
                },
            )
        )
        log(f"timing {case['label']}: SciPy solve_ivp loop over {horizon} s ...")
        r["scipy"] = time_scipy(arm, dt, horizon, scipy_repeat)
        out["results"][key] = r

    if mujoco is not None:
        log("timing MuJoCo mj_step ...")
        mj: dict[str, Any] = {}
        for integrator in ("Euler", "RK4"):
            model = mujoco.MjModel.from_xml_string(mujoco_xml(integrator))
            mj[integrator] = time_mujoco(mujoco, model, repeat)
        out["mujoco"] = mj
        model = mujoco.MjModel.from_xml_string(mujoco_xml("Euler"))
        err = check_mujoco(mujoco, model, np.random.default_rng(SEED))
        out["checks"]["mujoco qacc vs flexarm rigid numpy (max abs err)"] = err

    derive(out)
    out["machine"]["loadavg_at_end"] = list(os.getloadavg())
    return out


def derive(out: dict[str, Any]) -> None:
    """Real-time factors, per-step costs, ratios and the targets (best figures)."""
    for r in out["results"].values():
        fa = r["flexarm"]
        sim, n_steps = fa["sim_time_s"], fa["n_steps"]
        total, loop = fa["end_to_end_s"]["best"], fa["loop_s"]["best"]
        trivial = r["flexarm_trivial_controller"]["loop_s"]["best"]
        trivial2 = r["flexarm_trivial_controller_2_substeps"]["loop_s"]["best"]
        plant = trivial2 - trivial
        sp = r["scipy"]
        d = {
            "rtf_end_to_end": sim / total,
            "rtf_end_to_end_median": sim / fa["end_to_end_s"]["median"],
            "rtf_loop": sim / loop,
            "per_step_ns": {
                "simulate() end to end": total / n_steps * 1e9,
                "compiled loop (JT-PD)": loop / n_steps * 1e9,
                "loop, zero-torque controller, 1 substep": trivial / n_steps * 1e9,
                "loop, zero-torque controller, 2 substeps": trivial2 / n_steps * 1e9,
            },
            "breakdown_per_step_ns": {
                "plant: one RK4 step (2 substeps - 1 substep)": plant / n_steps * 1e9,
                "rest of the loop step (sense, record, control call)": (trivial - plant)
                / n_steps
                * 1e9,
                "JT-PD law over the zero-torque one": (loop - trivial) / n_steps * 1e9,
                "outside the loop (setup, result), per step": (total - loop) / n_steps * 1e9,
            },
            "flexarm_wall_per_sim_s": total / sim,
            "scipy_wall_per_sim_s": sp["wall_per_sim_s"]["best"],
            "scipy_over_flexarm": sp["wall_per_sim_s"]["best"] / (total / sim),
            "scipy_over_flexarm_loop": sp["wall_per_sim_s"]["best"] / (loop / sim),
            "scipy_rtf": 1.0 / sp["wall_per_sim_s"]["best"],
        }
        if "mujoco" in out:
            for integ, m in out["mujoco"].items():
                anchor = m["python_loop_ns"]["best"]
                d[f"loop step / mj_step {integ} (Python loop)"] = loop / n_steps * 1e9 / anchor
        d["targets"] = {
            f"real time x{TARGET_RTF:.0f} (end to end)": d["rtf_end_to_end"] >= TARGET_RTF,
            f"real time x{TARGET_RTF:.0f} (compiled loop only)": d["rtf_loop"] >= TARGET_RTF,
            f"x{TARGET_SCIPY:.0f} faster than SciPy": d["scipy_over_flexarm"] >= TARGET_SCIPY,
        }
        r["derived"] = d
        out["checks"][f"{r['label']}: SciPy vs flexarm RMS error (rel diff)"] = sp["rms_rel_diff"]


# ------------------------------------------------------------------ report
def _t(seconds: float) -> str:
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e6:.1f} µs"


def _ns(ns: float) -> str:
    return f"{ns / 1000:.2f} µs" if abs(ns) >= 1000 else f"{ns:.0f} ns"


def print_report(out: dict[str, Any]) -> None:
    m = out["machine"]
    print_machine(m, "mujoco")
    s = out["settings"]
    print(
        f"flexarm: {s['repeat']} timed runs each (after a warm-up); SciPy loop: "
        f"{s['scipy_repeat']} runs over the first {s['scipy_horizon_s']} s"
    )
    print(f"paper arm at dt = 1e-3 s (1 kHz): {out['paper_arm_at_1kHz']}")
    if "first_compilation" in out:
        c = out["first_compilation"]
        print(
            f"first compilation (empty Numba cache): import {c['import_s']:.1f} s, first "
            f"simulate() of case B {c['first_simulate_s']:.1f} s"
        )
    for r in out["results"].values():
        fa, sp, d = r["flexarm"], r["scipy"], r["derived"]
        print()
        print(
            f"{r['label']}  (Kp {r['gains']['kp']:.2f} N/m, Kd {r['gains']['kd']:.3f} N s/m; "
            f"{fa['n_steps']} control steps, {fa['sim_time_s']:g} s simulated)"
        )
        w = 46
        print(f"  {'what':<{w}} {'best':>10} {'median':>10} {'x real time':>12}")
        print("  " + "-" * (w + 35))
        rows = [
            ("flexarm, simulate() end to end", fa["end_to_end_s"], fa["sim_time_s"]),
            ("flexarm, compiled loop only", fa["loop_s"], fa["sim_time_s"]),
            (
                "flexarm, loop, zero-torque ctrl, 1 substep",
                r["flexarm_trivial_controller"]["loop_s"],
                fa["sim_time_s"],
            ),
            (
                "flexarm, loop, zero-torque ctrl, 2 substeps",
                r["flexarm_trivial_controller_2_substeps"]["loop_s"],
                fa["sim_time_s"],
            ),
            (f"SciPy solve_ivp loop, first {sp['horizon_s']:g} s", sp["wall_s"], sp["horizon_s"]),
        ]
        for name, t, sim in rows:
            print(
                f"  {name:<{w}} {_t(t['best']):>10} {_t(t['median']):>10} {sim / t['best']:>12.1f}"
            )
        print(
            f"  SciPy per simulated second: {_t(sp['wall_per_sim_s']['best'])} (best), "
            f"{_t(sp['wall_per_sim_s']['median'])} (median); "
            f"{sp['nfev_per_period']:.2f} dynamics calls per control period"
        )
        print(
            f"  RMS tracking error over the first {sp['horizon_s']:g} s: SciPy "
            f"{sp['rms_error_m']:.6f} m, flexarm {sp['flexarm_rms_error_m']:.6f} m "
            f"(rel diff {sp['rms_rel_diff']:.1e}; max tip difference "
            f"{sp['max_tip_diff_m']:.1e} m); flexarm over {fa['sim_time_s']:g} s: "
            f"{fa['rms_error_m']:.6f} m"
        )
        print("  per control step (best):")
        for k, v in d["per_step_ns"].items():
            print(f"    {k:<54} {_ns(v):>10}")
        print("  breakdown of a step (best figures, differences):")
        for k, v in d["breakdown_per_step_ns"].items():
            print(f"    {k:<54} {_ns(v):>10}")
        print("  ratios (best):")
        print(f"    {'real-time factor, end to end':<54} {d['rtf_end_to_end']:>10.1f}")
        print(f"    {'real-time factor, compiled loop only':<54} {d['rtf_loop']:>10.1f}")
        print(
            f"    {'SciPy / flexarm (wall per simulated s, end to end)':<54} "
            f"{d['scipy_over_flexarm']:>10.1f}"
        )
        print(
            f"    {'SciPy / flexarm compiled loop only':<54} {d['scipy_over_flexarm_loop']:>10.1f}"
        )
        for k, v in d.items():
            if k.startswith("loop step / mj_step"):
                print(f"    {k:<54} {v:>10.2f}")
        print("  targets:")
        for k, v in d["targets"].items():
            print(f"    {k:<54} {'met' if v else 'NOT met':>10}")
    print()
    if "mujoco" in out:
        print(f"MuJoCo mj_step, rigid two-link arm, timestep {MJ_TIMESTEP:g} s, per step:")
        for integ, mj in out["mujoco"].items():
            t = mj["python_loop_ns"]
            print(
                f"  {integ:<6} mujoco.mj_step from a Python loop   best {_ns(t['best']):>9}  "
                f"median {_ns(t['median']):>9}"
            )
            if "nstep_ns" in mj:
                t = mj["nstep_ns"]
                print(
                    f"  {integ:<6} mujoco.mj_step(nstep={MJ_STEPS}) (C loop) best "
                    f"{_ns(t['best']):>9}  median {_ns(t['median']):>9}"
                )
    else:
        print("MuJoCo not installed: no per-step anchor (pip install mujoco)")
    print()
    print("checks:")
    for k, v in out["checks"].items():
        tol = CHECK_TOL if k.startswith("mujoco") else ERR_TOL
        print(f"  {k:<72} {v:.1e}  {'ok' if v <= tol else 'MISMATCH'}")


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--repeat", type=int, default=7, help="timed runs per flexarm/MuJoCo measurement (>= 1)"
    )
    p.add_argument(
        "--scipy-repeat", type=int, default=3, help="timed runs of the SciPy loop (>= 1)"
    )
    p.add_argument(
        "--scipy-horizon",
        type=float,
        default=1.0,
        help="simulated seconds of the SciPy loop (it takes ~25 s per simulated s in case A)",
    )
    p.add_argument(
        "--compile-time",
        action="store_true",
        help="also time the first compilation in a fresh interpreter with an empty Numba "
        "cache (adds about 30 s)",
    )
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args(argv)
    if args.repeat < 1 or args.scipy_repeat < 1:
        p.error("--repeat and --scipy-repeat must be >= 1")
    if not 0.0 < args.scipy_horizon <= Square().duration:
        p.error(f"--scipy-horizon must be in (0, {Square().duration}] s")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    out = run(args.repeat, args.scipy_repeat, args.scipy_horizon, log, args.compile_time)
    if args.json:
        print(json.dumps(_jsonable(out), indent=2))
    else:
        print_report(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
