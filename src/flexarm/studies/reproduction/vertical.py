"""Beyond the paper: the paper's square in a vertical plane.

The same arm stands on its shoulder with gravity (0, -9.81) m/s**2 in the plane
of the square (-y down; the square, centre (5, 0) m, to the arm's side), so the
links stretched out sideways carry their weight: up to 115 N m at the shoulder
and a static sag of the tip of 0.17 to 1.0 m at the square's corners on the
paper's 4.5 m links.

Per sensor, a fixed list of candidates (:data:`CANDIDATES`), chosen by one rule
stated in advance: the smallest RMS error of the tip over the vertical square
(a diverged run counts as infinite; ties: the first listed). The joint sensor
(encoders): the paper's Jacobian-transpose PD with the holding torques of the
measured posture added (the baseline), the same law on the sag-corrected path
(:class:`~flexarm.control.sag.SagCorrectedPath`: the joint angles whose static
tip is on the square), and the LQG designed about the gravity equilibrium of
the postures on the path (holding torques of the reference posture in its
feedforward, beside the rigid inverse dynamics) on the sag-corrected path. The
tip sensor: that LQG with the tip alone (the weights the horizontal study chose
for it; the sag is its output's offset at each posture), and the reflected-tip
law at the horizontal study's reflection with the measured posture's
compensation, its path corrected by ``1 - alpha`` of the sag. The
Jacobian-transpose runs follow the raw square, as in the paper's matrix; the others the
square smoothed as in the rest of this study. Every vertical run starts at
rest carrying its weight in the posture its law holds at the square's first
point. Errors are
those of the deflected tip against the square itself.

Diagnosis: the PD without the compensation, and the static sag along the square
(the tip of the arm at rest at the inverse kinematics of each point), tell
whether the vertical PD's error is the sag, the compensation or the torque
(there is no torque limit in the study).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..._io import JSONValue
from ...control.controllers import Controller, JacobianTransposePD
from ...control.lqg import LQG
from ...control.reflected import ReflectedTipPD
from ...control.sag import SagCorrectedPath, rest_tips
from ...control.trajectories import Square, Trajectory
from ...model.arm import FlexibleArm
from ...sensing.sensors import JointSensor, Sensor, TipSensor
from ...sim.batch import Outcome, simulate_many
from ...sim.results import SimulationError
from .units import mm, sig

__all__ = [
    "CANDIDATES",
    "GRAVITY",
    "Vertical",
    "VerticalRun",
    "choose_vertical",
    "run_vertical",
    "static_sag",
]

GRAVITY = (0.0, -9.81)
"""Gravity in the plane of the square, m/s**2 (the arm stands on its shoulder; -y down)."""

CANDIDATES: dict[str, tuple[str, ...]] = {
    "joint": ("pd", "pd sag-corrected", "lqg"),
    "tip": ("lqg", "reflected"),
}
"""The laws tried per sensor in the vertical plane (module docstring), in order."""

DIAGNOSTIC = ("pd uncompensated", "joint")
"""The run beside the candidates that tells the compensation's share."""

HORIZONTAL = (("pd", "joint"), ("lqg", "joint"))
"""The horizontal runs the joint sensor's candidates need beside the vertical ones
(the tip's are the horizontal study's nominal rows)."""

SENSORS: dict[str, Sensor] = {"joint": JointSensor(), "tip": TipSensor()}


@dataclass(frozen=True)
class VerticalRun:
    """One run: the law, the sensor, the plane, and its figures (None: diverged)."""

    law: str
    sensor: str
    plane: str  # "vertical" or "horizontal"
    rms_error_m: float | None
    max_error_m: float | None
    max_torque_Nm: float | None
    diverged_at_s: float | None = None

    def as_dict(self) -> dict[str, JSONValue]:
        return dict(dataclasses.asdict(self))


def choose_vertical(runs: Sequence[VerticalRun], sensor: str) -> str:
    """The candidate of :data:`CANDIDATES` for ``sensor`` with the smallest vertical RMS
    error (diverged or missing: infinite; ties: the first listed)."""

    def rms(name: str) -> float:
        for r in runs:
            if (r.law, r.sensor, r.plane) == (name, sensor, "vertical"):
                return np.inf if r.rms_error_m is None else r.rms_error_m
        return np.inf

    return min(CANDIDATES[sensor], key=rms)


