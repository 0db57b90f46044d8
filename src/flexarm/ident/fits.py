"""One-call fits from data, each a result with ``summary()``, ``plot()`` and ``save()``.

* :func:`fit_regression` — the semi-recursive estimate (eq. 14) of ``E[y | x]``
  on a grid spanning the inputs (:class:`RegressionFit`);
* :func:`fit_hammerstein` — a Hammerstein model of ``u -> y`` for any
  exciting input, beside its linear baseline, with optional bootstrap bands
  (:class:`HammersteinFit`).

``flexarm identify fit`` and ``flexarm identify hammerstein DATA`` are these
functions on two columns of a file (:func:`flexarm.ident.data.read_xy`).
Plots take ``ax=None`` (or ``fig=None``), return the handles and never show
anything; they draw in :mod:`flexarm.figures`' style, sized for a column of a
paper, and ``save`` writes them as PNG, PDF or SVG
(:class:`~flexarm.figures.FigureFormat`). Matplotlib is imported when a plot is
drawn.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from .._budget import check_memory
from .._types import F64
from .._validation import check_array, check_int
from ..errors import InvalidValueError
from ..figures import (
    DOUBLE_COLUMN,
    SINGLE_COLUMN,
    FigureFormat,
    new_figure,
    save_figure,
    styled,
)
from ._output import output_directory, save_docstring, save_table_and_plot, write_csv
from .hammerstein.bootstrap import Bands
from .hammerstein.identifier import DEFAULT_BANDWIDTH, HammersteinIdentifier
from .hammerstein.solution import KnownPoints
from .regression.bandwidth import Silverman, as_rule
from .regression.estimators import SemiRecursiveKernelRegression
from .regression.kernels import KernelFunction

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["HammersteinFit", "RegressionFit", "fit_hammerstein", "fit_regression"]

_DENSITY_ABOVE = 2000
"""Data drawn as points up to this many samples, as a density of hexagonal bins above
(a cloud of thousands of points hides its own shape)."""
_FREE_RUN_WINDOW = 200
"""Samples of the free run drawn beside the measured output (the fit is over all)."""


def _xy(x: ArrayLike, y: ArrayLike, owner: str, names: tuple[str, str]) -> tuple[F64, F64]:
    xa = check_array(x, names[0], owner, shape=(-1,))
    ya = check_array(y, names[1], owner, shape=(xa.shape[0],))
    if xa.shape[0] < 2:
        raise InvalidValueError(
            f"The '{names[0]}' parameter of {owner} must hold at least 2 samples. "
            f"Got {xa.shape[0]} instead."
        )
    if np.ptp(xa) == 0.0:
        raise InvalidValueError(
            f"The '{names[0]}' parameter of {owner} must vary (the grid spans it). "
            "Got a constant instead."
        )
    return np.asarray(xa, dtype=np.float64), np.asarray(ya, dtype=np.float64)


@dataclass(frozen=True)
class RegressionFit:
    """The estimate of ``E[y | x]`` from :func:`fit_regression`.

    Attributes
    ----------
    x, y : ndarray, shape (n,)
        The data (units ``x_unit``, ``y_unit``).
    grid : ndarray, shape (g,)
        Evaluation points, spanning ``x`` (units ``x_unit``).
    estimate : ndarray, shape (g,)
        ``m_n`` on ``grid`` (units ``y_unit``); NaN where no sample has weight.
    estimator : SemiRecursiveKernelRegression
        The fitted estimator (grid mode).
    bandwidth_rule : str
        ``"given"``, or the rule that set ``h_1`` (``"silverman"``).
    error_bound : ndarray of shape (g,), or None
        Binned mode: the bound on ``|m_binned - m|`` on ``grid``.
    x_label, y_label, x_unit, y_unit : str
        Names and units for the axes.
    """

    x: F64
    y: F64
    grid: F64
    estimate: F64
    estimator: SemiRecursiveKernelRegression
    bandwidth_rule: str
    error_bound: F64 | None
    x_label: str = "x"
    y_label: str = "y"
    x_unit: str = "data units"
    y_unit: str = "data units"

    def summary(self) -> dict[str, Any]:
        """Settings and results as plain Python values (JSON-ready but for NaN)."""
        est = self.estimator
        h1 = float(est.bandwidth_[0])
        n = int(self.x.shape[0])
        return {
            "n_samples": n,
            "estimator": type(est).__name__,
            "kernel": est.kernel_,
            "bandwidth": h1,
            "bandwidth_rule": self.bandwidth_rule,
            "decay": est.decay,
            "last_bandwidth": h1 * float(n) ** (-est.decay),
            "binned": est.binned,
            "series": est.series,
            "error_bound_max": (
                None if self.error_bound is None else float(np.nanmax(self.error_bound))
            ),
            "grid": {
                "points": int(self.grid.shape[0]),
                "min": float(self.grid[0]),
                "max": float(self.grid[-1]),
            },
            "points_without_estimate": int(np.isnan(self.estimate).sum()),
            "estimate": {"x": self.grid.tolist(), "m": self.estimate.tolist()},
        }

    @styled
    def plot(self, ax: Axes | None = None) -> Axes:
        """The data and the estimate on the grid (one column of a paper wide).

        Up to 2000 samples are drawn as points; more as their density (grey
        hexagonal bins, darker where more samples fall), so that the cloud does
        not hide its shape.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw into; a new figure's axes if omitted.

        Returns
        -------
        matplotlib.axes.Axes
        """
        if ax is None:
            ax = new_figure(SINGLE_COLUMN, 2.6).add_subplot()
        _draw_data(ax, self.x, self.y)
        ax.plot(self.grid, self.estimate, "-", lw=1.5, label="estimate $m_n(x)$")
        ax.set_xlabel(f"{self.x_label} ({self.x_unit})")
        ax.set_ylabel(f"{self.y_label} ({self.y_unit})")
        est = self.estimator
        ax.set_title(
            f"{est.kernel_} kernel, $h_1$ = {float(est.bandwidth_[0]):.3g}, "
            f"decay {est.decay:g}, n = {self.x.shape[0]}",
            fontsize="small",
        )
        ax.legend(loc="best")
        return ax

    @save_docstring("``estimate.csv`` (columns ``x,m``) and ``estimate.png``", "estimate")
    def save(
        self,
        directory: str | os.PathLike[str],
        *,
        figure_format: FigureFormat | str | None = None,
    ) -> list[Path]:
        table = ([self.grid, self.estimate], "x,m", "%.12g")
        return save_table_and_plot(directory, "estimate", table, self.plot, 2.6, figure_format)


def _draw_data(ax: Axes, x: F64, y: F64) -> None:
    """The samples as points, or as their density when there are many (:data:`_DENSITY_ABOVE`)."""
    n = x.shape[0]
    if n <= _DENSITY_ABOVE:
        ax.plot(x, y, ".", ms=2.5, mew=0, alpha=0.5, color="0.45", label="data", zorder=1)
        return
    ax.hexbin(
        x, y, gridsize=(50, 25), bins="log", mincnt=1, cmap="Greys", alpha=0.6, lw=0, zorder=1
    )
    ax.plot([], [], "h", ms=5, color="0.55", label=f"data: density of {n} samples")


def fit_regression(
    x: ArrayLike,
    y: ArrayLike,
    *,
    kernel: str | KernelFunction = "gaussian",
    bandwidth: float | str | Silverman = "silverman",
    decay: float = 0.2,
    grid: int = 512,
    binned: float | None = None,
    series: bool = False,
    x_label: str = "x",
    y_label: str = "y",
) -> RegressionFit:
    """Fit the semi-recursive estimate (eq. 14) of ``E[y | x]`` and evaluate it on a grid.

    Parameters
    ----------
    x, y : array_like, shape (n,)
        Inputs and outputs (any units), finite; ``x`` not constant.
    kernel, bandwidth, decay, binned, series
        As :class:`~flexarm.ident.SemiRecursiveKernelRegression`; the default
        bandwidth is Silverman's rule for the last sample
        (:mod:`flexarm.ident.regression.bandwidth`).
    grid : int, default 512
        Points of the grid, equispaced from ``min(x)`` to ``max(x)`` (>= 2).
    x_label, y_label : str
        Names of ``x`` and ``y`` for the plot.

    Returns
    -------
    RegressionFit

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> x = rng.uniform(-1, 1, 2000)
    >>> res = fit_regression(x, x**2 + 0.05 * rng.normal(size=2000), grid=5)
    >>> np.round(res.estimate, 1)
    array([0.9, 0.3, 0. , 0.3, 0.9])
    """
    owner = "fit_regression"
    xa, ya = _xy(x, y, owner, ("x", "y"))
    g = check_int(grid, "grid", owner, minimum=2)
    check_memory(  # the grid, its sums and the estimate, a few copies each
        8.0 * 8 * g,
        f"an estimate on {g} grid points",
        owner,
        "Use fewer grid points (a few thousand resolve any smooth curve)",
    )
    points = np.linspace(float(xa.min()), float(xa.max()), g)
    rule = as_rule(bandwidth, "SemiRecursiveKernelRegression")
    est = SemiRecursiveKernelRegression(
        kernel=kernel, bandwidth=bandwidth, decay=decay, grid=points, binned=binned, series=series
    ).fit(xa, ya)
    return RegressionFit(
        x=xa,
        y=ya,
        grid=points,
        estimate=est.predict(points),
        estimator=est,
        bandwidth_rule="given" if rule is None else rule.label,
        error_bound=None if binned is None else est.error_bound(points),
        x_label=x_label,
        y_label=y_label,
    )


@dataclass(frozen=True)
class HammersteinFit:
    """A Hammerstein model of ``u -> y`` from :func:`fit_hammerstein`.

    Attributes
    ----------
    u, y : ndarray, shape (n,)
        The data (units ``u_unit``, ``y_unit``).
    y_hat : ndarray, shape (n,)
        Free-run output of the model (units ``y_unit``).
    y_baseline : ndarray, shape (n,)
        Free-run output of the linear baseline (units ``y_unit``).
    grid : ndarray, shape (g,)
        Points spanning ``u`` where ``phi`` is reported (units ``u_unit``).
    phi : ndarray, shape (g,)
        The identified nonlinearity on ``grid``.
    model : HammersteinIdentifier
        The fitted identifier (``model.report_``: path, reason, baseline, warnings).
    fit_percent : float
        Free-run fit on the data, percent.
    bands : Bands or None
        Bootstrap bands of ``phi`` and the impulse response, if asked for.
    u_label, y_label, u_unit, y_unit : str
        Names and units for the axes.
    """

    u: F64
    y: F64
    y_hat: F64
    y_baseline: F64
    grid: F64
    phi: F64
    model: HammersteinIdentifier
    fit_percent: float
    bands: Bands | None = None
    u_label: str = "u"
    y_label: str = "y"
    u_unit: str = "data units"
    y_unit: str = "data units"

    @property
    def normalisation(self) -> str:
        """``"two-point"`` with known points, else ``"up to an affine map"``."""
        return "two-point" if self.model.known_points is not None else "up to an affine map"

    def summary(self) -> dict[str, Any]:
        """Settings and results as plain Python values (the report included)."""
        m = self.model
        report = m.report_.summary()
        return {
            "n_samples": int(self.u.shape[0]),
            "method": m.method_,
            "reason": report["reason"],
            "whiteness": report["whiteness"],
            "n_lags": m.n_lags,
            "known_points": m.known_points,
            "normalisation": self.normalisation,
            "bandwidth": m.bandwidth_ if m.method_ == "white" else None,
            "arma_order": m.order_,
            "n_knots": int(m.grid_.shape[0]) if m.method_ == "correlated" else None,
            "structure": report["structure"],
            "a": list(m.arma_.a),
            "b": list(m.arma_.b),
            "impulse_response": m.impulse_response_.tolist(),
            "fit_percent": self.fit_percent,
            "baseline": report["baseline"],
            "nonlinear_helps": report["nonlinear_helps"],
            "loses_to_baseline": report["loses_to_baseline"],
            "winner": report["winner"],
            "comparison": report["comparison"],
            "warnings": report["warnings"],
            "bands": None if self.bands is None else self.bands.summary(),
            "nonlinearity": {"x": self.grid.tolist(), "phi": self.phi.tolist()},
        }

    @styled
    def plot(self, fig: Figure | None = None) -> Figure:
        """Three panels: the nonlinearity, the impulse response (with their bootstrap bands
        when computed), and the measured output beside the model's and the linear
        baseline's free runs over the first 200 samples (the fit percentages are over
        all of them). Two columns of a paper wide.

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Figure to draw into; a new one if omitted.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .hammerstein.bootstrap import draw_impulse_band, draw_phi_band

        if fig is None:
            fig = new_figure(DOUBLE_COLUMN, 2.5)
        ax1, ax2, ax3 = fig.subplots(1, 3)
        scale = "φ units" if self.model.known_points is not None else "normalised"
        if self.bands is not None:
            draw_phi_band(ax1, self.bands)
            draw_impulse_band(ax2, self.bands)
        ax1.plot(self.grid, self.phi, lw=1.5, label="estimate")
        ax1.set_xlabel(f"{self.u_label} ({self.u_unit})")
        ax1.set_ylabel(f"φ(u) ({scale})")
        ax1.set_title(f"nonlinearity, {self.normalisation}\n({self.model.method_}-input path)")
        ir = self.model.impulse_response_
        ax2.plot(np.arange(ir.shape[0]), ir, "o-", ms=2.5, label="estimate")
        ax2.set_xlabel("lag k (samples)")
        ax2.set_ylabel(f"$\\lambda_k$ ({self.y_unit} per φ unit)")
        ax2.set_title(f"impulse response\n(ARMA order {self.model.order_})")
        if self.bands is not None:
            ax1.legend(loc="best")
            ax2.legend(loc="best")
        n = self.u.shape[0]
        shown = slice(0, min(n, _FREE_RUN_WINDOW))
        k = np.arange(n)[shown]
        base = self.model.report_.baseline
        ax3.plot(k, self.y[shown], color="k", lw=0.8, label="measured")
        ax3.plot(k, self.y_hat[shown], lw=1.0, label=f"Hammerstein ({self.fit_percent:.1f} %)")
        ax3.plot(
            k,
            self.y_baseline[shown],
            lw=0.8,
            ls="--",
            label=f"linear ARX ({base['fit_percent']:.1f} %)",
        )
        ax3.set_xlabel("n (samples)")
        ax3.set_ylabel(f"{self.y_label} ({self.y_unit})")
        ax3.set_title(f"free run on the data\n(first {k.shape[0]} of {n} samples)")
        ax3.legend(loc="best")
        return fig

    @save_docstring(
        "``nonlinearity.csv`` (``u,phi``), ``impulse_response.csv``\n"
        "(``lag,impulse_response``; with bands, ``u,phi,phi_low,phi_high`` and\n"
        "``lag,impulse_response,low,high``) and ``hammerstein.png``",
        "hammerstein",
    )
    def save(
        self,
        directory: str | os.PathLike[str],
        *,
        figure_format: FigureFormat | str | None = None,
    ) -> list[Path]:
        out = output_directory(directory)
        ir = self.model.impulse_response_
        lags = np.arange(ir.shape[0], dtype=np.float64)
        b = self.bands
        if b is None:
            phi = write_csv(out / "nonlinearity.csv", [self.grid, self.phi], "u,phi")
            impulse = write_csv(out / "impulse_response.csv", [lags, ir], "lag,impulse_response")
        else:
            phi = write_csv(
                out / "nonlinearity.csv",
                [b.grid, b.phi, b.phi_low, b.phi_high],
                "u,phi,phi_low,phi_high",
            )
            impulse = write_csv(
                out / "impulse_response.csv",
                [lags, ir, b.impulse_low, b.impulse_high],
                "lag,impulse_response,low,high",
            )
        return [phi, impulse, save_figure(self.plot(), out / "hammerstein", figure_format)]


