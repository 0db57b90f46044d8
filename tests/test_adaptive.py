"""The fuzzy adaptive Jacobian-transpose law: neutral adaptation is the plain law,
the compiled gain is the fuzzy system's, each law by hand, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexarm as fa
from flexarm.control.adaptive import FuzzyAdaptiveJTPD, tip_deflections
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.signals import reference_size
from flexarm.errors import ScenarioError
from flexarm.fuzzy import FuzzySystem, Rule, Triangle, Variable, paper_system
from flexarm.sim import simulate
from flexarm.sim.scenario import Scenario


@pytest.fixture(scope="module")
def arm():
    return fa.FlexibleArm.paper()


@pytest.fixture(scope="module")
def arm2():
    """Two modes on the second link: the tip map must pick each link's own modes."""
    links = [fa.Link(4.5, 1676.0, 0.335, n_modes=1), fa.Link(4.5, 1676.0, 0.335, n_modes=2)]
    return fa.FlexibleArm(links, boundary="clamped-free", geometric_stiffening=False)


def signals(arm, seed, scale=0.05):
    rng = np.random.default_rng(seed)
    n = arm.n_links
    y = rng.normal(size=2 * n + 4 + sum(arm.n_modes))
    y[2 * n + 4 :] *= scale
    r = rng.normal(size=reference_size(n))
    return y, r


def evaluate(ctrl, arm, y, r):
    state = ctrl.initial_state(arm)
    tau = ctrl(0.0, y, r, ctrl.parameters(arm), state)
    return tau, state


def by_hand(arm, y, r, kp, kd, gp, gd):
    """tau = J(theta)' [gp Kp e + gd Kd de] with NumPy's rigid Jacobian."""
    n = arm.n_links
    e = r[0:2] - y[2 * n : 2 * n + 2]
    de = r[2:4] - y[2 * n + 2 : 2 * n + 4]
    force = gp * kp * e + gd * kd * de
    return arm.jacobian(y[:n]).T @ force


