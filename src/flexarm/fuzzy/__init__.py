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
:func:`paper_system` builds the adaptive law of the paper (its Sec. V.D): inputs
``delta1``, ``delta2`` (link deformations, m) on ``[-5, 5]`` with terms
``N = LeftShoulder(-5, 0)``, ``ZERO = Triangle(-5, 0, 5)``,
``P = RightShoulder(0, 5)``; output ``lambda`` on ``[0, 1]`` with
``ZERO = Triangle(0, 0, 0.5)``, ``PM = Triangle(0, 0.5, 1)``,
``PMAX = Triangle(0.5, 1, 1)`` (peaks at 0, 0.5 and 1 as the paper's figure
suggests; the supports, half-width 0.5, are our decision); MIN, MIN, MAX,
centroid; the rule table

========  ====  ====  ====
δ1 \\ δ2  N     ZERO  P
========  ====  ====  ====
N         PMAX  PM    PMAX
ZERO      PM    ZERO  PM
P         PMAX  PM    PMAX
========  ====  ====  ====

>>> from flexarm.fuzzy import paper_system
>>> fls = paper_system()
>>> round(float(fls(0.0, 0.0)), 12)
0.166666666667
>>> fls([0.0, 5.0], [0.0, 5.0]).shape
(2,)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .compiled import CompiledFuzzySystem as CompiledFuzzySystem
    from .compiled import evaluate as evaluate
    from .compiled import evaluate_into as evaluate_into
    from .compiled import evaluate_many as evaluate_many
    from .compiled import workspace_size as workspace_size
    from .paper import paper_system as paper_system
    from .paper import plot_surface as plot_surface
    from .sets import Gaussian as Gaussian
    from .sets import LeftShoulder as LeftShoulder
    from .sets import MembershipFunction as MembershipFunction
    from .sets import RightShoulder as RightShoulder
    from .sets import Rule as Rule
    from .sets import Trapezoid as Trapezoid
    from .sets import Triangle as Triangle
    from .sets import Variable as Variable
    from .system import AGGREGATIONS as AGGREGATIONS
    from .system import AND_OPERATORS as AND_OPERATORS
    from .system import DEFUZZIFIERS as DEFUZZIFIERS
    from .system import IMPLICATIONS as IMPLICATIONS
    from .system import FuzzySystem as FuzzySystem
