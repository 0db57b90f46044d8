"""What :func:`~flexarm.studies.reproduction.reproduce` found, and its report.

:class:`Reproduction` holds the case results, the verdicts and the settings,
and renders them: a JSON summary, a CSV table, a text summary, figures (PNG,
PDF or SVG: :class:`flexarm.figures.FigureFormat`) and a self-contained HTML
report (:func:`output_files`, written at once;
:mod:`~flexarm.studies.reproduction.html`). Matplotlib is imported only when a
figure is drawn.

Each controller has one name wherever it appears — the JSON summary, the
console, the figures and the report: ``pd`` (the paper's nonadaptive
Jacobian-transpose PD) and ``fuzzy`` (the paper's fuzzy adaptive law), the names
that select them on the command line. Numbers for people are rounded to what
they mean (:mod:`~flexarm.studies.reproduction.units`: errors in mm to three
significant figures); the JSON and CSV keep every digit, in SI units.
"""

from __future__ import annotations

import csv
import inspect
import json
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict, TypeVar

import numpy as np

from ..._io import JSONValue, json_ready, output_directory
from ...figures import (
    DOUBLE_COLUMN,
    SINGLE_COLUMN,
    FigureFormat,
    figure_bytes,
    new_figure,
    style,
    styled,
)
from .cases import (
    CONTROLLER_DESCRIPTIONS,
    CONTROLLER_KINDS,
    SENSOR_CASES,
    SENSOR_LABELS,
    CaseResult,
)
from .units import mm, sig
from .verdicts import Claim

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .beyond import Beyond
    from .converged import Converged

__all__ = [
    "FIGURES",
    "FIGURE_SIZE",
    "FIGURE_SIZES",
    "OUTPUT_FILES",
    "REPORT_DPI",
    "VOCABULARY",
    "Reproduction",
    "Settings",
    "output_files",
]

VOCABULARY = (
    "Each claim is judged under each sensor model and is made of parts, each about a set "
    "of runs; a part holds when it holds for every run it speaks of (a claim about every "
    "sensor holds only if it holds for each). Supported: every part holds. Not supported: "
    "no part holds. Partly supported: some parts hold and others do not, which happens only "
    "for a claim the paper states in parts (collocated and noncollocated sensors)."
)
VOCABULARY_SHORT = "supported: every part holds for every run it covers; partly: some parts only"

FIGURES = ("tracking", "deflections", "fuzzy_surface", "sensitivity")
"""The report's figures (file names without the format's suffix)."""
FIGURE_SIZES: dict[str, tuple[float, float]] = {
    "tracking": (DOUBLE_COLUMN, 8.0),
    "deflections": (DOUBLE_COLUMN, 6.4),
    "fuzzy_surface": (SINGLE_COLUMN, 3.0),
    "sensitivity": (DOUBLE_COLUMN, 2.9),
}
"""Size of each figure, inches: two columns of a paper wide (the surface: one)."""
FIGURE_SIZE = FIGURE_SIZES["tracking"]
"""Size of the report's multi-panel figures, inches (:data:`FIGURE_SIZES`)."""
OUTPUT_FILES = ("summary.json", "table.csv", "report.html", *(f"{f}.png" for f in FIGURES))
"""What :meth:`Reproduction.write` writes (figures as PNG, the default)."""
REPORT_DPI = 150.0
"""Resolution of the PNG figures embedded in ``report.html`` when the figure files are
PDF or SVG, or PNG finer than 300 dpi (the page stays light), dpi."""
_EMBED_MAX_DPI = 300.0


def output_files(figure_format: FigureFormat | str | None = None) -> tuple[str, ...]:
    """What :meth:`Reproduction.write` writes with figures in ``figure_format``."""
    fmt = FigureFormat.coerce(figure_format)
    return (*OUTPUT_FILES[:3], *(fmt.filename(f) for f in FIGURES))


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


_FIGURE_PARAMETERS = """

Parameters
----------
fig : matplotlib Figure, optional
    Where to draw (an empty figure); default a new figure of
    :data:`FIGURE_SIZES` (not registered with pyplot).

Returns
-------
Figure
"""

