"""Per-call cost of flexarm's forward dynamics, beside Pinocchio's ``aba``.

Run from the repository root::

    python benchmarks/bench_dynamics.py                 # table
    python benchmarks/bench_dynamics.py --json          # machine-readable
    python benchmarks/bench_dynamics.py --repeat 7 --calls 2000000

What is timed, per arm (rigid two-link, the paper's arm with one and with two
modes per link, with and without flexible joints, and a user-built arm with three
and five clamped-mass modes per link with and without geometric stiffening):

``kernel, compiled loop``
    :func:`flexarm.model.dynamics.forward_dynamics` called ``--calls`` times from a
    compiled driver loop, the way the simulator calls it (inlined, compiled
    without the refcount runtime like :mod:`flexarm.sim.loop`). The driver
    cycles through a table of random states, so every call sees a new state and
    nothing can be hoisted out of the loop; the loop's own cost (an index mask
    and three array views, about 1 ns) is included. Successive calls are
    independent, so the CPU may overlap one call with the next.
``kernel, dependent calls``
    The same, but each call's ``q`` is the table's plus ``1e-300 * qddot`` of the
    previous call (a copy of ``n_dof`` numbers), so a call cannot start before
    the previous one ends, as in the stages of an RK4 step: the latency of a
    call rather than its throughput.
``general kernel, dependent calls`` (two links with one mode each only)
    :func:`flexarm.model.dynamics.forward_dynamics_general`, the kernel every other
    structure takes, on the same states: what the scalar kernel of this
    structure saves.
``kernel, Python call``
    The same kernel called from a Python ``for`` loop with a preallocated
    workspace: Numba's dispatch overhead included.
``arm.forward_dynamics compiled`` / ``numpy``
    The public method with ``backend="compiled"`` (argument checks, a fresh
    workspace per call) and ``backend="numpy"`` (the reference).

The peer is Pinocchio's ``aba`` on the rigid two-link arm with the same
parameters, called from a Python loop exactly like ``kernel, Python call``
(``pip install pin``; skipped with a note if it is not importable).

Every measurement is warmed up first (JIT compilation excluded); each repeat
times a whole batch with ``time.perf_counter_ns``; the table gives the best and
the median of ``--repeat`` batches, in ns per call.
"""

from __future__ import annotations

import os

# NumPy's OpenBLAS threads spin for a while after each call into BLAS and take a
# core from the timed loops on a small machine; none of the matrices here is big
# enough to use them. Set before NumPy is imported; an explicit setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from _machine import machine_info, print_machine
from flexarm import FlexibleArm, Link, MakkarFriction, NonlinearJoint
from flexarm._compile import njit_runtime_free
from flexarm.model import dynamics

N_STATES = 1024  # states cycled by the compiled driver (power of two)
N_PY_STATES = 256  # states cycled by the Python-level loops
SEED = 20261122
CHECK_TOL = 1e-9  # q̈ agreement required of the kernel and of the peer's set-up

LENGTH, EI, RHO = 4.5, 1676.0, 0.335  # the paper's links (Sasiadek et al. 2014)


# ----------------------------------------------------------------------- arms
def make_arms() -> dict[str, FlexibleArm]:
    """The arms measured, keyed by a short label."""
    joints = [NonlinearJoint.default(MakkarFriction.default())] * 2
    return {
        "rigid 2-link (n_dof 2)": FlexibleArm([Link(LENGTH, EI, RHO, n_modes=0)] * 2),
        "paper, 1 mode/link (n_dof 4)": FlexibleArm.paper(),
        "paper, 2 modes/link (n_dof 6)": FlexibleArm.paper(n_modes=2),
        "paper + nonlinear joints, 1 mode/link (n_dof 6)": FlexibleArm.paper(joints=joints),
        "paper + nonlinear joints, 2 modes/link (n_dof 8)": FlexibleArm.paper(
            n_modes=2, joints=joints
        ),
        # the default of an arm a user builds (3 clamped-mass modes, geometric stiffening)
        # beside the same arm without stiffening, and with 5 modes
        "3 clamped-mass modes/link (n_dof 8)": FlexibleArm(
            [Link(LENGTH, EI, RHO, n_modes=3)] * 2, geometric_stiffening=False
        ),
        "3 clamped-mass modes/link, stiffening (n_dof 8)": FlexibleArm(
            [Link(LENGTH, EI, RHO, n_modes=3)] * 2, geometric_stiffening=True
        ),
        "5 clamped-mass modes/link (n_dof 12)": FlexibleArm(
            [Link(LENGTH, EI, RHO, n_modes=5)] * 2, geometric_stiffening=False
        ),
        "5 clamped-mass modes/link, stiffening (n_dof 12)": FlexibleArm(
            [Link(LENGTH, EI, RHO, n_modes=5)] * 2, geometric_stiffening=True
        ),
    }