def static_sag(arm: FlexibleArm, path: Trajectory, n: int = 201) -> tuple[float, float]:
    """RMS and largest distance (m) between each point of ``path`` (``n`` evenly
    spaced instants) and the tip of ``arm`` at rest at its inverse kinematics."""
    t = np.linspace(0.0, float(path.duration), n)
    points = np.asarray(path.evaluate(t)[0], dtype=float)
    theta = np.asarray(arm.inverse_kinematics(points), dtype=float)
    d = np.linalg.norm(rest_tips(arm, theta)[0] - points, axis=1)
    return float(np.sqrt(np.mean(d**2))), float(d.max())


@dataclass
class Vertical:
    """What the vertical study found (module docstring).

    Attributes
    ----------
    runs : list of VerticalRun
        Every run: the candidates and the diagnostic run in the vertical plane,
        the joint sensor's candidates in the horizontal one, and the tip's
        horizontal figures copied from the horizontal study.
    chosen : dict of str to str
        Per sensor, the candidate the rule chose.
    sag_rms_m, sag_max_m : float
        The static sag along the square (:func:`static_sag`), m.
    holding_max_Nm : float
        The largest holding torque along the square, N m.
    tip_weights : str
        The horizontal study's LQG candidate whose weights the tip LQG uses.
    """

    runs: list[VerticalRun]
    chosen: dict[str, str]
    sag_rms_m: float
    sag_max_m: float
    holding_max_Nm: float
    tip_weights: str

    def run(self, law: str, sensor: str, plane: str = "vertical") -> VerticalRun | None:
        """The run of ``law`` with ``sensor`` in ``plane`` (None if not made)."""
        for r in self.runs:
            if (r.law, r.sensor, r.plane) == (law, sensor, plane):
                return r
        return None

    def summary(self) -> dict[str, JSONValue]:
        """JSON-ready: the gravity, the rule's candidates and choice, every run, the diagnosis."""
        candidates: dict[str, JSONValue] = {s: list(c) for s, c in CANDIDATES.items()}
        return {
            "gravity_m_s2": list(GRAVITY),
            "rule": "smallest vertical RMS error (diverged: infinite; ties: first listed)",
            "candidates": candidates,
            "chosen": dict(self.chosen),
            "tip_lqg_weights": self.tip_weights,
            "runs": [r.as_dict() for r in self.runs],
            "static_sag_rms_m": self.sag_rms_m,
            "static_sag_max_m": self.sag_max_m,
            "holding_torque_max_Nm": self.holding_max_Nm,
        }

    def diagnosis(self) -> str:
        """Why the vertical PD's error is what it is, in one sentence with its numbers."""
        pd, raw = self.run("pd", "joint"), self.run(*DIAGNOSTIC)
        corrected = self.run("pd sag-corrected", "joint")
        flat = self.run("pd", "joint", "horizontal")

        def rms(r: VerticalRun | None) -> str:
            return mm(None if r is None else r.rms_error_m)

        return (
            f"The vertical PD's RMS error, {rms(pd)} ({rms(raw)} without the compensation of "
            f"the measured posture, {rms(flat)} horizontal), is the links' sag: the static sag "
            f"along the square alone is {mm(self.sag_rms_m)} RMS ({mm(self.sag_max_m)} at "
            f"the most), and the same law on the sag-corrected path has {rms(corrected)}. "
            f"The torque is not the limit: no limit is set, the weight needs up to "
            f"{sig(self.holding_max_Nm)} N m and the PD's peak is "
            f"{sig(None if pd is None else pd.max_torque_Nm)} N m."
        )

    def text_lines(self) -> list[str]:
        """The study in a few lines for the console."""
        lines = [
            f"  vertical plane (gravity {GRAVITY} m/s^2, the arm standing on its shoulder; "
            "rule: smallest vertical RMS):"
        ]
        for sensor, name in self.chosen.items():
            lines.append(f"    {sensor}: chosen {name!r} of {list(CANDIDATES[sensor])}")
        for r in self.runs:
            lines.append("    " + _run_text(r))
        lines.append("    " + self.diagnosis())
        return lines

    def html(self) -> str:
        """The section's vertical part: the rule, the choice, the table, the diagnosis."""
        import html as _html

        from .html import table
        from .units import MISSING

        def num(value: float | None, scale: float = 1.0) -> str:
            return MISSING if value is None else sig(scale * value)

        rows = []
        for sensor, name in self.chosen.items():
            for plane in ("vertical", "horizontal"):
                r = self.run(name, sensor, plane)
                if r is None:
                    continue
                rows.append(
                    [
                        f"{name} (chosen)",
                        sensor,
                        plane,
                        num(r.rms_error_m, 1e3),
                        num(r.max_error_m, 1e3),
                        num(r.max_torque_Nm),
                    ]
                )
        rows += [
            [
                r.law,
                r.sensor,
                r.plane,
                num(r.rms_error_m, 1e3),
                num(r.max_error_m, 1e3),
                num(r.max_torque_Nm),
            ]
            for r in self.runs
        ]
        headers = ("law", "sensor", "plane", "RMS error (mm)", "max error (mm)", "max torque (N m)")
        doc = [_plain(d) for d in (__doc__ or "").split("\n\n")[1:3]]
        chosen = "; ".join(f"{s}: {n}" for s, n in self.chosen.items())
        return (
            f"<h3>The square in a vertical plane (gravity {_html.escape(str(GRAVITY))} "
            "m/s<sup>2</sup>)</h3>"
            + "".join(f"<p>{_html.escape(' '.join(d.split()))}</p>" for d in doc)
            + f"<p>Chosen by the rule (smallest vertical RMS error): {_html.escape(chosen)}. "
            f"The tip LQG uses the weights {_html.escape(repr(self.tip_weights))}.</p>"
            + f"<p>{_html.escape(self.diagnosis())}</p>"
            + table(headers, rows, [False] * 3 + [True] * 3)
        )


