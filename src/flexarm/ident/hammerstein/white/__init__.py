"""The white-input path of Hammerstein identification: the paper's correlation approach.

For an i.i.d. input, ``m_k(x) = E[Y_{n+k} | X_n = x] = lambda_k phi(x) + c_k``
for every lag ``k``:

* :mod:`~flexarm.ident.hammerstein.white.lags` — the lag regressions, each
  the paper's semi-recursive kernel estimate on a grid, streamed chunk by chunk;
* :mod:`~flexarm.ident.hammerstein.white.correlation` — the impulse response
  and the nonlinearity from their rank-one array;
* :mod:`~flexarm.ident.hammerstein.white.arma` — the ARMA model of the impulse
  response (Prony's start, least-squares refinement, order by BIC).
"""

from __future__ import annotations

__all__: list[str] = []