def random_states(
    arm: FlexibleArm, n: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` random ``(q, dq, tau)`` rows: joint angles in [-pi, pi], joint rates in
    [-2, 2] rad/s, modal coordinates and rates small (a few cm of tip deflection),
    torques in [-5, 5] N m."""
    nl, nd = arm.n_links, arm.n_dof
    q = np.empty((n, nd))
    dq = np.empty((n, nd))
    q[:, :nl] = rng.uniform(-np.pi, np.pi, (n, nl))
    dq[:, :nl] = rng.uniform(-2.0, 2.0, (n, nl))
    q[:, nl:] = rng.uniform(-0.05, 0.05, (n, nd - nl))
    dq[:, nl:] = rng.uniform(-0.5, 0.5, (n, nd - nl))
    if arm.has_flexible_joints:  # motor angles near their links: deflections of mrad
        m = arm.motor_slice
        q[:, m] = q[:, :nl] + rng.uniform(-2e-3, 2e-3, (n, nl))
        dq[:, m] = dq[:, :nl] + rng.uniform(-0.1, 0.1, (n, nl))
    tau = rng.uniform(-5.0, 5.0, (n, nl))
    return q, dq, tau


# -------------------------------------------------------------------- timing
def measure(run_batch: Callable[[], int], repeat: int) -> dict[str, Any]:
    """Call ``run_batch`` (which returns how many dynamics calls it made) once to
    warm up, then ``repeat`` times under the clock; ns per call, best and median."""
    run_batch()
    per_call = []
    for _ in range(repeat):
        t0 = time.perf_counter_ns()
        n = run_batch()
        per_call.append((time.perf_counter_ns() - t0) / n)
    return {
        "best_ns": min(per_call),
        "median_ns": statistics.median(per_call),
        "all_ns": per_call,
        "calls": n,
        "repeat": repeat,
    }


@njit_runtime_free(nogil=True)
def _driver(Q, DQ, TAU, model, ws, ddq, n_calls):  # pragma: no cover - compiled
    """``n_calls`` kernel calls from compiled code, cycling through the state table."""
    mask = Q.shape[0] - 1
    acc = 0.0
    for i in range(n_calls):
        j = i & mask
        dynamics.forward_dynamics(Q[j], DQ[j], TAU[j], model, ws, ddq)
        acc += ddq[0]
    return acc


def _make_chained_driver(kernel: Any) -> Any:
    """A driver of dependent calls of ``kernel``: each call's ``q`` depends on the
    previous call's ``qddot``."""

    @njit_runtime_free(nogil=True)
    def driver(Q, DQ, TAU, model, ws, ddq, qs, n_calls):  # pragma: no cover - compiled
        mask = Q.shape[0] - 1
        acc = 0.0
        for i in range(n_calls):
            j = i & mask
            for r in range(qs.shape[0]):
                qs[r] = Q[j, r] + 1e-300 * ddq[r]
            kernel(qs, DQ[j], TAU[j], model, ws, ddq)
            acc += ddq[0]
        return acc

    return driver


_chained = _make_chained_driver(dynamics.forward_dynamics)
_chained_general = _make_chained_driver(dynamics.forward_dynamics_general)


def bench_compiled_loop(
    arm: FlexibleArm, states: tuple, calls: int, repeat: int, driver: str = "independent"
) -> dict:
    """``calls`` kernel calls per batch from a compiled driver: ``driver`` is
    ``"independent"``, ``"dependent"`` or ``"dependent-general"``."""
    Q, DQ, TAU = states
    model, ws, ddq = arm.arrays, dynamics.make_workspace(arm.n_dof), np.zeros(arm.n_dof)
    qs = np.zeros(arm.n_dof)
    sink = []

    def batch() -> int:
        if driver == "independent":
            sink.append(_driver(Q, DQ, TAU, model, ws, ddq, calls))
        elif driver == "dependent":
            sink.append(_chained(Q, DQ, TAU, model, ws, ddq, qs, calls))
        else:
            sink.append(_chained_general(Q, DQ, TAU, model, ws, ddq, qs, calls))
        return calls

    res = measure(batch, repeat)
    if not np.isfinite(sink[-1]):
        raise RuntimeError("the compiled driver produced a non-finite q̈")
    return res


def _py_rows(states: tuple) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The first ``N_PY_STATES`` states as separate contiguous arrays."""
    Q, DQ, TAU = states
    return [(Q[j].copy(), DQ[j].copy(), TAU[j].copy()) for j in range(N_PY_STATES)]


def bench_python_loop(
    call: Callable[[np.ndarray, np.ndarray, np.ndarray], Any], rows: list, calls: int, repeat: int
) -> dict:
    """``call(q, dq, tau)`` from a plain Python loop over ``rows``, about ``calls`` times."""
    cycles = max(1, calls // len(rows))

    def batch() -> int:
        for _ in range(cycles):
            for q, dq, tau in rows:
                call(q, dq, tau)
        return cycles * len(rows)

    return measure(batch, repeat)


def bench_python_harness(rows: list, calls: int, repeat: int) -> dict:
    """The Python loop alone, calling nothing: the harness's own cost per call."""
    cycles = max(1, calls // len(rows))

    def batch() -> int:
        for _ in range(cycles):
            for _q, _dq, _tau in rows:
                pass
        return cycles * len(rows)

    return measure(batch, repeat)


# ------------------------------------------------------------------ the peer
def pinocchio_rigid_arm(pin: Any) -> tuple[Any, Any]:
    """Pinocchio model of the rigid two-link arm: revolute-z joints, each link a uniform
    rod of length ``LENGTH`` and mass ``RHO * LENGTH`` along its x axis; no gravity."""
    m = RHO * LENGTH
    i_c = m * LENGTH**2 / 12.0  # rod inertia about its centre (y and z axes)
    inertia = pin.Inertia(m, np.array([LENGTH / 2.0, 0.0, 0.0]), np.diag([0.0, i_c, i_c]))
    model = pin.Model()
    model.gravity = pin.Motion.Zero()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "joint1")
    model.appendBodyToJoint(j1, inertia, pin.SE3.Identity())
    at_tip = pin.SE3(np.eye(3), np.array([LENGTH, 0.0, 0.0]))
    j2 = model.addJoint(j1, pin.JointModelRZ(), at_tip, "joint2")
    model.appendBodyToJoint(j2, inertia, pin.SE3.Identity())
    return model, model.createData()


def check_pinocchio(pin: Any, arm: FlexibleArm, model: Any, data: Any, rng) -> float:
    """Largest |q̈_pinocchio - q̈_flexarm| (numpy backend) over a few random states."""
    err = 0.0
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, 2)
        v = rng.uniform(-2.0, 2.0, 2)
        tau = rng.uniform(-5.0, 5.0, 2)
        a_pin = np.asarray(pin.aba(model, data, q, v, tau))
        a_fa = arm.forward_dynamics(q, v, tau, backend="numpy")
        err = max(err, float(np.max(np.abs(a_pin - a_fa))))
    return err


# ----------------------------------------------------------------- machine
# -------------------------------------------------------------------- main
def run(calls: int, repeat: int, log: Callable[[str], None]) -> dict[str, Any]:
    try:
        import pinocchio as pin
    except ImportError as exc:
        pin = None
        log(f"pinocchio not importable ({exc}); skipping the peer (pip install pin)")

    py_calls = max(N_PY_STATES, calls // 20)
    np_calls = max(N_PY_STATES, calls // 500)
    rng = np.random.default_rng(SEED)
    out: dict[str, Any] = {"machine": machine_info(pinocchio=pin), "results": {}, "checks": {}}
    out["settings"] = {
        "calls_compiled_loop": calls,
        "calls_python": py_calls,
        "calls_numpy": np_calls,
        "repeat": repeat,
    }
    res = out["results"]
    arms = make_arms()
    for label, arm in arms.items():
        log(f"timing {label} ...")
        states = random_states(arm, N_STATES, rng)
        rows = _py_rows(states)
        model, ws, ddq = arm.arrays, dynamics.make_workspace(arm.n_dof), np.empty(arm.n_dof)

        # the compiled kernel agrees with the NumPy reference on these states, norm-wise
        # (a small component of a large q̈ carries the rounding of the large ones)
        err = 0.0
        for q0, dq0, tau0 in rows[:16]:
            dynamics.forward_dynamics(q0, dq0, tau0, model, ws, ddq)
            ref = arm.forward_dynamics(q0, dq0, tau0, backend="numpy")
            err = max(err, float(np.max(np.abs(ddq - ref)) / max(1.0, np.max(np.abs(ref)))))
        out["checks"][f"{label}: kernel vs numpy (max rel err)"] = err

        def kernel_call(q, dq, tau, model=model, ws=ws, ddq=ddq):
            dynamics.forward_dynamics(q, dq, tau, model, ws, ddq)

        def method(backend, arm=arm):
            return lambda q, dq, tau: arm.forward_dynamics(q, dq, tau, backend=backend)

        res[label] = {
            "kernel, compiled loop": bench_compiled_loop(arm, states, calls, repeat),
            "kernel, dependent calls": bench_compiled_loop(arm, states, calls, repeat, "dependent"),
            "kernel, Python call": bench_python_loop(kernel_call, rows, py_calls, repeat),
            "arm.forward_dynamics compiled": bench_python_loop(
                method("compiled"), rows, py_calls, repeat
            ),
            "arm.forward_dynamics numpy": bench_python_loop(
                method("numpy"), rows, np_calls, repeat
            ),
        }
        if dynamics.is_two_links_one_mode(model):
            res[label]["general kernel, dependent calls"] = bench_compiled_loop(
                arm, states, calls, repeat, "dependent-general"
            )

    rigid = "rigid 2-link (n_dof 2)"
    log("timing the Python loop harness ...")
    rows = _py_rows(random_states(arms[rigid], N_STATES, rng))
    out["python_harness"] = bench_python_harness(rows, py_calls, repeat)
    if pin is not None:
        log("timing pinocchio aba ...")
        model, data = pinocchio_rigid_arm(pin)
        err = check_pinocchio(pin, arms[rigid], model, data, rng)
        out["checks"]["pinocchio aba vs flexarm rigid numpy (max abs err)"] = err
        aba = pin.aba

        def aba_call(q, v, tau, model=model, data=data):
            aba(model, data, q, v, tau)

        out["pinocchio_aba_rigid"] = bench_python_loop(aba_call, rows, py_calls, repeat)
        anchor = out["pinocchio_aba_rigid"]["best_ns"]
        ratios: dict[str, float] = {}
        for label, r in res.items():
            ratios[f"{label}: compiled loop / aba"] = r["kernel, compiled loop"]["best_ns"] / anchor
            ratios[f"{label}: Python call / aba"] = r["kernel, Python call"]["best_ns"] / anchor
        out["ratios_best"] = ratios
    out["machine"]["loadavg_at_end"] = list(os.getloadavg())
    return out


def _fmt(ns: float) -> str:
    return f"{ns / 1000:.3f} µs" if ns >= 1000 else f"{ns:.0f} ns"


def print_report(out: dict[str, Any]) -> None:
    m = out["machine"]
    print_machine(m, "pinocchio")
    s = out["settings"]
    print(
        f"calls per batch: compiled loop {s['calls_compiled_loop']}, Python "
        f"{s['calls_python']}, numpy {s['calls_numpy']}; {s['repeat']} batches"
    )
    print()
    w = 32
    print(f"{'arm':<{w}} {'what':<31} {'best / call':>12} {'median / call':>14}")
    print("-" * (w + 60))
    for label, r in out["results"].items():
        for what, t in r.items():
            print(f"{label:<{w}} {what:<31} {_fmt(t['best_ns']):>12} {_fmt(t['median_ns']):>14}")
    if "pinocchio_aba_rigid" in out:
        t = out["pinocchio_aba_rigid"]
        name = "rigid 2-link (pinocchio)"
        print(
            f"{name:<{w}} {'pin.aba, Python call':<31} "
            f"{_fmt(t['best_ns']):>12} {_fmt(t['median_ns']):>14}"
        )
    t = out["python_harness"]
    print(
        f"{'(none)':<{w}} {'Python loop harness alone':<31} "
        f"{_fmt(t['best_ns']):>12} {_fmt(t['median_ns']):>14}"
    )
    print()
    if "ratios_best" in out:
        print("ratios (best / best):")
        for k, v in out["ratios_best"].items():
            print(f"  {k:<55} {v:6.2f}")
    else:
        print("pinocchio not installed: no ratios")
    print()
    print(f"checks (tolerance {CHECK_TOL:.0e}):")
    for k, v in out["checks"].items():
        print(f"  {k:<60} {v:.2e}  {'ok' if v <= CHECK_TOL else 'MISMATCH'}")
    print()
    print("target <= 1 µs per call (compiled loop, best):")
    for label, r in out["results"].items():
        if "paper" in label:
            best = r["kernel, compiled loop"]["best_ns"]
            print(f"  {label:<32} {_fmt(best):>10}  {'met' if best <= 1000 else 'NOT met'}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7, help="timed batches per measurement (>= 1)")
    p.add_argument(
        "--calls",
        type=int,
        default=1_000_000,
        help="kernel calls per batch in the compiled loop; Python-level loops make "
        "calls/20 and the numpy backend calls/500",
    )
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args(argv)
    if args.repeat < 1 or args.calls < 1:
        p.error("--repeat and --calls must be >= 1")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    out = run(args.calls, args.repeat, log)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print_report(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