def _vertical_arm() -> FlexibleArm:
    return FlexibleArm.paper(gravity=GRAVITY)


def _at_rest(arm: FlexibleArm, path: Trajectory) -> tuple[float, ...]:
    """The state ``(q, dq)`` at rest carrying its weight in the posture the law holds at
    the path's first point: the sag-corrected angles of a corrected path (whatever its
    fraction: every law here puts the tip of the arm at rest there on the square's
    point), else the inverse kinematics of the path's first point."""
    if isinstance(path, SagCorrectedPath):
        theta = path.angles[0]
    else:
        theta = arm.inverse_kinematics(np.asarray(path.evaluate(0.0)[0], dtype=float))
    q = arm.equilibrium(theta).q
    return tuple(float(v) for v in np.concatenate([q, np.zeros_like(q)]))


Job = tuple[str, str, str, dict[str, object]]
"""A run to make: the law's name, the sensor's name, the plane, simulate's arguments."""


def _jobs(
    duration: float | None,
    dt: float,
    smoothing: float,
    tip_weights: Mapping[str, float],
    alpha: float,
) -> list[Job]:
    vertical, flat, square = _vertical_arm(), FlexibleArm.paper(), Square()
    corrected = SagCorrectedPath(vertical, square)
    reflected_path = SagCorrectedPath(vertical, square, fraction=1.0 - alpha)
    pd = JacobianTransposePD.from_arm(vertical)
    laws: dict[tuple[str, str], tuple[Controller, Trajectory, dict[str, object]]] = {
        ("pd", "joint"): (pd, square, {"smoothing": 0.0}),
        ("pd uncompensated", "joint"): (
            pd,
            square,
            {"smoothing": 0.0, "gravity_compensation": False},
        ),
        ("pd sag-corrected", "joint"): (pd, corrected, {"smoothing": 0.0}),
        ("lqg", "joint"): (LQG(model=vertical), corrected, {"smoothing": smoothing}),
        ("lqg", "tip"): (
            LQG(model=vertical, **tip_weights),  # type: ignore[arg-type]
            corrected,
            {"smoothing": smoothing},
        ),
        ("reflected", "tip"): (
            ReflectedTipPD.from_arm(vertical, alpha=alpha),
            reflected_path,
            {"smoothing": smoothing},
        ),
    }
    common = {"duration": duration, "dt": dt, "rng": 0, "progress": False}
    jobs: list[Job] = []
    for (law, sensor), (controller, path, extra) in laws.items():
        args = {
            "arm": vertical,
            "controller": controller,
            "trajectory": path,
            "sensor": SENSORS[sensor],
            "initial_state": _at_rest(vertical, path),
            **extra,
            **common,
        }
        jobs.append((law, sensor, "vertical", args))
    for law, sensor in HORIZONTAL:
        controller = JacobianTransposePD.from_arm(flat) if law == "pd" else LQG(model=flat)
        extra = {"smoothing": 0.0 if law == "pd" else smoothing}
        args = {
            "arm": flat,
            "controller": controller,
            "trajectory": square,
            "sensor": SENSORS[sensor],
            **extra,
            **common,
        }
        jobs.append((law, sensor, "horizontal", args))
    return jobs


