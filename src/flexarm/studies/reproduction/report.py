"""What :func:`~flexarm.studies.reproduction.reproduce` found, and its report.

:class:`Reproduction` holds the case results, the verdicts and the settings,
and renders them: a JSON summary, a CSV table, a text summary, figures and a
self-contained HTML report (:data:`OUTPUT_FILES`, written at once). Matplotlib
is imported only when a figure is drawn.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from ..._io import JSONValue, json_ready, output_directory
from .cases import (
    CONTROLLER_KINDS,
    CONTROLLER_LABELS,
    MODEL_LABELS,
    SENSOR_CASES,
    SENSOR_LABELS,
    CaseResult,
)
from .verdicts import Claim

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .beyond import Beyond
    from .converged import Converged

__all__ = ["FIGURE_SIZE", "OUTPUT_FILES", "VOCABULARY", "Reproduction", "Settings"]

VOCABULARY = (
    "Each claim is judged under each sensor model and is made of parts, each about a set "
    "of runs; a part holds when it holds for every run it speaks of (a claim about every "
    "sensor holds only if it holds for each). Supported: every part holds. Not supported: "
    "no part holds. Partly supported: some parts hold and others do not, which happens only "
    "for a claim the paper states in parts (collocated and noncollocated sensors)."
)
VOCABULARY_SHORT = "supported: every part holds for every run it covers; partly: some parts only"

OUTPUT_FILES = (
    "summary.json",
    "table.csv",
    "report.html",
    "tracking.png",
    "deflections.png",
    "fuzzy_surface.png",
    "sensitivity.png",
)
FIGURE_SIZE = (11.0, 6.5)
"""Size of every figure of the report, inches."""

_TABLE_COLUMNS = (
    "controller",
    "law",
    "ks",
    "sensor",
    "sensor_model",
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
)


class Settings(TypedDict):
    """The parameters of :func:`~flexarm.studies.reproduction.reproduce`, units in the keys."""

    duration_s: float | None
    dt_s: float
    ks: float
    law: str
    ks_range: list[float]
    laws: list[str]
    delays: list[str]
    sensitivity: bool
    beyond: bool
    tolerance: float
    square_side_m: float
    tolerance_m: float
    runs: int
    wall_time_s: float


@dataclass
class Reproduction:
    """Everything :func:`~flexarm.studies.reproduction.reproduce` found.

    Attributes
    ----------
    cases : list of CaseResult
        The paper's matrix (no delay, the default fuzzy settings), controller-major.
    delay_study, ks_study : list of CaseResult
        The sensitivity study (the matrix under each delay model; the fuzzy
        law over ``ks`` and the adaptation laws, no delay). Runs shared with
        the matrix are the same runs.
    claims : list of Claim
        One verdict per claim of the paper: ``claim``, ``verdict``
        ("supported", "partly supported", "not supported") and ``evidence``
        (:mod:`~flexarm.studies.reproduction.verdicts`).
    settings : Settings
        The study's parameters (units in the keys).
    beyond : Beyond or None
        The study beyond the paper (None when not run).
    converged : Converged or None
        The matrix on a converged arm and its verdicts (None when not run).
    """

    cases: list[CaseResult]
    delay_study: list[CaseResult]
    ks_study: list[CaseResult]
    claims: list[Claim]
    settings: Settings
    beyond: Beyond | None = None
    converged: Converged | None = None

    def summary(self) -> dict[str, JSONValue]:
        """The JSON summary (what ``flexarm reproduce --json`` prints)."""
        summary: dict[str, JSONValue] = json_ready(
            {
                "cases": [c.row() for c in self.cases],
                "claims": self.claims,
                "sensitivity": {
                    "delay": [c.row() for c in self.delay_study],
                    "ks": [c.row() for c in self.ks_study],
                },
                "settings": self.settings,
                "beyond": None if self.beyond is None else self.beyond.summary(),
                "converged": None if self.converged is None else self.converged.summary(),
            }
        )
        return summary

    def text(self) -> str:
        """A plain-text summary: the matrix's outcomes and the verdicts with their evidence."""
        s = self.settings
        lines = [
            f"{s['runs']} runs in {s['wall_time_s']:.1f} s "
            f"(control period {s['dt_s']:g} s; 'tracks well' = RMS <= {s['tolerance_m']:g} m)",
            f"  {'controller':<16}{'sensor':<14}{'model':<10}{'status':<22}"
            f"{'rms (m)':>10}{'max (m)':>10}",
        ]
        for c in self.cases:
            row = c.row()
            status = "ok" if c.status == "ok" else f"diverged at {c.diverged_at_s:.3g} s"
            rms = "" if row["rms_error_m"] is None else f"{row['rms_error_m']:.4g}"
            mx = "" if row["max_error_m"] is None else f"{row['max_error_m']:.4g}"
            name = "nonadaptive" if c.case.controller == "pd" else "fuzzy adaptive"
            model = "-" if c.case.sensor == "joint" else c.case.sensor_model
            lines.append(f"  {name:<16}{c.case.sensor:<14}{model:<10}{status:<22}{rms:>10}{mx:>10}")
        lines.append(f"claims ({VOCABULARY_SHORT}):")
        for claim in self.claims:
            lines.append(
                f"  - [{claim['sensor_model']} sensor model] {claim['claim']}: "
                f"{claim['verdict'].upper()}"
            )
            lines.append(f"      {claim['evidence']}")
        if self.converged is not None:
            lines += self.converged.text_lines()
        if self.beyond is not None:
            lines += self.beyond.text_lines()
        return "\n".join(lines)

    # ------------------------------------------------------------- artefacts
    def write(self, out: str | os.PathLike[str]) -> list[str]:
        """Write every artefact into the new (or empty) directory ``out`` at once.

        Returns the file names (:data:`OUTPUT_FILES`). Nothing appears under
        ``out`` unless all of them were written.
        """
        target = Path(os.path.abspath(out))
        figures = self.figures_png()
        with output_directory(target) as tmp:
            summary = self.summary()
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
            self._write_table(tmp / "table.csv")
            for name, data in figures.items():
                (tmp / name).write_bytes(data)
            (tmp / "report.html").write_text(self.html(figures))
        return list(OUTPUT_FILES)

    def figures_png(self, dpi: int = 100) -> dict[str, bytes]:
        """The report's figures as PNG bytes, by file name (drawn off screen, no pyplot)."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        draw: dict[str, Callable[[Figure], object]] = {
            "tracking.png": self.plot_tracking,
            "deflections.png": self.plot_deflections,
            "fuzzy_surface.png": lambda fig: self.plot_surface(fig.add_subplot(projection="3d")),
            "sensitivity.png": self.plot_sensitivity,
        }
        figures: dict[str, bytes] = {}
        for name, plot in draw.items():
            fig = Figure(figsize=FIGURE_SIZE, layout="constrained")
            FigureCanvasAgg(fig)
            plot(fig)
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi)
            figures[name] = buf.getvalue()
        return figures

    def _write_table(self, path: Path) -> None:
        groups = [("matrix", self.cases), ("delay", self.delay_study), ("ks", self.ks_study)]
        rows = [{"study": g, **c.row()} for g, cases in groups for c in cases]
        with path.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow({k: "" if v is None else v for k, v in row.items()})

    # ------------------------------------------------------------- figures
    def _panels(self, fig: Figure) -> Iterator[tuple[Axes, CaseResult]]:
        """One axes per case of the matrix (sensor models and controllers by rows,
        sensors by columns), titled with the case's outcome."""
        models = list(dict.fromkeys(c.case.sensor_model for c in self.cases))
        rows = [(m, ctrl) for m in models for ctrl in CONTROLLER_KINDS]
        grid = fig.add_gridspec(len(rows), len(SENSOR_CASES))
        for i, (model, ctrl) in enumerate(rows):
            for j, sensor in enumerate(SENSOR_CASES):
                ax = fig.add_subplot(grid[i, j])
                case = next(
                    c
                    for c in self.cases
                    if c.case.controller == ctrl
                    and c.case.sensor == sensor
                    and c.case.sensor_model == model
                )
                ax.set_title(_panel_title(case), fontsize=8)
                yield ax, case

    def plot_tracking(self, fig: Figure | None = None) -> Figure:
        """XY path of the end effector against the square, one panel per case of the matrix.

        Parameters
        ----------
        fig : matplotlib Figure, optional
            Where to draw (an empty figure); default a new pyplot figure.

        Returns
        -------
        Figure
        """
        fig = _figure(fig)
        for ax, c in self._panels(fig):
            r = c.result
            ax.plot(r.desired[:, 0], r.desired[:, 1], "k--", lw=1, label="reference")
            ax.plot(r.tip[:, 0], r.tip[:, 1], lw=1.2, label="end effector")
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
        fig.axes[0].legend(fontsize=8, loc="best")
        return fig

    def plot_deflections(self, fig: Figure | None = None) -> Figure:
        """Tip deflection of each link against time, one panel per case of the matrix.

        Parameters
        ----------
        fig : matplotlib Figure, optional
            Where to draw (an empty figure); default a new pyplot figure.

        Returns
        -------
        Figure
        """
        fig = _figure(fig)
        for ax, c in self._panels(fig):
            d = c.result.link_deflections
            for k in range(d.shape[1]):
                ax.plot(c.result.t, 1e3 * d[:, k], lw=1, label=f"link {k + 1}")
            ax.set_xlabel("t (s)")
            ax.set_ylabel("tip deflection (mm)")
        fig.axes[0].legend(fontsize=8)
        return fig

    def plot_surface(self, ax: Axes | None = None) -> tuple[Axes, Artist]:
        """The paper's fuzzy surface λ(δ1, δ2) (:func:`flexarm.fuzzy.plot_surface`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            A 3-D axes gets a surface, a 2-D axes a filled contour; default a
            new pyplot figure with a 3-D axes.

        Returns
        -------
        (ax, artist)
        """
        from ...fuzzy import paper_system, plot_surface

        ax, artist = plot_surface(paper_system(), ax=ax)
        ax.set_title("fuzzy adaptation λ(δ1, δ2) (paper's rule table)")
        return ax, artist

    def plot_sensitivity(self, fig: Figure | None = None) -> Figure:
        """RMS error of the fuzzy law against ``ks``, one panel per sensor (x: diverged).

        Parameters
        ----------
        fig : matplotlib Figure, optional
            Where to draw (an empty figure); default a new pyplot figure.

        Returns
        -------
        Figure
        """
        fig = _figure(fig)
        axes = np.atleast_1d(fig.subplots(1, len(SENSOR_CASES), sharey=True))
        ok = [c.rms for c in self.ks_study if c.status == "ok"]
        top = 2.0 * max(ok) if ok else 1.0
        ks_values = sorted({c.case.ks for c in self.ks_study})
        pos = {k: i for i, k in enumerate(ks_values)}
        models = list(dict.fromkeys(c.case.sensor_model for c in self.ks_study))
        markers = {"paper": "o", "physical": "s"}
        for ax, sensor in zip(axes, SENSOR_CASES, strict=True):
            for model in models:
                for law in self.settings["laws"]:
                    cs = [
                        c
                        for c in self.ks_study
                        if c.case.sensor == sensor
                        and c.case.law == law
                        and c.case.sensor_model == model
                    ]
                    cs.sort(key=lambda c: c.case.ks)
                    x = [pos[c.case.ks] for c in cs]
                    y = [c.rms if c.status == "ok" else np.nan for c in cs]
                    (line,) = ax.plot(
                        x, y, markers.get(model, "o") + "-", mfc="none", label=f"{model}, {law}"
                    )
                    xd = [pos[c.case.ks] for c in cs if c.status != "ok"]
                    ax.plot(xd, [top] * len(xd), "x", color=line.get_color(), ms=9)
            pd = [c for c in self.cases if c.case.controller == "pd" and c.case.sensor == sensor]
            if pd and pd[0].status == "ok":
                ax.axhline(pd[0].rms, color="k", ls="--", lw=1, label="nonadaptive (joint)")
            ax.set_xticks(range(len(ks_values)), [f"{k:g}" for k in ks_values])
            ax.set_xlabel("membership-width gain ks (-)")
            ax.set_yscale("log")
            ax.set_title(f"{SENSOR_LABELS[sensor]} sensor (x: diverged)", fontsize=9)
        axes[0].set_ylabel("RMS error (m)")
        axes[0].legend(fontsize=8)
        return fig

    # ------------------------------------------------------------- HTML
    def html(self, figures: dict[str, bytes]) -> str:
        """A self-contained HTML report (figures embedded as base64 PNG).

        Parameters
        ----------
        figures : dict of str to bytes
            The PNG figures by file name (:meth:`figures_png`).
        """
        parts = [
            "<!DOCTYPE html><html><head><meta charset='utf-8'>",
            "<title>flexarm reproduce</title><style>",
            "body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.4}",
            "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #bbb;"
            "padding:3px 7px;text-align:right}th{background:#eee}"
            ".supported{color:#060}.not{color:#a00}.partly{color:#a60}",
            "img{max-width:100%}</style></head><body>",
            "<h1>Sąsiadek et al. (2014), reproduced with flexarm</h1>",
            f"<p>{html.escape(_settings_text(self.settings))}</p>",
            "<h2>Claims</h2>",
            f"<p>{html.escape(VOCABULARY)}</p>",
        ]
        for model in dict.fromkeys(c["sensor_model"] for c in self.claims):
            parts.append(f"<h3>With {html.escape(MODEL_LABELS.get(model, model))}</h3><ul>")
            for c in self.claims:
                if c["sensor_model"] != model:
                    continue
                cls = {"supported": "supported", "not supported": "not"}.get(c["verdict"], "partly")
                parts.append(
                    f"<li><b>{html.escape(c['claim'])}</b> — <span class='{cls}'>"
                    f"{html.escape(c['verdict'])}</span>. {html.escape(c['evidence'])}</li>"
                )
            parts.append("</ul>")
        parts.append("<h2>The paper's matrix</h2>")
        parts.append(_html_table(self.cases))
        parts.append(_img(figures, "tracking.png", "End-effector path against the square."))
        parts.append(_img(figures, "deflections.png", "Tip deflections."))
        parts.append("<h2>Sensitivity: delay models</h2>")
        parts.append(_html_table(self.delay_study))
        parts.append("<h2>Sensitivity: the fuzzy law over ks</h2>")
        parts.append(_html_table(self.ks_study))
        parts.append(_img(figures, "sensitivity.png", "RMS error against ks."))
        parts.append(_img(figures, "fuzzy_surface.png", "The fuzzy surface."))
        if self.converged is not None:
            parts.append(self.converged.html())
        if self.beyond is not None:
            parts.append(self.beyond.html())
        parts.append("</body></html>\n")
        return "\n".join(parts)


