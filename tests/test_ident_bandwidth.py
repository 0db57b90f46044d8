"""The one default-bandwidth rule (Silverman's rule of thumb) against its closed form, and
every default that uses it: the estimators, the Hammerstein identifier, the study, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexarm.cli import main
from flexarm.ident import (
    HammersteinIdentifier,
    NadarayaWatson,
    RecursiveKernelRegression,
    SemiRecursiveKernelRegression,
    Silverman,
    convergence_study,
    silverman_bandwidth,
)
from flexarm.ident.hammerstein.identifier import DEFAULT_BANDWIDTH
from helpers.ident import saturation_samples, silverman

N = 400


@pytest.fixture(scope="module")
def samples():
    return saturation_samples(N)


def test_default_bandwidth_is_silverman_at_the_last_sample(samples):
    x, _ = samples
    q75, q25 = np.percentile(x, [75, 25])
    rule = 0.9 * min(np.std(x, ddof=1), (q75 - q25) / 1.34) * N ** (-0.2)
    for decay in (0.0, 0.2, 0.5):
        h1 = silverman_bandwidth(x, decay)[0]
        assert h1 * N ** (-decay) == pytest.approx(rule, rel=1e-12)


@pytest.mark.parametrize("factor", [1.0, 0.55, 3.0])
@pytest.mark.parametrize("decay", [0.0, 1 / 6, 0.4])
def test_rule_against_closed_form_in_two_dimensions(factor, decay):
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.normal(0, 2, 500), rng.standard_t(2, 500)])  # heavy tail: IQR
    got = Silverman(factor)(X, decay)
    np.testing.assert_allclose(got, silverman(X, factor=factor, decay=decay), rtol=1e-12)
    np.testing.assert_allclose(
        silverman_bandwidth(X, decay, n=2000, factor=factor),
        silverman(X, n=2000, factor=factor, decay=decay),
        rtol=1e-12,
    )


def test_decay_one_fifth_is_the_rule_at_every_sample():
    """d = 1, decay 0.2: h_1 does not depend on n, and h_i is the rule for i samples."""
    x = np.random.default_rng(0).normal(size=1000)
    assert silverman_bandwidth(x, 0.2, n=10)[0] == silverman_bandwidth(x, 0.2, n=10**6)[0]


def test_zero_iqr_falls_back_to_the_standard_deviation():
    x = np.r_[np.zeros(20), 1.0, -1.0]
    assert silverman_bandwidth(x, 0.0)[0] == pytest.approx(0.9 * np.std(x, ddof=1) * 22**-0.2)


@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (lambda: silverman_bandwidth(np.ones(10)), ValueError, "'X'.*must vary.*column 0"),
        (lambda: silverman_bandwidth([1.0]), ValueError, "'X'.*at least 2 samples"),
        (lambda: silverman_bandwidth([1.0, 2.0], decay=-1), ValueError, "'decay'.*>= 0"),
        (lambda: silverman_bandwidth(np.zeros((2, 2, 2))), ValueError, "'X'.*shape"),
        (lambda: silverman_bandwidth([1.0, np.nan]), ValueError, "'X'.*finite"),
        (lambda: Silverman(0.0), ValueError, "'factor' parameter of Silverman must be > 0"),
        (lambda: Silverman("big"), TypeError, "'factor'"),
    ],
)
def test_rule_bad_input(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


@pytest.mark.parametrize(
    "cls", [SemiRecursiveKernelRegression, RecursiveKernelRegression, NadarayaWatson]
)
@pytest.mark.parametrize("grid", [None, np.linspace(-1, 1, 21)], ids=["exact", "grid"])
def test_estimators_accept_the_rule(samples, cls, grid):
    x, y = samples
    decay = 0.0 if cls is NadarayaWatson else 0.25
    est = cls(bandwidth="silverman", grid=grid).set_params(
        **({} if cls is NadarayaWatson else {"decay": decay})
    )
    est.fit(x, y)
    h1 = silverman(x, decay=decay)
    np.testing.assert_allclose(est.bandwidth_, h1, rtol=1e-12)
    same = cls(bandwidth=est.bandwidth_[0], grid=grid).set_params(
        **({} if cls is NadarayaWatson else {"decay": decay})
    )
    q = np.linspace(-1, 1, 21)
    np.testing.assert_array_equal(est.predict(q), same.fit(x, y).predict(q))
    half = cls(bandwidth=Silverman(0.5), grid=grid).set_params(
        **({} if cls is NadarayaWatson else {"decay": decay})
    )
    np.testing.assert_allclose(half.fit(x, y).bandwidth_, 0.5 * h1, rtol=1e-12)


def test_rule_is_evaluated_on_the_first_partial_fit_and_saved(samples, tmp_path):
    x, y = samples
    est = SemiRecursiveKernelRegression(bandwidth=Silverman(0.7)).partial_fit(x[:100], y[:100])
    np.testing.assert_allclose(est.bandwidth_, silverman(x[:100], factor=0.7), rtol=1e-12)
    est.save(tmp_path / "s.npz")
    back = SemiRecursiveKernelRegression.load(tmp_path / "s.npz")
    assert back.bandwidth == Silverman(0.7)
    np.testing.assert_array_equal(back.bandwidth_, est.bandwidth_)
    for e in (est, back):
        e.partial_fit(x[100:], y[100:])  # the rule is not re-evaluated
    np.testing.assert_array_equal(back.predict(x[:9]), est.predict(x[:9]))
    np.testing.assert_allclose(back.bandwidth_, silverman(x[:100], factor=0.7), rtol=1e-12)


def test_hammerstein_default_is_the_rule_on_the_warmup_inputs():
    rng = np.random.default_rng(0)
    u = rng.uniform(-2, 2, 3000)
    y = np.convolve(np.tanh(u), [1.0, 0.5])[:3000] + 0.01 * rng.standard_normal(3000)
    assert Silverman(0.55) == DEFAULT_BANDWIDTH
    for decay in (0.2, 0.3):
        est = HammersteinIdentifier(decay=decay).fit(u, y)
        expected = silverman(u[:256], n=256, factor=0.55, decay=decay)[0]
        assert est.bandwidth_ == pytest.approx(expected, rel=1e-12)
    est = HammersteinIdentifier(bandwidth="silverman").fit(u, y)
    assert est.bandwidth_ == pytest.approx(silverman(u[:256], n=256)[0], rel=1e-12)


def test_study_default_is_the_rule_on_each_repetition():
    res = convergence_study("smooth", n=[50, 200], repetitions=3, rng=4)
    rng = np.random.default_rng(4)
    expected = []
    for _ in range(3):
        X = rng.uniform(-1, 1, 200)
        rng.standard_normal(200)  # the noise drawn after the inputs
        expected.append(silverman(X, decay=0.2)[0])
    np.testing.assert_allclose(res.settings["h1"], expected, rtol=1e-12)
    assert res.settings["bandwidth"] == "silverman"


def test_cli_fit_uses_the_rule(samples, tmp_path, capsys):
    x, y = samples
    p = tmp_path / "d.csv"
    np.savetxt(p, np.column_stack([x, y]), delimiter=",", header="u,w", comments="")
    assert main(["identify", "fit", str(p), "--json", "--grid", "8"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["bandwidth_rule"] == "silverman"
    assert s["bandwidth"] == pytest.approx(silverman(x)[0], rel=1e-12)
