"""The identified model's attributes, read from its :class:`Solution` (both paths)."""

from __future__ import annotations

from ..._types import F64
from .prediction import max_lag
from .solution import Solution
from .systems import ARMA

__all__ = ["SolutionAttributes"]


class SolutionAttributes:
    """The fitted attributes of a Hammerstein model, each a copy read from ``_solution()``."""

    def _solution(self) -> Solution:
        raise NotImplementedError  # pragma: no cover - the identifier defines it

    @property
    def impulse_response_(self) -> F64:
        """``lambda_0 .. lambda_{L-1}``, shape (n_lags,)."""
        return self._solution().impulse.copy()

    @property
    def nonlinearity_(self) -> F64:
        """The identified ``phi`` on ``grid_``, shape (g,)."""
        return self._solution().nonlinearity.copy()

    @property
    def shape_(self) -> F64:
        """The unnormalised shape of ``phi`` on ``grid_``, shape (g,)."""
        return self._solution().shape.copy()

    @property
    def grid_(self) -> F64:
        """Points (units of ``u``) where ``phi`` is estimated, shape (g,)."""
        return self._solution().grid.copy()

    @property
    def input_weights_(self) -> F64:
        """Share of the inputs at each point of ``grid_`` (sums to 1), shape (g,)."""
        return self._solution().weights.copy()

    @property
    def arma_(self) -> ARMA:
        """The ARMA model of the linear part."""
        return self._solution().arma.model

    @property
    def order_(self) -> int:
        """The ARMA order ``l`` in use."""
        return self._solution().arma.order

    @property
    def max_lag_(self) -> int:
        """``max(p, q)``: the initial conditions ``predict`` takes from ``y``."""
        return max_lag(self._solution().arma.model)

    @property
    def criterion_(self) -> dict[int, float]:
        """Criterion of each order tried (BIC/AIC, or the held-out MSE at the chosen knots)."""
        return dict(self._solution().arma.criterion)

    @property
    def offset_(self) -> float:
        """Output offset added by ``predict``, units of ``y``."""
        return self._solution().offset

    @property
    def singular_values_(self) -> F64:
        """Singular values of the rank-one array (rank one if Hammerstein)."""
        return self._solution().singular_values.copy()