_Plot = TypeVar("_Plot", bound=Callable[..., Any])


def _figure_parameters(plot: _Plot) -> _Plot:
    """Complete the docstring of a ``plot_*(fig=None)`` method with the sections all of
    them share."""
    plot.__doc__ = inspect.cleandoc(plot.__doc__ or "") + _FIGURE_PARAMETERS
    return plot


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
            f"(control period {s['dt_s']:g} s; 'tracks well' = RMS <= {mm(s['tolerance_m'])})",
            *(f"  {k}: {CONTROLLER_DESCRIPTIONS[k]}" for k in CONTROLLER_KINDS),
            f"  {'controller':<12}{'sensor':<18}{'model':<10}{'status':<24}"
            f"{'RMS error':>11}{'max error':>11}",
        ]
        for c in self.cases:
            row = c.row()
            status = "ok" if c.status == "ok" else f"diverged at {sig(c.diverged_at_s)} s"
            rms, mx = mm(_number(row["rms_error_m"])), mm(_number(row["max_error_m"]))
            model = "-" if c.case.sensor == "joint" else c.case.sensor_model
            sensor = SENSOR_LABELS[c.case.sensor]
            lines.append(
                f"  {c.case.controller:<12}{sensor:<18}{model:<10}{status:<24}{rms:>11}{mx:>11}"
            )
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
    def write(
        self, out: str | os.PathLike[str], *, figure_format: FigureFormat | str | None = None
    ) -> list[str]:
        """Write every artefact into the new (or empty) directory ``out`` at once.

        Parameters
        ----------
        out : str or path-like
            The directory.
        figure_format : FigureFormat or str, optional
            Format and resolution of the figure files (default PNG at
            :data:`flexarm.figures.DEFAULT_DPI`). ``report.html`` embeds them as
            PNG (drawn again at :data:`REPORT_DPI` when the files are PDF or SVG).

        Returns
        -------
        list of str
            The file names written (:func:`output_files`). Nothing appears under
            ``out`` unless all of them were written.
        """
        fmt = FigureFormat.coerce(figure_format)
        target = Path(os.path.abspath(out))
        drawn = {stem: self.draw(stem) for stem in FIGURES}
        files = {fmt.filename(stem): figure_bytes(fig, fmt) for stem, fig in drawn.items()}
        if fmt.format == "png" and fmt.dpi <= _EMBED_MAX_DPI:
            embedded, dpi = files, fmt.dpi
        else:  # the same figures, as PNG for the page
            dpi = REPORT_DPI
            page_format = FigureFormat("png", dpi)
            for fig in drawn.values():
                fig.set_layout_engine("none")  # laid out once already (in figure fractions)
            embedded = {f"{s}.png": figure_bytes(fig, page_format) for s, fig in drawn.items()}
        with output_directory(target) as tmp:
            summary = self.summary()
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
            self._write_table(tmp / "table.csv")
            for name, data in files.items():
                (tmp / name).write_bytes(data)
            (tmp / "report.html").write_text(self.html(embedded, dpi=dpi))
        return list(output_files(fmt))

    def figures(self, figure_format: FigureFormat | str | None = None) -> dict[str, bytes]:
        """The report's figures (:data:`FIGURES`) as file contents, by file name
        (``"tracking.pdf"``: :class:`flexarm.figures.FigureFormat`; drawn off
        screen, no pyplot)."""
        fmt = FigureFormat.coerce(figure_format)
        return {fmt.filename(stem): figure_bytes(self.draw(stem), fmt) for stem in FIGURES}

    def figures_png(self, dpi: float = REPORT_DPI) -> dict[str, bytes]:
        """The report's figures as PNG bytes at ``dpi``, by file name (:meth:`figures`)."""
        return self.figures(FigureFormat("png", dpi))

    def draw(self, name: str) -> Figure:
        """A new figure of :data:`FIGURES` at its size (:data:`FIGURE_SIZES`)."""
        fig = new_figure(*FIGURE_SIZES[name])
        if name == "fuzzy_surface":
            with style():
                ax = fig.add_subplot(projection="3d")
            self.plot_surface(ax)
        else:
            {
                "tracking": self.plot_tracking,
                "deflections": self.plot_deflections,
                "sensitivity": self.plot_sensitivity,
            }[name](fig)
        return fig

    def _write_table(self, path: Path) -> None:
        groups = [("matrix", self.cases), ("delay", self.delay_study), ("ks", self.ks_study)]
        rows = [{"study": g, **c.row()} for g, cases in groups for c in cases]
        with path.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow({k: "" if v is None else v for k, v in row.items()})

    # ------------------------------------------------------------- figures
    def _panels(self, fig: Figure, xlabel: str, ylabel: str) -> Iterator[tuple[Axes, CaseResult]]:
        """One axes per case of the matrix (sensor models and controllers by rows,
        sensors by columns), titled with the case's outcome. Every axes carries its
        labels; they are drawn on the bottom row and the left column only."""
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
                ax.set_title(_panel_title(case), fontsize="small")
                ax.set(xlabel=xlabel, ylabel=ylabel)
                ax.xaxis.label.set_visible(i == len(rows) - 1)
                ax.yaxis.label.set_visible(j == 0)
                yield ax, case

    @styled
    @_figure_parameters
    def plot_tracking(self, fig: Figure | None = None) -> Figure:
        """XY path of the end effector against the square, one panel per case of the matrix."""
        fig = _figure(fig, "tracking")
        for ax, c in self._panels(fig, "x (m)", "y (m)"):
            r = c.result
            step = max(1, r.t.shape[0] // _PATH_POINTS)  # a path far finer than the panel
            ax.plot(r.desired[::step, 0], r.desired[::step, 1], "k--", lw=0.8, label="reference")
            ax.plot(r.tip[::step, 0], r.tip[::step, 1], label="end effector")
            ax.set_aspect("equal", adjustable="datalim")
        if fig.axes:
            fig.axes[0].legend(loc="best")
        return fig

    @styled
    @_figure_parameters
    def plot_deflections(self, fig: Figure | None = None) -> Figure:
        """Tip deflection of each link against time, one panel per case of the matrix."""
        from ...sim.results import envelope

        fig = _figure(fig, "deflections")
        for ax, c in self._panels(fig, "t (s)", "tip deflection (mm)"):
            d = c.result.link_deflections
            for k in range(d.shape[1]):
                ax.plot(*envelope(c.result.t, 1e3 * d[:, k], _PATH_POINTS), label=f"link {k + 1}")
        if fig.axes:
            fig.axes[0].legend(loc="best")
        return fig

    @styled
    def plot_surface(self, ax: Axes | None = None) -> tuple[Axes, Artist]:
        """The paper's fuzzy surface λ(δ1, δ2) (:func:`flexarm.fuzzy.plot_surface`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            A 3-D axes gets a surface, a 2-D axes a filled contour; default a
            new figure with a 3-D axes, one column of a paper wide.

        Returns
        -------
        (ax, artist)
        """
        from ...fuzzy import paper_system, plot_surface

        ax, artist = plot_surface(paper_system(), ax=ax)
        ax.set_title("fuzzy adaptation λ(δ1, δ2), the paper's rules")
        return ax, artist

    @styled
    @_figure_parameters
    def plot_sensitivity(self, fig: Figure | None = None) -> Figure:
        """RMS error of the fuzzy law against ``ks``, one panel per sensor (x: diverged).

        Each series (sensor model and adaptation law) has its own colour, marker and
        line style, and is shifted a little along the ``ks`` axis, so that series
        with the same error (the encoders read the same under both sensor models)
        do not hide each other. The ``pd`` runs are horizontal lines.
        """
        from matplotlib.ticker import LogFormatter

        fig = _figure(fig, "sensitivity")
        axes = np.atleast_1d(fig.subplots(1, len(SENSOR_CASES), sharey=True))
        ok = [c.rms for c in self.ks_study if c.status == "ok"]
        top = 2.0 * max(ok) if ok else 1.0
        ks_values = sorted({c.case.ks for c in self.ks_study})
        pos = {k: i for i, k in enumerate(ks_values)}
        models = list(dict.fromkeys(c.case.sensor_model for c in self.ks_study))
        series = [(m, law) for m in models for law in self.settings["laws"]]
        width = 0.36 / max(len(series), 1)  # the series' shifts span a third of a ks step
        markers = ("o", "s", "^", "D", "v", "P")
        for ax, sensor in zip(axes, SENSOR_CASES, strict=True):
            for k, (model, law) in enumerate(series):
                shift = (k - (len(series) - 1) / 2) * width
                cs = sorted(
                    (
                        c
                        for c in self.ks_study
                        if c.case.sensor == sensor
                        and c.case.law == law
                        and c.case.sensor_model == model
                    ),
                    key=lambda c: c.case.ks,
                )
                x = [pos[c.case.ks] + shift for c in cs]
                y = [1e3 * c.rms if c.status == "ok" else np.nan for c in cs]
                (line,) = ax.plot(
                    x,
                    y,
                    marker=markers[k % len(markers)],
                    ls="-" if law == series[0][1] else "--",
                    mfc="none",
                    ms=4.5,
                    label=f"fuzzy, {model} model, {law} law",
                    zorder=3 + k,
                )
                xd = [pos[c.case.ks] + shift for c in cs if c.status != "ok"]
                ax.plot(xd, [1e3 * top] * len(xd), "x", color=line.get_color(), ms=5, zorder=3)
            drawn: set[tuple[str | float, ...]] = set()
            for model, ls in zip(models, ("-.", ":"), strict=False):
                pd = [
                    c
                    for c in self.cases
                    if c.case.controller == "pd"
                    and c.case.sensor == sensor
                    and c.case.sensor_model == model
                ]
                if pd and pd[0].status == "ok" and pd[0].case.key() not in drawn:
                    drawn.add(pd[0].case.key())  # the encoders' run is one run in both models
                    ax.axhline(
                        1e3 * pd[0].rms, color="k", ls=ls, lw=0.8, label=f"pd, {model} model"
                    )
            ax.set_xticks(range(len(ks_values)), [f"{k:g}" for k in ks_values])
            ax.set_xlabel("membership-width gain ks (-)")
            ax.set_ylabel("RMS error (mm)")
            ax.yaxis.label.set_visible(ax is axes[0])
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(LogFormatter())  # 200, not 2 x 10^2
            ax.yaxis.set_minor_formatter(LogFormatter(minor_thresholds=(1.0, 0.4)))
            ax.set_title(f"{SENSOR_LABELS[sensor]} sensor (x: diverged)")
            if not self.ks_study:
                ax.text(0.5, 0.5, "no ks study run", ha="center", transform=ax.transAxes)
        handles, labels = axes[0].get_legend_handles_labels()
        for ax in axes[1:]:  # every series once, wherever it appears
            for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
                if label not in labels:
                    handles.append(h)
                    labels.append(label)
        if handles:
            fig.legend(handles, labels, loc="outside lower center", ncols=3)
        return fig

    # ------------------------------------------------------------- HTML
    def html(self, figures: dict[str, bytes], *, dpi: float = REPORT_DPI) -> str:
        """A self-contained HTML report (:mod:`~flexarm.studies.reproduction.html`).

        Parameters
        ----------
        figures : dict of str to bytes
            The PNG figures by file name (:meth:`figures_png`).
        dpi : float
            Their resolution, dots per inch (sets the size they are shown at).
        """
        from .html import report_page

        return report_page(self, figures, dpi)


_PATH_POINTS = 4000
"""Points drawn per series of a panel at most (a panel is a few hundred pixels wide)."""


def _number(value: object) -> float | None:
    return float(value) if isinstance(value, int | float) else None


def _figure(fig: Figure | None, name: str) -> Figure:
    return new_figure(*FIGURE_SIZES[name]) if fig is None else fig


def _panel_title(c: CaseResult) -> str:
    head = f"{c.case.controller}, {SENSOR_LABELS[c.case.sensor]}"
    if c.case.sensor != "joint":
        head += f" ({c.case.sensor_model} model)"
    if c.status != "ok":
        return f"{head}\ndiverged at t = {sig(c.diverged_at_s)} s"
    return f"{head}\nRMS {mm(_number(c.metrics['rms_error_m']))}"
