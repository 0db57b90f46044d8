"""The streaming state of Hammerstein identification: one grid regression per lag.

:class:`LagRegressions` keeps, for ``k = 0 .. L-1``, the grid-mode sums of
``m_k(x) = E[Y_{n+k} | X_n = x]`` (a
:class:`~flexarm.ident.SemiRecursiveKernelRegression` each), the last
``L - 1`` inputs (so that chunks join seamlessly) and running sums of ``y``.
The first ``warmup`` samples are buffered until the grid and a rule's
bandwidth can be fixed from them. Every sum takes samples in arrival order, so
chunks give bit for bit what one call gives; :meth:`~LagRegressions.state`
and :meth:`~LagRegressions.from_state` (the lag regressions through their own
state description) resume exactly.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numba as nb
import numpy as np
from numpy.typing import NDArray

from ...._types import F64
from ....errors import InvalidValueError
from ...regression.accumulators import State
from ...regression.bandwidth import Silverman
from ...regression.estimators import SemiRecursiveKernelRegression
from ..solution import Solution
from .correlation import solve

__all__ = ["WHITE_MAX_ORDER", "LagRegressions", "solve_white", "white_solution"]

#: ``max_order=None``: the white path's largest ARMA order (BIC), as before the correlated path.
WHITE_MAX_ORDER = 4


@nb.njit(cache=True)
def _running_sums(y: F64, acc: F64) -> None:  # pragma: no cover - compiled
    """``acc[0] += sum y``, ``acc[1] += sum y**2``, one sample at a time in order."""
    for i in range(y.shape[0]):
        acc[0] += y[i]
        acc[1] += y[i] * y[i]


class LagRegressions:
    """Lag regressions of a Hammerstein identification (module docstring).

    Parameters
    ----------
    params : mapping
        Validated hyperparameters of the identifier: ``n_lags``, ``kernel``,
        ``bandwidth`` (``h_1`` in units of ``u``, or a :class:`Silverman`
        rule), ``decay``, ``grid_size``, ``warmup``.
    owner : str
        Named in error messages.
    """

    def __init__(self, params: Mapping[str, Any], owner: str) -> None:
        self.params = params
        self.owner = owner
        self.n_samples = 0
        self.sums = np.zeros(2)  # sum y, sum y**2
        self.buffer_u: list[F64] = []
        self.buffer_y: list[F64] = []
        self.regressions: list[SemiRecursiveKernelRegression] | None = None
        self.bandwidth = 0.0  # h_1 (units of u), once started
        self.grid = np.zeros(0)
        self.tail = np.zeros(0)

    def add_chunk(self, u: F64, y: F64) -> None:
        """Add the next samples, shape (m,) each (units of ``u`` and ``y``)."""
        if u.shape[0] == 0:
            return
        _running_sums(y, self.sums)
        self.n_samples += u.shape[0]
        if self.regressions is None:
            self.buffer_u.append(u)
            self.buffer_y.append(y)
            if self.n_samples < self.params["warmup"]:
                return
            u = np.concatenate(self.buffer_u)
            y = np.concatenate(self.buffer_y)
            self.buffer_u, self.buffer_y = [], []
            self._start(u[: self.params["warmup"]])
        self._add(u, y)

    def _start(self, u0: F64) -> None:
        p = self.params
        spread = float(np.std(u0))
        if not spread > 0.0:
            raise InvalidValueError(
                f"The 'u' parameter of {self.owner} must vary (its spread sets the grid and the "
                f"bandwidth). Got a constant input over the first {u0.shape[0]} samples instead."
            )
        lo, hi = float(np.min(u0)), float(np.max(u0))
        margin = 0.1 * (hi - lo)
        grid = np.linspace(lo - margin, hi + margin, p["grid_size"])
        rule = p["bandwidth"]
        if isinstance(rule, Silverman):
            h1 = float(rule(u0[:, None], p["decay"], owner=self.owner, name="u")[0])
        else:
            h1 = float(rule)
        self.bandwidth = h1
        self.grid = grid
        self.regressions = [
            SemiRecursiveKernelRegression(
                kernel=p["kernel"], bandwidth=h1, decay=p["decay"], grid=grid
            )
            for _ in range(p["n_lags"])
        ]
        self.tail = np.zeros(0)

    def _add(self, u: F64, y: F64) -> None:
        assert self.regressions is not None
        L = self.params["n_lags"]
        t = self.tail.shape[0]
        ext = np.concatenate([self.tail, u])
        m = u.shape[0]
        for k, reg in enumerate(self.regressions):
            j0 = max(0, k - t)
            if j0 >= m:
                continue
            reg.partial_fit(ext[t + j0 - k : t + m - k], y[j0:])
        self.tail = ext[-(L - 1) :].copy() if L > 1 else np.zeros(0)

    @property
    def ready(self) -> bool:
        """Whether every lag regression has at least two samples."""
        regs = self.regressions
        return regs is not None and getattr(regs[-1], "n_samples_", 0) >= 2

    def lag_sums(self) -> tuple[F64, F64]:
        """Grid sums ``N_k(x)``, ``D_k(x)`` of every lag, shape ``(n_lags, grid_size)`` each."""
        assert self.regressions is not None
        num = np.array([r.numerator_ for r in self.regressions])
        den = np.array([r.denominator_ for r in self.regressions])
        return num, den

    def state(self) -> State:
        """Everything needed to resume, as plain arrays (lag ``k``'s keys prefixed ``lagk.``)."""
        state: State = {"n_samples": np.array(self.n_samples), "sums": self.sums.copy()}
        if self.regressions is None:
            state["buffer_u"] = np.concatenate([np.zeros(0), *self.buffer_u])
            state["buffer_y"] = np.concatenate([np.zeros(0), *self.buffer_y])
            return state
        state.update(bandwidth_=np.array(self.bandwidth), grid=self.grid, tail=self.tail)
        for k, reg in enumerate(self.regressions):
            state.update({f"lag{k}.{key}": v for key, v in reg.to_arrays().items()})
        return state

    @classmethod
    def from_state(
        cls, params: Mapping[str, Any], owner: str, state: Mapping[str, NDArray[Any]]
    ) -> Self:
        """Resume from :meth:`state` output (with the same validated ``params``)."""
        lags = cls(params, owner)
        lags.sums = np.array(state["sums"], dtype=np.float64)
        lags.n_samples = int(state["n_samples"])
        if "buffer_u" in state:
            if state["buffer_u"].shape[0]:
                lags.buffer_u = [np.array(state["buffer_u"], dtype=np.float64)]
                lags.buffer_y = [np.array(state["buffer_y"], dtype=np.float64)]
            return lags
        lags.bandwidth = float(state["bandwidth_"])
        lags.grid = np.array(state["grid"], dtype=np.float64)
        lags.tail = np.array(state["tail"], dtype=np.float64)
        lags.regressions = []
        for k in range(params["n_lags"]):
            prefix = f"lag{k}."
            sub = {key[len(prefix) :]: v for key, v in state.items() if key.startswith(prefix)}
            lags.regressions.append(SemiRecursiveKernelRegression.from_arrays(sub))
        return lags


def white_solution(params: Mapping[str, Any], u: F64, y: F64) -> Solution:
    """The white path's model of one record (validated ``params``), without a report."""
    lags = LagRegressions(params, "HammersteinIdentifier")
    lags.add_chunk(u, y)
    return solve_white(params, lags)


def solve_white(params: Mapping[str, Any], lags: LagRegressions) -> Solution:
    """The correlation approach on the lag regressions' sums (``correlation.solve``)."""
    order = params["order"]
    return solve(
        *lags.lag_sums(),
        lags.grid,
        instrument=params["instrument"],
        known_points=params["known_points"],
        order="bic" if order == "auto" else order,
        max_order=WHITE_MAX_ORDER if params["max_order"] is None else params["max_order"],
        mean_y=float(lags.sums[0] / lags.n_samples),
        owner="HammersteinIdentifier",
    )
