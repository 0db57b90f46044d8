r"""Bootstrap bands for an identified Hammerstein model: ``phi`` and the impulse response.

:func:`bootstrap_bands` resamples the record by the **circular block
bootstrap** (Politis & Romano 1992; Künsch 1989 for the moving-block
bootstrap): blocks of ``b`` consecutive ``(u, y)`` pairs, started at uniform
random positions on the record wrapped into a circle, are laid end to end
until the record's length is reached. Blocks keep the dependence inside a
block — the dynamics, the input's colour, the noise's — so the spread of the
re-estimates reflects it; the joints cost a transient each, a small bias when
``b`` is much longer than the model's memory. The default ``b`` is
``max(n**(1/3), 4 m)`` with ``m`` the memory (white path: ``n_lags``;
correlated path: ten times the order), at most ``n / 10``.

Each replicate is estimated by the path and structure of the fitted model
(the correlated path's order and knots are kept: the bands are conditional on
the chosen structure). Without known points ``phi`` and the impulse response
are determined up to ``phi -> s phi + t``, ``lambda -> lambda / s``: each
replicate is mapped onto the estimate by the least-squares ``s`` on the
impulse response and the input-weighted least-squares ``t`` on ``phi``.
The bands are the pointwise ``(1 - level) / 2`` and ``(1 + level) / 2``
quantiles of the replicates on the estimate's grid and lags.

References
----------
* D. N. Politis, J. P. Romano, "A circular block-resampling procedure for
  stationary data", in *Exploring the Limits of Bootstrap*, Wiley (1992) 263–270.
* H. R. Künsch, "The jackknife and the bootstrap for general stationary
  observations", Ann. Statist. 17 (1989) 1217–1241.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64, I64
from ..._validation import check_int, check_real, check_rng
from ...errors import InvalidValueError
from ...figures import DOUBLE_COLUMN, new_figure, styled
from ._state import HammersteinState
from .correlated.arx import fit_structure
from .correlated.hatbasis import evaluate, locate
from .correlated.solve import normalise
from .prediction import check_record
from .white.lags import white_solution

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["Bands", "FittedIdentifier", "bootstrap_bands", "circular_blocks"]


def circular_blocks(n: int, block: int, rng: np.random.Generator) -> I64:
    """Indices of one circular block resample of ``0, …, n-1``, shape (n,)."""
    starts = rng.integers(0, n, math.ceil(n / block))
    idx: I64 = ((starts[:, None] + np.arange(block)[None, :]) % n).ravel()[:n]
    return idx


@dataclass(frozen=True)
class Bands:
    """Pointwise bootstrap bands of ``phi`` and of the impulse response.

    Attributes
    ----------
    grid : ndarray, shape (g,)
        Where ``phi`` is given (units of ``u``).
    phi, phi_low, phi_high : ndarray, shape (g,)
        The estimate and its band.
    impulse, impulse_low, impulse_high : ndarray, shape (L,)
        The impulse response and its band.
    level : float
        Pointwise coverage.
    n_boot, block_length : int
        Replicates, and samples per block.
    method : str
        The path the replicates were estimated by.
    """

    grid: F64
    phi: F64
    phi_low: F64
    phi_high: F64
    impulse: F64
    impulse_low: F64
    impulse_high: F64
    level: float
    n_boot: int
    block_length: int
    method: str

    def summary(self) -> dict[str, Any]:
        """Plain values for JSON."""
        return {
            "method": f"circular block bootstrap, {self.method} path",
            "level": self.level,
            "n_boot": self.n_boot,
            "block_length": self.block_length,
            "phi_band_max_width": float(np.max(self.phi_high - self.phi_low)),
            "impulse_band_max_width": float(np.max(self.impulse_high - self.impulse_low)),
        }

    @styled
    def plot(self, fig: Figure | None = None, *, u_label: str = "u (data units)") -> Figure:
        """Two panels: ``phi`` and the impulse response, each with its band (two columns
        of a paper wide).

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Figure to draw into (a new one if omitted; never shown).
        u_label : str
            Label of the input axis, ``"name (unit)"``.

        Returns
        -------
        matplotlib.figure.Figure
        """
        if fig is None:
            fig = new_figure(DOUBLE_COLUMN, 2.5)
        ax1, ax2 = fig.subplots(1, 2)
        pct = f"{100 * self.level:g} % band"
        draw_phi_band(ax1, self)
        ax1.plot(self.grid, self.phi, lw=1.5, label="estimate")
        ax1.set(xlabel=u_label, ylabel="φ(u) (normalised)")
        ax1.set_title("nonlinearity")
        ax1.legend(loc="best")
        k = np.arange(self.impulse.shape[0])
        draw_impulse_band(ax2, self)
        ax2.plot(k, self.impulse, "o-", ms=2.5, label="estimate")
        ax2.set(xlabel="lag k (samples)", ylabel="$\\lambda_k$ (per φ unit)")
        ax2.set_title(f"impulse response\n{pct}, {self.n_boot} block-bootstrap replicates")
        ax2.legend(loc="best")
        return fig


def draw_phi_band(ax: Any, bands: Bands) -> None:
    """Shade ``phi``'s band on ``ax``."""
    label = f"{100 * bands.level:g} % band"
    ax.fill_between(bands.grid, bands.phi_low, bands.phi_high, alpha=0.3, lw=0, label=label)


