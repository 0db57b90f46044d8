"""The paper's experiments in one call: :func:`reproduce`.

The matrix {nonadaptive PD, fuzzy adaptive} x {joint sensor, end-effector
sensor, sensor 0.5 m from the elbow} on the default square (paper.md §4), a
sensitivity study (the same matrix under each delay model; the fuzzy law over
a range of ``ks`` and both adaptation laws), and a verdict on each of the
paper's claims with the numbers behind it.

What "tracks well" means is stated, not tuned: a run tracks well when it
completes without diverging and its RMS end-effector error is at most
``tolerance`` times the square's side (default 5 %: 0.2 m on the 4 m square).
The paper gives no figure; the tolerance is a parameter and the report prints
every error beside the verdict, so a reader can apply their own.

Every run is one :func:`flexarm.simulate` call built from a
:class:`flexarm.sim.scenario.Scenario`, so each case can be rerun with
``flexarm simulate --scenario`` (the report lists the settings). A run that
diverges is reported as such, with the time, and its partial result is kept
for the figures.
"""

from __future__ import annotations

import base64
import csv
import dataclasses
import html
import io
import json
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import json_ready, output_directory
from .._validation import check_int, check_option, check_real
from ..control.adaptive import ADAPTATION_LAWS
from ..control.linearize import closed_loop_poles
from ..errors import InvalidValueError
from ..sim.closed_loop import simulate
from ..sim.results import SimulationError, SimulationResult
from ..sim.scenario import Scenario

__all__ = [
    "CONTROLLER_KINDS",
    "DELAY_CASES",
    "OUTPUT_FILES",
    "SENSOR_CASES",
    "Case",
    "CaseResult",
    "Reproduction",
    "reproduce",
]

CONTROLLER_KINDS = ("pd", "fuzzy")
"""Nonadaptive (the paper's JT-PD gains) and fuzzy adaptive."""
SENSOR_CASES = ("joint", "tip", "point:1:0.5")
"""Joint encoders, the end effector, and 0.5 m from the elbow along link 2."""
DELAY_CASES = ("none", "seed", "dispersive")
"""No delay, the seed's wave speed, the dispersive bending-wave speed."""
DEFAULT_KS_RANGE = (0.0, 1.0, 10.0, 100.0, 1000.0)
OUTPUT_FILES = (
    "summary.json",
    "table.csv",
    "report.html",
    "tracking.png",
    "deflections.png",
    "fuzzy_surface.png",
    "sensitivity.png",
)
_LABEL = {"pd": "nonadaptive PD", "fuzzy": "fuzzy adaptive"}
_SENSOR_LABEL = {"joint": "joint", "tip": "end effector", "point:1:0.5": "0.5 m from elbow"}


@dataclass(frozen=True)
class Case:
    """One run of the study.

    Parameters
    ----------
    controller : {"pd", "fuzzy"}
    sensor : {"joint", "tip", "point:1:0.5"}
    delay : {"none", "seed", "dispersive"}
    ks : float
        Membership-width gain of the fuzzy law (ignored by "pd").
    law : {"scaled", "damping"}
        Adaptation law of the fuzzy controller (ignored by "pd").
    """

    controller: str
    sensor: str
    delay: str = "none"
    ks: float = 1.0
    law: str = "scaled"

    def key(self) -> tuple[Any, ...]:
        """Identity of the run (the fuzzy settings do not matter for "pd")."""
        if self.controller == "pd":
            return ("pd", self.sensor, self.delay)
        return (self.controller, self.sensor, self.delay, self.ks, self.law)

    def scenario_dict(self, duration: float | None, dt: float) -> dict[str, Any]:
        """The case in the scenario-file schema (:mod:`flexarm.sim.scenario`)."""
        if self.sensor.startswith("point:"):
            _, link, distance = self.sensor.split(":")
            sensor: dict[str, Any] = {
                "kind": "point",
                "link": int(link),
                "distance": float(distance),
            }
        else:
            sensor = {"kind": self.sensor}
        controller: dict[str, Any] = {"kind": self.controller}
        if self.controller == "fuzzy":
            controller.update(ks=self.ks, law=self.law)
        simulation: dict[str, Any] = {"dt": dt}
        if duration is not None:
            simulation["duration"] = duration
        data: dict[str, Any] = {
            "sensor": sensor,
            "controller": controller,
            "simulation": simulation,
        }
        if self.delay != "none":
            data["delay"] = {"delay": self.delay}
        return data

    @property
    def label(self) -> str:
        text = f"{_LABEL[self.controller]}, {_SENSOR_LABEL[self.sensor]} sensor"
        if self.controller == "fuzzy":
            text += f" (ks = {self.ks:g}, {self.law})"
        if self.delay != "none":
            text += f", {self.delay} delay"
        return text