def _result(job: Job, outcome: Outcome) -> VerticalRun:
    """A job's figures from its outcome: the deflected tip against the square itself."""
    law, sensor, plane, _ = job
    if isinstance(outcome, SimulationError):
        return VerticalRun(law, sensor, plane, None, None, None, float(outcome.time))
    if isinstance(outcome, Exception):
        raise outcome
    t = np.asarray(outcome.t, dtype=float)
    desired = np.asarray(Square().evaluate(t)[0], dtype=float)
    error = np.linalg.norm(np.asarray(outcome.tip, dtype=float) - desired, axis=1)
    return VerticalRun(
        law,
        sensor,
        plane,
        float(np.sqrt(np.mean(error**2))),
        float(error.max()),
        float(np.max(np.abs(outcome.tau))),
    )


def run_vertical(
    duration: float | None,
    dt: float,
    *,
    smoothing: float,
    tip_weights: str,
    tip_weight_values: Mapping[str, float],
    alpha: float,
    horizontal_tip: Mapping[str, tuple[float | None, float | None, float | None]],
    workers: int = 1,
) -> Vertical:
    """Run the vertical study (module docstring) for ``duration`` s a run (None: the
    square) at control period ``dt`` (s).

    ``smoothing`` (s) is the LQG's and reflected law's reference smoothing,
    ``tip_weights`` the name of the horizontal study's LQG candidate for the tip and
    ``tip_weight_values`` its weights, ``alpha`` the reflection, ``horizontal_tip``
    the horizontal study's nominal tip figures per law (``"lqg"``, ``"reflected"``:
    RMS, max error, m, and max torque, N m).
    """
    jobs = _jobs(duration, dt, smoothing, tip_weight_values, alpha)
    outcomes = simulate_many(
        [args for *_, args in jobs], workers=workers, errors="return", progress=False
    )
    runs = [_result(job, out) for job, out in zip(jobs, outcomes, strict=True)]
    for law, (rms, mx, torque) in horizontal_tip.items():
        runs.append(VerticalRun(law, "tip", "horizontal", rms, mx, torque))
    chosen = {sensor: choose_vertical(runs, sensor) for sensor in CANDIDATES}
    arm, square = _vertical_arm(), Square()
    sag_rms, sag_max = static_sag(arm, square)
    t = np.union1d(np.linspace(0.0, square.duration, 201), square.corner_times)
    theta = arm.inverse_kinematics(np.asarray(square.evaluate(t)[0]))
    holding = float(np.max(np.abs(rest_tips(arm, theta)[1])))
    return Vertical(runs, chosen, sag_rms, sag_max, holding, tip_weights)


def _plain(text: str) -> str:
    """Docstring text without its reST markup (roles to their last name, literals bare)."""
    text = re.sub(r":\w+:`~?(?:[\w.]+\.)?([\w]+)`", r"\1", text)
    return text.replace("``", "")


def _run_text(r: VerticalRun) -> str:
    name = f"{r.law}, {r.sensor}, {r.plane}"
    if r.rms_error_m is None:
        at = "" if r.diverged_at_s is None else f" at {r.diverged_at_s:.3g} s"
        return f"{name}: diverged{at}"
    return (
        f"{name}: RMS {mm(r.rms_error_m)}, max {mm(r.max_error_m)}, "
        f"torque {sig(r.max_torque_Nm)} N m"
    )
