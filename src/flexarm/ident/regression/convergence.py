"""Monte Carlo convergence study of the kernel regression estimate (paper §5, Theorem 1).

:func:`convergence_study` draws i.i.d. pairs ``Y = m(X) + sigma e``, streams
them through :class:`~flexarm.ident.regression.estimators.SemiRecursiveKernelRegression`
in grid mode, and records the integrated squared error
``ISE_n = int_I (m_n(x) - m(x))**2 dx`` at every ``n`` of the sequence (the
estimate at ``n`` uses the first ``n`` samples, so one pass per repetition
serves the whole sequence). Averaged over repetitions this is the MISE; its
log–log slope against ``n`` is set beside the theoretical ``-2p/(2p+1)``.

Regression functions
--------------------
Named functions live on ``[-1, 1]``; ``p`` is the smoothness order that sets
the rate (bias ``O(h**p)`` in ``L2``, so ``MISE = O(h**2p + 1/(n h))`` and
``h_n ∝ n**(-1/(2p+1))``, i.e. ``decay = 1/(2p+1)``, gives ``n**(-2p/(2p+1))``):

============ ========================================= ===== =========================
name         m(x)                                      p     class
============ ========================================= ===== =========================
smooth       ``sin(pi x)``                             2     C², symmetric kernel
deadzone     ``sign(x) max(|x| - 0.3, 0)``             1     Lipschitz (paper's rate)
saturation   ``clip(1.5 x, -0.75, 0.75)``              1     Lipschitz (paper's rate)
quantizer    ``round(2 x) / 2``                        1/2   jumps (``L2`` order 1/2)
============ ========================================= ===== =========================

For Lipschitz functions ``p = 1`` is the rate Theorem 1 guarantees; functions
with a few isolated kinks, like the dead zone and the saturation, converge
faster in MISE (their ``L2`` order is 3/2), so their fitted slope is steeper
than the guaranteed one. A user callable ``m`` takes its ``order`` from the
caller (default 1, the theorem's Lipschitz case).

The MISE is integrated over ``interval`` (default ``[-0.5, 0.5]``), inside the
support of the inputs, so the boundary bias of the kernel estimate (``O(h)``
within ``h`` of an edge) does not mask the interior rate.

Bandwidth
---------
By default (``bandwidth="silverman"``) each repetition's ``h_1`` comes from
Silverman's rule of thumb on its own inputs, anchored at the largest ``n``
(:mod:`flexarm.ident.regression.bandwidth`): ``h_1 = 0.9 min(sd, IQR/1.34)
n_max**(decay - 1/5)``, so the last estimate's bandwidth is the rule's. A
number fixes ``h_1`` for every repetition.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._types import F64
from ..._validation import check_array, check_int, check_option, check_real
from ...errors import InvalidTypeError, InvalidValueError
from ...figures import SINGLE_COLUMN, FigureFormat, new_figure, styled
from .._output import save_docstring, save_table_and_plot
from ..options import DISTRIBUTIONS
from .bandwidth import Silverman, as_rule
from .estimators import SemiRecursiveKernelRegression

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.axes import Axes

__all__ = [
    "DISTRIBUTIONS",
    "FUNCTIONS",
    "ConvergenceResult",
    "convergence_study",
    "regression_function",
    "sample_sizes",
]

_OWNER = "convergence_study"


def _smooth(x: F64) -> F64:
    out: F64 = np.sin(np.pi * x)
    return out


def _deadzone(x: F64) -> F64:
    out: F64 = np.sign(x) * np.maximum(np.abs(x) - 0.3, 0.0)
    return out


def _saturation(x: F64) -> F64:
    out: F64 = np.clip(1.5 * x, -0.75, 0.75)
    return out


def _quantizer(x: F64) -> F64:
    out: F64 = np.round(2.0 * x) / 2.0
    return out


#: Named regression functions: name -> (m, smoothness order p).
FUNCTIONS: dict[str, tuple[Callable[[F64], F64], float]] = {
    "smooth": (_smooth, 2.0),
    "deadzone": (_deadzone, 1.0),
    "saturation": (_saturation, 1.0),
    "quantizer": (_quantizer, 0.5),
}


def regression_function(name: str) -> Callable[[F64], F64]:
    """The named regression function ``m`` (see the module docstring).

    >>> regression_function("quantizer")(np.array([0.2, 0.3, -0.8]))
    array([ 0. ,  0.5, -1. ])
    """
    return FUNCTIONS[check_option(name, "function", "regression_function", FUNCTIONS)][0]


def sample_sizes(n_min: int = 250, n_max: int = 16000, steps: int = 7) -> NDArray[np.int64]:
    """Sample sizes for a study: ``steps`` values geometric from ``n_min`` to ``n_max``, rounded.

    Duplicates after rounding are dropped; the default is the study's default
    sequence ``250, 500, ..., 16000``.

    Parameters
    ----------
    n_min, n_max : int
        Smallest and largest size, ``1 <= n_min < n_max``.
    steps : int
        Number of sizes, >= 2.

    Returns
    -------
    ndarray of int, shape (k,)
        Increasing sizes, ``2 <= k <= steps``.

    Examples
    --------
    >>> sample_sizes(100, 800, 3)
    array([100, 283, 800])
    """
    owner = "sample_sizes"
    lo = check_int(n_min, "n_min", owner, minimum=1)
    hi = check_int(n_max, "n_max", owner, minimum=1)
    k = check_int(steps, "steps", owner, minimum=2)
    if not lo < hi:
        raise InvalidValueError(
            f"The 'n_min' parameter of {owner} must be < n_max = {hi}. Got {lo} instead."
        )
    out: NDArray[np.int64] = np.unique(np.round(np.geomspace(lo, hi, k)).astype(np.int64))
    return out


def _draw(distribution: str, rng: np.random.Generator, n: int) -> F64:
    if distribution == "uniform":
        out: F64 = rng.uniform(-1.0, 1.0, n)
    else:
        out = rng.normal(0.0, 0.5, n)
    return out


@dataclass(frozen=True)
class ConvergenceResult:
    """What :func:`convergence_study` measured.

    Attributes
    ----------
    n : ndarray of int, shape (k,)
        Sample sizes.
    mise : ndarray, shape (k,)
        Mean over repetitions of the ISE (units of the response squared times
        units of the input).
    std : ndarray, shape (k,)
        Standard deviation of the ISE over repetitions (same units).
    slope, intercept : float
        Least-squares fit ``log mise = intercept + slope log n``.
    theory_slope : float
        ``-2p/(2p+1)``.
    order : float
        ``p``.
    settings : dict
        The study's parameters (function, distribution, noise, kernel,
        bandwidth — a number or the rule's name —, ``h1`` — each repetition's
        ``h_1`` —, decay, interval, grid, repetitions, seed description).
    """

    n: NDArray[np.int64]
    mise: F64
    std: F64
    slope: float
    intercept: float
    theory_slope: float
    order: float
    settings: dict[str, Any] = field(default_factory=dict)

    def table(self) -> tuple[list[str], F64]:
        """Column names and the table, shape ``(k, 3)``: ``n``, ``mise``, ``std``."""
        return ["n", "mise", "std"], np.column_stack([self.n.astype(float), self.mise, self.std])

    def to_pandas(self) -> pd.DataFrame:
        """The table as a :class:`pandas.DataFrame` (pandas is imported here, lazily)."""
        import pandas as pd

        return pd.DataFrame({"n": self.n, "mise": self.mise, "std": self.std})

    def summary(self) -> dict[str, Any]:
        """Plain-Python summary (JSON-ready): the table, the slopes and the settings."""
        return {
            "n": [int(v) for v in self.n],
            "mise": [float(v) for v in self.mise],
            "std": [float(v) for v in self.std],
            "slope": self.slope,
            "intercept": self.intercept,
            "theory_slope": self.theory_slope,
            "order": self.order,
            "settings": dict(self.settings),
        }

    @styled
    def plot(self, ax: Axes | None = None) -> Axes:
        """Log–log MISE against ``n`` with the fitted line and the theoretical slope
        (one column of a paper wide).

        The theoretical line has slope ``-2p/(2p+1)`` through the geometric
        centre of the measured points. Matplotlib is imported lazily; nothing
        is shown (the caller decides).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw into; a new figure's axes if omitted.

        Returns
        -------
        matplotlib.axes.Axes
        """
        if ax is None:
            ax = new_figure(SINGLE_COLUMN, 2.8).add_subplot()
        n = self.n.astype(float)
        ax.errorbar(
            n, self.mise, yerr=self.std, fmt="o", ms=3, capsize=2, label="MISE (± std of ISE)"
        )
        ax.plot(
            n,
            np.exp(self.intercept) * n**self.slope,
            "-",
            label=f"fit: slope {self.slope:.3f}",
        )
        ln, lm = np.log(n).mean(), np.log(self.mise).mean()
        ax.plot(
            n,
            np.exp(lm + self.theory_slope * (np.log(n) - ln)),
            "--",
            label=f"theory: slope -2p/(2p+1) = {self.theory_slope:.3f}",
        )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xticks(n, [f"{v:g}" for v in self.n], minor=False)  # ticks at the sizes run
        ax.set_xticks([], minor=True)
        ax.set_xlabel("n (samples)")
        ax.set_ylabel("MISE (-)")  # the study's functions and noise are dimensionless
        ax.set_title(f"{self.settings.get('function', 'm')}: p = {self.order:g}")
        ax.legend()
        return ax

    @save_docstring("``study.csv`` (columns ``n,mise,std``) and ``study.png``", "study")
    def save(
        self,
        directory: str | os.PathLike[str],
        *,
        figure_format: FigureFormat | str | None = None,
    ) -> list[Path]:
        header, table = self.table()
        columns = (list(table.T), ",".join(header), "%.10g")
        return save_table_and_plot(directory, "study", columns, self.plot, 2.8, figure_format)


def _progress_bar(total: int, enabled: bool) -> Callable[[int], None]:
    if not enabled:
        return lambda done: None

    def show(done: int) -> None:
        width = 30
        filled = int(width * done / total)
        sys.stderr.write(f"\rconvergence study [{'#' * filled}{'.' * (width - filled)}] ")
        sys.stderr.write(f"{done}/{total} repetitions")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def convergence_study(
    function: str | Callable[[F64], ArrayLike] = "smooth",
    *,
    n: Sequence[int] | ArrayLike | None = None,
    repetitions: int = 20,
    noise: float = 0.1,
    distribution: str = "uniform",
    kernel: str = "gaussian",
    bandwidth: float | str | Silverman = "silverman",
    decay: float | None = None,
    order: float | None = None,
    interval: tuple[float, float] = (-0.5, 0.5),
    grid: int = 101,
    rng: np.random.Generator | int | None = None,
    progress: bool | None = None,
) -> ConvergenceResult:
    """Monte Carlo MISE of the semi-recursive estimate (eq. 14) against ``n``.

    Parameters
    ----------
    function : str or callable, default "smooth"
        One of :data:`FUNCTIONS` or ``m(x)`` mapping shape ``(k,)`` to ``(k,)``.
    n : sequence of int, shape (k,), optional
        Increasing sample sizes (>= 2 of them, each >= 1); default
        :func:`sample_sizes` ``()``, i.e. ``250, 500, ..., 16000``.
    repetitions : int, default 20
        Independent data sets (>= 2, for the spread).
    noise : float, default 0.1
        Standard deviation of the Gaussian output noise (units of the response).
    distribution : {"uniform", "normal"}, default "uniform"
        Inputs ``X ~ U[-1, 1]`` or ``N(0, 0.5**2)``.
    kernel : str, default "gaussian"
        A kernel name (:data:`flexarm.ident.KERNELS`).
    bandwidth : float, "silverman" or Silverman, default "silverman"
        ``h_1`` (units of ``X``), or the rule that sets it from each
        repetition's inputs (module docstring).
    decay : float, optional
        ``h_i = bandwidth i**-decay``; default ``1/(2p+1)``, the rate-optimal choice.
    order : float, optional
        Smoothness order ``p`` of ``m``; default the named function's (1 for a callable).
    interval : (float, float), default (-0.5, 0.5)
        Where the ISE is integrated (trapezoid rule on ``grid`` points).
    grid : int, default 101
        Evaluation points in ``interval``.
    rng : numpy.random.Generator or int, optional
        Source of all randomness; an int seeds a new generator. ``None`` draws
        fresh entropy (the result is then not reproducible).
    progress : bool, optional
        Draw a progress bar on stderr. ``None`` (default): only when stderr is
        a terminal and the study is long (over 2 million samples in all);
        ``True``: whenever stderr is a terminal; ``False``: never.

    Returns
    -------
    ConvergenceResult

    Examples
    --------
    >>> res = convergence_study("smooth", n=[200, 800, 3200], repetitions=4, rng=1)
    >>> res.mise.shape, res.theory_slope
    ((3,), -0.8)
    >>> bool(-1.2 < res.slope < -0.5)
    True
    """
    if isinstance(function, str):
        m, p_named = FUNCTIONS[check_option(function, "function", _OWNER, FUNCTIONS)]
        fname = function
    elif callable(function):
        user = function

        def m(x: F64) -> F64:
            out = np.asarray(user(x), dtype=np.float64)
            if out.shape != x.shape or not np.all(np.isfinite(out)):
                raise InvalidValueError(
                    f"The 'function' parameter of {_OWNER} must map shape {x.shape} to finite "
                    f"values of the same shape. Got shape {out.shape} instead."
                )
            return out

        p_named = 1.0
        fname = getattr(function, "__name__", "callable")
    else:
        raise InvalidTypeError(
            f"The 'function' parameter of {_OWNER} must be a name in {tuple(FUNCTIONS)} or a "
            f"callable. Got {function!r} instead."
        )
    p = p_named if order is None else check_real(order, "order", _OWNER, positive=True)
    sizes = check_array(sample_sizes() if n is None else n, "n", _OWNER, shape=(-1,))
    if sizes.shape[0] < 2 or np.any(sizes < 1) or np.any(sizes != np.round(sizes)):
        raise InvalidValueError(
            f"The 'n' parameter of {_OWNER} must be at least two positive integers. "
            f"Got {sizes.tolist()!r} instead."
        )
    if np.any(np.diff(sizes) <= 0):
        raise InvalidValueError(
            f"The 'n' parameter of {_OWNER} must be increasing. Got {sizes.tolist()!r} instead."
        )
    ns = sizes.astype(np.int64)
    reps = check_int(repetitions, "repetitions", _OWNER, minimum=2)
    sigma = check_real(noise, "noise", _OWNER, nonnegative=True)
    dist = check_option(distribution, "distribution", _OWNER, DISTRIBUTIONS)
    rule = as_rule(bandwidth, _OWNER)
    h1 = None if rule is not None else check_real(bandwidth, "bandwidth", _OWNER, positive=True)
    dec = 1.0 / (2.0 * p + 1.0) if decay is None else check_real(decay, "decay", _OWNER)
    lo, hi = (check_real(v, "interval", _OWNER) for v in interval)
    if not lo < hi:
        raise InvalidValueError(
            f"The 'interval' parameter of {_OWNER} must have lo < hi. Got {interval!r} instead."
        )
    g = check_int(grid, "grid", _OWNER, minimum=2)
    if progress is not None and not isinstance(progress, bool):
        raise InvalidTypeError(
            f"The 'progress' parameter of {_OWNER} must be None or a bool. Got {progress!r} "
            "instead."
        )
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)

    x = np.linspace(lo, hi, g)
    truth = m(x)
    weights = np.full(g, (hi - lo) / (g - 1))
    weights[[0, -1]] *= 0.5  # trapezoid rule
    ise = np.empty((reps, ns.shape[0]))
    h1s = np.empty(reps)
    tty = sys.stderr.isatty()
    show = _progress_bar(
        reps, tty and (progress is True or (progress is None and reps * int(ns[-1]) > 2_000_000))
    )
    for rep in range(reps):
        X = _draw(dist, gen, int(ns[-1]))
        y = m(X) + sigma * gen.standard_normal(X.shape[0])
        h1s[rep] = h1 if rule is None else float(rule(X[:, None], dec, owner=_OWNER)[0])
        est = SemiRecursiveKernelRegression(kernel, h1s[rep], dec, grid=x)
        done = 0
        for k, nk in enumerate(ns):
            est.partial_fit(X[done:nk], y[done:nk])
            done = int(nk)
            err = est.predict(x) - truth
            # no sample near a point yet (NaN): count the whole function there
            err = np.where(np.isnan(err), np.abs(truth) + 1.0, err)
            ise[rep, k] = float(weights @ (err * err))
        show(rep + 1)
    mise = ise.mean(axis=0)
    std = ise.std(axis=0, ddof=1)
    slope, intercept = np.polyfit(np.log(ns.astype(float)), np.log(mise), 1)
    settings = {
        "function": fname,
        "distribution": dist,
        "noise": sigma,
        "kernel": kernel,
        "bandwidth": h1 if rule is None else rule.label,
        "h1": [float(v) for v in h1s],
        "decay": dec,
        "interval": [lo, hi],
        "grid": g,
        "repetitions": reps,
        "rng": "Generator" if isinstance(rng, np.random.Generator) else rng,
    }
    return ConvergenceResult(
        n=ns,
        mise=mise,
        std=std,
        slope=float(slope),
        intercept=float(intercept),
        theory_slope=-2.0 * p / (2.0 * p + 1.0),
        order=p,
        settings=settings,
    )