@dataclass
class CaseResult:
    """The outcome of one :class:`Case`.

    Attributes
    ----------
    case : Case
    status : {"ok", "diverged"}
    diverged_at_s : float or None
        When the state diverged.
    metrics : dict
        :meth:`SimulationResult.metrics` of the completed run; for a diverged
        run only ``sim_time_s`` and ``wall_time_s`` (errors of a run that blew
        up are not tracking errors).
    delay_s : float
        The sensor delay the case ran with, s.
    max_real_pole : float
        Largest real part of the closed-loop poles linearised at the start of
        the path, in continuous time without delay
        (:func:`flexarm.control.linearize.closed_loop_poles`), rad/s: > 0 means the
        loop cannot hold the path's start whatever the control period.
    result : SimulationResult
        The (partial, if diverged) time series, for the figures.
    """

    case: Case
    status: str
    diverged_at_s: float | None
    metrics: dict[str, Any]
    delay_s: float
    max_real_pole: float
    result: SimulationResult = field(repr=False)

    @property
    def rms(self) -> float:
        """RMS tracking error, m (inf if diverged)."""
        return float(self.metrics["rms_error_m"]) if self.status == "ok" else float("inf")

    def row(self) -> dict[str, Any]:
        """One flat, JSON-ready table row."""
        m = self.metrics
        corners = [x for x in m.get("corner_errors_m", []) if x is not None and np.isfinite(x)]
        return {
            "controller": self.case.controller,
            "law": self.case.law if self.case.controller == "fuzzy" else None,
            "ks": self.case.ks if self.case.controller == "fuzzy" else None,
            "sensor": self.case.sensor,
            "delay": self.case.delay,
            "delay_s": self.delay_s,
            "status": self.status,
            "diverged_at_s": self.diverged_at_s,
            "max_real_pole_rad_s": self.max_real_pole,
            "rms_error_m": m.get("rms_error_m"),
            "max_error_m": m.get("max_error_m"),
            "corner_error_max_m": max(corners) if corners else None,
            "residual_vibration_m": m.get("residual_vibration_m"),
            "control_effort_N2m2s": m.get("control_effort_N2m2s"),
            "max_torque_Nm": m.get("max_torque_Nm"),
            "sim_time_s": m.get("sim_time_s"),
            "wall_time_s": m.get("wall_time_s"),
        }


def _run(case: Case, duration: float | None, dt: float) -> CaseResult:
    scenario = Scenario.from_dict(case.scenario_dict(duration, dt), source="reproduce")
    delay_s = scenario.delay.delay
    start = np.asarray(scenario.trajectory.evaluate(np.zeros(1))[0][0], dtype=float)
    poles = closed_loop_poles(scenario.arm, scenario.controller, start, scenario.sensor)
    pole = float(poles[0].real)
    try:
        result = simulate(scenario.arm, **scenario.simulate_kwargs(), progress=False)
    except SimulationError as exc:
        partial = exc.result
        metrics = {"sim_time_s": float(exc.time), "wall_time_s": partial.info.get("wall_time_s")}
        return CaseResult(case, "diverged", float(exc.time), metrics, delay_s, pole, partial)
    return CaseResult(case, "ok", None, result.metrics(), delay_s, pole, result)