def draw_impulse_band(ax: Any, bands: Bands) -> None:
    """Shade the impulse response's band on ``ax``."""
    k = np.arange(bands.impulse.shape[0])
    label = f"{100 * bands.level:g} % band"
    ax.fill_between(k, bands.impulse_low, bands.impulse_high, alpha=0.3, lw=0, label=label)


class FittedIdentifier(Protocol):
    """What :func:`bootstrap_bands` reads of a fitted
    :class:`~flexarm.ident.hammerstein.identifier.HammersteinIdentifier`: its settings
    (the checked hyperparameters of its state), the path it took and the structure it
    found, refitted on each resampled record."""

    n_lags: int

    @property
    def state_(self) -> HammersteinState: ...
    @property
    def n_samples_(self) -> int: ...
    @property
    def method_(self) -> str: ...
    @property
    def order_(self) -> int: ...
    @property
    def grid_(self) -> F64: ...
    @property
    def nonlinearity_(self) -> F64: ...
    @property
    def impulse_response_(self) -> F64: ...
    @property
    def input_weights_(self) -> F64: ...


def _replicate(est: FittedIdentifier, u: F64, y: F64) -> tuple[F64, F64, F64] | None:
    """``(grid, phi, impulse)`` of one resampled record by the fitted path and structure."""
    p = est.state_.checked
    if est.method_ == "white":
        try:
            sol = white_solution(p, u, y)
        except InvalidValueError:
            return None
        return sol.grid, sol.nonlinearity, sol.impulse
    fit = fit_structure(u, y, est.order_, est.grid_.shape[0])
    if fit is None:
        return None
    try:
        sol = normalise(
            fit, u, y, n_lags=p["n_lags"], known_points=p["known_points"], criterion={}, owner=""
        )
    except InvalidValueError:
        return None
    return sol.grid, sol.nonlinearity, sol.impulse


def bootstrap_bands(
    est: FittedIdentifier,
    u: ArrayLike,
    y: ArrayLike,
    *,
    n_boot: int = 100,
    level: float = 0.9,
    block_length: int | None = None,
    rng: np.random.Generator | int | None = None,
) -> Bands:
    """Circular-block-bootstrap bands of a fitted identifier (module docstring).

    Parameters
    ----------
    est : HammersteinIdentifier
        Fitted to ``(u, y)``.
    u, y : array_like, shape (n,)
        The record.
    n_boot : int
        Replicates (>= 10).
    level : float
        Pointwise coverage, in (0, 1).
    block_length : int, optional
        Samples per block (``1 <= b <= n / 2``); default in the module docstring.
    rng : numpy.random.Generator or int, optional
        Source of the block starts.

    Returns
    -------
    Bands
    """
    owner = "HammersteinIdentifier.bands"
    ua, ya = check_record(u, y, owner, 2)
    if ua.shape[0] != est.n_samples_:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must be the record the identifier was fitted to "
            f"({est.n_samples_} samples). Got {ua.shape[0]} samples instead."
        )
    n = ua.shape[0]
    reps = check_int(n_boot, "n_boot", owner, minimum=10)
    lvl = check_real(level, "level", owner, positive=True)
    if not lvl < 1.0:
        raise InvalidValueError(f"The 'level' parameter of {owner} must be < 1. Got {lvl}.")
    memory = est.n_lags if est.method_ == "white" else 10 * est.order_
    default = min(max(round(n ** (1 / 3)), 4 * memory), max(1, n // 10))
    block = default if block_length is None else check_int(block_length, "block_length", owner)
    if not 1 <= block <= n // 2:
        raise InvalidValueError(
            f"The 'block_length' parameter of {owner} must be in [1, {n // 2}]. Got {block}."
        )
    gen = check_rng(rng, owner)
    grid, phi, lam = est.grid_, est.nonlinearity_, est.impulse_response_
    weights = est.input_weights_
    known = est.state_.checked["known_points"] is not None
    phis, lams = [], []
    for _ in range(reps):
        idx = circular_blocks(n, block, gen)
        rep = _replicate(est, ua[idx], ya[idx])
        if rep is None:
            continue
        g, p_rep, l_rep = rep
        if est.method_ == "white":
            p_on = np.interp(grid, g, p_rep)
        else:
            p_on = evaluate(*locate(grid, g), p_rep)
        if not known:  # align the affine ambiguity with the estimate
            s = float(l_rep @ lam) / float(l_rep @ l_rep)
            l_rep, p_on = l_rep * s, p_on / s
            p_on = p_on + float(weights @ (phi - p_on))
        phis.append(p_on)
        lams.append(l_rep)
    if len(phis) < max(10, reps // 2):
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must allow re-estimation on resampled records. "
            f"Got {len(phis)} usable replicates of {reps} instead."
        )
    q = [(1.0 - lvl) / 2.0, (1.0 + lvl) / 2.0]
    p_lo, p_hi = np.quantile(np.array(phis), q, axis=0)
    l_lo, l_hi = np.quantile(np.array(lams), q, axis=0)
    return Bands(grid, phi, p_lo, p_hi, lam, l_lo, l_hi, lvl, len(phis), block, est.method_)
