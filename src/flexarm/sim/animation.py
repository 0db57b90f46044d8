"""Watching a run: the deflected arm drawn from its mode shapes, frame by frame.

:func:`animate` turns a run (a :class:`flexarm.SimulationResult`) into a
Matplotlib ``FuncAnimation``: each link drawn along its length from the
assumed-mode shapes sampled in the result, the reference path, the end
effector's trail, the sensed point (what the controller saw) and a time
label, with the recorded instants subsampled to a frame rate.
:func:`write_animation` writes one to a GIF (through Pillow) or an MP4
(through ffmpeg) atomically. ``SimulationResult.animate`` is the method form.

Kinematics (as :func:`flexarm.model.kinematics.deflected_point`): link ``i``'s
point at ``x`` along it is ``p_i + R(alpha_i) (x, w_i(x))`` with
``w_i(x) = sum_j phi_ij(x) delta_ij``; the next link starts at the deflected tip
and turns by its joint angle from the tip's tangent, ``alpha_{i+1} = alpha_i +
theta_{i+1} + w_i'(L_i)``. A result saved by an older flexarm, without the
sampled shapes, is drawn with rigid links from the joint angles (the true tip
still marked).

This module needs Matplotlib (imported when called) and not the result class:
it reads a run through :class:`AnimatedRun`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import NDArray

from .._io import JSONValue, atomic_path
from .._validation import check_real
from ..errors import InvalidValueError

if TYPE_CHECKING:
    from matplotlib.animation import FuncAnimation
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure

__all__ = ["ANIMATION_FORMATS", "AnimatedRun", "animate", "arm_outline", "write_animation"]

F64 = NDArray[np.float64]
ANIMATION_FORMATS = (".gif", ".mp4")
"""File types :func:`write_animation` writes (by suffix)."""


class AnimatedRun(Protocol):
    """What :func:`animate` reads of a run (a :class:`flexarm.SimulationResult`)."""

    t: F64
    q: F64
    tip: F64
    desired: F64
    measurement: F64
    link_lengths: F64
    mode_start: NDArray[np.int64]
    info: dict[str, JSONValue]
    tip_slope_gains: F64 | None
    mode_shape_samples: F64 | None


def arm_outline(run: AnimatedRun, rows: NDArray[np.int64]) -> F64:
    """Points along every link at the instants ``rows``, m.

    Returns
    -------
    ndarray, shape (len(rows), n_links, S, 2)
        ``S`` points per link from its joint to its tip (the samples of
        ``run.mode_shape_samples``; 2 for a run without them, rigid links).
    """
    q = run.q[rows]
    lengths = np.asarray(run.link_lengths, dtype=float)
    n_links = lengths.shape[0]
    ms = np.asarray(run.mode_start)
    shapes, slopes = run.mode_shape_samples, run.tip_slope_gains
    if shapes is None or slopes is None:
        shapes, slopes = np.zeros((q.shape[1], 2)), np.zeros(q.shape[1])
    n_s = shapes.shape[1]
    x = np.linspace(0.0, 1.0, n_s)
    out = np.zeros((q.shape[0], n_links, n_s, 2))
    base = np.zeros((q.shape[0], 2))
    alpha = np.zeros(q.shape[0])
    for i in range(n_links):
        s = slice(int(ms[i]), int(ms[i + 1]))
        alpha = alpha + q[:, i]
        w = q[:, s] @ shapes[s]  # (m, S) deflection along the link, m
        c, sn = np.cos(alpha)[:, None], np.sin(alpha)[:, None]
        xi = lengths[i] * x[None, :]
        out[:, i, :, 0] = base[:, :1] + xi * c - w * sn
        out[:, i, :, 1] = base[:, 1:] + xi * sn + w * c
        base = out[:, i, -1, :]
        alpha = alpha + q[:, s] @ slopes[s]
    return out


def _frame_rows(t: F64, fps: float, speed: float) -> NDArray[np.int64]:
    """The recorded instants shown at ``fps`` frames per second of playback, ``speed``
    seconds of run per second: the last instant at or before each frame's time."""
    finite = int(np.max(np.flatnonzero(np.isfinite(t)), initial=0)) + 1
    t = t[:finite]
    times = np.arange(t[0], t[-1] + 1e-12, speed / fps)
    rows = np.searchsorted(t, times + 1e-9 * speed / fps, side="right") - 1
    return np.unique(np.clip(rows, 0, finite - 1)).astype(np.int64)