@dataclass
class Reproduction:
    """Everything :func:`reproduce` found.

    Attributes
    ----------
    cases : list of CaseResult
        The paper's matrix (no delay, the default fuzzy settings), controller-major.
    delay_study, ks_study : list of CaseResult
        The sensitivity study (the matrix under each delay model; the fuzzy
        law over ``ks`` and the adaptation laws, no delay). Runs shared with
        the matrix are the same objects.
    claims : list of dict
        One verdict per claim of the paper: ``claim``, ``verdict``
        ("supported", "partly supported", "not supported") and ``evidence``.
    settings : dict
        The study's parameters.
    """

    cases: list[CaseResult]
    delay_study: list[CaseResult]
    ks_study: list[CaseResult]
    claims: list[dict[str, Any]]
    settings: dict[str, Any]

    def summary(self) -> dict[str, Any]:
        """The JSON summary (what ``flexarm reproduce --json`` prints)."""
        summary: dict[str, Any] = json_ready(
            {
                "cases": [c.row() for c in self.cases],
                "claims": self.claims,
                "sensitivity": {
                    "delay": [c.row() for c in self.delay_study],
                    "ks": [c.row() for c in self.ks_study],
                },
                "settings": self.settings,
            }
        )
        return summary

    # ------------------------------------------------------------- artefacts
    def write(self, out: str | os.PathLike[str]) -> list[str]:
        """Write every artefact into the new (or empty) directory ``out`` at once.

        Returns the file names (:data:`OUTPUT_FILES`). Nothing appears under
        ``out`` unless all of them were written.
        """
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        target = Path(os.path.abspath(out))
        figures: dict[str, bytes] = {}
        for name, draw in (
            ("tracking.png", self.plot_tracking),
            ("deflections.png", self.plot_deflections),
            ("fuzzy_surface.png", self.plot_surface),
            ("sensitivity.png", self.plot_sensitivity),
        ):
            fig = Figure(figsize=(11, 6.5), layout="constrained")
            FigureCanvasAgg(fig)
            draw(fig)
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=100)
            figures[name] = buf.getvalue()
        with output_directory(target) as tmp:
            summary = self.summary()
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
            self._write_table(tmp / "table.csv")
            for name, data in figures.items():
                (tmp / name).write_bytes(data)
            (tmp / "report.html").write_text(self.html(figures))
        return list(OUTPUT_FILES)

    def _write_table(self, path: Path) -> None:
        groups = [("matrix", self.cases), ("delay", self.delay_study), ("ks", self.ks_study)]
        rows = [{"study": g, **c.row()} for g, cases in groups for c in cases]
        with path.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow({k: "" if v is None else v for k, v in row.items()})

    def _panels(self, fig: Any) -> Iterator[tuple[Any, CaseResult]]:
        """One axes per case of the matrix (controllers by rows, sensors by columns),
        titled with the case's outcome."""
        grid = fig.add_gridspec(len(CONTROLLER_KINDS), len(SENSOR_CASES))
        for i, ctrl in enumerate(CONTROLLER_KINDS):
            for j, sensor in enumerate(SENSOR_CASES):
                ax = fig.add_subplot(grid[i, j])
                case = next(
                    c for c in self.cases if c.case.controller == ctrl and c.case.sensor == sensor
                )
                ax.set_title(_panel_title(case), fontsize=9)
                yield ax, case

    def plot_tracking(self, fig: Any) -> Any:
        """XY path of the end effector against the square, one panel per case."""
        for ax, c in self._panels(fig):
            r = c.result
            ax.plot(r.desired[:, 0], r.desired[:, 1], "k--", lw=1, label="reference")
            ax.plot(r.tip[:, 0], r.tip[:, 1], lw=1.2, label="end effector")
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
        fig.axes[0].legend(fontsize=8, loc="best")
        return fig

    def plot_deflections(self, fig: Any) -> Any:
        """Tip deflection of each link against time, one panel per case."""
        for ax, c in self._panels(fig):
            d = c.result.link_deflections
            for k in range(d.shape[1]):
                ax.plot(c.result.t, 1e3 * d[:, k], lw=1, label=f"link {k + 1}")
            ax.set_xlabel("t (s)")
            ax.set_ylabel("tip deflection (mm)")
        fig.axes[0].legend(fontsize=8)
        return fig

    def plot_surface(self, fig: Any) -> Any:
        """The paper's fuzzy surface lambda(delta1, delta2)."""
        from ..fuzzy import paper_system, plot_surface

        ax = fig.add_subplot(1, 1, 1, projection="3d")
        plot_surface(paper_system(), ax=ax)
        ax.set_title("fuzzy adaptation lambda(delta1, delta2) (paper's rule table)")
        return fig

    def plot_sensitivity(self, fig: Any) -> Any:
        """RMS error of the fuzzy law against ``ks`` (diverged runs marked at the top)."""
        axes = fig.subplots(1, len(SENSOR_CASES), sharey=True)
        ok = [c.rms for c in self.ks_study if c.status == "ok"]
        top = 2.0 * max(ok) if ok else 1.0
        ks_values = sorted({c.case.ks for c in self.ks_study})
        pos = {k: i for i, k in enumerate(ks_values)}
        for ax, sensor in zip(np.atleast_1d(axes), SENSOR_CASES, strict=True):
            for law in self.settings["laws"]:
                cs = [c for c in self.ks_study if c.case.sensor == sensor and c.case.law == law]
                cs.sort(key=lambda c: c.case.ks)
                x = [pos[c.case.ks] for c in cs]
                y = [c.rms if c.status == "ok" else np.nan for c in cs]
                (line,) = ax.plot(x, y, "o-", label=f"fuzzy, {law}")
                xd = [pos[c.case.ks] for c in cs if c.status != "ok"]
                ax.plot(xd, [top] * len(xd), "x", color=line.get_color(), ms=9)
            pd = [c for c in self.cases if c.case.controller == "pd" and c.case.sensor == sensor]
            if pd and pd[0].status == "ok":
                ax.axhline(pd[0].rms, color="k", ls="--", lw=1, label="nonadaptive")
            ax.set_xticks(range(len(ks_values)), [f"{k:g}" for k in ks_values])
            ax.set_xlabel("ks (membership-width gain)")
            ax.set_yscale("log")
            ax.set_title(f"{_SENSOR_LABEL[sensor]} sensor (x: diverged)", fontsize=9)
        np.atleast_1d(axes)[0].set_ylabel("RMS error (m)")
        np.atleast_1d(axes)[0].legend(fontsize=8)
        return fig

    def html(self, figures: dict[str, bytes]) -> str:
        """A self-contained HTML report (figures embedded as base64 PNG)."""
        s = self.settings
        parts = [
            "<!DOCTYPE html><html><head><meta charset='utf-8'>",
            "<title>flexarm reproduce</title><style>",
            "body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.4}",
            "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #bbb;"
            "padding:3px 7px;text-align:right}th{background:#eee}"
            ".supported{color:#060}.not{color:#a00}.partly{color:#a60}",
            "img{max-width:100%}</style></head><body>",
            "<h1>Sąsiadek et al. (2014), reproduced with flexarm</h1>",
            f"<p>{html.escape(_settings_text(s))}</p>",
            "<h2>Claims</h2><ul>",
        ]
        for c in self.claims:
            cls = {"supported": "supported", "not supported": "not"}.get(c["verdict"], "partly")
            parts.append(
                f"<li><b>{html.escape(c['claim'])}</b> — <span class='{cls}'>"
                f"{html.escape(c['verdict'])}</span>. {html.escape(c['evidence'])}</li>"
            )
        parts.append("</ul><h2>The paper's matrix</h2>")
        parts.append(_html_table([c.row() for c in self.cases]))
        parts.append(_img(figures, "tracking.png", "End-effector path against the square."))
        parts.append(_img(figures, "deflections.png", "Tip deflections."))
        parts.append("<h2>Sensitivity: delay models</h2>")
        parts.append(_html_table([c.row() for c in self.delay_study]))
        parts.append("<h2>Sensitivity: the fuzzy law over ks</h2>")
        parts.append(_html_table([c.row() for c in self.ks_study]))
        parts.append(_img(figures, "sensitivity.png", "RMS error against ks."))
        parts.append(_img(figures, "fuzzy_surface.png", "The fuzzy surface."))
        parts.append("</body></html>\n")
        return "\n".join(parts)


