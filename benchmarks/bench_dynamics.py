"""Per-call cost of flexarm's dynamics from compiled code and from Python, beside
Pinocchio; and how the cost grows with the number of links and of modes.

Run from the repository root::

    python benchmarks/bench_dynamics.py                 # both sections, a table
    python benchmarks/bench_dynamics.py --json          # machine-readable
    python benchmarks/bench_dynamics.py --section calls # or: --section growth
    python benchmarks/bench_dynamics.py --repeat 7 --calls 2000000

Section "calls". What is timed, per arm (rigid two-link, the paper's arm with one
and with two modes per link, with and without flexible joints, and a user-built
arm with three and five clamped-mass modes per link with and without geometric
stiffening):

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
    workspace: Numba's dispatch of the ~26 arrays of ``ArmArrays`` and
    ``Workspace`` included (the way the public method called it before the
    packed arm).
``arm.forward_dynamics`` / ``arm.mass_matrix`` / ``arm.tip_position``
    The public methods with their default backend: for real float64 input, the
    packed arm (:mod:`flexarm.model.packed`), checks and a new output array
    included.
``arm.forward_dynamics numpy``
    ``backend="numpy"``, the reference.
``arm.forward_dynamics, batch``
    ``arm.forward_dynamics`` on ``(4096, n_dof)`` arrays (one compiled call); the
    table gives the time per state.

The peers are Pinocchio's ``aba``, ``crba`` and ``forwardKinematics`` on the rigid
two-link arm with the same parameters, called from a Python loop exactly like
the flexarm rows (``pip install pin``; skipped with a note if it is not
importable). The ratios divide by ``aba`` measured in the same process.

Section "growth". One forward-dynamics call from 4 to 64 coordinates, along three
lines: more rigid links, more links of one mode each (and of three modes with
geometric stiffening, the default of an arm you build), and more modes on two
links. Per arm: the dense kernel (mass matrix and ``L D L'``) and the recursive
kernel (articulated-body, :func:`flexarm.model.dynamics.forward_dynamics_recursive`), both as
``kernel, dependent calls``; ``arm.forward_dynamics`` from Python (the kernel the
arm chooses); and Pinocchio's ``aba`` from Python on a rigid chain with as many
joints as the arm has coordinates. Growth exponents are log-log slopes.

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
_chained_dense = _make_chained_driver(dynamics.forward_dynamics_dense)
_chained_recursive = _make_chained_driver(dynamics.forward_dynamics_recursive)
_DEPENDENT = {
    "dependent": _chained,
    "dependent-general": _chained_general,
    "dependent-dense": _chained_dense,
    "dependent-recursive": _chained_recursive,
}


def bench_compiled_loop(
    arm: FlexibleArm, states: tuple, calls: int, repeat: int, driver: str = "independent"
) -> dict:
    """``calls`` kernel calls per batch from a compiled driver: ``driver`` is
    ``"independent"`` or one of the dependent drivers (``"dependent"``,
    ``"dependent-general"``, ``"dependent-dense"``, ``"dependent-recursive"``)."""
    Q, DQ, TAU = states
    model, ws, ddq = arm.arrays, dynamics.make_workspace(arm.n_dof), np.zeros(arm.n_dof)
    qs = np.zeros(arm.n_dof)
    sink = []

    def batch() -> int:
        if driver == "independent":
            sink.append(_driver(Q, DQ, TAU, model, ws, ddq, calls))
        else:
            sink.append(_DEPENDENT[driver](Q, DQ, TAU, model, ws, ddq, qs, calls))
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
def pinocchio_rigid_arm(pin: Any, n_joints: int = 2, length: float = LENGTH) -> tuple[Any, Any]:
    """Pinocchio model of a rigid planar chain of ``n_joints`` links: revolute-z joints,
    each link a uniform rod of ``length`` (m) and mass ``RHO * length`` along its x
    axis, the next joint at its tip; no gravity."""
    m = RHO * length
    i_c = m * length**2 / 12.0  # rod inertia about its centre (y and z axes)
    inertia = pin.Inertia(m, np.array([length / 2.0, 0.0, 0.0]), np.diag([0.0, i_c, i_c]))
    model = pin.Model()
    model.gravity = pin.Motion.Zero()
    parent, place = 0, pin.SE3.Identity()
    at_tip = pin.SE3(np.eye(3), np.array([length, 0.0, 0.0]))
    for k in range(n_joints):
        parent = model.addJoint(parent, pin.JointModelRZ(), place, f"joint{k + 1}")
        model.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
        place = at_tip
    return model, model.createData()


def check_pinocchio(pin: Any, arm: FlexibleArm, model: Any, data: Any, rng) -> float:
    """Largest |q̈_pinocchio - q̈_flexarm| / max(1, |q̈|) (flexarm's default backend) over
    a few random states of the rigid chain ``arm``."""
    err, n = 0.0, arm.n_links
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, n)
        v = rng.uniform(-2.0, 2.0, n)
        tau = rng.uniform(-5.0, 5.0, n)
        a_pin = np.asarray(pin.aba(model, data, q, v, tau))
        a_fa = arm.forward_dynamics(q, v, tau)
        err = max(err, float(np.max(np.abs(a_pin - a_fa)) / max(1.0, np.max(np.abs(a_fa)))))
    return err


def bench_pinocchio(pin: Any, model: Any, data: Any, rows: list, calls: int, repeat: int) -> dict:
    """``aba``, ``crba`` and ``forwardKinematics`` of ``model`` from a Python loop."""
    aba, crba, fk = pin.aba, pin.crba, pin.forwardKinematics

    def aba_call(q, v, tau, model=model, data=data):
        aba(model, data, q, v, tau)

    def crba_call(q, v, tau, model=model, data=data):
        crba(model, data, q)

    def fk_call(q, v, tau, model=model, data=data):
        fk(model, data, q)

    return {
        "pin.aba": bench_python_loop(aba_call, rows, calls, repeat),
        "pin.crba": bench_python_loop(crba_call, rows, calls, repeat),
        "pin.forwardKinematics": bench_python_loop(fk_call, rows, calls, repeat),
    }


# -------------------------------------------------------------- section: calls
BATCH = 4096  # states of the batch row (a multiple of N_STATES)


def bench_calls(
    pin: Any, calls: int, repeat: int, rng, log: Callable[[str], None], out: dict[str, Any]
) -> None:
    """The section "calls" (module docstring) into ``out``."""
    py_calls = max(N_PY_STATES, calls // 20)
    np_calls = max(N_PY_STATES, calls // 500)
    out["settings"] = {
        "calls_compiled_loop": calls,
        "calls_python": py_calls,
        "calls_numpy": np_calls,
        "batch": BATCH,
        "repeat": repeat,
    }
    res = out["results"] = {}
    arms = make_arms()
    for label, arm in arms.items():
        log(f"timing {label} ...")
        states = random_states(arm, N_STATES, rng)
        rows = _py_rows(states)
        model, ws, ddq = arm.arrays, dynamics.make_workspace(arm.n_dof), np.empty(arm.n_dof)

        # the compiled kernel agrees with the NumPy reference on these states, norm-wise
        # (a small component of a large q̈ carries the rounding of the large ones), and
        # the public method with the kernel bit for bit
        err, same = 0.0, True
        for q0, dq0, tau0 in rows[:16]:
            dynamics.forward_dynamics(q0, dq0, tau0, model, ws, ddq)
            ref = arm.forward_dynamics(q0, dq0, tau0, backend="numpy")
            err = max(err, float(np.max(np.abs(ddq - ref)) / max(1.0, np.max(np.abs(ref)))))
            same = same and bool(np.array_equal(arm.forward_dynamics(q0, dq0, tau0), ddq))
        out["checks"][f"{label}: kernel vs numpy (max rel err)"] = err
        out["checks"][f"{label}: arm.forward_dynamics == kernel (1 if bit for bit)"] = 0.0 + (
            not same
        )

        def kernel_call(q, dq, tau, model=model, ws=ws, ddq=ddq):
            dynamics.forward_dynamics(q, dq, tau, model, ws, ddq)

        fd, mm, tip = arm.forward_dynamics, arm.mass_matrix, arm.tip_position
        big = tuple(np.concatenate([x] * (BATCH // N_STATES)) for x in states)

        def batch(fd=fd, big=big) -> int:
            fd(*big)
            return BATCH

        res[label] = {
            "kernel, compiled loop": bench_compiled_loop(arm, states, calls, repeat),
            "kernel, dependent calls": bench_compiled_loop(arm, states, calls, repeat, "dependent"),
            "kernel, Python call": bench_python_loop(kernel_call, rows, py_calls, repeat),
            "arm.forward_dynamics": bench_python_loop(fd, rows, py_calls, repeat),
            "arm.mass_matrix": bench_python_loop(
                lambda q, dq, tau, mm=mm: mm(q), rows, py_calls, repeat
            ),
            "arm.tip_position": bench_python_loop(
                lambda q, dq, tau, tip=tip: tip(q), rows, py_calls, repeat
            ),
            "arm.forward_dynamics, batch": measure(batch, repeat),
            "arm.forward_dynamics numpy": bench_python_loop(
                lambda q, dq, tau, fd=fd: fd(q, dq, tau, backend="numpy"), rows, np_calls, repeat
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
    if pin is None:
        return
    log("timing pinocchio ...")
    model, data = pinocchio_rigid_arm(pin)
    out["checks"]["pinocchio aba vs flexarm rigid (max rel err)"] = check_pinocchio(
        pin, arms[rigid], model, data, rng
    )
    out["pinocchio_rigid"] = bench_pinocchio(pin, model, data, rows, py_calls, repeat)
    anchor = out["pinocchio_rigid"]["pin.aba"]
    ratios: dict[str, dict[str, float]] = {}
    for label, r in res.items():
        ratios[label] = {
            what: r[what][stat] / anchor[stat]
            for what in (
                "kernel, compiled loop",
                "kernel, Python call",
                "arm.forward_dynamics",
                "arm.mass_matrix",
                "arm.tip_position",
            )
            for stat in ("best_ns",)
        }
        ratios[label]["arm.forward_dynamics (median / median)"] = (
            r["arm.forward_dynamics"]["median_ns"] / anchor["median_ns"]
        )
    out["ratios_to_aba"] = ratios


# ------------------------------------------------------------- section: growth
GROWTH_REACH = 9.0  # m: every chain of the growth section spans the paper's two links


def growth_arms() -> dict[str, list[FlexibleArm]]:
    """The growth section's series, each from 4 to 64 coordinates."""

    def chain(n_links: int, modes: int, stiffening: bool) -> FlexibleArm:
        link = Link(GROWTH_REACH / n_links, EI, RHO, n_modes=modes)
        return FlexibleArm([link] * n_links, geometric_stiffening=stiffening)

    return {
        "rigid links": [chain(n, 0, False) for n in (4, 8, 16, 32, 64)],
        "links of 1 mode": [chain(n, 1, False) for n in (2, 4, 8, 16, 32)],
        "links of 3 modes, stiffening": [chain(n, 3, True) for n in (1, 2, 4, 8, 16)],
        "2 links, modes": [chain(2, m, False) for m in (1, 3, 7, 15, 31)],
    }


def slope(xs: list[int], ys: list[float]) -> float:
    """Least-squares slope of log y against log x: the growth exponent."""
    return float(np.polyfit(np.log(xs), np.log(ys), 1)[0])


def bench_growth(
    pin: Any, calls: int, repeat: int, rng, log: Callable[[str], None], out: dict[str, Any]
) -> None:
    """The section "growth" (module docstring) into ``out``."""
    res: dict[str, list[dict[str, Any]]] = {}
    for series, arms in growth_arms().items():
        res[series] = []
        for arm in arms:
            n = arm.n_dof
            log(f"growth: {series}, {arm.n_links} links x {arm.n_modes[0]} modes (n_dof {n}) ...")
            states = random_states(arm, N_STATES, rng)
            rows = _py_rows(states)
            k_calls = max(500, calls // (4 * n))  # the kernels' batches shrink as they slow
            p_calls = max(N_PY_STATES, calls // (20 * n))
            q0, dq0, tau0 = rows[0]
            d, r = np.empty(n), np.empty(n)
            dynamics.forward_dynamics_dense(
                q0, dq0, tau0, arm.arrays, dynamics.make_workspace(n), d
            )
            dynamics.forward_dynamics_recursive(
                q0, dq0, tau0, arm.arrays, dynamics.make_workspace(n), r
            )
            row: dict[str, Any] = {
                "n_links": arm.n_links,
                "n_modes": arm.n_modes[0],
                "n_dof": n,
                "recursive vs dense (max rel err)": float(
                    np.max(np.abs(r - d)) / max(1.0, np.max(np.abs(d)))
                ),
                "dense kernel": bench_compiled_loop(
                    arm, states, k_calls, repeat, "dependent-dense"
                ),
                "recursive kernel": bench_compiled_loop(
                    arm, states, k_calls, repeat, "dependent-recursive"
                ),
                "arm.forward_dynamics": bench_python_loop(
                    arm.forward_dynamics, rows, p_calls, repeat
                ),
            }
            if pin is not None:
                model, data = pinocchio_rigid_arm(pin, n, GROWTH_REACH / n)
                chain_rows = _py_rows(random_states(_rigid_chain(n), N_STATES, rng))
                row["pin.aba, rigid chain"] = bench_python_loop(
                    lambda q, v, tau, model=model, data=data: pin.aba(model, data, q, v, tau),
                    chain_rows,
                    p_calls,
                    repeat,
                )
                row["pin.aba vs flexarm rigid chain (max rel err)"] = check_pinocchio(
                    pin, _rigid_chain(n), model, data, rng
                )
            res[series].append(row)
    out["growth"] = res
    exponents: dict[str, dict[str, float]] = {}
    for series, rows_ in res.items():
        xs = [row["n_links"] if series != "2 links, modes" else row["n_dof"] for row in rows_]
        exponents[series] = {
            what: slope(xs, [row[what]["best_ns"] for row in rows_])
            for what in rows_[0]
            if isinstance(rows_[0][what], dict)
        }
    out["growth_exponents"] = exponents


def _rigid_chain(n: int) -> FlexibleArm:
    """flexarm's rigid chain of ``n`` links spanning GROWTH_REACH (Pinocchio's twin)."""
    return FlexibleArm([Link(GROWTH_REACH / n, EI, RHO, n_modes=0)] * n)


# -------------------------------------------------------------------- main
def run(calls: int, repeat: int, section: str, log: Callable[[str], None]) -> dict[str, Any]:
    try:
        import pinocchio as pin
    except ImportError as exc:
        pin = None
        log(f"pinocchio not importable ({exc}); skipping the peer (pip install pin)")
    rng = np.random.default_rng(SEED)
    out: dict[str, Any] = {"machine": machine_info(pinocchio=pin), "checks": {}}
    if section in ("all", "calls"):
        bench_calls(pin, calls, repeat, rng, log, out)
    if section in ("all", "growth"):
        bench_growth(pin, calls, repeat, rng, log, out)
    out["machine"]["loadavg_at_end"] = list(os.getloadavg())
    return out


def _fmt(ns: float) -> str:
    return f"{ns / 1000:.3f} µs" if ns >= 1000 else f"{ns:.0f} ns"


def print_calls(out: dict[str, Any]) -> None:
    s = out["settings"]
    print(
        f"calls per batch: compiled loop {s['calls_compiled_loop']}, Python "
        f"{s['calls_python']}, numpy {s['calls_numpy']}, batch row {s['batch']} states; "
        f"{s['repeat']} batches"
    )
    print()
    w = 48
    print(f"{'arm':<{w}} {'what':<34} {'best / call':>12} {'median / call':>14}")
    print("-" * (w + 62))
    for label, r in out["results"].items():
        for what, t in r.items():
            unit = " per state" if what.endswith("batch") else ""
            print(
                f"{label:<{w}} {what + unit:<34} {_fmt(t['best_ns']):>12} "
                f"{_fmt(t['median_ns']):>14}"
            )
    for what, t in out.get("pinocchio_rigid", {}).items():
        print(
            f"{'rigid 2-link (pinocchio)':<{w}} {what + ', Python call':<34} "
            f"{_fmt(t['best_ns']):>12} {_fmt(t['median_ns']):>14}"
        )
    t = out["python_harness"]
    print(
        f"{'(none)':<{w}} {'Python loop harness alone':<34} "
        f"{_fmt(t['best_ns']):>12} {_fmt(t['median_ns']):>14}"
    )
    print()
    for label, r in out["results"].items():
        per_state = r["arm.forward_dynamics, batch"]["best_ns"]
        print(f"  batch: {label:<{w}} {1e9 / per_state:12.3g} states/s (best)")
    print()
    if "ratios_to_aba" not in out:
        print("pinocchio not installed: no ratios")
        return
    print("ratios to pin.aba from Python (best / best, same process):")
    whats = list(next(iter(out["ratios_to_aba"].values())))
    print(f"  {'arm':<{w}} " + " ".join(f"{k[:22]:>22}" for k in whats))
    for label, r in out["ratios_to_aba"].items():
        print(f"  {label:<{w}} " + " ".join(f"{r[k]:22.2f}" for k in whats))


def print_growth(out: dict[str, Any]) -> None:
    print("growth: best ns per call (kernels: dependent calls; Python: public call)")
    for series, rows in out["growth"].items():
        print(f"  {series}")
        whats = [k for k in rows[0] if isinstance(rows[0][k], dict)]
        print(f"    {'links x modes':>14} {'n_dof':>5} " + " ".join(f"{k[:24]:>24}" for k in whats))
        for row in rows:
            lm = f"{row['n_links']} x {row['n_modes']}"
            print(
                f"    {lm:>14} {row['n_dof']:>5} "
                + " ".join(f"{_fmt(row[k]['best_ns']):>24}" for k in whats)
            )
        ex = out["growth_exponents"][series]
        x = "n_dof" if series == "2 links, modes" else "n_links"
        print(f"    {'exponent in ' + x:>20} " + " ".join(f"{ex[k]:24.2f}" for k in whats))


def print_report(out: dict[str, Any]) -> None:
    print_machine(out["machine"], "pinocchio")
    if "results" in out:
        print_calls(out)
        print()
    if "growth" in out:
        print_growth(out)
        print()
    print(f"checks (tolerance {CHECK_TOL:.0e}):")
    for k, v in out["checks"].items():
        print(f"  {k:<72} {v:.2e}  {'ok' if v <= CHECK_TOL else 'MISMATCH'}")
    for series, rows in out.get("growth", {}).items():
        for row in rows:
            for k, v in row.items():
                if k.endswith("(max rel err)"):
                    ok = "ok" if v <= CHECK_TOL else "MISMATCH"
                    print(f"  {series}, n_dof {row['n_dof']}: {k:<48} {v:.2e}  {ok}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7, help="timed batches per measurement (>= 1)")
    p.add_argument(
        "--calls",
        type=int,
        default=1_000_000,
        help="kernel calls per batch in the compiled loop; Python-level loops make "
        "calls/20 and the numpy backend calls/500 (the growth section divides by n_dof too)",
    )
    p.add_argument("--section", choices=("all", "calls", "growth"), default="all")
    p.add_argument("--json", action="store_true", help="print the results as JSON only")
    args = p.parse_args(argv)
    if args.repeat < 1 or args.calls < 1:
        p.error("--repeat and --calls must be >= 1")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    out = run(args.calls, args.repeat, args.section, log)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print_report(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