def _figure(fig: Figure | None) -> Figure:
    if fig is not None:
        return fig
    import matplotlib.pyplot as plt

    new: Figure = plt.figure(figsize=FIGURE_SIZE, layout="constrained")
    return new


def _panel_title(c: CaseResult) -> str:
    head = f"{CONTROLLER_LABELS[c.case.controller]}, {SENSOR_LABELS[c.case.sensor]}"
    if c.case.sensor != "joint":
        head += f" ({c.case.sensor_model})"
    if c.status != "ok":
        return f"{head}\ndiverged at t = {c.diverged_at_s:.3g} s"
    return f"{head}\nRMS {c.metrics['rms_error_m']:.3g} m"


def _settings_text(s: Settings) -> str:
    dur = "the full square" if s["duration_s"] is None else f"{s['duration_s']:g} s"
    return (
        f"The paper's arm (two 4.5 m links, one mode each) on the default square ({dur}), "
        f"control period {s['dt_s']:g} s. Fuzzy law: {s['law']}, ks = {s['ks']:g}. "
        f"A run tracks well when it completes and its RMS error is at most "
        f"{s['tolerance']:g} x the square's side = {s['tolerance_m']:g} m. "
        f"{s['runs']} runs in {s['wall_time_s']:.1f} s."
    )


def _fmt(v: object) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{v:.4g}"
    return html.escape(str(v))


def _html_table(cases: Sequence[CaseResult]) -> str:
    rows = [c.row() for c in cases]
    head = "".join(f"<th>{c}</th>" for c in _TABLE_COLUMNS)
    body = "".join(
        "<tr>" + "".join(f"<td>{_fmt(json_ready(r[c]))}</td>" for c in _TABLE_COLUMNS) + "</tr>"
        for r in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def _img(figures: dict[str, bytes], name: str, caption: str) -> str:
    data = base64.b64encode(figures[name]).decode("ascii")
    return f"<figure><img src='data:image/png;base64,{data}' alt='{name}'>" + (
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )
