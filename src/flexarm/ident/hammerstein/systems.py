r"""Hammerstein systems (paper §5, Fig. 5): static nonlinearities, ARMA subsystems, simulation.

A Hammerstein system is a memoryless nonlinearity followed by a stable linear
dynamic subsystem. In the paper's convention

.. math:: W_n = \varphi(U_n) + \xi_n, \qquad
          Y_n = a_1 Y_{n-1} + \dots + a_p Y_{n-p} + b_0 W_n + \dots + b_q W_{n-q},

with ``xi_n`` white noise independent of the input. :func:`simulate_hammerstein`
produces ``Y`` for a given input; :class:`ARMA` holds the linear part (with its
impulse response ``lambda_k`` and stability check) and the classes below are a
library of static nonlinearities, each a small frozen, vectorised callable —
including the discontinuous ones (dead zone with a jump, quantizer, hard
limiter, sign) that a nonparametric method must recover too.

:data:`EXAMPLE_ARMA` gives a few stable ARMA systems of orders 1 to 3.

Every nonlinearity maps an array of any shape to a float array of the same
shape; the units are those of the signal (the library is unit-agnostic).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._types import F64
from ..._validation import check_array, check_int, check_real, check_rng, validate_real_fields
from ...errors import InvalidTypeError, InvalidValueError
from .._estimator import callable_output

__all__ = [
    "ARMA",
    "EXAMPLE_ARMA",
    "Cubic",
    "DeadZone",
    "HardLimiter",
    "Nonlinearity",
    "PiecewiseLinear",
    "Quantizer",
    "Saturation",
    "Sign",
    "simulate_hammerstein",
    "spectral_radius",
]


class Nonlinearity(Protocol):
    """A static map ``phi``: any array of inputs to an array of outputs of the same shape."""

    def __call__(self, x: ArrayLike) -> F64:  # pragma: no cover - protocol
        ...


def _x(x: ArrayLike) -> F64:
    arr: F64 = np.asarray(x, dtype=np.float64)
    return arr


# --------------------------------------------------------------------------- nonlinearities


@dataclass(frozen=True)
class Saturation:
    """``phi(x) = clip(slope x, -limit, limit)``: a linear amplifier that saturates.

    Parameters
    ----------
    limit : float
        Output level at saturation (> 0).
    slope : float
        Gain in the linear range (> 0).

    Examples
    --------
    >>> Saturation(1.0, 2.0)([-1.0, 0.25, 3.0])
    array([-1. ,  0.5,  1. ])
    """

    limit: float = 1.0
    slope: float = 1.0

    def __post_init__(self) -> None:
        validate_real_fields(self, "Saturation", positive=("limit", "slope"))

    def __call__(self, x: ArrayLike) -> F64:
        out: F64 = np.clip(self.slope * _x(x), -self.limit, self.limit)
        return out


@dataclass(frozen=True)
class DeadZone:
    """No output for ``|x| <= width``; outside, ``sign(x) (jump + slope (|x| - width))``.

    ``jump = 0`` is the continuous dead zone; ``jump > 0`` makes it jump at
    ``|x| = width`` (a relay with dead zone plus a linear part: discontinuous).

    Parameters
    ----------
    width : float
        Half-width of the dead band (>= 0).
    slope : float
        Gain outside the dead band (>= 0).
    jump : float
        Output step at the edge of the dead band (>= 0).

    Examples
    --------
    >>> DeadZone(0.5, 1.0, jump=0.2)([-1.0, 0.3, 0.5, 0.6])
    array([-0.7,  0. ,  0. ,  0.3])
    """

    width: float = 0.5
    slope: float = 1.0
    jump: float = 0.0

    def __post_init__(self) -> None:
        validate_real_fields(self, "DeadZone", nonnegative=("width", "slope", "jump"))

    def __call__(self, x: ArrayLike) -> F64:
        v = _x(x)
        a = np.abs(v)
        out: F64 = np.where(
            a > self.width, np.sign(v) * (self.jump + self.slope * (a - self.width)), 0.0
        )
        return out


@dataclass(frozen=True)
class Quantizer:
    """Mid-tread quantizer ``phi(x) = step floor(x / step + 1/2)`` (rounds half up).

    Parameters
    ----------
    step : float
        Quantization step (> 0).

    Examples
    --------
    >>> Quantizer(0.5)([-0.3, 0.2, 0.25, 0.9])
    array([-0.5,  0. ,  0.5,  1. ])
    """

    step: float = 0.5

    def __post_init__(self) -> None:
        validate_real_fields(self, "Quantizer", positive=("step",))

    def __call__(self, x: ArrayLike) -> F64:
        out: F64 = self.step * np.floor(_x(x) / self.step + 0.5)
        return out


@dataclass(frozen=True)
class HardLimiter:
    """Relay: ``high`` for ``x >= threshold``, ``low`` below (``low < high``).

    Parameters
    ----------
    low, high : float
        The two output levels.
    threshold : float
        Switching point.

    Examples
    --------
    >>> HardLimiter(-1.0, 2.0, threshold=0.5)([0.0, 0.5, 1.0])
    array([-1.,  2.,  2.])
    """

    low: float = -1.0
    high: float = 1.0
    threshold: float = 0.0

    def __post_init__(self) -> None:
        for name in ("low", "high", "threshold"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, "HardLimiter"))
        if not self.low < self.high:
            raise InvalidValueError(
                f"The 'high' parameter of HardLimiter must be > low = {self.low}. "
                f"Got {self.high} instead."
            )

    def __call__(self, x: ArrayLike) -> F64:
        out: F64 = np.where(_x(x) >= self.threshold, self.high, self.low)
        return out


@dataclass(frozen=True)
class Sign:
    """``phi(x) = level sign(x)`` (``sign(0) = 0``): an ideal relay.

    Parameters
    ----------
    level : float
        Output magnitude (> 0).

    Examples
    --------
    >>> Sign(2.0)([-0.1, 0.0, 3.0])
    array([-2.,  0.,  2.])
    """

    level: float = 1.0

    def __post_init__(self) -> None:
        validate_real_fields(self, "Sign", positive=("level",))

    def __call__(self, x: ArrayLike) -> F64:
        out: F64 = self.level * np.sign(_x(x))
        return out


@dataclass(frozen=True)
class Cubic:
    """Polynomial ``phi(x) = c0 + c1 x + c2 x**2 + c3 x**3`` (``c2`` alone makes it even).

    Examples
    --------
    >>> Cubic(c1=1.0, c3=-0.5)([0.0, 1.0, 2.0])
    array([ 0. ,  0.5, -2. ])
    """

    c0: float = 0.0
    c1: float = 1.0
    c2: float = 0.0
    c3: float = 1.0

    def __post_init__(self) -> None:
        for name in ("c0", "c1", "c2", "c3"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, "Cubic"))

    def __call__(self, x: ArrayLike) -> F64:
        v = _x(x)
        out: F64 = self.c0 + v * (self.c1 + v * (self.c2 + v * self.c3))
        return out


@dataclass(frozen=True)
class PiecewiseLinear:
    """Linear interpolation through ``(breakpoints[i], values[i])``, linear extrapolation.

    Beyond the end breakpoints the end segments continue (their slopes).

    Parameters
    ----------
    breakpoints : sequence of float, strictly increasing, length >= 2
    values : sequence of float, same length

    Examples
    --------
    >>> phi = PiecewiseLinear((-1.0, 0.0, 1.0), (1.0, 0.0, 2.0))
    >>> phi([-2.0, -0.5, 0.5, 2.0])
    array([2. , 0.5, 1. , 4. ])
    """

    breakpoints: tuple[float, ...] = (-1.0, 0.0, 1.0)
    values: tuple[float, ...] = (-1.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        owner = "PiecewiseLinear"
        bp = check_array(self.breakpoints, "breakpoints", owner, shape=(-1,))
        vals = check_array(self.values, "values", owner, shape=(-1,))
        if bp.shape[0] < 2 or not np.all(np.diff(bp) > 0):
            raise InvalidValueError(
                f"The 'breakpoints' parameter of {owner} must be strictly increasing with "
                f"at least 2 entries. Got {tuple(bp.tolist())} instead."
            )
        if vals.shape != bp.shape:
            raise InvalidValueError(
                f"The 'values' parameter of {owner} must have {bp.shape[0]} entries like "
                f"breakpoints. Got {vals.shape[0]} instead."
            )
        object.__setattr__(self, "breakpoints", tuple(float(b) for b in bp))
        object.__setattr__(self, "values", tuple(float(v) for v in vals))

    def __call__(self, x: ArrayLike) -> F64:
        v = _x(x)
        bp = np.asarray(self.breakpoints)
        vals = np.asarray(self.values)
        out = np.interp(v, bp, vals)
        lo_slope = (vals[1] - vals[0]) / (bp[1] - bp[0])
        hi_slope = (vals[-1] - vals[-2]) / (bp[-1] - bp[-2])
        out = np.where(v < bp[0], vals[0] + lo_slope * (v - bp[0]), out)
        res: F64 = np.where(v > bp[-1], vals[-1] + hi_slope * (v - bp[-1]), out)
        return res


# --------------------------------------------------------------------------- ARMA


def _check_coefficients(a: ArrayLike, b: ArrayLike, owner: str) -> tuple[F64, F64]:
    """Validate ``a`` (AR, may be empty) and ``b`` (MA, non-zero); reject unstable ``a``."""
    aa = check_array(a, "a", owner)
    bb = check_array(b, "b", owner)
    if aa.dtype.kind == "c" or bb.dtype.kind == "c":
        name = "a" if aa.dtype.kind == "c" else "b"
        raise InvalidTypeError(
            f"The '{name}' parameter of {owner} must be real. Got complex instead."
        )
    aa = np.atleast_1d(aa).astype(np.float64)
    bb = np.atleast_1d(bb).astype(np.float64)
    if aa.ndim != 1:
        raise InvalidValueError(
            f"The 'a' parameter of {owner} must be of shape (p,). Got shape {aa.shape} instead."
        )
    if bb.ndim != 1 or bb.shape[0] < 1:
        raise InvalidValueError(
            f"The 'b' parameter of {owner} must be of shape (q + 1,) with q >= 0. "
            f"Got shape {bb.shape} instead."
        )
    if not np.any(bb != 0.0):
        raise InvalidValueError(
            f"The 'b' parameter of {owner} must not be all zero. Got {bb!r} instead."
        )
    radius = spectral_radius(aa)
    if not radius < 1.0:
        raise InvalidValueError(
            f"The 'a' parameter of {owner} must give a stable ARMA system (every root of "
            f"z**p - a1 z**(p-1) - ... - ap strictly inside the unit circle). Got "
            f"{aa.tolist()} instead, with a root of modulus {radius:.6g}."
        )
    return aa, bb


def spectral_radius(a: ArrayLike) -> float:
    """Largest modulus of the roots of ``z**p - a1 z**(p-1) - … - ap`` (0 for ``p = 0``)."""
    aa = np.asarray(a, dtype=np.float64).ravel()
    if aa.shape[0] == 0:
        return 0.0
    roots = np.roots(np.r_[1.0, -aa])
    return float(np.max(np.abs(roots))) if roots.size else 0.0


@dataclass(frozen=True)
class ARMA:
    """A stable ARMA subsystem in the paper's convention.

    ``Y_n = a1 Y_{n-1} + ... + ap Y_{n-p} + b0 W_n + ... + bq W_{n-q}``.

    Parameters
    ----------
    a : sequence of float, length p >= 0
        Autoregressive coefficients ``(a1, ..., ap)``; the roots of
        ``z**p - a1 z**(p-1) - … - ap`` must lie strictly inside the unit
        circle (``ValueError`` otherwise).
    b : sequence of float, length q + 1 >= 1
        Moving-average coefficients ``(b0, ..., bq)``, not all zero.

    Examples
    --------
    >>> ARMA(a=(0.5,), b=(1.0,)).impulse_response(4)
    array([1.   , 0.5  , 0.25 , 0.125])
    """

    a: tuple[float, ...] = ()
    b: tuple[float, ...] = (1.0,)

    def __post_init__(self) -> None:
        aa, bb = _check_coefficients(self.a, self.b, "ARMA")
        object.__setattr__(self, "a", tuple(float(v) for v in aa))
        object.__setattr__(self, "b", tuple(float(v) for v in bb))

    @property
    def order(self) -> tuple[int, int]:
        """``(p, q)``: the AR order and the MA order."""
        return len(self.a), len(self.b) - 1

    @property
    def denominator(self) -> F64:
        """``[1, -a1, ..., -ap]``, the ``scipy.signal.lfilter`` denominator."""
        out: F64 = np.r_[1.0, -np.asarray(self.a, dtype=np.float64)]
        return out

    @property
    def poles(self) -> NDArray[np.complex128]:
        """Roots of ``z**p - a1 z**(p-1) - … - ap``, shape (p,)."""
        if not self.a:
            return np.zeros(0, dtype=np.complex128)
        out: NDArray[np.complex128] = np.roots(self.denominator).astype(np.complex128)
        return out

    @property
    def dc_gain(self) -> float:
        """``sum_k lambda_k = sum b / (1 - sum a)`` (the steady-state gain)."""
        return float(np.sum(self.b) / (1.0 - np.sum(self.a)))

    def filter(self, w: ArrayLike) -> F64:
        """Output ``Y`` for the input ``W`` (zero initial conditions).

        Parameters
        ----------
        w : array_like, shape (n,)
            Input of the linear part.

        Returns
        -------
        ndarray, shape (n,)
        """
        from scipy.signal import lfilter

        arr = check_array(w, "w", "ARMA.filter", shape=(-1,))
        out: F64 = np.asarray(lfilter(np.asarray(self.b), self.denominator, arr), dtype=np.float64)
        return out

    def impulse_response(self, n: int) -> F64:
        """``lambda_0, ..., lambda_{n-1}``: the response to a unit impulse, shape (n,)."""
        delta = np.zeros(check_int(n, "n", "ARMA.impulse_response", minimum=1))
        delta[0] = 1.0
        return self.filter(delta)


EXAMPLE_ARMA: dict[str, ARMA] = {
    "order1": ARMA(a=(0.6,), b=(1.0, 0.0)),
    "order2": ARMA(a=(1.2, -0.5), b=(1.0, 0.4, 0.0)),
    "order3": ARMA(a=(0.9, -0.5, 0.2), b=(1.0, -0.3, 0.2, 0.0)),
    "resonant": ARMA(a=(1.6, -0.8), b=(0.5, 0.3, 0.0)),
}
"""A few stable ARMA systems (orders 1, 2, 3 and a lightly damped resonance, ``|pole| = 0.89``)."""


# --------------------------------------------------------------------------- simulation


def simulate_hammerstein(
    phi: Any,
    a: ArrayLike,
    b: ArrayLike,
    u: ArrayLike,
    noise_std: float = 0.0,
    rng: np.random.Generator | int | None = None,
) -> F64:
    """Output of the Hammerstein system ``phi`` -> ARMA(a, b) for the input ``u``.

    ``W_n = phi(u_n) + xi_n`` with ``xi_n ~ N(0, noise_std**2)`` i.i.d., then
    ``Y_n = a1 Y_{n-1} + ... + ap Y_{n-p} + b0 W_n + ... + bq W_{n-q}``
    from rest (zero initial conditions).

    Parameters
    ----------
    phi : callable
        Vectorised static nonlinearity: array of shape (n,) to array of shape (n,).
    a : array_like, shape (p,)
        AR coefficients ``(a1, ..., ap)``; must be stable (``ValueError`` otherwise).
    b : array_like, shape (q + 1,)
        MA coefficients ``(b0, ..., bq)``.
    u : array_like, shape (n,)
        Input sequence (units of ``phi``'s argument).
    noise_std : float
        Standard deviation of ``xi_n`` (units of ``phi``'s output), >= 0.
    rng : numpy.random.Generator or int, optional
        Source of the noise.

    Returns
    -------
    ndarray, shape (n,)
        The output ``Y``.

    Examples
    --------
    >>> simulate_hammerstein(Saturation(1.0), [0.5], [1.0], [2.0, 0.0, 0.0])
    array([1.  , 0.5 , 0.25])
    """
    owner = "simulate_hammerstein"
    if not callable(phi):
        raise InvalidTypeError(
            f"The 'phi' parameter of {owner} must be a callable. Got {type(phi).__name__} instead."
        )
    aa, bb = _check_coefficients(a, b, owner)
    ua = check_array(u, "u", owner, shape=(-1,))
    if ua.dtype.kind == "c":
        raise InvalidTypeError(f"The 'u' parameter of {owner} must be real. Got complex instead.")
    if ua.shape[0] == 0:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must hold at least 1 sample. Got 0 instead."
        )
    sigma = check_real(noise_std, "noise_std", owner, nonnegative=True)
    gen = check_rng(rng, owner)
    expected = f"an array of the input's shape {ua.shape}"
    w = callable_output(phi(ua), "phi", owner, ua.shape, expected)
    if sigma > 0.0:
        w = w + sigma * gen.standard_normal(ua.shape[0])
    from scipy.signal import lfilter

    out: F64 = np.asarray(lfilter(bb, np.r_[1.0, -aa], w), dtype=np.float64)
    return out
