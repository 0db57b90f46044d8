r"""Mamdani fuzzy inference with exact defuzzification, and the paper's adaptive law.

A :class:`FuzzySystem` maps crisp inputs to one crisp output in four steps:

1. *Fuzzification*: each input is clipped to its universe and every term's
   membership function is evaluated at it.
2. *Rule firing*: a :class:`Rule`'s strength is the AND (``"min"`` or
   ``"product"``) of the memberships named in its antecedent (``None`` means
   "don't care").
3. *Implication and aggregation*: each rule's consequent set is cut
   (``"min"``) or scaled (``"product"``) by the rule's strength; the implied
   sets are combined by ``"max"`` or ``"bounded-sum"`` (``min(1, sum)``).
4. *Defuzzification* on the output universe ``[lo, hi]``: ``"centroid"``
   (``∫xμ / ∫μ``), ``"bisector"`` (the ``x`` that halves ``∫μ``; the first such
   ``x`` when a gap of zero membership straddles the half) or
   ``"mean-of-maxima"`` (the mean of the set where ``μ`` is largest: the
   length-weighted mean of its plateaus, or the mean of its isolated maximisers
   when it has no plateau).

Exact integration
-----------------
With piecewise-linear output sets (:class:`Triangle`, :class:`Trapezoid`,
:class:`LeftShoulder`, :class:`RightShoulder`) every implied set is piecewise
linear with breakpoints at the set's vertices and (min implication) where the
set crosses the cut level. Their aggregate is linear between consecutive points
of the union of these breakpoints and of the pairwise crossings of the implied
sets (max) or of the sum with 1 (bounded sum). All those points are computed,
the aggregate is evaluated at each piece's ends (as one-sided limits, so jumps
such as a triangle with ``a == b`` are handled), and ``∫μ`` and ``∫xμ`` are
summed exactly piece by piece: over ``[a, b]`` with end values ``μa, μb``,
``∫μ = (b-a)(μa+μb)/2`` and ``∫xμ = (b-a)/6 (a(2μa+μb) + b(μa+2μb))``. The
bisector solves the quadratic of the cumulative area inside the piece where it
crosses one half; the mean of maxima reads the plateaus off the pieces. No
universe is discretised.

If any output set is a :class:`Gaussian` the aggregate is not piecewise linear;
``"centroid"`` and ``"bisector"`` then fall back to adaptive quadrature
(:func:`scipy.integrate.quad`, absolute tolerance 1e-12, relative 1e-10, with
the breakpoints above as hints) and ``"mean-of-maxima"`` is refused at
construction.

When no rule fires (all strengths zero, so the aggregate vanishes) the output
is the ``default`` given at construction, NaN unless stated. Non-finite inputs
give NaN.

Compiled evaluation
-------------------
:meth:`FuzzySystem.compiled` packs a system into a :class:`CompiledFuzzySystem`
(a NamedTuple of plain arrays) for the Numba-compiled :func:`evaluate` (one
input vector) and :func:`evaluate_many` (rows of inputs), meant for the
simulation loop. The compiled path supports every input membership function,
every AND/implication/aggregation operator, piecewise-linear output sets and
the centroid only; :meth:`FuzzySystem.compiled` raises otherwise. The
pure-NumPy path of :meth:`FuzzySystem.__call__` stays the reference.

The paper's system
------------------
:func:`paper_system` builds the adaptive law of the paper (spec §4): inputs
``delta1``, ``delta2`` (link deformations, m) on ``[-5, 5]`` with terms
``N = LeftShoulder(-5, 0)``, ``ZERO = Triangle(-5, 0, 5)``,
``P = RightShoulder(0, 5)``; output ``lambda`` on ``[0, 1]`` with
``ZERO = Triangle(0, 0, 0.5)``, ``PM = Triangle(0, 0.5, 1)``,
``PMAX = Triangle(0.5, 1, 1)`` (peaks at 0, 0.5 and 1 as the paper's figure
suggests; the supports, half-width 0.5, are our decision); MIN, MIN, MAX,
centroid; the rule table

========  ====  ====  ====
δ1 \ δ2    N     ZERO  P
========  ====  ====  ====
N         PMAX  PM    PMAX
ZERO      PM    ZERO  PM
P         PMAX  PM    PMAX
========  ====  ====  ====

>>> fls = paper_system()
>>> round(float(fls(0.0, 0.0)), 12)
0.166666666667
>>> fls([0.0, 5.0], [0.0, 5.0]).shape
(2,)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._validation import check_int, check_option, check_real, check_sequence_of

__all__ = [
    "AGGREGATIONS",
    "AND_OPERATORS",
    "DEFUZZIFIERS",
    "IMPLICATIONS",
    "CompiledFuzzySystem",
    "FuzzySystem",
    "Gaussian",
    "LeftShoulder",
    "MembershipFunction",
    "RightShoulder",
    "Rule",
    "Trapezoid",
    "Triangle",
    "Variable",
    "evaluate",
    "evaluate_into",
    "evaluate_many",
    "paper_system",
    "plot_surface",
    "workspace_size",
]

AND_OPERATORS = ("min", "product")
IMPLICATIONS = ("min", "product")
AGGREGATIONS = ("max", "bounded-sum")
DEFUZZIFIERS = ("centroid", "bisector", "mean-of-maxima")

_TRAPEZOID = 0
_GAUSSIAN = 1
_INF = math.inf
_QUAD_OPTIONS: dict[str, Any] = {"epsabs": 1e-12, "epsrel": 1e-10, "limit": 200}

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------- MFs


def _order_error(name: str, owner: str, relation: str, got: float) -> ValueError:
    return ValueError(f"The '{name}' parameter of {owner} must be {relation}. Got {got!r} instead.")


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

    def _packed(self) -> tuple[int, tuple[float, float, float, float]]:
        return _TRAPEZOID, self.trapezoid()


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
        owner = "Triangle"
        for name in ("a", "b", "c"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, owner))
        if self.b < self.a:
            raise _order_error("b", owner, f">= a = {self.a!r}", self.b)
        if self.c < self.b:
            raise _order_error("c", owner, f">= b = {self.b!r}", self.c)
        if not self.c > self.a:
            raise _order_error("c", owner, f"> a = {self.a!r}", self.c)

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
        owner = "Trapezoid"
        for name in ("a", "b", "c", "d"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, owner))
        for prev, name in (("a", "b"), ("b", "c"), ("c", "d")):
            if getattr(self, name) < getattr(self, prev):
                raise _order_error(
                    name, owner, f">= {prev} = {getattr(self, prev)!r}", getattr(self, name)
                )
        if not self.d > self.a:
            raise _order_error("d", owner, f"> a = {self.a!r}", self.d)

    def trapezoid(self) -> tuple[float, float, float, float]:
        return (self.a, self.b, self.c, self.d)


@dataclass(frozen=True, eq=False)
class LeftShoulder(MembershipFunction):
    """1 up to ``b``, falling linearly to 0 at ``c`` (``b < c``), 0 beyond."""

    b: float
    c: float

    def __post_init__(self) -> None:
        owner = "LeftShoulder"
        for name in ("b", "c"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, owner))
        if not self.c > self.b:
            raise _order_error("c", owner, f"> b = {self.b!r}", self.c)

    def trapezoid(self) -> tuple[float, float, float, float]:
        return (-_INF, -_INF, self.b, self.c)


@dataclass(frozen=True, eq=False)
class RightShoulder(MembershipFunction):
    """0 up to ``a``, rising linearly to 1 at ``b`` (``a < b``), 1 beyond."""

    a: float
    b: float

    def __post_init__(self) -> None:
        owner = "RightShoulder"
        for name in ("a", "b"):
            object.__setattr__(self, name, check_real(getattr(self, name), name, owner))
        if not self.b > self.a:
            raise _order_error("b", owner, f"> a = {self.a!r}", self.b)

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
        raise TypeError("a Gaussian membership function is not piecewise linear")

    def vertices(self) -> tuple[float, ...]:
        return (self.mean,)

    def _packed(self) -> tuple[int, tuple[float, float, float, float]]:
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
            raise TypeError(f"The 'name' parameter of {owner} must be a str. Got {self.name!r}.")
        u = self.universe
        if not isinstance(u, Sequence) or isinstance(u, str) or len(u) != 2:
            raise TypeError(
                f"The 'universe' parameter of {owner} must be a pair (lo, hi). Got {u!r} instead."
            )
        lo = check_real(u[0], "universe", owner)
        hi = check_real(u[1], "universe", owner)
        if not hi > lo:
            raise _order_error("universe", owner, "(lo, hi) with lo < hi", (lo, hi))  # type: ignore[arg-type]
        object.__setattr__(self, "universe", (lo, hi))
        if not isinstance(self.terms, Mapping) or len(self.terms) == 0:
            raise TypeError(
                f"The 'terms' parameter of {owner} must be a non-empty mapping of names to "
                f"membership functions. Got {self.terms!r} instead."
            )
        for key, mf in self.terms.items():
            if not isinstance(key, str) or not isinstance(mf, MembershipFunction):
                raise TypeError(
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
    """``IF input_0 IS antecedent[0] AND ... THEN output IS consequent``.

    ``antecedent`` holds one term name per input, or ``None`` for "don't care".
    """

    antecedent: tuple[str | None, ...]
    consequent: str

    def __post_init__(self) -> None:
        owner = "Rule"
        ante: Any = self.antecedent
        if isinstance(ante, str) or not isinstance(ante, Sequence):
            raise TypeError(
                f"The 'antecedent' parameter of {owner} must be a sequence of term names. "
                f"Got {ante!r} instead."
            )
        if not all(a is None or isinstance(a, str) for a in ante):
            raise TypeError(
                f"The 'antecedent' parameter of {owner} must hold str or None. "
                f"Got {ante!r} instead."
            )
        object.__setattr__(self, "antecedent", tuple(ante))
        if not isinstance(self.consequent, str):
            raise TypeError(
                f"The 'consequent' parameter of {owner} must be a str. "
                f"Got {self.consequent!r} instead."
            )


class CompiledFuzzySystem(NamedTuple):
    """A :class:`FuzzySystem` as plain arrays for :func:`evaluate`."""

    term_type: NDArray[np.int64]  # (T,) 0 trapezoid (a, b, c, d), 1 Gaussian (mean, sigma)
    term_par: FloatArray  # (T, 4)
    term_input: NDArray[np.int64]  # (T,) input index of each term
    input_bounds: FloatArray  # (n_in, 2) input universes
    rule_ante: NDArray[np.int64]  # (R, n_in) global term index, -1 for "don't care"
    rule_cons: NDArray[np.int64]  # (R,) output term index
    out_par: FloatArray  # (K, 4) output trapezoids (a, b, c, d)
    ops: NDArray[np.int64]  # (3,) AND (0 min, 1 product), implication, aggregation (0 max)
    out_range: FloatArray  # (3,) lo, hi, default


# ------------------------------------------------------------------- the system


@dataclass(frozen=True, eq=False)
class FuzzySystem:
    """A Mamdani fuzzy system with one crisp output.

    Parameters
    ----------
    inputs : sequence of Variable
        The input variables, in call order.
    output : Variable
        The output variable.
    rules : sequence of Rule
        Each rule names one term of each input (or ``None``) and one output term.
    and_op : {"min", "product"}
        The AND of the antecedents.
    implication : {"min", "product"}
        Cut or scale the consequent set by the firing strength.
    aggregation : {"max", "bounded-sum"}
        Combine the implied sets (bounded sum: ``min(1, sum)``).
    defuzzifier : {"centroid", "bisector", "mean-of-maxima"}
        See the module docstring.
    default : float
        The output when no rule fires (NaN allowed, the default).
    """

    inputs: tuple[Variable, ...]
    output: Variable
    rules: tuple[Rule, ...]
    and_op: str = "min"
    implication: str = "min"
    aggregation: str = "max"
    defuzzifier: str = "centroid"
    default: float = math.nan

    def __post_init__(self) -> None:
        owner = "FuzzySystem"
        inputs = check_sequence_of(self.inputs, "inputs", owner, Variable, "Variable")
        if not inputs:
            raise ValueError(f"The 'inputs' parameter of {owner} must be non-empty. Got ().")
        object.__setattr__(self, "inputs", inputs)
        if not isinstance(self.output, Variable):
            raise TypeError(
                f"The 'output' parameter of {owner} must be a Variable. "
                f"Got {type(self.output).__name__} instead."
            )
        rules = check_sequence_of(self.rules, "rules", owner, Rule, "Rule")
        if not rules:
            raise ValueError(f"The 'rules' parameter of {owner} must be non-empty. Got ().")
        for k, rule in enumerate(rules):
            if len(rule.antecedent) != len(inputs):
                raise ValueError(
                    f"The 'rules' parameter of {owner} must hold rules with one antecedent "
                    f"per input ({len(inputs)}). Got {len(rule.antecedent)} at position {k}."
                )
            for var, term in zip(inputs, rule.antecedent, strict=True):
                if term is not None and term not in var.terms:
                    raise ValueError(
                        f"The 'rules' parameter of {owner} must name terms of {var.name!r} "
                        f"{var.term_names}. Got {term!r} at position {k} instead."
                    )
            if rule.consequent not in self.output.terms:
                raise ValueError(
                    f"The 'rules' parameter of {owner} must name terms of the output "
                    f"{self.output.term_names}. Got {rule.consequent!r} at position {k} instead."
                )
        object.__setattr__(self, "rules", rules)
        check_option(self.and_op, "and_op", owner, AND_OPERATORS)
        check_option(self.implication, "implication", owner, IMPLICATIONS)
        check_option(self.aggregation, "aggregation", owner, AGGREGATIONS)
        check_option(self.defuzzifier, "defuzzifier", owner, DEFUZZIFIERS)
        if self.defuzzifier == "mean-of-maxima" and not self.piecewise_linear:
            raise ValueError(
                f"The 'defuzzifier' parameter of {owner} must be 'centroid' or 'bisector' "
                "with non-piecewise-linear output sets. Got 'mean-of-maxima' instead."
            )
        if isinstance(self.default, bool) or not isinstance(self.default, (int, float)):
            raise TypeError(
                f"The 'default' parameter of {owner} must be a real number (or NaN). "
                f"Got {self.default!r} instead."
            )
        object.__setattr__(self, "default", float(self.default))

    @property
    def piecewise_linear(self) -> bool:
        """Whether every output set is piecewise linear (exact integration)."""
        return all(mf.piecewise_linear for mf in self.output.terms.values())

    # ------------------------------------------------------------------ firing

    def firing_strengths(self, *inputs: ArrayLike) -> FloatArray:
        """Rule strengths, shape ``broadcast(inputs).shape + (n_rules,)``."""
        xs = self._check_inputs(inputs, "firing_strengths")
        return self._strengths(xs)

    def _check_inputs(self, inputs: tuple[ArrayLike, ...], method: str) -> list[FloatArray]:
        if len(inputs) != len(self.inputs):
            raise ValueError(
                f"The 'inputs' parameter of FuzzySystem.{method} must be {len(self.inputs)} "
                f"arrays, one per input variable. Got {len(inputs)} instead."
            )
        arrays = [np.asarray(x, dtype=float) for x in inputs]
        try:
            return list(np.broadcast_arrays(*arrays))
        except ValueError as exc:
            shapes = [a.shape for a in arrays]
            raise ValueError(
                f"The 'inputs' parameter of FuzzySystem.{method} must be broadcastable arrays. "
                f"Got shapes {shapes} instead."
            ) from exc

    def _strengths(self, xs: list[FloatArray]) -> FloatArray:
        shape = xs[0].shape
        memberships = []
        for var, x in zip(self.inputs, xs, strict=True):
            lo, hi = var.universe
            xc = np.clip(np.nan_to_num(x.ravel(), nan=lo), lo, hi)
            memberships.append({name: mf(xc) for name, mf in var.terms.items()})
        n = int(np.prod(shape))
        w = np.ones((n, len(self.rules)))
        for r, rule in enumerate(self.rules):
            for j, term in enumerate(rule.antecedent):
                if term is None:
                    continue
                mu = memberships[j][term]
                w[:, r] = np.minimum(w[:, r], mu) if self.and_op == "min" else w[:, r] * mu
        return w.reshape((*shape, len(self.rules)))

    # ------------------------------------------------------------------- call

    def __call__(self, *inputs: ArrayLike) -> FloatArray:
        """The crisp output for crisp inputs.

        Parameters
        ----------
        *inputs : array_like
            One array per input variable (in its unit), broadcast together.

        Returns
        -------
        ndarray
            The output, shape ``broadcast(inputs).shape`` (0-d for scalars).
        """
        xs = self._check_inputs(inputs, "__call__")
        shape = xs[0].shape
        w = self._strengths(xs).reshape(-1, len(self.rules))
        finite = np.all([np.isfinite(x.ravel()) for x in xs], axis=0)
        out = np.full(w.shape[0], np.nan)
        cache: dict[bytes, float] = {}
        for i in range(w.shape[0]):
            if not finite[i]:
                continue
            key = w[i].tobytes()
            if key not in cache:
                cache[key] = self._defuzzify(w[i])
            out[i] = cache[key]
        return out.reshape(shape)

    def _implied_sets(self, w: FloatArray) -> tuple[list[MembershipFunction], FloatArray]:
        terms = list(self.output.terms.values())
        names = self.output.term_names
        cons = np.array([names.index(r.consequent) for r in self.rules])
        if self.aggregation == "max":
            # max_r imp(w_r, mu_k) = imp(max_r w_r, mu_k): merge rules per consequent.
            levels = np.zeros(len(terms))
            np.maximum.at(levels, cons, w)
            keep = np.flatnonzero(levels > 0.0)
            return [terms[k] for k in keep], levels[keep]
        keep = np.flatnonzero(w > 0.0)
        return [terms[cons[r]] for r in keep], w[keep]

    def _aggregate_fn(
        self, sets: list[MembershipFunction], levels: FloatArray
    ) -> tuple[Callable[[FloatArray], FloatArray], Callable[[FloatArray], FloatArray]]:
        """``(implied, aggregate)``: the implied sets' values (M, n) and their aggregate (n,)."""

        def implied(x: FloatArray) -> FloatArray:
            mu = np.array([mf(x) for mf in sets])
            out: FloatArray
            if self.implication == "min":
                out = np.minimum(mu, levels[:, None])
            else:
                out = mu * levels[:, None]
            return out

        def aggregate(x: FloatArray) -> FloatArray:
            vals = implied(x)
            if self.aggregation == "max":
                out: FloatArray = vals.max(axis=0)
            else:
                out = np.minimum(1.0, vals.sum(axis=0))
            return out

        return implied, aggregate

    def _defuzzify(self, w: FloatArray) -> float:
        sets, levels = self._implied_sets(w)
        if not sets:
            return self.default
        lo, hi = self.output.universe
        if not self.piecewise_linear:
            return self._defuzzify_quad(sets, levels)
        implied, aggregate = self._aggregate_fn(sets, levels)
        # Breakpoints of each implied set.
        cand = [lo, hi]
        for mf, lev in zip(sets, levels, strict=True):
            cand.extend(mf.vertices())
            a, b, c, d = mf.trapezoid()
            if self.implication == "min" and lev < 1.0:
                if a < b and math.isfinite(a):
                    cand.append(a + lev * (b - a))
                if c < d and math.isfinite(d):
                    cand.append(d - lev * (d - c))
        p = np.unique(np.clip(cand, lo, hi))
        left, right = _piece_ends(implied, p)  # (M, I)
        h = np.diff(p)
        if self.aggregation == "max":
            dl = left[:, None, :] - left[None, :, :]
            dr = right[:, None, :] - right[None, :, :]
        else:
            dl = left.sum(axis=0)[None, None, :] - 1.0
            dr = right.sum(axis=0)[None, None, :] - 1.0
        cross = dl * dr < 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = p[:-1] + h * dl / (dl - dr)
        p = np.unique(np.clip(np.concatenate([p, xc[cross]]), lo, hi))
        mu_l, mu_r = _piece_ends(lambda x: aggregate(x)[None, :], p)
        return _pl_defuzzify(self.defuzzifier, p, mu_l[0], mu_r[0], self.default)

    def _defuzzify_quad(self, sets: list[MembershipFunction], levels: FloatArray) -> float:
        from scipy.integrate import quad

        lo, hi = self.output.universe
        _, aggregate = self._aggregate_fn(sets, levels)
        points = sorted({min(max(v, lo), hi) for mf in sets for v in mf.vertices()})

        def f(x: float) -> float:
            return float(aggregate(np.array([x]))[0])

        area = quad(f, lo, hi, points=points, **_QUAD_OPTIONS)[0]
        if not area > 0.0:
            return self.default
        if self.defuzzifier == "centroid":
            moment = quad(lambda x: x * f(x), lo, hi, points=points, **_QUAD_OPTIONS)[0]
            return float(moment / area)
        from scipy.optimize import brentq

        def excess(x: float) -> float:
            inner = [q for q in points if lo < q < x]
            return float(quad(f, lo, x, points=inner or None, **_QUAD_OPTIONS)[0] - area / 2)

        return float(brentq(excess, lo, hi, xtol=1e-13, rtol=1e-13))

    # --------------------------------------------------------------- compiled

    def compiled(self) -> CompiledFuzzySystem:
        """The system as plain arrays for :func:`evaluate` / :func:`evaluate_many`.

        Raises
        ------
        ValueError
            If the defuzzifier is not the centroid or an output set is not
            piecewise linear (the compiled path supports only those).
        """
        owner = "FuzzySystem.compiled"
        if self.defuzzifier != "centroid":
            raise ValueError(
                f"The 'defuzzifier' parameter of {owner} must be 'centroid'. "
                f"Got {self.defuzzifier!r} instead."
            )
        if not self.piecewise_linear:
            raise ValueError(
                f"The 'output' parameter of {owner} must have piecewise-linear sets. "
                "Got a Gaussian instead."
            )
        types: list[int] = []
        pars: list[tuple[float, ...]] = []
        owners: list[int] = []
        offsets: list[int] = []
        for j, var in enumerate(self.inputs):
            offsets.append(len(types))
            for mf in var.terms.values():
                code, par = mf._packed()
                types.append(code)
                pars.append(par)
                owners.append(j)
        ante = np.full((len(self.rules), len(self.inputs)), -1, dtype=np.int64)
        names = self.output.term_names
        for r, rule in enumerate(self.rules):
            for j, term in enumerate(rule.antecedent):
                if term is not None:
                    ante[r, j] = offsets[j] + self.inputs[j].term_names.index(term)
        return CompiledFuzzySystem(
            term_type=np.array(types, dtype=np.int64),
            term_par=np.array(pars, dtype=float),
            term_input=np.array(owners, dtype=np.int64),
            input_bounds=np.array([v.universe for v in self.inputs], dtype=float),
            rule_ante=ante,
            rule_cons=np.array([names.index(r.consequent) for r in self.rules], dtype=np.int64),
            out_par=np.array([mf.trapezoid() for mf in self.output.terms.values()], dtype=float),
            ops=np.array(
                [
                    AND_OPERATORS.index(self.and_op),
                    IMPLICATIONS.index(self.implication),
                    AGGREGATIONS.index(self.aggregation),
                ],
                dtype=np.int64,
            ),
            out_range=np.array([*self.output.universe, self.default], dtype=float),
        )


def _piece_ends(
    f: Callable[[FloatArray], FloatArray], p: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """One-sided end values of a function linear on each ``[p_i, p_{i+1}]``.

    Evaluated at the thirds of each piece and extrapolated, so jumps at the
    breakpoints are seen from the correct side.
    """
    h = np.diff(p)
    f1 = f(p[:-1] + h / 3.0)
    f2 = f(p[:-1] + 2.0 * h / 3.0)
    return 2.0 * f1 - f2, 2.0 * f2 - f1


def _pl_defuzzify(
    kind: str, p: FloatArray, mu_l: FloatArray, mu_r: FloatArray, default: float
) -> float:
    """Exact defuzzification of a piecewise-linear membership (end values per piece)."""
    mu_l = np.maximum(mu_l, 0.0)
    mu_r = np.maximum(mu_r, 0.0)
    a, b = p[:-1], p[1:]
    h = b - a
    areas = h * (mu_l + mu_r) / 2.0
    area = float(areas.sum())
    if not area > 0.0:
        return default
    if kind == "centroid":
        moment = float(np.sum(h / 6.0 * (a * (2 * mu_l + mu_r) + b * (mu_l + 2 * mu_r))))
        return moment / area
    if kind == "bisector":
        cum = np.concatenate([[0.0], np.cumsum(areas)])
        half = area / 2.0
        i = int(np.clip(np.searchsorted(cum, half, side="left") - 1, 0, len(h) - 1))
        target = half - cum[i]
        slope = (mu_r[i] - mu_l[i]) / h[i]
        root = math.sqrt(max(mu_l[i] ** 2 + 2.0 * slope * target, 0.0))
        denom = mu_l[i] + root
        t = 2.0 * target / denom if denom > 0.0 else 0.0
        return float(a[i] + min(max(t, 0.0), h[i]))
    # mean of maxima
    top = max(float(mu_l.max()), float(mu_r.max()))
    tol = 1e-12 * max(top, 1.0)
    plateau = (mu_l >= top - tol) & (mu_r >= top - tol)
    if np.any(plateau):
        lengths = h[plateau]
        mids = (a[plateau] + b[plateau]) / 2.0
        return float(np.sum(lengths * mids) / np.sum(lengths))
    xs = np.unique(np.concatenate([a[mu_l >= top - tol], b[mu_r >= top - tol]]))
    return float(xs.mean())


# ------------------------------------------------------------ compiled kernels


@nb.njit(cache=True, nogil=True)
def _trap1(a: float, b: float, c: float, d: float, x: float) -> float:
    if x >= b and x <= c:
        return 1.0
    if x <= a or x >= d:
        return 0.0
    if x < b:
        return (x - a) / (b - a)
    return (d - x) / (d - c)


@nb.njit(cache=True, nogil=True)
def _imp1(sp: Any, sw: Any, i: int, imp: int, x: float) -> float:
    mu = _trap1(sp[i, 0], sp[i, 1], sp[i, 2], sp[i, 3], x)
    v: float = min(mu, sw[i]) if imp == 0 else mu * sw[i]
    return v


@nb.njit(cache=True, nogil=True)
def _linear_aggregate(left: Any, right: Any, m: int, agg: int, u: float) -> float:
    """Max (agg 0) or bounded sum (agg 1) of ``m`` linear functions at ``u`` in [0, 1]."""
    acc = 0.0
    for i in range(m):
        v = left[i] + u * (right[i] - left[i])
        if agg == 0:
            acc = max(acc, v)
        else:
            acc += v
    return acc if agg == 0 else min(acc, 1.0)


@nb.njit(cache=True, nogil=True)
def _insertion_sort(v: Any, start: int, stop: int) -> None:
    """Sort ``v[:stop]`` in place, given ``v[:start]`` already sorted."""
    for i in range(max(start, 1), stop):
        key = v[i]
        k = i - 1
        while k >= 0 and v[k] > key:
            v[k + 1] = v[k]
            k -= 1
        v[k + 1] = key


@nb.njit(cache=True, nogil=True)
def workspace_size(system: CompiledFuzzySystem) -> int:
    """Length of the scratch buffer :func:`evaluate_into` needs for ``system``."""
    n_terms = system.term_type.shape[0]
    n_rules = system.rule_ante.shape[0]
    n_out = system.out_par.shape[0]
    cap = n_rules if system.ops[2] == 1 else n_out
    n1 = 2 + 6 * cap  # breakpoints of the implied sets
    n_cross = cap * (cap - 1) // 2 if system.ops[2] == 0 else 1  # crossings on one piece
    return int(n_terms + 7 * cap + n1 + n_cross + 2)


@nb.njit(cache=True, nogil=True)
def evaluate(system: CompiledFuzzySystem, x: FloatArray) -> float:
    """Compiled centroid output of a packed system at one input vector.

    Parameters
    ----------
    system : CompiledFuzzySystem
        From :meth:`FuzzySystem.compiled`.
    x : ndarray, shape (n_in,)
        The inputs, each in its variable's unit.

    Returns
    -------
    float
        Equal (to rounding) to :meth:`FuzzySystem.__call__` at ``x``; the
        system's default when no rule fires, NaN for non-finite inputs.
        Allocates its scratch; inside a loop prefer :func:`evaluate_into`.
    """
    return evaluate_into(system, x, np.empty(workspace_size(system)))


@nb.njit(cache=True, nogil=True)
def evaluate_into(system: CompiledFuzzySystem, x: FloatArray, buf: FloatArray) -> float:
    """:func:`evaluate` with caller-owned scratch ``buf`` of length
    :func:`workspace_size` (allocation-free: what a simulation loop calls)."""
    and_op = system.ops[0]
    imp = system.ops[1]
    agg = system.ops[2]
    lo = system.out_range[0]
    hi = system.out_range[1]
    default: float = system.out_range[2]
    n_in = system.rule_ante.shape[1]
    for j in range(n_in):
        if not np.isfinite(x[j]):
            return np.nan
    n_terms = system.term_type.shape[0]
    n_rules = system.rule_ante.shape[0]
    n_out = system.out_par.shape[0]
    cap = n_rules if agg == 1 else n_out
    # One workspace: input memberships, implied sets (params, levels), breakpoints.
    mu_in = buf[:n_terms]
    sp = buf[n_terms : n_terms + 4 * cap].reshape((cap, 4))
    sw = buf[n_terms + 4 * cap : n_terms + 5 * cap]
    v1 = buf[n_terms + 5 * cap : n_terms + 6 * cap]
    v2 = buf[n_terms + 6 * cap : n_terms + 7 * cap]
    pts = buf[n_terms + 7 * cap :]
    for t in range(n_terms):
        j = system.term_input[t]
        xj = min(max(x[j], system.input_bounds[j, 0]), system.input_bounds[j, 1])
        pa = system.term_par[t]
        if system.term_type[t] == 0:
            mu_in[t] = _trap1(pa[0], pa[1], pa[2], pa[3], xj)
        else:
            z = (xj - pa[0]) / pa[1]
            mu_in[t] = math.exp(-0.5 * z * z)
    if agg == 0:
        for k in range(n_out):
            sw[k] = 0.0
    m = 0
    for r in range(n_rules):
        s = 1.0
        for j in range(n_in):
            t = system.rule_ante[r, j]
            if t >= 0:
                s = min(s, mu_in[t]) if and_op == 0 else s * mu_in[t]
        if agg == 0:
            k = system.rule_cons[r]
            sw[k] = max(sw[k], s)
        elif s > 0.0:
            sp[m, :] = system.out_par[system.rule_cons[r]]
            sw[m] = s
            m += 1
    if agg == 0:
        for k in range(n_out):
            if sw[k] > 0.0:
                sp[m, :] = system.out_par[k]
                sw[m] = sw[k]
                m += 1
    if m == 0:
        return default
    # Breakpoints of the implied sets.
    pts[0] = lo
    pts[1] = hi
    n = 2
    for i in range(m):
        for q in range(4):
            v = sp[i, q]
            if q > 0 and v == sp[i, q - 1]:
                continue
            if np.isfinite(v) and v > lo and v < hi:
                pts[n] = v
                n += 1
        if imp == 0 and sw[i] < 1.0:
            a, b, c, d = sp[i, 0], sp[i, 1], sp[i, 2], sp[i, 3]
            if a < b and np.isfinite(a):
                pts[n] = min(max(a + sw[i] * (b - a), lo), hi)
                n += 1
            if c < d and np.isfinite(d):
                pts[n] = min(max(d - sw[i] * (d - c), lo), hi)
                n += 1
    _insertion_sort(pts, 0, n)
    # On each piece between breakpoints every implied set is linear, so the
    # aggregate is the max (or the bounded sum) of linear functions: linear
    # between the crossings of any two of them (max) or of the sum with 1
    # (bounded sum). Integrate it exactly, piece by piece, from the end values.
    us = pts[n:]
    area = 0.0
    moment = 0.0
    for s in range(n - 1):
        p0 = pts[s]
        h = pts[s + 1] - p0
        if h <= 0.0:
            continue
        x1 = p0 + h / 3.0
        x2 = p0 + 2.0 * h / 3.0
        for i in range(m):  # end values of set i on this piece (extrapolated from thirds)
            f1 = _imp1(sp, sw, i, imp, x1)
            f2 = _imp1(sp, sw, i, imp, x2)
            v1[i] = 2.0 * f1 - f2
            v2[i] = 2.0 * f2 - f1
        us[0] = 0.0
        k_u = 1
        if agg == 0:
            for i in range(m):
                for k in range(i + 1, m):
                    dl = v1[i] - v1[k]
                    dr = v2[i] - v2[k]
                    if dl * dr < 0.0:
                        us[k_u] = dl / (dl - dr)
                        k_u += 1
        else:
            sl = -1.0
            sr = -1.0
            for i in range(m):
                sl += v1[i]
                sr += v2[i]
            if sl * sr < 0.0:
                us[k_u] = sl / (sl - sr)
                k_u += 1
        us[k_u] = 1.0
        k_u += 1
        _insertion_sort(us, 1, k_u - 1)
        f_prev = _linear_aggregate(v1, v2, m, agg, 0.0)
        for q in range(1, k_u):
            u0 = us[q - 1]
            u1 = us[q]
            f_next = _linear_aggregate(v1, v2, m, agg, u1)
            if u1 > u0:
                a = p0 + h * u0
                b = p0 + h * u1
                w = b - a
                ml = max(f_prev, 0.0)
                mr = max(f_next, 0.0)
                area += w * (ml + mr) / 2.0
                moment += w / 6.0 * (a * (2.0 * ml + mr) + b * (ml + 2.0 * mr))
            f_prev = f_next
    if not area > 0.0:
        return default
    return moment / area


@nb.njit(cache=True, nogil=True)
def evaluate_many(system: CompiledFuzzySystem, x: FloatArray) -> FloatArray:
    """:func:`evaluate` on each row of ``x`` (n, n_in); returns (n,)."""
    out = np.empty(x.shape[0])
    buf = np.empty(workspace_size(system))
    for i in range(x.shape[0]):
        out[i] = evaluate_into(system, x[i], buf)
    return out


# -------------------------------------------------------------- the paper system


def paper_system(defuzzifier: str = "centroid") -> FuzzySystem:
    """The paper's fuzzy adaptive law ``lambda(delta1, delta2)`` (module docstring).

    The inputs are the link deformations in m, the output ``lambda`` in
    ``[0, 1]`` is dimensionless. No rule-free region exists (every input pair
    fires at least one rule), so the default (NaN) is never returned for
    finite inputs.

    Parameters
    ----------
    defuzzifier : {"centroid", "bisector", "mean-of-maxima"}
        The paper uses the centroid.
    """
    check_option(defuzzifier, "defuzzifier", "paper_system", DEFUZZIFIERS)
    deltas = [
        Variable(
            name,
            (-5.0, 5.0),  # m
            {
                "N": LeftShoulder(-5.0, 0.0),
                "ZERO": Triangle(-5.0, 0.0, 5.0),
                "P": RightShoulder(0.0, 5.0),
            },
        )
        for name in ("delta1", "delta2")
    ]
    lam = Variable(
        "lambda",
        (0.0, 1.0),
        {
            "ZERO": Triangle(0.0, 0.0, 0.5),
            "PM": Triangle(0.0, 0.5, 1.0),
            "PMAX": Triangle(0.5, 1.0, 1.0),
        },
    )
    table = {
        "N": ("PMAX", "PM", "PMAX"),
        "ZERO": ("PM", "ZERO", "PM"),
        "P": ("PMAX", "PM", "PMAX"),
    }
    rules = tuple(
        Rule((d1, d2), cons)
        for d1, row in table.items()
        for d2, cons in zip(("N", "ZERO", "P"), row, strict=True)
    )
    return FuzzySystem(tuple(deltas), lam, rules, defuzzifier=defuzzifier)


def plot_surface(fls: FuzzySystem, ax: Any = None, n: int = 101) -> tuple[Any, Any]:
    """Draw the output of a two-input system over its input universes.

    Parameters
    ----------
    fls : FuzzySystem
        A system with exactly two inputs.
    ax : matplotlib Axes, optional
        A 3-D axes gets a surface, a 2-D axes a filled contour. ``None`` makes a
        new figure with a 3-D axes.
    n : int
        Grid points per input.

    Returns
    -------
    (ax, artist)
        The axes and the surface (``Poly3DCollection``) or contour set.
    """
    if not isinstance(fls, FuzzySystem) or len(fls.inputs) != 2:
        raise ValueError(
            "The 'fls' parameter of plot_surface must be a FuzzySystem with two inputs. "
            f"Got {fls!r} instead."
        )
    n = check_int(n, "n", "plot_surface", minimum=2)
    import matplotlib.pyplot as plt

    g1 = np.linspace(*fls.inputs[0].universe, n)
    g2 = np.linspace(*fls.inputs[1].universe, n)
    x1, x2 = np.meshgrid(g1, g2, indexing="ij")
    try:
        packed = fls.compiled()
    except ValueError:
        z = fls(x1, x2)
    else:
        z = evaluate_many(packed, np.column_stack([x1.ravel(), x2.ravel()])).reshape(x1.shape)
    if ax is None:
        fig = plt.figure()
        ax = fig.add_subplot(projection="3d")
    if getattr(ax, "name", "") == "3d":
        artist = ax.plot_surface(x1, x2, z, cmap="viridis")
        ax.set_zlabel(fls.output.name)
    else:
        artist = ax.contourf(x1, x2, z, levels=20, cmap="viridis")
    ax.set_xlabel(fls.inputs[0].name)
    ax.set_ylabel(fls.inputs[1].name)
    return ax, artist
