"""``flexarm identify --hammerstein``: a Hammerstein model from data, or the robot-joint study.

With DATA, :class:`flexarm.ident.HammersteinIdentifier` is fitted to an input
column ``u`` and an output column ``y``; without, the nonlinear-joint robot is
excited with a random torque and its stiffness, friction and drive
nonlinearity are identified (:func:`flexarm.studies.joint_identification.identify_joint`).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._io import json_ready, output_directory
from ..ident import HammersteinIdentifier
from ._common import UsageError

__all__ = ["DATA_FILES", "ROBOT_FILES", "fit_data", "parse_known", "parse_order", "run_robot"]

PROG = "flexarm identify --hammerstein"
DATA_FILES = ("nonlinearity.csv", "impulse_response.csv", "hammerstein.png", "summary.json")
ROBOT_FILES = ("summary.json", "curves.npz", "identify_joint.png")
F64 = NDArray[np.float64]


def _fail(message: str) -> UsageError:
    return UsageError(f"{PROG}: error: {message}")


def parse_order(text: str) -> int | str:
    """``--order``: "bic", "aic" or a positive integer."""
    if text in ("bic", "aic"):
        return text
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(
            f"must be 'bic', 'aic' or an integer >= 1. Got {text!r} instead."
        )
    return value


def parse_known(text: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """``--known X1:PHI1,X2:PHI2``: two points where the nonlinearity is known."""
    try:
        pairs = [tuple(float(v) for v in item.split(":")) for item in text.split(",")]
    except ValueError:
        pairs = []
    if len(pairs) != 2 or any(len(p) != 2 for p in pairs):
        raise argparse.ArgumentTypeError(
            f"must be two points X1:PHI1,X2:PHI2 (numbers). Got {text!r} instead."
        )
    (x1, p1), (x2, p2) = pairs
    return (x1, p1), (x2, p2)


def fit_data(x: F64, y: F64, dropped: int, args: argparse.Namespace, out: Path | None) -> Any:
    """Fit the identifier to ``u = x``, ``y``; write the files into ``out`` if given."""
    t0 = time.perf_counter()
    model = HammersteinIdentifier(
        n_lags=40 if args.lags is None else args.lags,
        order="bic" if args.order is None else args.order,
        known_points=args.known,
    )
    try:
        model.fit(x, y)
        y_hat = model.predict(x)
        fit = model.score(x, y)
    except (TypeError, ValueError) as exc:
        raise _fail(str(exc)) from None
    grid = np.linspace(float(x.min()), float(x.max()), 201)
    phi = model.nonlinearity(grid)
    summary: dict[str, Any] = json_ready(
        {
            "status": "ok",
            "mode": "hammerstein",
            "data": str(args.data),
            "columns": {"u": args.x, "y": args.y},
            "n_samples": int(x.shape[0]),
            "dropped_nan_rows": dropped,
            "n_lags": model.n_lags,
            "known_points": args.known,
            "normalisation": "two-point" if args.known is not None else "up to an affine map",
            "bandwidth": model.bandwidth_,
            "arma_order": model.order_,
            "a": list(model.arma_.a),
            "b": list(model.arma_.b),
            "impulse_response": model.impulse_response_,
            "fit_percent": fit,
            "nonlinearity": {"x": grid, "phi": phi},
            "wall_time_s": time.perf_counter() - t0,
            "out": None if out is None else str(out),
            "files": [] if out is None else list(DATA_FILES),
        }
    )
    if out is not None:
        _write_data(out, x, y, y_hat, grid, phi, model.impulse_response_, summary)
    return summary


def _write_data(
    out: Path, u: F64, y: F64, y_hat: F64, grid: F64, phi: F64, ir: F64, summary: dict[str, Any]
) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with output_directory(out) as tmp:
        np.savetxt(
            tmp / "nonlinearity.csv",
            np.column_stack([grid, phi]),
            fmt="%.12g",
            delimiter=",",
            header="u,phi",
            comments="",
        )
        np.savetxt(
            tmp / "impulse_response.csv",
            np.column_stack([np.arange(ir.shape[0]), ir]),
            fmt="%.12g",
            delimiter=",",
            header="lag,impulse_response",
            comments="",
        )
        fig = Figure(figsize=(11, 4), layout="constrained")
        FigureCanvasAgg(fig)
        ax1, ax2, ax3 = fig.subplots(1, 3)
        ax1.plot(grid, phi, lw=2)
        ax1.set_xlabel("u")
        ax1.set_ylabel("identified nonlinearity")
        ax1.set_title(summary["normalisation"])
        ax2.stem(np.arange(ir.shape[0]), ir)
        ax2.set_xlabel("lag")
        ax2.set_title(f"impulse response (ARMA order {summary['arma_order']})")
        shown = slice(0, min(u.shape[0], 2000))
        ax3.plot(y[shown], lw=1, label="measured")
        ax3.plot(y_hat[shown], lw=1, label="model (free run)")
        ax3.set_xlabel("sample")
        ax3.set_title(f"fit {summary['fit_percent']:.1f} %")
        ax3.legend(fontsize=8)
        fig.savefig(tmp / "hammerstein.png", dpi=100)
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


def run_robot(args: argparse.Namespace, out: Path | None) -> Any:
    """The random-torque experiment on the nonlinear-joint robot."""
    from ..studies.joint_identification import JointExcitation, identify_joint

    t0 = time.perf_counter()
    try:
        excitation = JointExcitation(duration=60.0 if args.duration is None else args.duration)
        res = identify_joint(
            excitation=excitation,
            torque_measurement="sensor" if args.torque_sensor else "motor-balance",
            n_lags=40 if args.lags is None else args.lags,
            rng=0 if args.seed is None else args.seed,
        )
    except (TypeError, ValueError) as exc:
        raise _fail(str(exc)) from None
    summary: dict[str, Any] = json_ready(
        {
            "status": "ok",
            "mode": "hammerstein-robot",
            "duration_s": excitation.duration,
            "torque_measurement": "sensor" if args.torque_sensor else "motor-balance",
            "seed": 0 if args.seed is None else args.seed,
            **res.summary(),
            "wall_time_s": time.perf_counter() - t0,
            "out": None if out is None else str(out),
            "files": [] if out is None else list(ROBOT_FILES),
        }
    )
    if out is not None:
        with output_directory(out) as tmp:
            res.save(tmp)
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def format_summary(summary: dict[str, Any]) -> str:
    """The human-readable summary."""
    if summary["mode"] == "hammerstein":
        return "\n".join(
            [
                f"{PROG}: {summary['n_samples']} samples from {summary['data']} "
                f"(u = column {summary['columns']['u']}, y = column {summary['columns']['y']})",
                f"  linear part: {summary['n_lags']} lags, ARMA order {summary['arma_order']}; "
                f"nonlinearity {summary['normalisation']}",
                f"  free-run fit on the data: {summary['fit_percent']:.2f} %",
            ]
        )
    s, f, d, h = summary["stiffness"], summary["friction"], summary["drive"], summary["hammerstein"]
    return "\n".join(
        [
            f"{PROG}: random-torque experiment on the nonlinear joint "
            f"({summary['duration_s']:g} s, tau_s by {summary['torque_measurement']})",
            f"  stiffness curve: RMS error {s['rms_error']:.4g} {s['y_unit']}",
            f"  friction curve:  RMS error {f['rms_error']:.4g} {f['y_unit']}",
            f"  drive nonlinearity (Hammerstein): RMS error {d['rms_error']:.4g} {d['y_unit']}",
            f"  Hammerstein free-run fit on held-out data: {h['fit_percent']:.2f} % "
            f"(reference {h['reference_fit_percent']:.2f} %)",
        ]
    )
