"""The result of a simulation: time series, metrics, persistence and plots.

:class:`SimulationResult` is what :func:`flexarm.simulate` (closed loop) and
:func:`flexarm.simulate_open_loop` (driven by joint torques) both return;
:func:`assemble_result` is the one place that turns a run's raw arrays into it,
and :class:`SimulationError` carries the partial result of a run that diverged.
"""

from __future__ import annotations

import itertools
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._io import JSONValue, atomic_path, output_directory
from ..errors import FlexarmError, InvalidValueError
from ..figures import DOUBLE_COLUMN, FigureFormat, new_figure, save_figure, styled
from ..model.arrays import ArmArrays
from . import metrics as _m

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.animation import FuncAnimation
    from matplotlib.figure import Figure

__all__ = [
    "RESULT_FILES",
    "SimulationError",
    "SimulationResult",
    "assemble_result",
    "result_files",
]

RESULT_FILES = ("result.npz", "summary.json", "timeseries.csv", "tracking.png")
"""What :meth:`SimulationResult.write` puts in a directory (figures as PNG, the default)."""


def result_files(figure_format: FigureFormat | str | None = None) -> tuple[str, ...]:
    """What :meth:`SimulationResult.write` puts in a directory with figures in
    ``figure_format`` (:class:`flexarm.figures.FigureFormat`; default PNG)."""
    fmt = FigureFormat.coerce(figure_format)
    return (*RESULT_FILES[:-1], fmt.filename("tracking"))


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
_OPTIONAL_ARRAYS = ("tip_slope_gains", "mode_shape_samples")  # absent from older files
_SHAPE_POINTS = 21
"""Points per link at which :func:`assemble_result` samples the mode shapes."""
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
    tip_slope_gains : ndarray, shape (n_dof,), optional
        Slope of each mode at its link's tip (0 at the other coordinates).
    mode_shape_samples : ndarray, shape (n_dof, S), optional
        Each mode's shape at ``S`` evenly spaced points from its link's joint
        to its tip (0 at the other coordinates): the deflected links that
        :meth:`animate` draws. Results saved by older versions have neither.

    A run driven open loop (:func:`flexarm.simulate_open_loop`) has no
    reference and no measurement (``reference`` and ``measurement`` have no
    columns) and its ``desired`` path is NaN, so its tracking metrics are NaN.
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
    info: dict[str, JSONValue] = field(default_factory=dict)
    tip_slope_gains: F64 | None = None
    mode_shape_samples: F64 | None = None

    # ----------------------------------------------------------- derived series
    @property
    def n_links(self) -> int:
        return int(self.link_lengths.shape[0])

    @property
    def error(self) -> F64:
        """End-effector position error ``|tip - desired|``, m, shape (K,)."""
        return _m.row_distances(self.tip, self.desired)

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
        phi = self.q[:, : self.n_links].copy()  # absolute angles: a cumulative sum by column
        for i in range(1, self.n_links):
            phi[:, i] += phi[:, i - 1]
        return np.stack([np.cos(phi) @ self.link_lengths, np.sin(phi) @ self.link_lengths], axis=1)

    @property
    def elastic_deflection(self) -> F64:
        """Distance between the true tip and the rigid-kinematics tip, m, (K,)."""
        return self._elastic_deflection(slice(None))

    def _elastic_deflection(self, rows: slice) -> F64:
        """:attr:`elastic_deflection` of ``rows`` (each row's number as in the whole)."""
        angles = self.q[rows, : self.n_links]
        return _m.elastic_deflection(angles, self.link_lengths, self.tip[rows])

    # ------------------------------------------------------------------ metrics
    def metrics(
        self, corner_window: float = 1.0, settle_tolerance: float = 0.01
    ) -> dict[str, float | list[float]]:
        """The standard metrics (:mod:`flexarm.sim.metrics`) as a JSON-able dict.

        Parameters
        ----------
        corner_window : float
            Window after each corner for the corner errors, s.
        settle_tolerance : float
            Error band for the settling time, m.
        """
        t, err, tau = self.t, self.error, self.tau
        end = _float(self.info.get("motion_end_s"), float(t[-1]))
        corners = self.corner_times
        # the elastic deflection of the rows the residual vibration reads, only
        deflection = self._elastic_deflection(slice(_m.residual_start(t, end), None))
        return {
            "rms_error_m": _m.rms_error(err),
            "max_error_m": _m.max_error(err),
            "corner_errors_m": _m.corner_errors(t, err, corners, corner_window).tolist(),
            "residual_vibration_m": _m.residual_vibration(t, deflection, end),
            "settling_time_s": _m.settling_time(t, err, end, settle_tolerance),
            "control_effort_N2m2s": _m.control_effort(t, tau),
            "max_torque_Nm": _max_abs(tau),
            "sim_time_s": float(self.t[-1]),
            "wall_time_s": _float(self.info.get("wall_time_s"), float("nan")),
        }

    @property
    def corner_times(self) -> list[float]:
        """The trajectory's corner times, s (empty for an open-loop run)."""
        corners = self.info.get("corner_times_s", [])
        if not isinstance(corners, list):
            return []
        return [float(c) for c in corners if isinstance(c, int | float)]

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
            tip_slope_gains=self.tip_slope_gains,
            mode_shape_samples=self.mode_shape_samples,
        )

    # ------------------------------------------------------------------ export
    def table(self) -> tuple[list[str], F64]:
        """Column names and a 2-D array of the main series: t, q, dq, tau, desired,
        reference and tip positions, error (what ``timeseries.csv`` and
        :meth:`to_pandas` hold)."""
        return self._table_rows(0, self.t.shape[0])

    def _table_rows(self, k0: int, k1: int) -> tuple[list[str], F64]:
        """:meth:`table` of rows ``k0 <= k < k1``."""
        names = list(self.coordinate_names)
        header = ["t", *names, *(f"d{n}" for n in names)]
        header += [f"tau{i + 1}" for i in range(self.n_links)]
        header += ["x_desired", "y_desired"]
        rows = slice(k0, k1)
        tip, desired = self.tip[rows], self.desired[rows]
        columns = [self.t[rows], self.q[rows], self.dq[rows], self.tau[rows], desired]
        if self.reference.shape[1]:
            header += ["x_ref", "y_ref"]
            columns.append(self.reference[rows, :2])
        header += ["x_tip", "y_tip", "error"]
        columns += [tip, np.linalg.norm(tip - desired, axis=1)]
        return header, np.column_stack(columns)

    def _write_csv(self, path: Path, rows_per_chunk: int = 16384) -> None:
        """``timeseries.csv``: :meth:`table` written a chunk of rows at a time (bounded
        memory; each chunk formatted in one operation)."""
        header, _ = self._table_rows(0, 0)
        line = ",".join(["%.10g"] * len(header)) + "\n"
        with open(path, "w", encoding="ascii", newline="") as fh:
            fh.write(",".join(header) + "\n")
            for k0 in range(0, self.t.shape[0], rows_per_chunk):
                _, block = self._table_rows(k0, k0 + rows_per_chunk)
                fh.write((line * block.shape[0]) % tuple(block.ravel().tolist()))

    def to_pandas(self) -> pd.DataFrame:
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
        arrays |= {k: getattr(self, k) for k in _OPTIONAL_ARRAYS if getattr(self, k) is not None}
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
                arrays |= {k: np.array(data[k]) for k in _OPTIONAL_ARRAYS if k in data.files}
        except FileNotFoundError:
            raise
        except Exception as exc:
            raise InvalidValueError(f"{path} is not a flexarm simulation result: {exc}") from exc
        if meta.get("format") != _FORMAT:
            raise InvalidValueError(f"{path} is not a flexarm simulation result (format field).")
        return cls(**arrays, coordinate_names=list(meta["coordinate_names"]), info=meta["info"])

    def write(
        self,
        directory: str | os.PathLike[str],
        summary: Mapping[str, JSONValue],
        *,
        figure_format: FigureFormat | str | None = None,
    ) -> Path:
        """Write :func:`result_files` into ``directory`` (new, or empty) all at once:
        ``result.npz`` (:meth:`save`), ``summary.json`` (``summary``),
        ``timeseries.csv`` (:meth:`table`) and ``tracking.png`` (:meth:`plot`; or
        ``.pdf``, ``.svg`` as ``figure_format`` says, :class:`flexarm.figures.FigureFormat`),
        written beside it and renamed into place, so that an interrupted write
        leaves nothing behind."""
        fmt = FigureFormat.coerce(figure_format)
        out = Path(directory)
        with output_directory(out) as tmp:
            self.save(tmp / "result.npz")
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
            self._write_csv(tmp / "timeseries.csv")
            save_figure(self.plot(), tmp / "tracking", fmt)
        return out

    # ------------------------------------------------------------------ plots
    def animate(
        self, *, fps: float = 25.0, speed: float = 1.0, fig: Figure | None = None
    ) -> FuncAnimation:
        """The deflected arm moving (Matplotlib ``FuncAnimation``; never shown):
        :func:`flexarm.sim.animation.animate`, whose parameters these are."""
        from .animation import animate

        return animate(self, fps=fps, speed=speed, fig=fig)

    @styled
    def plot(self, fig: Figure | None = None) -> Figure:
        """Three panels: the XY path against the desired one, the error, the link
        deflections (in :mod:`flexarm.figures`' style, across two columns of a paper).

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Drawn into (a new figure by default, not registered with pyplot).

        Returns
        -------
        matplotlib.figure.Figure
            Never shown, never blocks.
        """
        if fig is None:
            fig = new_figure(DOUBLE_COLUMN, 3.6)
        grid = fig.add_gridspec(2, 2, width_ratios=(1.15, 1.0))
        ax_xy = fig.add_subplot(grid[:, 0])
        ax_err = fig.add_subplot(grid[0, 1])
        ax_def = fig.add_subplot(grid[1, 1], sharex=ax_err)
        stride = max(1, self.t.shape[0] // _PLOT_POINTS)  # a path far finer than the page
        desired, tip = self.desired[::stride], self.tip[::stride]
        ax_xy.plot(desired[:, 0], desired[:, 1], "k--", lw=0.8, label="desired")
        ax_xy.plot(tip[:, 0], tip[:, 1], label="end effector")
        ax_xy.set(xlabel="x (m)", ylabel="y (m)")
        ax_xy.set_aspect("equal", adjustable="datalim")
        ax_xy.set_title(
            f"controller {self.info.get('controller', '')}, sensor {self.info.get('sensor', '')}"
        )
        ax_xy.legend(loc="best")
        ax_err.plot(*envelope(self.t, 1e3 * self.error, _PLOT_POINTS))
        ax_err.set(ylabel="error (mm)")
        ax_err.tick_params(labelbottom=False)
        t0, t1 = (float(self.t[0]), float(self.t[-1])) if self.t.size else (0.0, 0.0)
        for tc in self.corner_times:
            if t0 <= tc <= t1:  # corners after a short run's end would stretch the axis
                ax_err.axvline(tc, color="0.8", lw=0.6, zorder=0)
        for i in range(self.n_links):
            deflection = envelope(self.t, 1e3 * self.link_deflections[:, i], _PLOT_POINTS)
            ax_def.plot(*deflection, label=f"link {i + 1}")
        ax_def.set(xlabel="t (s)", ylabel="tip deflection (mm)")
        if self.n_links:
            ax_def.legend(loc="best")
        return fig


_PLOT_POINTS = 5000
"""Points per plotted series beyond which a plot shows an envelope (the page has
fewer pixels; a 600 s run recorded at 5 kHz would otherwise draw 3 million)."""


def envelope(t: F64, y: F64, max_points: int) -> tuple[F64, F64]:
    """``(t, y)`` as at most about ``max_points`` points that draw the same line at
    page resolution: in each of ``max_points // 2`` buckets, the smallest and the
    largest value in time order (peaks and NaN gaps kept). Short series are
    returned as they are."""
    n = t.shape[0]
    buckets = max_points // 2
    if n <= max_points or buckets < 1:
        return t, y
    edges = np.linspace(0, n, buckets + 1).astype(np.int64)
    keep: list[int] = []
    for a, b in itertools.pairwise(edges.tolist()):
        seg = y[a:b]
        if not np.any(np.isfinite(seg)):
            keep.append(a)  # a NaN: the gap stays a gap
            continue
        keep += sorted({a + int(np.nanargmin(seg)), a + int(np.nanargmax(seg))})
    rows = np.array(keep, dtype=np.int64)
    return t[rows], y[rows]


def _max_abs(x: F64) -> float:
    """``nanmax(|x|)`` (0 for no samples), without a temporary when every sample is
    finite: ``max(max(x), -min(x))``, the same number."""
    if not x.size:
        return 0.0
    if np.isfinite(x).all():
        return float(max(x.max(), -x.min()))
    return float(np.nanmax(np.abs(x)))


def _float(value: JSONValue, default: float) -> float:
    return float(value) if isinstance(value, int | float) else default


class SimulationError(FlexarmError, RuntimeError):
    """The simulated state diverged (non-finite, overflow or runaway deflection).

    Attributes
    ----------
    time : float
        Last control instant recorded, s.
    state : ndarray, shape (2 n_dof,)
        ``(q, dq)`` at that instant.
    result : SimulationResult
        The partial result up to ``time``.
    """

    def __init__(
        self, message: str, time: float, state: NDArray[np.float64], result: SimulationResult
    ):
        super().__init__(message)
        self.time = time
        self.state = state
        self.result = result


class ResultArm(Protocol):
    """What :func:`assemble_result` reads of the arm."""

    @property
    def arrays(self) -> ArmArrays: ...
    @property
    def link_lengths(self) -> F64: ...
    @property
    def coordinate_names(self) -> list[str]: ...

    def tip_position(self, q: ArrayLike) -> F64: ...


def assemble_result(
    arm: ResultArm,
    *,
    t: F64,
    q: F64,
    dq: F64,
    tau: F64,
    measurement: F64,
    reference: F64,
    desired: F64,
    diverged: bool,
    last_row: int,
    info: dict[str, JSONValue],
    tip: F64 | None = None,
) -> SimulationResult:
    """The :class:`SimulationResult` of a run whose rows up to ``last_row`` were written.

    Rows after ``last_row`` become NaN; the tip follows from ``q`` where the state
    is finite, unless the loop recorded it (``tip``, shape (K, 2), m: the rows up
    to ``last_row`` written, the state finite there); ``info["status"]`` is set.
    A run that ``diverged`` raises :class:`SimulationError` with the partial
    result attached.
    """
    for series in (q, dq, tau, measurement):
        series[last_row + 1 :] = np.nan
    if tip is None:
        tip = np.full((t.shape[0], 2), np.nan)
        reached = q[: last_row + 1]
        done = np.all(np.isfinite(reached), axis=1)
        tip[: last_row + 1][done] = arm.tip_position(reached[done])
    else:
        tip[last_row + 1 :] = np.nan
    info["status"] = "diverged" if diverged else "ok"
    result = SimulationResult(
        t=t,
        q=q,
        dq=dq,
        tau=tau,
        reference=reference,
        desired=desired,
        measurement=measurement,
        tip=tip,
        coordinate_names=list(arm.coordinate_names),
        tip_deflection_gains=np.asarray(arm.arrays.tip_deflection),
        mode_start=np.asarray(arm.arrays.mode_start),
        link_lengths=np.asarray(arm.link_lengths, dtype=float),
        info=info,
        tip_slope_gains=np.asarray(arm.arrays.tip_slope, dtype=float),
        mode_shape_samples=_mode_shape_samples(arm),
    )
    if diverged:
        tk = float(t[last_row])
        x = np.r_[q[last_row], dq[last_row]]
        raise SimulationError(
            f"the simulation diverged after t = {tk:.6g} s (state non-finite, overflowing "
            f"or a tip deflection beyond max_deflection); last state q, dq = "
            f"{np.array2string(x, precision=4, max_line_width=200)}",
            tk,
            x,
            result.truncated(last_row + 1),
        )
    return result


def _mode_shape_samples(arm: ResultArm) -> F64 | None:
    """Each mode's shape at :data:`_SHAPE_POINTS` points along its link, shape
    (n_dof, S); None for a plant without ``modes``."""
    modes = getattr(arm, "modes", None)
    if modes is None:
        return None
    ms = np.asarray(arm.arrays.mode_start)
    out = np.zeros((arm.arrays.tip_slope.shape[0], _SHAPE_POINTS))
    for i, length in enumerate(np.asarray(arm.link_lengths, dtype=float)):
        if ms[i + 1] > ms[i]:
            x = np.linspace(0.0, length, _SHAPE_POINTS)
            out[ms[i] : ms[i + 1]] = np.asarray(modes[i].shape(x), dtype=float)
    return out