def fit_hammerstein(
    u: ArrayLike,
    y: ArrayLike,
    *,
    n_lags: int = 40,
    order: int | str = "auto",
    known_points: KnownPoints | None = None,
    bandwidth: float | str | Silverman = DEFAULT_BANDWIDTH,
    method: str = "auto",
    n_knots: int | str = "auto",
    bootstrap: int = 0,
    rng: np.random.Generator | int | None = None,
    grid: int = 201,
    u_label: str = "u",
    y_label: str = "y",
) -> HammersteinFit:
    """Identify a Hammerstein model of ``u -> y`` and score its free run on the same data.

    Parameters
    ----------
    u, y : array_like, shape (n,)
        Input (white or not: ``method``) and output.
    n_lags, order, known_points, bandwidth, method, n_knots
        As :class:`~flexarm.ident.HammersteinIdentifier`.
    bootstrap : int, default 0
        Block-bootstrap replicates for the bands of ``phi`` and the impulse
        response (0: none; otherwise >= 10), drawn from ``rng``.
    rng : numpy.random.Generator or int, optional
        Source of the bootstrap resampling.
    grid : int, default 201
        Points, spanning ``u``, where the nonlinearity is reported (>= 2).
    u_label, y_label : str
        Names of ``u`` and ``y`` for the plot.

    Returns
    -------
    HammersteinFit
    """
    owner = "fit_hammerstein"
    ua, ya = _xy(u, y, owner, ("u", "y"))
    g = check_int(grid, "grid", owner, minimum=2)
    boot = check_int(bootstrap, "bootstrap", owner, minimum=0)
    model = HammersteinIdentifier(
        n_lags=n_lags,
        order=order,
        known_points=known_points,
        bandwidth=bandwidth,
        method=method,
        n_knots=n_knots,
    ).fit(ua, ya)
    points = np.linspace(float(ua.min()), float(ua.max()), g)
    bands = model.bands(ua, ya, n_boot=boot, rng=rng) if boot else None
    return HammersteinFit(
        u=ua,
        y=ya,
        y_hat=model.predict(ua),
        y_baseline=model.baseline_.predict(ua),
        grid=points,
        phi=model.nonlinearity(points),
        model=model,
        fit_percent=model.fit_percent(ua, ya),
        bands=bands,
        u_label=u_label,
        y_label=y_label,
    )
