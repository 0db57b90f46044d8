r"""Is an input white? Portmanteau tests on the input and on its squares.

The paper's correlation approach (:mod:`flexarm.ident.hammerstein.identifier`) is exact for
an i.i.d. input. :func:`whiteness_test` measures how far a record is from that:

* **Ljung–Box** on the centred input ``x``: ``Q = n (n + 2) sum_{k=1}^{m}
  r_k**2 / (n - k)`` with ``r_k`` the lag-``k`` autocorrelation; ``Q`` is
  ``chi2(m)`` for an i.i.d. input (Ljung & Box 1978). It catches a coloured
  input: a sweep, a multisine, filtered noise.
* **McLeod–Li**: the same statistic on ``x**2`` (McLeod & Li 1983). It catches
  inputs that are uncorrelated but not independent (a changing amplitude, a
  random-phase multisine's envelope), which the correlation approach also
  cannot use.

The input counts as white when neither test rejects at level ``alpha / 2``
(Bonferroni: the pair rejects a truly i.i.d. input with probability at most
``alpha``). The default ``alpha = 0.001`` sends one white record in a thousand
to the correlated path (which serves it too), while the coloured inputs of
practice are rejected with p-values far smaller (a sine sweep: 1e-100). The
default ``m = min(20, n // 10)`` lags.

References
----------
* G. M. Ljung, G. E. P. Box, "On a measure of lack of fit in time series
  models", Biometrika 65 (1978) 297–303.
* A. I. McLeod, W. K. Li, "Diagnostic checking ARMA time series models using
  squared-residual autocorrelations", J. Time Series Anal. 4 (1983) 269–273.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64
from ..._validation import check_array, check_int, check_real
from ...errors import InvalidValueError

__all__ = ["DEFAULT_ALPHA", "IdentificationWarning", "WhitenessReport", "whiteness_test"]


#: Default level of the whiteness test (both statistics together; module docstring).
DEFAULT_ALPHA = 0.001


class IdentificationWarning(UserWarning):
    """An identification ran with its assumptions not met (a coloured input on the
    white-input path, a nonlinear model that loses to its linear baseline)."""


def _autocorrelation(x: F64, m: int) -> F64:
    """``r_1 .. r_m`` of ``x`` (centred inside), biased estimator (divides by ``n``)."""
    c = x - float(np.mean(x))
    denom = float(c @ c)
    n = c.shape[0]
    out: F64 = np.array([float(c[k:] @ c[: n - k]) / denom for k in range(1, m + 1)])
    return out


def _ljung_box(r: F64, n: int) -> float:
    k = np.arange(1, r.shape[0] + 1)
    return float(n * (n + 2) * np.sum(r**2 / (n - k)))


@dataclass(frozen=True)
class WhitenessReport:
    """How white an input is (module docstring).

    Attributes
    ----------
    n_samples : int
        Samples tested.
    n_lags : int
        ``m``, the lags of each statistic.
    alpha : float
        Level of the pair of tests.
    autocorrelation : ndarray, shape (m,)
        ``r_1 .. r_m`` of the input.
    ljung_box, ljung_box_p : float
        Ljung–Box statistic of the input and its p-value (``chi2(m)``).
    mcleod_li, mcleod_li_p : float
        The same on the squared centred input.
    white : bool
        Neither p-value below ``alpha / 2``.
    """

    n_samples: int
    n_lags: int
    alpha: float
    autocorrelation: F64
    ljung_box: float
    ljung_box_p: float
    mcleod_li: float
    mcleod_li_p: float
    white: bool

    @property
    def lag1(self) -> float:
        """Lag-1 autocorrelation of the input."""
        return float(self.autocorrelation[0])

    @property
    def reason(self) -> str:
        """One sentence: the verdict and the figures behind it."""
        figures = (
            f"lag-1 autocorrelation {self.lag1:.3f}; Ljung-Box p = {self.ljung_box_p:.3g}, "
            f"McLeod-Li p = {self.mcleod_li_p:.3g} over {self.n_lags} lags, "
            f"level {self.alpha:g}"
        )
        if self.white:
            return f"the input looks white ({figures})"
        which = [
            name
            for name, p in (("coloured", self.ljung_box_p), ("dependent", self.mcleod_li_p))
            if p < self.alpha / 2
        ]
        return f"the input is not white: {' and '.join(which)} ({figures})"

    def summary(self) -> dict[str, Any]:
        """Plain values for JSON."""
        return {
            "white": self.white,
            "reason": self.reason,
            "n_samples": self.n_samples,
            "n_lags": self.n_lags,
            "alpha": self.alpha,
            "lag1_autocorrelation": self.lag1,
            "ljung_box": self.ljung_box,
            "ljung_box_p": self.ljung_box_p,
            "mcleod_li": self.mcleod_li,
            "mcleod_li_p": self.mcleod_li_p,
        }


def whiteness_test(
    u: ArrayLike, n_lags: int | None = None, alpha: float = DEFAULT_ALPHA
) -> WhitenessReport:
    """Test an input for whiteness: Ljung–Box on ``u``, McLeod–Li on ``u**2``.

    Parameters
    ----------
    u : array_like, shape (n,)
        The input (any unit), finite, not constant, ``n >= 20``.
    n_lags : int, optional
        Lags ``m`` of each statistic (``1 <= m < n / 2``); default
        ``min(20, n // 10)``.
    alpha : float
        Level of the pair of tests, in (0, 1).

    Returns
    -------
    WhitenessReport

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> whiteness_test(rng.normal(size=5000)).white
    True
    >>> x = np.convolve(rng.normal(size=5000), np.ones(4))[:5000]
    >>> rep = whiteness_test(x)
    >>> rep.white, round(rep.lag1, 1)
    (False, 0.8)
    """
    from scipy.stats import chi2

    owner = "whiteness_test"
    x = check_array(u, "u", owner, shape=(-1,))
    n = x.shape[0]
    if n < 20:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must hold at least 20 samples. Got {n} instead."
        )
    if np.ptp(x) == 0.0:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must vary. Got a constant input instead."
        )
    m = min(20, n // 10) if n_lags is None else check_int(n_lags, "n_lags", owner, minimum=1)
    if not m < n / 2:
        raise InvalidValueError(
            f"The 'n_lags' parameter of {owner} must be < n / 2 = {n / 2:g}. Got {m} instead."
        )
    level = check_real(alpha, "alpha", owner, positive=True)
    if not level < 1.0:
        raise InvalidValueError(
            f"The 'alpha' parameter of {owner} must be in (0, 1). Got {level} instead."
        )
    r = _autocorrelation(x, m)
    sq = (x - float(np.mean(x))) ** 2
    r2 = _autocorrelation(sq, m) if np.ptp(sq) > 0.0 else np.zeros(m)
    q1, q2 = _ljung_box(r, n), _ljung_box(r2, n)
    p1, p2 = float(chi2.sf(q1, m)), float(chi2.sf(q2, m))
    white = bool(p1 >= level / 2 and p2 >= level / 2)
    return WhitenessReport(n, m, level, r, q1, p1, q2, p2, white)
