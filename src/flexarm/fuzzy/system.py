"""The Mamdani system: rule firing, implication, aggregation, exact defuzzification."""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_option, check_sequence_of
from ..errors import InvalidTypeError, InvalidValueError
from .compiled import CompiledFuzzySystem
from .sets import (
    MembershipFunction,
    Rule,
    Variable,
)

__all__ = ["AGGREGATIONS", "AND_OPERATORS", "DEFUZZIFIERS", "IMPLICATIONS", "FuzzySystem"]

AND_OPERATORS = ("min", "product")
IMPLICATIONS = ("min", "product")
AGGREGATIONS = ("max", "bounded-sum")
DEFUZZIFIERS = ("centroid", "bisector", "mean-of-maxima")

_QUAD_OPTIONS: dict[str, Any] = {"epsabs": 1e-12, "epsrel": 1e-10, "limit": 200}
_COMPILED_FROM = 64  # points from which __call__ takes the compiled path by default
_CHUNK = 1 << 15  # points per task when a large call runs on several cores

FloatArray = NDArray[np.float64]


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


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
            raise InvalidValueError(f"The 'inputs' parameter of {owner} must be non-empty. Got ().")
        object.__setattr__(self, "inputs", inputs)
        if not isinstance(self.output, Variable):
            raise InvalidTypeError(
                f"The 'output' parameter of {owner} must be a Variable. "
                f"Got {type(self.output).__name__} instead."
            )
        rules = check_sequence_of(self.rules, "rules", owner, Rule, "Rule")
        if not rules:
            raise InvalidValueError(f"The 'rules' parameter of {owner} must be non-empty. Got ().")
        for k, rule in enumerate(rules):
            if len(rule.antecedent) != len(inputs):
                raise InvalidValueError(
                    f"The 'rules' parameter of {owner} must hold rules with one antecedent "
                    f"per input ({len(inputs)}). Got {len(rule.antecedent)} at position {k}."
                )
            for var, term in zip(inputs, rule.antecedent, strict=True):
                if term is not None and term not in var.terms:
                    raise InvalidValueError(
                        f"The 'rules' parameter of {owner} must name terms of {var.name!r} "
                        f"{var.term_names}. Got {term!r} at position {k} instead."
                    )
            if rule.consequent not in self.output.terms:
                raise InvalidValueError(
                    f"The 'rules' parameter of {owner} must name terms of the output "
                    f"{self.output.term_names}. Got {rule.consequent!r} at position {k} instead."
                )
        object.__setattr__(self, "rules", rules)
        check_option(self.and_op, "and_op", owner, AND_OPERATORS)
        check_option(self.implication, "implication", owner, IMPLICATIONS)
        check_option(self.aggregation, "aggregation", owner, AGGREGATIONS)
        check_option(self.defuzzifier, "defuzzifier", owner, DEFUZZIFIERS)
        if self.defuzzifier == "mean-of-maxima" and not self.piecewise_linear:
            raise InvalidValueError(
                f"The 'defuzzifier' parameter of {owner} must be 'centroid' or 'bisector' "
                "with non-piecewise-linear output sets. Got 'mean-of-maxima' instead."
            )
        if isinstance(self.default, bool) or not isinstance(self.default, (int, float)):
            raise InvalidTypeError(
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
            raise InvalidValueError(
                f"The 'inputs' parameter of FuzzySystem.{method} must be {len(self.inputs)} "
                f"arrays, one per input variable. Got {len(inputs)} instead."
            )
        arrays = [np.asarray(x, dtype=float) for x in inputs]
        try:
            return list(np.broadcast_arrays(*arrays))
        except ValueError as exc:
            shapes = [a.shape for a in arrays]
            raise InvalidValueError(
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

    def __call__(self, *inputs: ArrayLike, backend: str = "auto") -> FloatArray:
        """The crisp output for crisp inputs.

        Parameters
        ----------
        *inputs : array_like
            One array per input variable (in its unit), broadcast together.
        backend : {"auto", "compiled", "numpy"}
            ``"compiled"``: the compiled kernel (:func:`~flexarm.fuzzy.compiled.evaluate_many`;
            centroid, piecewise-linear output sets), on every core for large
            inputs; ``"numpy"``: exact integration in NumPy/SciPy, any system;
            ``"auto"`` (default): compiled where it applies and the input has at
            least 64 points. Both agree to rounding (the tests hold them to 1e-12).

        Returns
        -------
        ndarray
            The output, shape ``broadcast(inputs).shape`` (0-d for scalars); NaN
            where an input is not finite; the system's default where no rule fires.
        """
        owner = "FuzzySystem.__call__"
        check_option(backend, "backend", owner, ("auto", "compiled", "numpy"))
        xs = self._check_inputs(inputs, "__call__")
        shape = xs[0].shape
        compilable = self.defuzzifier == "centroid" and self.piecewise_linear
        if backend == "compiled" and not compilable:
            raise InvalidValueError(
                f"The 'backend' parameter of {owner} can be 'compiled' only for a centroid "
                "system with piecewise-linear output sets. Got 'compiled' instead."
            )
        if backend == "compiled" or (
            backend == "auto" and compilable and xs[0].size >= _COMPILED_FROM
        ):
            return self._call_compiled(xs).reshape(shape)
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

    def _call_compiled(self, xs: list[FloatArray]) -> FloatArray:
        """The compiled kernel on the flattened inputs; large inputs in chunks on
        every core (the kernel releases the GIL)."""
        from ._kernels import evaluate_many_kernel  # the system built it: no checks

        x = np.ascontiguousarray(np.stack([a.ravel() for a in xs], axis=1), dtype=np.float64)
        system = self._packed
        n = x.shape[0]
        workers = min(_cores(), n // _CHUNK)
        if workers <= 1:
            return evaluate_many_kernel(system, x)
        from concurrent.futures import ThreadPoolExecutor

        out = np.empty(n)

        def run(k0: int) -> None:
            out[k0 : k0 + _CHUNK] = evaluate_many_kernel(system, x[k0 : k0 + _CHUNK])

        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(run, range(0, n, _CHUNK)))
        return out

    @functools.cached_property
    def _packed(self) -> CompiledFuzzySystem:
        return self.compiled()

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
        """The system as plain arrays for :func:`~flexarm.fuzzy.compiled.evaluate` /
        :func:`~flexarm.fuzzy.compiled.evaluate_many`.

        Raises
        ------
        ValueError
            If the defuzzifier is not the centroid or an output set is not
            piecewise linear (the compiled path supports only those).
        """
        owner = "FuzzySystem.compiled"
        if self.defuzzifier != "centroid":
            raise InvalidValueError(
                f"The 'defuzzifier' parameter of {owner} must be 'centroid'. "
                f"Got {self.defuzzifier!r} instead."
            )
        if not self.piecewise_linear:
            raise InvalidValueError(
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
                code, par = mf.packed()
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
