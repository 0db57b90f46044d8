"""The estimator contract both families share: one rule for "parameters changed", one
frozen fitted state (``state_``), an estimator rebuilt from it, and its plain arrays."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from flexarm.ident import (
    HammersteinIdentifier,
    LinearARX,
    NadarayaWatson,
    NotFittedError,
    SemiRecursiveKernelRegression,
    simulate_hammerstein,
)
from flexarm.ident.hammerstein.identifier import HammersteinState
from flexarm.ident.hammerstein.linear import LinearFit
from flexarm.ident.regression.estimators import RegressionState

RNG = np.random.default_rng(5)
X = RNG.uniform(0, 1, 2000)
Y = np.sin(6 * X) + 0.1 * RNG.standard_normal(2000)
U = RNG.uniform(-2, 2, 3000)
YH = simulate_hammerstein(np.tanh, [0.5], [1.0, 0.3], U, noise_std=0.05, rng=RNG)


def regression(**kw):
    return SemiRecursiveKernelRegression(bandwidth=0.1, grid=np.linspace(0, 1, 3000), **kw)


def identifier(**kw):
    return HammersteinIdentifier(n_lags=12, warmup=128, **kw)


FAMILIES = {
    "regression": (regression, X, Y),
    "hammerstein": (identifier, U, YH),
}


def halves(family):
    """The family's estimator maker, the two halves of its record, and a fit to all of it."""
    make, u, y = FAMILIES[family]
    n = u.shape[0] // 2
    return make, (u[:n], y[:n]), (u[n:], y[n:]), make().fit(u, y)


# ----------------------------------------------------------------------------- the change rule


@pytest.mark.parametrize(
    ("family", "name", "value"),
    [("regression", "decay", 0.3), ("hammerstein", "decay", 0.3), ("hammerstein", "n_lags", 14)],
)
def test_a_changed_parameter_stops_streaming(family, name, value):
    make, first, then, _ = halves(family)
    est = make().partial_fit(*first)
    est.set_params(**{name: value})
    with pytest.raises(ValueError, match=rf"\['{name}'\].*changed since the first partial_fit"):
        est.partial_fit(*then)


def test_a_change_in_place_is_seen_in_both_families():
    """The first fit freezes copies: changing the given object afterwards is a change.
    (A comparison of repr misses the regression's case: NumPy elides the middle of a
    3000-point grid.)"""
    grid = np.linspace(0, 1, 3000)
    est = SemiRecursiveKernelRegression(bandwidth=0.1, grid=grid).partial_fit(X[:900], Y[:900])
    grid[1500] += 1e-3
    with pytest.raises(ValueError, match=r"\['grid'\].*changed"):
        est.partial_fit(X[900:], Y[900:])
    known = [[0.0, 0.0], [1.0, 0.7]]
    ham = identifier(known_points=known).partial_fit(U[:900], YH[:900])
    known[1][1] = 0.8
    with pytest.raises(ValueError, match=r"\['known_points'\].*changed"):
        ham.partial_fit(U[900:], YH[900:])


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_the_same_value_again_is_no_change(family):
    """Equal values are the same parameter: a new float object, an int as a NumPy int."""
    make, first, then, whole = halves(family)
    est = make().partial_fit(*first)
    est.set_params(decay=float("0.2"))
    if family == "hammerstein":
        est.set_params(n_lags=np.int64(12), known_points=None)
    else:
        est.set_params(grid=np.linspace(0, 1, 3000))  # an equal array, another object
    est.partial_fit(*then)
    q = np.linspace(0, 1, 3000)[::7] if family == "regression" else np.linspace(-1.5, 1.5, 9)
    got = est.predict(q) if family == "regression" else est.nonlinearity(q)
    want = whole.predict(q) if family == "regression" else whole.nonlinearity(q)
    np.testing.assert_array_equal(got, want)


# ----------------------------------------------------------------------------- one fitted state


@pytest.mark.parametrize(
    ("make", "inputs", "outputs", "kind", "q"),
    [
        (regression, X, Y, RegressionState, np.linspace(0, 1, 3000)[::15]),
        (lambda: NadarayaWatson(bandwidth=0.05), X, Y, RegressionState, X[:200]),
        (identifier, U, YH, HammersteinState, U[:200]),
        (lambda: identifier(method="correlated"), U, YH, HammersteinState, U[:200]),
        (LinearARX, U, YH, LinearFit, U[:200]),
    ],
    ids=["grid", "exact", "white", "correlated", "linear"],
)
def test_the_state_is_one_frozen_value_and_rebuilds_the_estimator(make, inputs, outputs, kind, q):
    est = make()
    with pytest.raises(NotFittedError, match="not fitted yet"):
        _ = est.state_
    params = est.get_params()
    est.fit(inputs, outputs)
    state = est.state_
    assert type(state) is kind and dataclasses.is_dataclass(state)
    with pytest.raises(dataclasses.FrozenInstanceError):
        state.params = {}  # type: ignore[misc]
    assert state.params.keys() == params.keys()
    for k, v in params.items():
        assert (
            np.array_equal(state.params[k], v)
            if isinstance(v, np.ndarray)
            else (state.params[k] == v)
        ), k
    again = type(est).from_state(state)
    assert again.state_ is state and again.get_params().keys() == params.keys()
    np.testing.assert_array_equal(again.predict(q), est.predict(q))


def test_the_correlated_baseline_reuses_the_identifiers_selection():
    est = identifier(method="correlated").fit(U, YH)
    base = est.baseline_
    assert base.state_.selection is est.selection_
    alone = LinearARX(max_order=10, validation_fraction=0.25).fit(U, YH)
    assert base.order_ == alone.order_
    np.testing.assert_array_equal(base.predict(U), alone.predict(U))


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_to_arrays_and_from_arrays_resume_exactly(family):
    make, first, then, whole = halves(family)
    est = make().partial_fit(*first)
    arrays = est.to_arrays()
    assert all(isinstance(v, np.ndarray) for v in arrays.values())
    resumed = type(est).from_arrays(arrays).partial_fit(*then)
    if family == "regression":
        q = np.linspace(0, 1, 3000)[::5]
        np.testing.assert_array_equal(resumed.predict(q), whole.predict(q))
    else:
        np.testing.assert_array_equal(resumed.impulse_response_, whole.impulse_response_)
        np.testing.assert_array_equal(resumed.nonlinearity_, whole.nonlinearity_)


@pytest.mark.parametrize(
    ("run", "match"),
    [
        (lambda: _phi(lambda u: u[:3]), r"'phi' .* must return an array of the input's shape"),
        (lambda: _phi(lambda u: u * np.nan), r"'phi' .* must return finite values"),
        (lambda: _kernel(lambda u: np.ones(3)), r"'kernel' .* must return shape \(2,\)"),
        (lambda: _kernel(lambda u: np.full(u.shape[0], np.inf)), "'kernel' .* finite values"),
    ],
)
def test_a_user_callable_that_returns_a_bad_array_is_named(run, match):
    from flexarm.errors import InvalidValueError

    with pytest.raises(InvalidValueError, match=match):
        run()


def _phi(phi):
    from flexarm.ident import simulate_hammerstein

    return simulate_hammerstein(phi, [0.5], [1.0], np.ones(10))


def _kernel(kernel):
    from flexarm.ident import SemiRecursiveKernelRegression

    return SemiRecursiveKernelRegression(kernel=kernel).fit([0.0, 1.0], [1.0, 2.0]).predict([0.5])
