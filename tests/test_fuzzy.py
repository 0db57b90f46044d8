"""Tests of :mod:`flexarm.fuzzy` against hand results, fine discretisations and scikit-fuzzy.

Oracles (none calls the inference code under test to produce the expected value):

* hand-computed single-rule outputs (centroid, bisector, mean of maxima of a full or
  clipped triangle);
* symmetries of the paper's rule table: ``lambda(d1, d2) = lambda(-d1, d2) = lambda(d2, d1)``;
* a discretised reference written here (memberships and rule strengths computed in
  the test, the aggregate sampled on 10**6 + 1 points, integrated with the trapezoid
  rule), whose error for piecewise-linear sets is O(h**2) per kink, ~1e-10 here;
* scikit-fuzzy's ``skfuzzy.control`` on a fine universe (skipped if absent);
* the compiled path against the Python path (1e-12).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexarm.fuzzy import (
    FuzzySystem,
    Gaussian,
    LeftShoulder,
    MembershipFunction,
    RightShoulder,
    Rule,
    Trapezoid,
    Triangle,
    Variable,
    evaluate,
    evaluate_many,
    paper_system,
    plot_surface,
)

N_REF = 1_000_001
N_FAST = 200_001  # error ~5e-10 on the random systems below (1e-6 / 25 at 10**6 points)
OPS = [
    (and_op, imp, agg)
    for and_op in ("min", "product")
    for imp in ("min", "product")
    for agg in ("max", "bounded-sum")
]


def _one_input_system(out_mf: MembershipFunction, **kw: object) -> FuzzySystem:
    """x on [0, 1] with A = Triangle(-1, 0, 1) (so strength 1 - x), one rule A -> OUT."""
    x = Variable("x", (0.0, 1.0), {"A": Triangle(-1.0, 0.0, 1.0)})
    y = Variable("y", (0.0, 1.0), {"OUT": out_mf})
    return FuzzySystem((x,), y, (Rule(("A",), "OUT"),), **kw)


# ------------------------------------------------------------ the reference


def _strengths(fls: FuzzySystem, point: tuple[float, ...]) -> np.ndarray:
    w = []
    for rule in fls.rules:
        mus = []
        for var, term, x in zip(fls.inputs, rule.antecedent, point, strict=True):
            if term is None:
                continue
            lo, hi = var.universe
            mus.append(float(var.terms[term](min(max(x, lo), hi))))
        if not mus:
            w.append(1.0)
        elif fls.and_op == "min":
            w.append(min(mus))
        else:
            w.append(math.prod(mus))
    return np.array(w)


def _reference(fls: FuzzySystem, point: tuple[float, ...], n: int = N_REF) -> float:
    kind = fls.defuzzifier
    lo, hi = fls.output.universe
    y = np.linspace(lo, hi, n)
    agg = np.zeros_like(y)
    for rule, w in zip(fls.rules, _strengths(fls, point), strict=True):
        mu = fls.output.terms[rule.consequent](y)
        implied = np.minimum(mu, w) if fls.implication == "min" else mu * w
        agg = np.maximum(agg, implied) if fls.aggregation == "max" else agg + implied
    if fls.aggregation == "bounded-sum":
        agg = np.minimum(agg, 1.0)
    area = np.trapezoid(agg, y)
    if area == 0.0:
        return math.nan
    if kind == "centroid":
        return float(np.trapezoid(y * agg, y) / area)
    if kind == "bisector":
        cum = np.concatenate([[0.0], np.cumsum(np.diff(y) * (agg[1:] + agg[:-1]) / 2)])
        return float(np.interp(area / 2, cum, y))
    top = agg.max()
    return float(y[agg >= top - 1e-9].mean())


def _random_pl(rng: np.random.Generator, lo: float, hi: float) -> MembershipFunction:
    span = hi - lo
    kind = rng.integers(4)
    p = np.sort(rng.uniform(lo - 0.2 * span, hi + 0.2 * span, 4))
    if kind == 0:
        return Triangle(p[0], p[1], p[2])
    if kind == 1:
        return Trapezoid(*p)
    if kind == 2:
        return LeftShoulder(p[1], p[2])
    return RightShoulder(p[1], p[2])


def _random_system(rng: np.random.Generator, ops: tuple[str, str, str], **kw: object):
    and_op, imp, agg = ops
    inputs = []
    for name in ("u", "v"):
        terms: dict[str, MembershipFunction] = {
            "L": LeftShoulder(-0.5, rng.uniform(0.0, 0.5)),
            "M": Triangle(-0.8, rng.uniform(-0.3, 0.3), 0.8),
            "H": RightShoulder(rng.uniform(-0.5, 0.0), 0.5),
            "G": Gaussian(rng.uniform(-1, 1), rng.uniform(0.2, 0.6)),
        }
        inputs.append(Variable(name, (-1.0, 1.0), terms))
    out_terms = {f"O{k}": _random_pl(rng, 0.0, 1.0) for k in range(4)}
    out = Variable("out", (0.0, 1.0), out_terms)
    names = ["L", "M", "H", "G", None]
    rules = tuple(
        Rule((names[rng.integers(5)], names[rng.integers(4)]), f"O{rng.integers(4)}")
        for _ in range(7)
    )
    return FuzzySystem(
        tuple(inputs), out, rules, and_op=and_op, implication=imp, aggregation=agg, **kw
    )


# ------------------------------------------------------- membership functions


def test_membership_functions_by_hand():
    x = np.array([-6.0, -5.0, -2.5, 0.0, 2.5, 5.0, 6.0])
    np.testing.assert_allclose(LeftShoulder(-5, 0)(x), [1, 1, 0.5, 0, 0, 0, 0])
    np.testing.assert_allclose(Triangle(-5, 0, 5)(x), [0, 0, 0.5, 1, 0.5, 0, 0])
    np.testing.assert_allclose(RightShoulder(0, 5)(x), [0, 0, 0, 0, 0.5, 1, 1])
    np.testing.assert_allclose(Trapezoid(-5, -2.5, 0, 5)(x), [0, 0, 1, 1, 0.5, 0, 0])
    np.testing.assert_allclose(Triangle(0, 0, 0.5)([0.0, 0.25, -0.1]), [1, 0.5, 0])
    np.testing.assert_allclose(Gaussian(1.0, 2.0)([1.0, 3.0]), [1.0, math.exp(-0.5)])
    assert Triangle(0, 1, 2)(np.zeros((2, 3))).shape == (2, 3)
    assert Triangle(0, 1, 2)(0.5).shape == ()


# ------------------------------------------------------------ hand results


def test_single_rule_full_triangle_centroid_is_one_sixth():
    fls = paper_system()
    assert float(fls(0.0, 0.0)) == pytest.approx(1 / 6, abs=1e-15)
    assert float(fls(5.0, 5.0)) == pytest.approx(5 / 6, abs=1e-15)
    assert float(fls(-5.0, 0.0)) == pytest.approx(0.5, abs=1e-15)  # PM alone


def test_single_rule_clipped_at_half():
    # Triangle(0, 0, 0.5) cut at 0.5: 0.5 on [0, 1/4], then down to 0 at 1/2.
    # Area 1/8 + 1/16 = 3/16, moment 1/64 + 1/48 = 7/192, centroid 7/36.
    fls = _one_input_system(Triangle(0.0, 0.0, 0.5))
    assert float(fls(0.5)) == pytest.approx(7 / 36, abs=1e-15)
    # half area 3/32 lies in the rectangle: x = (3/32) / 0.5
    bis = _one_input_system(Triangle(0.0, 0.0, 0.5), defuzzifier="bisector")
    assert float(bis(0.5)) == pytest.approx(3 / 16, abs=1e-15)
    mom = _one_input_system(Triangle(0.0, 0.0, 0.5), defuzzifier="mean-of-maxima")
    assert float(mom(0.5)) == pytest.approx(1 / 8, abs=1e-15)  # plateau [0, 1/4]


def test_single_rule_bisector_and_mom_of_full_triangle():
    # area right of x is (1/2 - x)**2 = 1/8  ->  x = 1/2 - sqrt(1/8)
    assert float(paper_system("bisector")(0.0, 0.0)) == pytest.approx(
        0.5 - math.sqrt(0.125), abs=1e-15
    )
    assert float(paper_system("mean-of-maxima")(0.0, 0.0)) == 0.0  # isolated peak at 0
    assert float(paper_system("mean-of-maxima")(-5.0, 0.0)) == pytest.approx(0.5)


def test_jump_inside_the_universe():
    # Triangle(0.3, 0.3, 0.8) jumps from 0 to 1 at 0.3: centroid (0.3 + 0.3 + 0.8) / 3
    fls = _one_input_system(Triangle(0.3, 0.3, 0.8))
    assert float(fls(0.0)) == pytest.approx(1.4 / 3, abs=1e-15)
    assert evaluate(fls.compiled(), np.array([0.0])) == pytest.approx(1.4 / 3, abs=1e-15)
    # cut at 0.4: the reference sees the jump with an O(h) = 1e-6 error
    assert float(fls(0.6)) == pytest.approx(_reference(fls, (0.6,)), abs=1e-5)


def test_product_implication_keeps_the_centroid_of_one_set():
    fls = _one_input_system(Triangle(0.0, 0.0, 0.5), implication="product")
    np.testing.assert_allclose(fls([0.0, 0.3, 0.7]), 1 / 6, atol=1e-15)


def test_no_rule_fires_gives_the_default():
    assert math.isnan(float(_one_input_system(Triangle(0, 0.5, 1))(1.0)))
    fls = _one_input_system(Triangle(0, 0.5, 1), default=0.25)
    assert float(fls(1.0)) == 0.25
    assert float(evaluate(fls.compiled(), np.array([1.0]))) == 0.25
    assert math.isnan(float(paper_system()(math.nan, 0.0)))


# --------------------------------------------------------- the paper system


def test_paper_system_symmetries_and_bounds():
    rng = np.random.default_rng(1)
    d1, d2 = rng.uniform(-5, 5, (2, 40))
    fls = paper_system()
    lam = fls(d1, d2)
    np.testing.assert_allclose(fls(-d1, d2), lam, atol=1e-14)
    np.testing.assert_allclose(fls(d1, -d2), lam, atol=1e-14)
    np.testing.assert_allclose(fls(d2, d1), lam, atol=1e-14)
    assert np.all((lam >= 0.0) & (lam <= 1.0))
    # extremes: the corners fire PMAX alone, the edge midpoints PM alone
    corners = fls([-5, -5, 5, 5, 9], [-5, 5, -5, 5, 9])
    np.testing.assert_allclose(corners, 5 / 6, atol=1e-15)
    np.testing.assert_allclose(fls([0, 5, 0, -5], [5, 0, -5, 0]), 0.5, atol=1e-15)


@pytest.mark.parametrize("kind", ["centroid", "bisector", "mean-of-maxima"])
def test_paper_system_matches_discretised_reference(kind):
    fls = paper_system(kind)
    rng = np.random.default_rng(2)
    for point in rng.uniform(-5, 5, (3, 2)):
        tol = 1e-9 if kind != "mean-of-maxima" else 2e-6
        assert float(fls(*point)) == pytest.approx(_reference(fls, tuple(point)), abs=tol)


# ------------------------------------------------- general systems vs reference


@pytest.mark.parametrize("ops", OPS, ids="-".join)
@pytest.mark.parametrize("kind", ["centroid", "bisector"])
def test_random_systems_match_discretised_reference(ops, kind):
    rng = np.random.default_rng([OPS.index(ops), len(kind)])
    checked = 0
    for _ in range(3):
        fls = _random_system(rng, ops, defuzzifier=kind)
        point = tuple(rng.uniform(-1, 1, 2))
        ref = _reference(fls, point, N_FAST)
        got = float(fls(*point))
        if math.isnan(ref):
            assert math.isnan(got)
            continue
        checked += 1
        assert got == pytest.approx(ref, abs=1e-8)
    assert checked > 0


def test_mean_of_maxima_matches_discretised_reference():
    rng = np.random.default_rng(3)
    for _ in range(4):
        fls = _random_system(rng, ("min", "min", "max"), defuzzifier="mean-of-maxima")
        point = tuple(rng.uniform(-1, 1, 2))
        assert float(fls(*point)) == pytest.approx(_reference(fls, point, N_FAST), abs=2e-5)


@pytest.mark.parametrize("kind", ["centroid", "bisector"])
def test_gaussian_output_sets_by_quadrature(kind):
    x = Variable("x", (-1.0, 1.0), {"A": LeftShoulder(-1, 1), "B": RightShoulder(-1, 1)})
    y = Variable("y", (0.0, 1.0), {"LO": Gaussian(0.2, 0.1), "HI": Gaussian(0.7, 0.2)})
    fls = FuzzySystem((x,), y, (Rule(("A",), "LO"), Rule(("B",), "HI")), defuzzifier=kind)
    for point in (-0.5, 0.8):
        assert float(fls(point)) == pytest.approx(_reference(fls, (point,)), abs=1e-7)


# ------------------------------------------------------------ scikit-fuzzy


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_paper_system_agrees_with_scikit_fuzzy():
    fuzz = pytest.importorskip("skfuzzy")
    ctrl = pytest.importorskip("skfuzzy.control")
    u = np.linspace(-5, 5, 2001)
    d1, d2 = ctrl.Antecedent(u, "delta1"), ctrl.Antecedent(u, "delta2")
    for var in (d1, d2):
        var["N"] = fuzz.trimf(u, [-5, -5, 0])
        var["ZERO"] = fuzz.trimf(u, [-5, 0, 5])
        var["P"] = fuzz.trimf(u, [0, 5, 5])
    v = np.linspace(0, 1, 20001)
    lam = ctrl.Consequent(v, "lambda", defuzzify_method="centroid")
    lam["ZERO"] = fuzz.trimf(v, [0, 0, 0.5])
    lam["PM"] = fuzz.trimf(v, [0, 0.5, 1])
    lam["PMAX"] = fuzz.trimf(v, [0.5, 1, 1])
    table = {"N": "PMAX PM PMAX", "ZERO": "PM ZERO PM", "P": "PMAX PM PMAX"}
    rules = [
        ctrl.Rule(d1[a] & d2[b], lam[c])
        for a, row in table.items()
        for b, c in zip(("N", "ZERO", "P"), row.split(), strict=True)
    ]
    sim = ctrl.ControlSystemSimulation(ctrl.ControlSystem(rules))
    fls = paper_system()
    rng = np.random.default_rng(4)
    for a, b in rng.uniform(-5, 5, (10, 2)):
        sim.input["delta1"], sim.input["delta2"] = a, b
        sim.compute()
        # sampled clipped sets: kinks off the grid cost O(h**2), h = 5e-5
        assert float(fls(a, b)) == pytest.approx(sim.output["lambda"], abs=1e-6)


# ---------------------------------------------------------------- compiled


def test_compiled_paper_system_equals_python_path():
    fls = paper_system()
    rng = np.random.default_rng(5)
    x = rng.uniform(-6, 6, (150, 2))
    python = fls(x[:, 0], x[:, 1], backend="numpy")
    np.testing.assert_allclose(evaluate_many(fls.compiled(), x), python, atol=1e-12)
    assert evaluate(fls.compiled(), np.array([0.0, 0.0])) == pytest.approx(1 / 6, abs=1e-15)


@pytest.mark.parametrize("ops", OPS, ids="-".join)
def test_compiled_random_systems_equal_python_path(ops):
    rng = np.random.default_rng([10, OPS.index(ops)])
    for _ in range(3):
        fls = _random_system(rng, ops)
        x = rng.uniform(-1.2, 1.2, (15, 2))
        np.testing.assert_allclose(
            evaluate_many(fls.compiled(), x), fls(x[:, 0], x[:, 1], backend="numpy"), atol=1e-12
        )


def test_compiled_refuses_what_it_does_not_support():
    with pytest.raises(ValueError, match="'defuzzifier'"):
        paper_system("bisector").compiled()
    y = Variable("y", (0.0, 1.0), {"G": Gaussian(0.5, 0.1)})
    fls = FuzzySystem(paper_system().inputs[:1], y, (Rule(("N",), "G"),))
    with pytest.raises(ValueError, match="'output'"):
        fls.compiled()


@pytest.mark.parametrize("ops", OPS, ids="-".join)
def test_the_public_call_is_compiled_for_many_points(ops):
    """Many points go to the compiled kernel (on every core past one chunk); the
    answer is the NumPy path's to 1e-12, NaN for non-finite inputs, inputs clipped
    to the universes alike."""
    rng = np.random.default_rng([11, OPS.index(ops)])
    fls = _random_system(rng, ops)
    x = rng.uniform(-1.5, 1.5, (2, 3 * 2**15 + 17))
    x[0, :3] = [np.nan, np.inf, -np.inf]
    auto = fls(x[0], x[1])
    compiled = fls(x[0], x[1], backend="compiled")
    np.testing.assert_array_equal(auto, compiled)
    np.testing.assert_array_equal(compiled, evaluate_many(fls.compiled(), x.T.copy()))
    sample = np.r_[0:3, rng.integers(3, x.shape[1], 200)]
    python = fls(x[0, sample], x[1, sample], backend="numpy")
    np.testing.assert_allclose(compiled[sample], python, atol=1e-12)
    assert np.all(np.isnan(compiled[:3]))


def test_backend_is_checked():
    with pytest.raises(ValueError, match="'backend'"):
        paper_system()(0.0, 0.0, backend="fast")
    with pytest.raises(ValueError, match=r"'backend'.*centroid"):
        paper_system("bisector")(0.0, 0.0, backend="compiled")


# ----------------------------------------------------------- vectorisation


def test_vectorisation_and_broadcasting():
    fls = paper_system()
    d1 = np.linspace(-5, 5, 4)[:, None]
    d2 = np.linspace(-5, 5, 3)[None, :]
    out = fls(d1, d2)
    assert out.shape == (4, 3)
    for i in range(4):
        for j in range(3):
            assert out[i, j] == float(fls(d1[i, 0], d2[0, j]))
    assert fls(0.0, 0.0).shape == ()
    assert fls([1.0, 2.0], 0.5).shape == (2,)
    assert fls.firing_strengths(d1, d2).shape == (4, 3, 9)


def _face_means(fls: FuzzySystem, n: int) -> np.ndarray:
    """The Python path's output on the n x n grid of the universes, averaged over each
    cell's four corners (the value matplotlib colours a surface's face by), row-major
    with the first input along the rows."""
    g1, g2 = (np.linspace(*var.universe, n) for var in fls.inputs)
    x1, x2 = np.meshgrid(g1, g2, indexing="ij")
    z = fls(x1, x2, backend="numpy")
    return ((z[:-1, :-1] + z[1:, :-1] + z[:-1, 1:] + z[1:, 1:]) / 4).ravel()


def test_plot_surface():
    import matplotlib.pyplot as plt

    ax, surf = plot_surface(paper_system(), n=11)
    assert ax.name == "3d"
    np.testing.assert_allclose(surf.get_array(), _face_means(paper_system(), 11), atol=1e-12)
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("δ1 (m)", "δ2 (m)", "λ (-)")
    # an asymmetric system: the first input runs along x, the surface is its output
    fls = _random_system(np.random.default_rng(5), OPS[3])
    ax, surf = plot_surface(fls, n=9)
    np.testing.assert_allclose(surf.get_array(), _face_means(fls, 9), atol=1e-12)
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("u", "v", "out")
    _fig, ax2 = plt.subplots()
    ax_out, contour = plot_surface(paper_system(), ax=ax2, n=11)
    assert ax_out is ax2
    # the 11 x 11 grid holds (0, 0) -> 1/6 and the corners -> 5/6
    assert contour.zmin == pytest.approx(1 / 6) and contour.zmax == pytest.approx(5 / 6)
    plt.close("all")


# --------------------------------------------------------------- bad input


def _x() -> Variable:
    return Variable("x", (0.0, 1.0), {"A": Triangle(0, 0.5, 1)})


def _one_rule(**options: object) -> FuzzySystem:
    """x -> x by the one rule A -> A, with ``options`` (operators, defuzzifier)."""
    return FuzzySystem((_x(),), _x(), (Rule(("A",), "A"),), **options)


@pytest.mark.parametrize(
    ("make", "exc", "param"),
    [
        (lambda: Triangle(1.0, 0.5, 2.0), ValueError, "b"),
        (lambda: Triangle(0.0, 2.0, 1.0), ValueError, "c"),
        (lambda: Triangle(0.0, 0.0, 0.0), ValueError, "c"),
        (lambda: Triangle(math.nan, 0.0, 1.0), ValueError, "a"),
        (lambda: Trapezoid(0, 1, 0.5, 2), ValueError, "c"),
        (lambda: Trapezoid(0, 1, 2, math.inf), ValueError, "d"),
        (lambda: LeftShoulder(1.0, 0.0), ValueError, "c"),
        (lambda: RightShoulder(1.0, 0.0), ValueError, "b"),
        (lambda: Gaussian(0.0, 0.0), ValueError, "sigma"),
        (lambda: Gaussian("0", 1.0), TypeError, "mean"),
        (lambda: Variable("x", (1.0, 0.0), {"A": Triangle(0, 1, 2)}), ValueError, "universe"),
        (lambda: Variable("x", (0.0, 1.0), {}), TypeError, "terms"),
        (lambda: Variable("x", (0.0, 1.0), {"A": 3}), TypeError, "terms"),
        (lambda: Rule("A", "B"), TypeError, "antecedent"),
        (lambda: Rule(("A",), 3), TypeError, "consequent"),
        (lambda: FuzzySystem((_x(),), _x(), (Rule(("Q",), "A"),)), ValueError, "rules"),
        (lambda: FuzzySystem((_x(),), _x(), (Rule(("A",), "Q"),)), ValueError, "rules"),
        (lambda: FuzzySystem((_x(),), _x(), (Rule(("A", "A"), "A"),)), ValueError, "rules"),
        (lambda: FuzzySystem((_x(),), _x(), ()), ValueError, "rules"),
        (lambda: FuzzySystem((_x(),), "y", (Rule(("A",), "A"),)), TypeError, "output"),
        (lambda: _one_rule(and_op="max"), ValueError, "and_op"),
        (lambda: _one_rule(implication="lukasiewicz"), ValueError, "implication"),
        (lambda: _one_rule(aggregation="sum"), ValueError, "aggregation"),
        (lambda: _one_rule(defuzzifier="lom"), ValueError, "defuzzifier"),
        (lambda: paper_system("som"), ValueError, "defuzzifier"),
        (lambda: paper_system()(1.0), ValueError, "inputs"),
        (lambda: paper_system()([1.0, 2.0], [1.0, 2.0, 3.0]), ValueError, "inputs"),
        (lambda: plot_surface(paper_system(), n=1), ValueError, "n"),
    ],
)
def test_bad_input(make, exc, param):
    with pytest.raises(exc, match=f"'{param}'"):
        make()


def test_mean_of_maxima_refused_for_gaussian_outputs():
    y = Variable("y", (0.0, 1.0), {"G": Gaussian(0.5, 0.1)})
    with pytest.raises(ValueError, match="'defuzzifier'"):
        FuzzySystem((_x(),), y, (Rule(("A",), "G"),), defuzzifier="mean-of-maxima")


def test_evaluate_into_reuses_a_buffer_whatever_it_holds():
    from flexarm.fuzzy import evaluate, evaluate_into, paper_system, workspace_size

    compiled = paper_system().compiled()
    rng = np.random.default_rng(7)
    buf = np.full(workspace_size(compiled), np.nan)  # garbage must not leak into results
    for x in rng.uniform(-6.0, 6.0, (50, 2)):
        assert evaluate_into(compiled, x, buf) == evaluate(compiled, x)