@pytest.mark.parametrize("law", ["scaled", "damping"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_neutral_adaptation_is_the_plain_law(arm, law, seed):
    y, r = signals(arm, seed, scale=10.0)  # large deflections: ks = 0 must ignore them
    plain = JacobianTransposePD.from_arm(arm)
    fuzzy = FuzzyAdaptiveJTPD.from_arm(arm, ks=0.0, law=law)
    tau_plain = plain(0.0, y, r, plain.parameters(arm), np.zeros(0))
    tau_fuzzy, state = evaluate(fuzzy, arm, y, r)
    np.testing.assert_allclose(tau_fuzzy, tau_plain, rtol=1e-13, atol=1e-12)
    assert state[1] == 1.0


def test_gain_is_one_with_straight_links(arm):
    ctrl = FuzzyAdaptiveJTPD.from_arm(arm, ks=50.0)
    assert ctrl.lambda0 == pytest.approx(1.0 / 6.0, rel=1e-14)  # centroid of the ZERO triangle
    assert ctrl.gain([0.0, 0.0]) == pytest.approx(1.0, rel=1e-14)


@pytest.mark.parametrize("arm_name", ["arm", "arm2"])
@pytest.mark.parametrize("seed", [3, 4])
def test_compiled_lambda_is_the_fuzzy_system_of_the_tip_deflections(request, arm_name, seed):
    arm = request.getfixturevalue(arm_name)
    ks = 40.0
    ctrl = FuzzyAdaptiveJTPD.from_arm(arm, ks=ks)
    y, r = signals(arm, seed)
    _, state = evaluate(ctrl, arm, y, r)
    eta = y[2 * arm.n_links + 4 :]
    # tip deflections from each link's own mode shapes at x = L (independent of the map)
    deltas, start = [], 0
    for link, modes in zip(arm.links, arm.modes, strict=True):
        k = len(modes.frequencies)
        deltas.append(float(modes.shape(np.array([link.length]))[:, 0] @ eta[start : start + k]))
        start += k
    lam = float(paper_system()(ks * deltas[0], ks * deltas[1]))
    assert state[0] == pytest.approx(lam, rel=1e-12)
    assert state[1] == pytest.approx(lam * 6.0, rel=1e-12)


@pytest.mark.parametrize("law", ["scaled", "damping"])
def test_each_law_by_hand(arm, law):
    ctrl = FuzzyAdaptiveJTPD(kp=150.0, kd=17.0, ks=30.0, law=law)
    y, r = signals(arm, 5)
    tau, state = evaluate(ctrl, arm, y, r)
    g = state[1]
    assert g > 1.05  # the deflections are large enough to adapt
    gp = g if law == "scaled" else 1.0
    np.testing.assert_allclose(tau, by_hand(arm, y, r, 150.0, 17.0, gp, g), rtol=1e-12)


def test_tip_deflection_map_picks_each_links_modes(arm2):
    m = tip_deflections(arm2)
    assert m.shape == (2, 3)
    assert m[0, 1:].tolist() == [0.0, 0.0]
    assert m[1, 0] == 0.0
    np.testing.assert_allclose(m[1, 1:], arm2.modes[1].shape(np.array([4.5]))[:, 0], rtol=1e-12)


def test_gain_symmetries_and_bounds(arm):
    ctrl = FuzzyAdaptiveJTPD.from_arm(arm, ks=100.0)
    d = np.random.default_rng(6).normal(scale=0.05, size=(200, 2))
    g = ctrl.gain(d)
    np.testing.assert_allclose(g, ctrl.gain(d * [-1, 1]), rtol=1e-13)
    np.testing.assert_allclose(g, ctrl.gain(d[:, ::-1]), rtol=1e-13)
    assert np.all(g >= 1.0 - 1e-12) and np.all(g <= 5.0 + 1e-12)


def test_simulation_with_neutral_adaptation_equals_the_plain_law(arm):
    plain = simulate(arm, JacobianTransposePD.from_arm(arm), duration=0.3)
    fuzzy = simulate(arm, FuzzyAdaptiveJTPD.from_arm(arm, ks=0.0), duration=0.3)
    np.testing.assert_allclose(fuzzy.q, plain.q, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fuzzy.tau, plain.tau, rtol=1e-10, atol=1e-9)


def test_adaptation_changes_the_run_and_records_lambda(arm):
    plain = simulate(arm, JacobianTransposePD.from_arm(arm), duration=0.5)
    fuzzy = simulate(arm, FuzzyAdaptiveJTPD.from_arm(arm, ks=20.0, law="damping"), duration=0.5)
    assert not np.allclose(fuzzy.tau, plain.tau)
    lam, gain = fuzzy.info["controller_state"][:2]
    assert gain == pytest.approx(lam * 6.0, rel=1e-12)


def test_scenario_builds_the_fuzzy_controller(arm):
    s = Scenario.from_dict({"controller": {"kind": "fuzzy", "ks": 5.0, "law": "damping"}})
    assert isinstance(s.controller, FuzzyAdaptiveJTPD)
    assert (s.controller.ks, s.controller.law) == (5.0, "damping")
    assert s.description["controller"]["law"] == "damping"
    with pytest.raises(ScenarioError, match=r"controller\.gain"):
        Scenario.from_dict({"controller": {"kind": "fuzzy", "gain": 5.0}})
    with pytest.raises(ScenarioError, match=r"controller\.law"):
        Scenario.from_dict({"controller": {"kind": "fuzzy", "law": "magic"}})


def _three_input_system():
    var = Variable("d", (-1.0, 1.0), {"Z": Triangle(-1.0, 0.0, 1.0)})
    out = Variable("l", (0.0, 1.0), {"Z": Triangle(0.0, 0.5, 1.0)})
    return FuzzySystem((var, var, var), out, (Rule(("Z", "Z", "Z"), "Z"),))


def _zero_at_rest_system():
    var = Variable("d", (-1.0, 1.0), {"Z": Triangle(-1.0, 0.0, 1.0)})
    out = Variable("l", (-1.0, 1.0), {"Z": Triangle(-0.5, 0.0, 0.5)})
    return FuzzySystem((var, var), out, (Rule(("Z", "Z"), "Z"),))


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"ks": -1.0}, ValueError, "'ks'"),
        ({"ks": math.nan}, ValueError, "'ks'"),
        ({"ks": "big"}, TypeError, "'ks'"),
        ({"law": "magic"}, ValueError, "'law'"),
        ({"fls": "paper"}, TypeError, "'fls'"),
    ],
)
def test_bad_parameters(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        FuzzyAdaptiveJTPD(**kwargs)


@pytest.mark.parametrize(
    ("fls", "match"),
    [(_three_input_system, "one input per link"), (_zero_at_rest_system, "positive output")],
)
def test_fuzzy_system_must_fit_the_arm(arm, fls, match):
    ctrl = FuzzyAdaptiveJTPD(fls=fls())
    with pytest.raises(ValueError, match=match):
        ctrl.parameters(arm)