class _Scene:
    """The figure's artists and how one instant updates them."""

    def __init__(self, run: AnimatedRun, rows: NDArray[np.int64], fig: Figure | None) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.run, self.rows = run, rows
        self.outline = arm_outline(run, rows)
        self.fig = fig if fig is not None else Figure(figsize=(6, 6), layout="constrained")
        if self.fig.canvas is None or type(self.fig.canvas).__name__ == "FigureCanvasBase":
            FigureCanvasAgg(self.fig)
        ax = self.fig.add_subplot()
        reach = float(np.sum(run.link_lengths)) * 1.1
        ax.set(xlim=(-reach, reach), ylim=(-reach, reach), aspect="equal")
        ax.set(xlabel="x (m)", ylabel="y (m)")
        ax.set_title(f"{run.info.get('controller', '')}, sensor {run.info.get('sensor', '-')}")
        desired = run.desired[np.all(np.isfinite(run.desired), axis=1)]
        if desired.shape[0]:
            ax.plot(desired[:, 0], desired[:, 1], "k--", lw=0.8, label="reference")
        (self.trail,) = ax.plot([], [], color="C0", lw=0.8, alpha=0.6, label="end effector")
        self.links = [
            ax.plot([], [], "-", lw=3, color=f"C{1 + i}", solid_capstyle="round")[0]
            for i in range(self.outline.shape[1])
        ]
        (self.joints,) = ax.plot([], [], "o", color="k", ms=4)
        n_links = self.outline.shape[1]
        cols = self.run.measurement.shape[1]
        self.sensed = None
        if cols >= 2 * n_links + 2:  # y[2N:2N+2]: the point the controller saw
            self.sensed = ax.plot([], [], "x", color="C3", ms=9, mew=2, label="sensed")[0]
        self.label = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top")
        ax.legend(loc="lower right", fontsize="small")

    def update(self, frame: int) -> list[Artist]:
        row = int(self.rows[frame])
        run, pts = self.run, self.outline[frame]
        for i, line in enumerate(self.links):
            line.set_data(pts[i, :, 0], pts[i, :, 1])
        joints = np.vstack([pts[:, 0], pts[-1:, -1]])
        self.joints.set_data(joints[:, 0], joints[:, 1])
        self.trail.set_data(run.tip[: row + 1, 0], run.tip[: row + 1, 1])
        artists: list[Artist] = [*self.links, self.joints, self.trail, self.label]
        if self.sensed is not None:
            n = 2 * pts.shape[0]
            self.sensed.set_data(
                run.measurement[row, n : n + 1], run.measurement[row, n + 1 : n + 2]
            )
            artists.append(self.sensed)
        self.label.set_text(f"t = {run.t[row]:.2f} s")
        return artists


def _rows(run: AnimatedRun, fps: float, speed: float) -> NDArray[np.int64]:
    check_real(fps, "fps", "animate", positive=True)
    check_real(speed, "speed", "animate", positive=True)
    if run.t.shape[0] == 0:
        raise InvalidValueError("The 'result' parameter of animate must hold at least one instant.")
    return _frame_rows(np.asarray(run.t, dtype=float), fps, speed)


def animate(
    run: AnimatedRun, *, fps: float = 25.0, speed: float = 1.0, fig: Figure | None = None
) -> FuncAnimation:
    """The run as a Matplotlib animation (module docstring).

    Parameters
    ----------
    run : SimulationResult
        The run to draw.
    fps : float
        Frames per second of playback (> 0): the recorded instants are
        subsampled to one frame every ``speed / fps`` seconds of the run.
    speed : float
        Seconds of run per second of playback (1: real time).
    fig : matplotlib.figure.Figure, optional
        Drawn into (a new 6 x 6 in figure by default, not registered with pyplot).

    Returns
    -------
    matplotlib.animation.FuncAnimation
        Never shown; ``.save(...)``, ``.to_jshtml()``, or :func:`write_animation`.
    """
    from matplotlib.animation import FuncAnimation

    rows = _rows(run, fps, speed)
    scene = _Scene(run, rows, fig)
    return FuncAnimation(
        scene.fig,
        scene.update,
        frames=rows.shape[0],
        interval=1000.0 / fps,
        blit=False,
        cache_frame_data=False,
    )


def write_animation(
    run: AnimatedRun,
    path: str | os.PathLike[str],
    *,
    fps: float = 25.0,
    speed: float = 1.0,
    dpi: float = 80.0,
) -> Path:
    """Write :func:`animate`'s frames to ``path`` (``.gif`` or ``.mp4``) atomically.

    A GIF is written by Pillow; an MP4 by ffmpeg (which must be on ``PATH``).
    The file appears complete or not at all (``flexarm._io.atomic_path``).

    Parameters
    ----------
    run : SimulationResult
    path : path
        The file; its suffix chooses the format.
    fps, speed : float
        As :func:`animate`'s.
    dpi : float
        Resolution (a 6 in figure at 80 dpi is 480 x 480 pixels).
    """
    from matplotlib.animation import FFMpegWriter

    target = Path(path)
    suffix = target.suffix.lower()
    if suffix not in ANIMATION_FORMATS:
        raise InvalidValueError(
            f"The 'path' parameter of write_animation must end in .gif or .mp4. "
            f"Got {str(target)!r} instead."
        )
    if suffix == ".mp4" and not FFMpegWriter.isAvailable():
        raise InvalidValueError("Writing an MP4 needs ffmpeg on PATH (not found); write a .gif.")
    check_real(dpi, "dpi", "write_animation", positive=True)
    rows = _rows(run, fps, speed)
    scene = _Scene(run, rows, None)
    with atomic_path(target) as tmp:
        if suffix == ".mp4":
            writer = FFMpegWriter(fps=round(fps), extra_args=["-f", "mp4"])
            with writer.saving(scene.fig, str(tmp), dpi):
                for k in range(rows.shape[0]):
                    scene.update(k)
                    writer.grab_frame()
        else:
            _write_gif(scene, rows.shape[0], tmp, fps, dpi)
    return target


def _write_gif(scene: _Scene, n_frames: int, path: Path, fps: float, dpi: float) -> None:
    """Frames rendered one at a time, each reduced to a palette image at once (a
    byte a pixel held until Pillow writes the file)."""
    from PIL import Image

    scene.fig.set_dpi(dpi)
    frames = []
    for k in range(n_frames):
        scene.update(k)
        scene.fig.canvas.draw()
        rgba = np.asarray(scene.fig.canvas.buffer_rgba())  # type: ignore[attr-defined]
        frames.append(Image.fromarray(rgba[..., :3]).quantize(colors=64))
    with open(path, "wb") as fh:
        frames[0].save(
            fh,
            format="GIF",
            save_all=True,
            append_images=frames[1:],
            duration=max(20, round(1000.0 / fps)),
            loop=0,
        )
