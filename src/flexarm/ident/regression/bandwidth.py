r"""Default bandwidths: Silverman's rule of thumb, the one rule behind every default.

Rule
----
For samples ``X_1 .. X_n`` in ``d`` dimensions, coordinate ``j`` gets

.. math::

    s_j = \min(\mathrm{sd}_j, \mathrm{IQR}_j / 1.34), \qquad
    h_{n,j} = 0.9\, s_j\, n^{-1/(d+4)}

with ``sd`` the sample standard deviation (``ddof = 1``) and ``IQR`` the
interquartile range (NumPy's linear percentiles). For ``d = 1`` this is
Silverman's rule of thumb (B. W. Silverman, *Density Estimation for Statistics
and Data Analysis*, Chapman & Hall, 1986, eq. 3.31); for ``d > 1`` each
coordinate keeps that spread and constant with the exponent ``-1/(d+4)`` of the
normal reference rule in ``d`` dimensions (D. W. Scott, *Multivariate Density
Estimation*, Wiley, 1992, §6.3.1). Where ``IQR_j = 0`` (a column that is mostly
one value) ``s_j = sd_j``; a constant column has no rule and is refused.

The estimators use ``h_i = h_1 i**(-decay)``; the rule fixes ``h_1`` so that the
**last** of the ``n`` samples gets the rule's bandwidth:

.. math:: h_{1,j} = c\, h_{n,j}\, n^{\mathrm{decay}}
          = c\, 0.9\, s_j\, n^{\mathrm{decay} - 1/(d+4)}

with the factor ``c = 1`` for ``bandwidth="silverman"``. With
``decay = 1/(d+4)`` (``0.2`` for ``d = 1``, the default) ``h_1 = 0.9 c s`` does
not depend on ``n``, and every ``h_i`` is the rule's bandwidth for the first
``i`` samples.

The rule is the mean-integrated-squared-error optimum for a normal density and
a Gaussian kernel; it oversmooths functions with jumps. :class:`Silverman`
with a factor ``c < 1`` keeps the rule's scaling (units, ``n``, ``decay``)
with a narrower width: :class:`~flexarm.ident.HammersteinIdentifier` uses
``Silverman(0.55)`` by default (its nonlinearities may be discontinuous).

Who uses it: ``SemiRecursiveKernelRegression(bandwidth="silverman")`` and its
siblings (evaluated on the samples of the first ``fit``/``partial_fit`` call),
:class:`~flexarm.ident.HammersteinIdentifier` (on its ``warmup`` samples),
:func:`~flexarm.ident.convergence_study` (on each repetition's data) and
``flexarm identify``.

Examples
--------
>>> x = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
>>> h = silverman_bandwidth(x, decay=0.2)   # 0.9 min(1.58, 2 / 1.34)
>>> round(float(h[0]), 6)
1.343284
>>> bool(Silverman(0.5)(x, decay=0.2)[0] == 0.5 * h[0])
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64
from ..._validation import check_array, check_int, check_real
from ...errors import InvalidTypeError, InvalidValueError
from ..options import BANDWIDTH_RULES

__all__ = ["BANDWIDTH_RULES", "Silverman", "as_rule", "silverman_bandwidth"]


def _spread(X: F64, owner: str, name: str) -> F64:
    """``min(sd, IQR / 1.34)`` per column (``sd`` where the IQR is 0); shape (d,)."""
    q75, q25 = np.percentile(X, [75.0, 25.0], axis=0)
    sd = np.std(X, axis=0, ddof=1)
    out = np.empty(X.shape[1])
    for j in range(X.shape[1]):
        s = min(float(sd[j]), float(q75[j] - q25[j]) / 1.34)
        if not s > 0.0:
            s = float(sd[j])
        if not s > 0.0:
            raise InvalidValueError(
                f"The '{name}' parameter of {owner} must vary for the 'silverman' bandwidth "
                f"rule. Got a constant column {j} instead."
            )
        out[j] = s
    return out


def silverman_bandwidth(
    X: ArrayLike,
    decay: float = 0.2,
    *,
    n: int | None = None,
    factor: float = 1.0,
) -> F64:
    """``h_1`` such that the last sample's ``h_n`` is ``factor`` times Silverman's rule.

    ``h_1 = factor * 0.9 * min(sd, IQR / 1.34) * n**(decay - 1/(d + 4))`` per
    coordinate (module docstring).

    Parameters
    ----------
    X : array_like, shape (n,) or (n, d)
        Inputs (units of the regressor); shape ``(n,)`` means ``d = 1``. At
        least two samples, not all equal in any coordinate.
    decay : float, default 0.2
        The estimator's ``h_i = h_1 i**(-decay)``, >= 0.
    n : int, optional
        Sample size the rule is anchored at; default ``len(X)``.
    factor : float, default 1.0
        Multiple of the rule's bandwidth, > 0.

    Returns
    -------
    ndarray, shape (d,)
        ``h_1`` per input coordinate (units of the regressor).

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=1000)
    >>> h1 = silverman_bandwidth(x, decay=0.0)   # fixed h: the textbook rule itself
    >>> bool(abs(h1[0] - 0.9 * 1000 ** -0.2) < 0.05)
    True
    """
    return Silverman(factor)(X, decay, n=n)


@dataclass(frozen=True)
class Silverman:
    """Silverman's rule of thumb times ``factor`` (module docstring), as a bandwidth value.

    ``bandwidth="silverman"`` means ``Silverman()``; an instance may be passed
    wherever an estimator takes a bandwidth.

    Parameters
    ----------
    factor : float, default 1.0
        Multiple of the rule's bandwidth, > 0 (dimensionless).
    """

    factor: float = 1.0

    def __post_init__(self) -> None:
        factor = check_real(self.factor, "factor", "Silverman", positive=True)
        object.__setattr__(self, "factor", factor)

    @property
    def name(self) -> str:
        """The rule's name in :data:`BANDWIDTH_RULES`: ``"silverman"``."""
        return "silverman"

    @property
    def label(self) -> str:
        """``"silverman"``, or ``"silverman x c"`` for a multiple ``c`` of the rule."""
        return "silverman" if self.factor == 1.0 else f"silverman x {self.factor:g}"

    def __call__(
        self,
        X: ArrayLike,
        decay: float,
        *,
        n: int | None = None,
        owner: str = "silverman_bandwidth",
        name: str = "X",
    ) -> F64:
        """``h_1`` per coordinate for samples ``X`` of shape ``(m,)`` or ``(m, d)``; shape ``(d,)``.

        ``owner`` and ``name`` are the estimator and parameter named in errors
        (see :func:`silverman_bandwidth` for the other parameters).
        """
        arr = check_array(X, name, owner)
        if arr.dtype.kind == "c":
            raise InvalidTypeError(f"The '{name}' parameter of {owner} must be real. Got complex.")
        if arr.ndim == 1:
            arr = arr[:, None]
        if arr.ndim != 2 or arr.shape[1] < 1:
            raise InvalidValueError(
                f"The '{name}' parameter of {owner} must be of shape (n,) or (n, d). "
                f"Got shape {arr.shape} instead."
            )
        decay = check_real(decay, "decay", owner, nonnegative=True)
        if arr.shape[0] < 2:
            raise InvalidValueError(
                f"The '{name}' parameter of {owner} must hold at least 2 samples for the "
                f"'silverman' bandwidth rule. Got {arr.shape[0]} instead."
            )
        size = arr.shape[0] if n is None else check_int(n, "n", owner, minimum=1)
        d = arr.shape[1]
        spread = _spread(np.asarray(arr, dtype=np.float64), owner, name)
        h: F64 = 0.9 * spread * float(float(size) ** (decay - 1.0 / (d + 4)))
        if self.factor != 1.0:
            h = self.factor * h
        return h


def as_rule(value: object, owner: str) -> Silverman | None:
    """The rule ``value`` names (``"silverman"`` or a :class:`Silverman`), else ``None``.

    Strings other than a rule name raise :class:`~flexarm.errors.InvalidValueError`
    naming the ``bandwidth`` parameter of ``owner``.
    """
    if isinstance(value, Silverman):
        return value
    if isinstance(value, str):
        if value not in BANDWIDTH_RULES:
            raise InvalidValueError(
                f"The 'bandwidth' parameter of {owner} must be > 0 or a rule in "
                f"{BANDWIDTH_RULES}. Got {value!r} instead."
            )
        return Silverman()
    return None
