"""Membership functions, linguistic variables and rules."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_real
from ..errors import InvalidTypeError, InvalidValueError

__all__ = [
    "Gaussian",
    "LeftShoulder",
    "MembershipFunction",
    "RightShoulder",
    "Rule",
    "Trapezoid",
    "Triangle",
    "Variable",
]

_TRAPEZOID = 0
_GAUSSIAN = 1
_INF = math.inf

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------- MFs


def _order_error(name: str, owner: str, relation: str, got: float) -> InvalidValueError:
    return InvalidValueError(
        f"The '{name}' parameter of {owner} must be {relation}. Got {got!r} instead."
    )


def _trapezoid_values(a: float, b: float, c: float, d: float, x: FloatArray) -> FloatArray:
    """Membership of the (possibly infinite-shouldered) trapezoid ``a <= b <= c <= d``."""
    out = np.zeros_like(x)
    out[(x >= b) & (x <= c)] = 1.0
    rising = (x > a) & (x < b)
    if np.any(rising):
        out[rising] = (x[rising] - a) / (b - a)
    falling = (x > c) & (x < d)
    if np.any(falling):
        out[falling] = (d - x[falling]) / (d - c)
    return out


class MembershipFunction:
    """Base of the membership functions: ``mf(x)`` maps an array to ``[0, 1]``."""

    #: ``True`` for piecewise-linear functions (exact integration applies).
    piecewise_linear: bool = True

    def __call__(self, x: ArrayLike) -> FloatArray:
        """Membership degree of ``x`` (any shape, same unit as the universe), same shape."""
        arr = np.asarray(x, dtype=float)
        return self._values(np.atleast_1d(arr).ravel()).reshape(arr.shape)

    def _values(self, x: FloatArray) -> FloatArray:
        return _trapezoid_values(*self.trapezoid(), x)

    def trapezoid(self) -> tuple[float, float, float, float]:
        """The equivalent trapezoid ``(a, b, c, d)`` (shoulders use ``±inf``)."""
        raise NotImplementedError

    def vertices(self) -> tuple[float, ...]:
        """Finite abscissae where the function may have a kink or a jump."""
        return tuple(v for v in self.trapezoid() if math.isfinite(v))

    def packed(self) -> tuple[int, tuple[float, float, float, float]]:
        """The function as the compiled evaluation stores it: a kind code (0 a
        trapezoid ``(a, b, c, d)``, 1 a Gaussian ``(mean, sigma, 0, 0)``) and four
        parameters (:meth:`flexarm.fuzzy.system.FuzzySystem.compiled`)."""
        return _TRAPEZOID, self.trapezoid()

    def _check_order(self, names: tuple[str, ...]) -> None:
        """Store the fields ``names`` as floats; more than two must not decrease, and
        the last must exceed the first (a support of positive width)."""
        owner = type(self).__name__
        for name in names:
            object.__setattr__(self, name, check_real(getattr(self, name), name, owner))
        if len(names) > 2:
            for prev, name in itertools.pairwise(names):
                if getattr(self, name) < getattr(self, prev):
                    raise _order_error(
                        name, owner, f">= {prev} = {getattr(self, prev)!r}", getattr(self, name)
                    )
        first, last = names[0], names[-1]
        if not getattr(self, last) > getattr(self, first):
            raise _order_error(
                last, owner, f"> {first} = {getattr(self, first)!r}", getattr(self, last)
            )


@dataclass(frozen=True, eq=False)
class Triangle(MembershipFunction):
    """Triangle rising from ``a`` to 1 at ``b`` and falling to 0 at ``c``.

    ``a <= b <= c`` and ``a < c``; ``a == b`` (or ``b == c``) gives a
    right (left) triangle that jumps to 1 at ``a`` (``c``).
    """

    a: float
    b: float
    c: float

    def __post_init__(self) -> None:
        self._check_order(("a", "b", "c"))

    def trapezoid(self) -> tuple[float, float, float, float]:
        return (self.a, self.b, self.b, self.c)


@dataclass(frozen=True, eq=False)
class Trapezoid(MembershipFunction):
    """Trapezoid: 0 up to ``a``, rising to 1 at ``b``, 1 up to ``c``, 0 from ``d``.

    ``a <= b <= c <= d`` and ``a < d``.
    """

    a: float
    b: float
    c: float
    d: float

    def __post_init__(self) -> None:
        self._check_order(("a", "b", "c", "d"))

    def trapezoid(self) -> tuple[float, float, float, float]:
        return (self.a, self.b, self.c, self.d)


@dataclass(frozen=True, eq=False)
class LeftShoulder(MembershipFunction):
    """1 up to ``b``, falling linearly to 0 at ``c`` (``b < c``), 0 beyond."""

    b: float
    c: float

    def __post_init__(self) -> None:
        self._check_order(("b", "c"))

    def trapezoid(self) -> tuple[float, float, float, float]:
        return (-_INF, -_INF, self.b, self.c)


@dataclass(frozen=True, eq=False)
class RightShoulder(MembershipFunction):
    """0 up to ``a``, rising linearly to 1 at ``b`` (``a < b``), 1 beyond."""

    a: float
    b: float

    def __post_init__(self) -> None:
        self._check_order(("a", "b"))

    def trapezoid(self) -> tuple[float, float, float, float]:
        return (self.a, self.b, _INF, _INF)


@dataclass(frozen=True, eq=False)
class Gaussian(MembershipFunction):
    """``exp(-(x - mean)**2 / (2 sigma**2))``, ``sigma > 0`` (not piecewise linear)."""

    mean: float
    sigma: float
    piecewise_linear = False

    def __post_init__(self) -> None:
        owner = "Gaussian"
        object.__setattr__(self, "mean", check_real(self.mean, "mean", owner))
        object.__setattr__(self, "sigma", check_real(self.sigma, "sigma", owner, positive=True))

    def _values(self, x: FloatArray) -> FloatArray:
        z = (x - self.mean) / self.sigma
        out: FloatArray = np.exp(-0.5 * z * z)
        return out

    def trapezoid(self) -> tuple[float, float, float, float]:
        raise InvalidTypeError("a Gaussian membership function is not piecewise linear")

    def vertices(self) -> tuple[float, ...]:
        return (self.mean,)

    def packed(self) -> tuple[int, tuple[float, float, float, float]]:
        return _GAUSSIAN, (self.mean, self.sigma, 0.0, 0.0)


# --------------------------------------------------------------- variables, rules


@dataclass(frozen=True, eq=False)
class Variable:
    """A linguistic variable: a name, a universe ``(lo, hi)`` and named terms.

    Parameters
    ----------
    name : str
        The variable's name.
    universe : tuple of float
        ``(lo, hi)`` with ``lo < hi``, in the variable's unit. Inputs are
        clipped to it; the output is defuzzified over it.
    terms : mapping of str to MembershipFunction
        The terms, in order (the order fixes the compiled term indices).
    """

    name: str
    universe: tuple[float, float]
    terms: Mapping[str, MembershipFunction] = field(repr=False)

    def __post_init__(self) -> None:
        owner = "Variable"
        if not isinstance(self.name, str):
            raise InvalidTypeError(
                f"The 'name' parameter of {owner} must be a str. Got {self.name!r}."
            )
        u = self.universe
        if not isinstance(u, Sequence) or isinstance(u, str) or len(u) != 2:
            raise InvalidTypeError(
                f"The 'universe' parameter of {owner} must be a pair (lo, hi). Got {u!r} instead."
            )
        lo = check_real(u[0], "universe", owner)
        hi = check_real(u[1], "universe", owner)
        if not hi > lo:
            raise _order_error("universe", owner, "(lo, hi) with lo < hi", (lo, hi))  # type: ignore[arg-type]
        object.__setattr__(self, "universe", (lo, hi))
        if not isinstance(self.terms, Mapping) or len(self.terms) == 0:
            raise InvalidTypeError(
                f"The 'terms' parameter of {owner} must be a non-empty mapping of names to "
                f"membership functions. Got {self.terms!r} instead."
            )
        for key, mf in self.terms.items():
            if not isinstance(key, str) or not isinstance(mf, MembershipFunction):
                raise InvalidTypeError(
                    f"The 'terms' parameter of {owner} must map str to MembershipFunction. "
                    f"Got {key!r}: {type(mf).__name__} instead."
                )
        object.__setattr__(self, "terms", dict(self.terms))

    @property
    def term_names(self) -> tuple[str, ...]:
        """The term names in order."""
        return tuple(self.terms)


@dataclass(frozen=True, eq=False)
class Rule:
    """``IF input_0 IS antecedent[0] AND … THEN output IS consequent``.

    ``antecedent`` holds one term name per input, or ``None`` for "don't care".
    """

    antecedent: tuple[str | None, ...]
    consequent: str

    def __post_init__(self) -> None:
        owner = "Rule"
        ante: Any = self.antecedent
        if isinstance(ante, str) or not isinstance(ante, Sequence):
            raise InvalidTypeError(
                f"The 'antecedent' parameter of {owner} must be a sequence of term names. "
                f"Got {ante!r} instead."
            )
        if not all(a is None or isinstance(a, str) for a in ante):
            raise InvalidTypeError(
                f"The 'antecedent' parameter of {owner} must hold str or None. "
                f"Got {ante!r} instead."
            )
        object.__setattr__(self, "antecedent", tuple(ante))
        if not isinstance(self.consequent, str):
            raise InvalidTypeError(
                f"The 'consequent' parameter of {owner} must be a str. "
                f"Got {self.consequent!r} instead."
            )