def _panel_title(c: CaseResult) -> str:
    head = f"{_LABEL[c.case.controller]}, {_SENSOR_LABEL[c.case.sensor]}"
    if c.status != "ok":
        return f"{head}\ndiverged at t = {c.diverged_at_s:.3g} s"
    return f"{head}\nRMS {c.metrics['rms_error_m']:.3g} m"


def _settings_text(s: dict[str, Any]) -> str:
    dur = "the full square" if s["duration_s"] is None else f"{s['duration_s']:g} s"
    return (
        f"The paper's arm (two 4.5 m links, one mode each) on the default square ({dur}), "
        f"control period {s['dt_s']:g} s. Fuzzy law: {s['law']}, ks = {s['ks']:g}. "
        f"A run tracks well when it completes and its RMS error is at most "
        f"{s['tolerance']:g} x the square's side = {s['tolerance_m']:g} m. "
        f"{s['runs']} runs in {s['wall_time_s']:.1f} s."
    )


def _fmt(v: Any) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{v:.4g}"
    return html.escape(str(v))


def _html_table(rows: list[dict[str, Any]]) -> str:
    cols = [
        "controller",
        "law",
        "ks",
        "sensor",
        "delay",
        "delay_s",
        "status",
        "diverged_at_s",
        "max_real_pole_rad_s",
        "rms_error_m",
        "max_error_m",
        "corner_error_max_m",
        "residual_vibration_m",
        "control_effort_N2m2s",
    ]
    head = "".join(f"<th>{c}</th>" for c in cols)
    body = "".join(
        "<tr>" + "".join(f"<td>{_fmt(json_ready(r[c]))}</td>" for c in cols) + "</tr>" for r in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def _img(figures: dict[str, bytes], name: str, caption: str) -> str:
    data = base64.b64encode(figures[name]).decode("ascii")
    return f"<figure><img src='data:image/png;base64,{data}' alt='{name}'>" + (
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


# ------------------------------------------------------------------ claims
def _describe(c: CaseResult) -> str:
    pole = f"linearised poles up to Re {c.max_real_pole:+.3g} rad/s"
    if c.status != "ok":
        return f"{_SENSOR_LABEL[c.case.sensor]}: diverged at t = {c.diverged_at_s:.3g} s ({pole})"
    return f"{_SENSOR_LABEL[c.case.sensor]}: RMS {c.rms:.3g} m ({pole})"


def _claims(
    cases: list[CaseResult], ks_study: list[CaseResult], tol_m: float
) -> list[dict[str, Any]]:
    def good(c: CaseResult) -> bool:
        return c.status == "ok" and c.rms <= tol_m

    def verdict(hits: int, total: int) -> str:
        if hits == total:
            return "supported"
        return "not supported" if hits == 0 else "partly supported"

    pd = [c for c in cases if c.case.controller == "pd"]
    fz = [c for c in cases if c.case.controller == "fuzzy"]
    poor = [c for c in pd if not good(c)]
    claims = [
        {
            "claim": "Nonadaptive control tracks poorly with collocated and noncollocated sensors",
            "verdict": verdict(len(poor), len(pd)),
            "evidence": "; ".join(_describe(c) for c in pd)
            + f" (tracks well: completes with RMS <= {tol_m:.3g} m).",
        },
        {
            "claim": "Fuzzy adaptive control tracks well regardless of sensor location",
            "verdict": verdict(sum(good(c) for c in fz), len(fz)),
            "evidence": "; ".join(_describe(c) for c in fz)
            + f" (tracks well: completes with RMS <= {tol_m:.3g} m).",
        },
    ]
    better = [(a, b) for a in fz for b in pd if a.case.sensor == b.case.sensor and a.rms < b.rms]
    claims.append(
        {
            "claim": "Fuzzy adaptation improves on the nonadaptive law",
            "verdict": verdict(len(better), len(fz)),
            "evidence": "sensors where the adaptive RMS error is lower: "
            + (", ".join(_SENSOR_LABEL[a.case.sensor] for a, _ in better) or "none")
            + " (adaptive vs nonadaptive: "
            + "; ".join(
                f"{_SENSOR_LABEL[a.case.sensor]}: {a.rms:.4g} vs {b.rms:.4g} m"
                for a in fz
                for b in pd
                if a.case.sensor == b.case.sensor
            )
            + ", inf = diverged).",
        }
    )
    if ks_study:
        per_sensor = []
        for sensor in SENSOR_CASES:
            runs = [c for c in ks_study if c.case.sensor == sensor]
            best = min(runs, key=lambda c: c.rms)
            per_sensor.append((sensor, best, any(good(c) for c in runs)))
        tracked = sum(ok for _, _, ok in per_sensor)
        claims.append(
            {
                "claim": "Some setting of the fuzzy law (any ks, either law) tracks well "
                "with every sensor",
                "verdict": verdict(tracked, len(per_sensor)),
                "evidence": "best over the ks study: "
                + "; ".join(
                    f"{_SENSOR_LABEL[s]}: "
                    + (
                        f"RMS {b.rms:.3g} m at ks = {b.case.ks:g} ({b.case.law})"
                        if b.status == "ok"
                        else "every setting diverged"
                    )
                    for s, b, _ in per_sensor
                )
                + ".",
            }
        )
    return claims


# ------------------------------------------------------------------ driver
def reproduce(
    *,
    duration: float | None = None,
    dt: float = 2e-4,
    ks: float = 1.0,
    law: str = "scaled",
    ks_range: Sequence[float] = DEFAULT_KS_RANGE,
    laws: Sequence[str] = ADAPTATION_LAWS,
    delays: Sequence[str] = DELAY_CASES,
    sensitivity: bool = True,
    tolerance: float = 0.05,
    workers: int | None = None,
    progress: Callable[[int, int, Case], None] | bool | None = None,
) -> Reproduction:
    """Run the paper's experiments (module docstring).

    Parameters
    ----------
    duration : float, optional
        Simulated time per run, s (default: the whole square, 20 s).
    dt : float
        Control period, s (2e-4: the hubless paper arm under the paper's gains
        is sampled-data unstable at 1 ms).
    ks, law
        The fuzzy law of the paper's matrix (:class:`flexarm.control.adaptive.FuzzyAdaptiveJTPD`).
    ks_range : sequence of float
        The ``ks`` values of the sensitivity study (each >= 0).
    laws : sequence of {"scaled", "damping"}
        The adaptation laws of the sensitivity study.
    delays : sequence of {"none", "seed", "dispersive"}
        The delay models of the sensitivity study.
    sensitivity : bool
        Run the sensitivity study (else only the matrix).
    tolerance : float
        "Tracks well" means RMS error <= ``tolerance`` x the square's side.
    workers : int, optional
        Runs in parallel (threads; the compiled loop releases the GIL).
        Default: the CPU count, at most 4.
    progress : bool or callable, optional
        ``True`` prints one line per finished run on stderr; a callable gets
        ``(done, total, case)``. Default: on when stderr is a terminal.

    Returns
    -------
    Reproduction
    """
    owner = "reproduce"
    if duration is not None:
        duration = check_real(duration, "duration", owner, positive=True)
    dt = check_real(dt, "dt", owner, positive=True)
    ks = check_real(ks, "ks", owner, nonnegative=True)
    check_option(law, "law", owner, ADAPTATION_LAWS)
    ks_values = tuple(check_real(k, "ks_range", owner, nonnegative=True) for k in ks_range)
    law_values = tuple(check_option(x, "laws", owner, ADAPTATION_LAWS) for x in laws)
    delay_values = tuple(check_option(x, "delays", owner, DELAY_CASES) for x in delays)
    if sensitivity and not (ks_values and law_values and delay_values):
        raise InvalidValueError(
            f"The 'ks_range', 'laws' and 'delays' parameters of {owner} must be non-empty "
            "when sensitivity is on. Got an empty one instead."
        )
    tolerance = check_real(tolerance, "tolerance", owner, positive=True)
    if workers is None:
        workers = min(4, os.cpu_count() or 1)
    workers = check_int(workers, "workers", owner, minimum=1)

    matrix = [Case(c, s, "none", ks, law) for c in CONTROLLER_KINDS for s in SENSOR_CASES]
    delay_cases = [
        Case(c, s, d, ks, law)
        for d in (delay_values if sensitivity else ())
        for c in CONTROLLER_KINDS
        for s in SENSOR_CASES
    ]
    ks_cases = [
        Case("fuzzy", s, "none", k, lw)
        for lw in (law_values if sensitivity else ())
        for k in ks_values
        for s in SENSOR_CASES
    ]
    unique: dict[tuple[Any, ...], Case] = {}
    for c in [*matrix, *delay_cases, *ks_cases]:
        unique.setdefault(c.key(), c)
    # Validate every scenario before the first run (bad settings fail fast).
    for c in unique.values():
        Scenario.from_dict(c.scenario_dict(duration, dt), source="reproduce")

    report = _progress_printer(progress)
    start = time.perf_counter()
    results: dict[tuple[Any, ...], CaseResult] = {}
    todo = list(unique.items())
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_run, case, duration, dt): key for key, case in todo}
        for done, fut in enumerate(_as_completed(futures), start=1):
            key = futures[fut]
            results[key] = fut.result()
            if report is not None:
                report(done, len(todo), unique[key])
    wall = time.perf_counter() - start

    def pick(cases: list[Case]) -> list[CaseResult]:
        out = []
        for c in cases:
            r = results[c.key()]
            if r.case != c:  # the same run under another name (pd ignores ks and law)
                r = dataclasses.replace(r, case=c)
            out.append(r)
        return out

    side = float(Scenario.from_dict({}, source="reproduce").trajectory.side)
    cases, delay_study, ks_study = pick(matrix), pick(delay_cases), pick(ks_cases)
    settings = {
        "duration_s": duration,
        "dt_s": dt,
        "ks": ks,
        "law": law,
        "ks_range": list(ks_values),
        "laws": list(law_values),
        "delays": list(delay_values),
        "sensitivity": sensitivity,
        "tolerance": tolerance,
        "square_side_m": side,
        "tolerance_m": tolerance * side,
        "runs": len(todo),
        "wall_time_s": wall,
    }
    claims = _claims(cases, ks_study, tolerance * side)
    return Reproduction(cases, delay_study, ks_study, claims, settings)


def _as_completed(futures: dict[Any, Any]) -> Any:
    from concurrent.futures import as_completed

    return as_completed(futures)


def _progress_printer(
    progress: Callable[[int, int, Case], None] | bool | None,
) -> Callable[[int, int, Case], None] | None:
    if callable(progress):
        return progress
    show = sys.stderr.isatty() if progress is None else bool(progress)
    if not show:
        return None

    def report(done: int, total: int, case: Case) -> None:
        print(f"[{done}/{total}] {case.label}", file=sys.stderr, flush=True)

    return report
