"""The correlated-input path of Hammerstein identification: the ARX-Hammerstein structure.

* :mod:`~flexarm.ident.hammerstein.correlated.hatbasis` — the piecewise-linear
  basis of the nonlinearity, knots at the input's quantiles;
* :mod:`~flexarm.ident.hammerstein.correlated.arx` — over-parameterised least
  squares, Bai's rank-one separation, instrumental-variable steps;
* :mod:`~flexarm.ident.hammerstein.correlated.selection` — order and knots by
  the one-standard-error rule on held-out free-run error;
* :mod:`~flexarm.ident.hammerstein.correlated.solve` — the chosen structure
  refitted and normalised into the white path's terms.
"""

from __future__ import annotations

__all__: list[str] = []
