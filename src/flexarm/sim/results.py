"""The result of a simulation: time series, metrics, persistence and plots."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_path
from ..errors import InvalidValueError
from . import metrics as _m

__all__ = ["SimulationResult"]

F64 = NDArray[np.float64]
_ARRAYS = (
    "t",
    "q",
    "dq",
    "tau",
    "reference",
    "desired",
    "measurement",
    "tip",
    "tip_deflection_gains",
    "mode_start",
    "link_lengths",
)
_FORMAT = "flexarm-simulation-result"
_VERSION = 1


@dataclass
class SimulationResult:
    """Time series of one closed-loop run (rows are control instants ``t_k``).

    Attributes
    ----------
    t : ndarray, shape (K,)
        Control instants, s.
    q, dq : ndarray, shape (K, n_dof)
        Coordinates and rates (names in ``coordinate_names``).
    tau : ndarray, shape (K, n_links)
        Torque applied over ``[t_k, t_k+1)`` (after saturation), N m.
    reference : ndarray, shape (K, 6 + 2 n_links)
        What the controller was given (:mod:`flexarm.control.signals` layout): shaped
        and delayed if those options were on.
    desired : ndarray, shape (K, 2)
        The desired end-effector path, m (errors are measured against it).
    measurement : ndarray, shape (K, 2 n_links + 4 + n_modes)
        What the controller saw.
    tip : ndarray, shape (K, 2)
        True end-effector position with deflection, m.
    info : dict
        Settings and run data (JSON-able).
    """

    t: F64
    q: F64
    dq: F64
    tau: F64
    reference: F64
    desired: F64
    measurement: F64
    tip: F64
    coordinate_names: list[str]
    tip_deflection_gains: F64
    mode_start: NDArray[np.int64]
    link_lengths: F64
    info: dict[str, Any] = field(default_factory=dict)

    # ----------------------------------------------------------- derived series
    @property
    def n_links(self) -> int:
        return int(self.link_lengths.shape[0])

    @property
    def error(self) -> F64:
        """End-effector position error ``|tip - desired|``, m, shape (K,)."""
        return np.linalg.norm(self.tip - self.desired, axis=1)  # type: ignore[no-any-return]

    @property
    def link_deflections(self) -> F64:
        """Tip deflection of each link in its own frame, m, shape (K, n_links)."""
        out = np.zeros((self.t.shape[0], self.n_links))
        for i in range(self.n_links):
            s = slice(int(self.mode_start[i]), int(self.mode_start[i + 1]))
            out[:, i] = self.q[:, s] @ self.tip_deflection_gains[s]
        return out

    @property
    def rigid_tip(self) -> F64:
        """Where the rigid kinematics of the joint angles puts the tip, m, (K, 2)."""
        phi = np.cumsum(self.q[:, : self.n_links], axis=1)
        return np.stack([np.cos(phi) @ self.link_lengths, np.sin(phi) @ self.link_lengths], axis=1)

    @property
    def elastic_deflection(self) -> F64:
        """Distance between the true tip and the rigid-kinematics tip, m, (K,)."""
        return np.linalg.norm(self.tip - self.rigid_tip, axis=1)  # type: ignore[no-any-return]

    # ------------------------------------------------------------------ metrics
    def metrics(self, corner_window: float = 1.0, settle_tolerance: float = 0.01) -> dict[str, Any]:
        """The standard metrics (:mod:`flexarm.sim.metrics`) as a JSON-able dict.

        Parameters
        ----------
        corner_window : float
            Window after each corner for the corner errors, s.
        settle_tolerance : float
            Error band for the settling time, m.
        """
        err = self.error
        end = float(self.info.get("motion_end_s", self.t[-1]))
        corners = self.info.get("corner_times_s", [])
        return {
            "rms_error_m": _m.rms_error(err),
            "max_error_m": _m.max_error(err),
            "corner_errors_m": _m.corner_errors(self.t, err, corners, corner_window).tolist(),
            "residual_vibration_m": _m.residual_vibration(self.t, self.elastic_deflection, end),
            "settling_time_s": _m.settling_time(self.t, err, end, settle_tolerance),
            "control_effort_N2m2s": _m.control_effort(self.t, self.tau),
            "max_torque_Nm": float(np.nanmax(np.abs(self.tau))) if self.tau.size else 0.0,
            "sim_time_s": float(self.t[-1]),
            "wall_time_s": float(self.info.get("wall_time_s", float("nan"))),
        }

    def truncated(self, rows: int) -> SimulationResult:
        """The first ``rows`` rows (used for the partial result of a diverged run)."""
        cut = {
            k: getattr(self, k)[:rows]
            for k in ("t", "q", "dq", "tau", "reference", "desired", "measurement", "tip")
        }
        return SimulationResult(
            **cut,
            coordinate_names=list(self.coordinate_names),
            tip_deflection_gains=self.tip_deflection_gains,
            mode_start=self.mode_start,
            link_lengths=self.link_lengths,
            info=dict(self.info),
        )

    # ------------------------------------------------------------------ export
    def table(self) -> tuple[list[str], F64]:
        """Column names and a 2-D array of the main series: t, q, dq, tau, desired,
        reference and tip positions, error (what ``timeseries.csv`` and
        :meth:`to_pandas` hold)."""
        names = list(self.coordinate_names)
        header = ["t", *names, *(f"d{n}" for n in names)]
        header += [f"tau{i + 1}" for i in range(self.n_links)]
        header += ["x_desired", "y_desired", "x_ref", "y_ref", "x_tip", "y_tip", "error"]
        values = np.column_stack(
            [
                self.t,
                self.q,
                self.dq,
                self.tau,
                self.desired,
                self.reference[:, :2],
                self.tip,
                self.error,
            ]
        )
        return header, values

    def to_pandas(self) -> Any:
        """A ``pandas.DataFrame`` of :meth:`table` indexed by time (pandas is
        imported on demand)."""
        import pandas as pd

        header, values = self.table()
        frame = pd.DataFrame(values, columns=header)
        return frame.set_index("t")

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write an ``.npz`` file atomically (a temporary file, then a rename)."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        meta = {
            "format": _FORMAT,
            "version": _VERSION,
            "coordinate_names": self.coordinate_names,
            "info": self.info,
        }
        arrays = {k: getattr(self, k) for k in _ARRAYS}
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, meta=np.array(json.dumps(meta)), **arrays)
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SimulationResult:
        """Read a file written by :meth:`save`; malformed files raise ValueError."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as data:
                meta = json.loads(str(data["meta"]))
                arrays = {k: np.array(data[k]) for k in _ARRAYS}
        except FileNotFoundError:
            raise
        except Exception as exc:
            raise InvalidValueError(f"{path} is not a flexarm simulation result: {exc}") from exc
        if meta.get("format") != _FORMAT:
            raise InvalidValueError(f"{path} is not a flexarm simulation result (format field).")
        return cls(**arrays, coordinate_names=list(meta["coordinate_names"]), info=meta["info"])

    # ------------------------------------------------------------------ plots
    def plot(self, fig: Any = None) -> Any:
        """Three panels: the XY path against the desired one, the error, the link
        deflections. Returns the matplotlib figure (never blocks)."""
        import matplotlib.pyplot as plt

        if fig is None:
            fig = plt.figure(figsize=(10, 6.5), layout="constrained")
        grid = fig.add_gridspec(2, 2)
        ax_xy = fig.add_subplot(grid[:, 0])
        ax_err = fig.add_subplot(grid[0, 1])
        ax_def = fig.add_subplot(grid[1, 1], sharex=ax_err)
        ax_xy.plot(self.desired[:, 0], self.desired[:, 1], "k--", lw=1, label="desired")
        ax_xy.plot(self.tip[:, 0], self.tip[:, 1], lw=1.2, label="end effector")
        ax_xy.set(
            xlabel="x [m]",
            ylabel="y [m]",
            aspect="equal",
            title=f"{self.info.get('controller', '')}, sensor {self.info.get('sensor', '')}",
        )
        ax_xy.legend(loc="best", fontsize="small")
        ax_err.plot(self.t, 1e3 * self.error, lw=1)
        ax_err.set(ylabel="error [mm]")
        for tc in self.info.get("corner_times_s", []):
            ax_err.axvline(tc, color="0.8", lw=0.8, zorder=0)
        for i in range(self.n_links):
            ax_def.plot(self.t, 1e3 * self.link_deflections[:, i], lw=1, label=f"link {i + 1}")
        ax_def.set(xlabel="t [s]", ylabel="tip deflection [mm]")
        ax_def.legend(loc="best", fontsize="small")
        return fig
