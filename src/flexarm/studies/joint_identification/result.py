"""What the joint study found: estimated curves beside the truth, the Hammerstein model, plots.

Matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from ..._io import JSONValue, atomic_path
from ..._types import F64
from ...figures import DOUBLE_COLUMN, FigureFormat, new_figure, save_figure, styled
from ...ident._output import output_directory, save_docstring
from .parameters import DriveNonlinearity

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ...ident.hammerstein.identifier import HammersteinIdentifier

__all__ = ["SAVED_FILES", "CurveEstimate", "JointIdentification", "saved_files"]

SAVED_FILES = ("summary.json", "curves.npz", "identify_joint.png")
"""What :meth:`JointIdentification.save` writes (the figure as PNG, the default)."""
_FIGURE_SIZE = (DOUBLE_COLUMN, 5.0)  # inches: two columns of a paper


def saved_files(figure_format: FigureFormat | str | None = None) -> tuple[str, ...]:
    """What :meth:`JointIdentification.save` writes with its figure in ``figure_format``."""
    return (*SAVED_FILES[:-1], FigureFormat.coerce(figure_format).filename("identify_joint"))


@dataclass(frozen=True)
class CurveEstimate:
    """An estimated static curve beside the true one, on a common grid.

    Attributes
    ----------
    name : str
    x : ndarray, shape (g,)
        Grid (units ``x_unit``).
    estimate, truth : ndarray, shape (g,)
        Estimated and true values (units ``y_unit``); NaN where no sample reached.
    x_unit, y_unit : str
    """

    name: str
    x: F64
    estimate: F64
    truth: F64
    x_unit: str
    y_unit: str

    @property
    def rms_error(self) -> float:
        """Root-mean-square error over the grid, units of ``y``."""
        ok = np.isfinite(self.estimate)
        return float(np.sqrt(np.mean((self.estimate[ok] - self.truth[ok]) ** 2)))

    @property
    def max_error(self) -> float:
        """Largest absolute error over the grid, units of ``y``."""
        ok = np.isfinite(self.estimate)
        return float(np.max(np.abs(self.estimate[ok] - self.truth[ok])))

    @property
    def relative_rms_error(self) -> float:
        """:attr:`rms_error` over the range of the true curve on the grid (NaN if flat)."""
        spread = float(np.ptp(self.truth))
        return self.rms_error / spread if spread > 0.0 else math.nan

    def summary(self) -> dict[str, JSONValue]:
        """Error figures as a JSON-able dict."""
        return {
            "grid": [float(self.x[0]), float(self.x[-1])],
            "x_unit": self.x_unit,
            "y_unit": self.y_unit,
            "rms_error": self.rms_error,
            "max_error": self.max_error,
            "relative_rms_error": (
                None if math.isnan(self.relative_rms_error) else self.relative_rms_error
            ),
        }


@dataclass(frozen=True)
class JointIdentification:
    """What :func:`~flexarm.studies.joint_identification.identify_joint` found, beside the truth.

    Attributes
    ----------
    stiffness : CurveEstimate
        ``tau_s(Delta)``: rad to N m.
    friction : CurveEstimate
        ``f(v)``: rad/s to N m.
    drive : CurveEstimate
        The Hammerstein model's static part against the true drive map, N m to N m.
    windup : dict
        Secant stiffness (N m/rad) of the estimate and the truth inside the
        soft-windup region (``|Delta| <= 0.2 / sqrt(asw)``) and outside it
        (between ``2`` and ``4 / sqrt(asw)``, both signs); empty for a linear joint.
    hammerstein : HammersteinIdentifier
        The fitted model (commanded torque, N m, to link acceleration, rad/s**2).
    validation : dict of str to ndarray
        ``"u"`` (N m), ``"y"`` and ``"y_hat"`` (rad/s**2) on the held-out part,
        and ``"t"`` (s); each of shape (n_holds - n_fit,).
    fit_percent : float
        Free-run fit of the Hammerstein model on the held-out part, %.
    reference_fit_percent : float
        Fit of a least-squares FIR model driven by the true ``phi(u)``, %.
    info : dict
        Settings (JSON-able).
    dead_band : dict
        How the Hammerstein model's static part resolves the drive's dead band
        (:func:`~flexarm.studies.joint_identification.estimation.dead_band_summary`).
    """

    stiffness: CurveEstimate
    friction: CurveEstimate
    drive: CurveEstimate
    windup: dict[str, float]
    hammerstein: HammersteinIdentifier
    validation: dict[str, F64]
    fit_percent: float
    reference_fit_percent: float
    info: dict[str, JSONValue]
    dead_band: dict[str, float] = field(default_factory=dict)

    def summary(self) -> dict[str, JSONValue]:
        """Error figures and settings as a JSON-able dict."""
        return {
            "stiffness": self.stiffness.summary(),
            "friction": self.friction.summary(),
            "drive": self.drive.summary(),
            "windup": dict(self.windup),
            "dead_band": dict(self.dead_band),
            "hammerstein": {
                "fit_percent": self.fit_percent,
                "reference_fit_percent": self.reference_fit_percent,
                "method": self.hammerstein.method_,
                "arma_order": self.hammerstein.order_,
                "a": list(self.hammerstein.arma_.a),
                "b": list(self.hammerstein.arma_.b),
                "impulse_response": self.hammerstein.impulse_response_.tolist(),
            },
            "info": dict(self.info),
        }

    @save_docstring(
        "``summary.json``, ``curves.npz`` and ``identify_joint.png``",
        "identify_joint",
        note="The figure is drawn off screen (no pyplot, no change of backend).",
        returns=" (:func:`saved_files`)",
    )
    def save(
        self,
        directory: str | os.PathLike[str],
        *,
        figure_format: FigureFormat | str | None = None,
    ) -> list[Path]:
        out = output_directory(directory)
        paths = [out / name for name in SAVED_FILES[:-1]]
        with atomic_path(paths[0]) as tmp:
            tmp.write_text(json.dumps(self.summary(), indent=2) + "\n")
        arrays: dict[str, F64] = {}
        for curve in (self.stiffness, self.friction, self.drive):
            arrays[f"{curve.name}_x"] = curve.x
            arrays[f"{curve.name}_estimate"] = curve.estimate
            arrays[f"{curve.name}_truth"] = curve.truth
        arrays["impulse_response"] = self.hammerstein.impulse_response_
        with atomic_path(paths[1]) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays)  # type: ignore[arg-type]
        paths.append(save_figure(self.plot(), out / "identify_joint", figure_format))
        return paths

    @styled
    def plot(self, fig: Figure | None = None) -> Figure:
        """Four panels: stiffness (with the windup region enlarged), friction, drive, validation.

        Parameters
        ----------
        fig : matplotlib Figure, optional
            Where to draw (an empty figure); default a new figure two columns of a
            paper wide (not registered with pyplot).

        Returns
        -------
        Figure
            Never blocks.
        """
        if fig is None:
            fig = new_figure(*_FIGURE_SIZE)
        axes = fig.subplots(2, 2)
        s = self.stiffness
        ax = axes[0, 0]
        _curves(ax, 1e3 * s.x, s.truth, s.estimate, ("true", "estimate"), "upper left")
        ax.set(
            xlabel="deflection Δ (mrad)",
            ylabel="stiffness torque τ_s (N m)",
            title="joint stiffness torque",
        )
        w = self.info.get("windup_width_rad")
        if isinstance(w, int | float) and w:  # the soft-windup width, rad (0: none)
            sel = np.abs(s.x) <= 3 * w
            _inset(ax, 1e3 * s.x[sel], s.truth[sel], s.estimate[sel], "soft windup")
        f = self.friction
        ax = axes[0, 1]
        _curves(ax, f.x, f.truth, f.estimate, ("true", "estimate"), "best")
        ax.set(xlabel="link rate v (rad/s)", ylabel="friction f(v) (N m)", title="joint friction")
        d = self.drive
        ax = axes[1, 0]
        _curves(ax, d.x, d.truth, d.estimate, ("true drive map", "Hammerstein φ̂"), "upper left")
        ax.set(xlabel="command u (N m)", ylabel="applied torque (N m)", title="drive nonlinearity")
        span = self.dead_band.get("span_Nm")
        drive = self.info.get("drive")
        if span and isinstance(drive, dict):  # the dead band, enlarged
            truth = DriveNonlinearity(float(drive["dead_band_Nm"]), float(drive["limit_Nm"]))  # type: ignore[arg-type]
            xs = np.linspace(-span, span, 241)
            _inset(ax, xs, truth(xs), self.hammerstein.nonlinearity(xs), "dead band")
        v = self.validation
        ax = axes[1, 1]
        m = min(200, v["t"].shape[0])
        ax.plot(v["t"][:m], v["y"][:m], "k", lw=0.8, label="measured")
        ax.plot(v["t"][:m], v["y_hat"][:m], lw=1.0, label=f"model ({self.fit_percent:.1f} %)")
        ax.set(xlabel="t (s)", ylabel="link acceleration (rad/s²)", title="held-out data")
        ax.legend(loc="best")
        return fig


def _curves(
    ax: Axes,
    x: F64,
    truth: F64,
    estimate: F64,
    labels: tuple[str, str],
    legend: Literal["best", "upper left"],
) -> None:
    """The true curve (dashed, on top) and its estimate against ``x``, with a legend at
    ``legend``."""
    ax.plot(x, truth, "k--", lw=0.8, zorder=3, label=labels[0])
    ax.plot(x, estimate, lw=1.2, label=labels[1])
    ax.legend(loc=legend)


def _inset(ax: Axes, x: F64, truth: F64, estimate: F64, title: str) -> None:
    """The true curve and its estimate enlarged in an inset at the lower right of ``ax``."""
    inset = ax.inset_axes((0.58, 0.08, 0.38, 0.38))
    inset.plot(x, truth, "k--", lw=0.8, zorder=3)
    inset.plot(x, estimate, lw=1.2)
    inset.set_title(title, fontsize=7, pad=2)
    inset.tick_params(labelsize=6, pad=1)
