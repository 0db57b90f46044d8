"""Prediction from data (initial conditions, k steps ahead), scores, the whiteness test, the
linear baseline, persistence of the correlated path, and bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import lfilter

from flexarm.ident import (
    ARMA,
    EXAMPLE_ARMA,
    HammersteinIdentifier,
    IdentificationWarning,
    LinearARX,
    NotFittedError,
    Saturation,
    fit_percent,
    r2_score,
    simulate_hammerstein,
    whiteness_test,
)
from flexarm.ident.hammerstein.prediction import predict_output
from flexarm.ident.hammerstein.white.correlation import solve
from flexarm.ident.regression.estimators import SemiRecursiveKernelRegression


def ar1(n, seed, c=0.9):
    e = np.random.default_rng(seed).standard_normal(n + 500)
    return lfilter([1.0], [1.0, -c], e)[500:]


# ----------------------------------------------------------------------------- prediction


ARMA2 = ARMA((1.2, -0.5), (1.0, 0.4, 0.2))


def one_step(arma, w, y, offset):
    """The one-step predictor written out: y_n = offset + sum a_i (y_{n-i} - offset) + sum b w."""
    p, q = arma.order
    out = y.copy()
    for n in range(max(p, q), len(y)):
        out[n] = offset + sum(arma.a[i - 1] * (y[n - i] - offset) for i in range(1, p + 1))
        out[n] += sum(arma.b[j] * w[n - j] for j in range(q + 1))
    return out


def test_k_step_prediction_closed_forms():
    rng = np.random.default_rng(0)
    w = rng.normal(size=400)
    y = ARMA2.filter(w) + 3.0 + 0.3 * rng.normal(size=400)  # noisy, offset 3
    one = predict_output(ARMA2, w, 3.0, y, 1, owner="t")
    np.testing.assert_allclose(one, one_step(ARMA2, w, y, 3.0), atol=1e-12)
    # k >= n: the free run from the initial conditions y[:m]
    free = predict_output(ARMA2, w, 3.0, y, None, owner="t")
    np.testing.assert_allclose(predict_output(ARMA2, w, 3.0, y, 1000, owner="t"), free)
    np.testing.assert_array_equal(free[:2], y[:2])
    # two steps = one step applied to the one-step predictions (the k-step recursion)
    two = predict_output(ARMA2, w, 3.0, y, 2, owner="t")
    mixed = one_step_from(ARMA2, w, y, one, 3.0)
    np.testing.assert_allclose(two[3:], mixed[3:], atol=1e-12)


def one_step_from(arma, w, y, pred, offset):
    """y_hat_{n|n-2}: the lag-1 output is the one-step prediction, lag 2 the measurement."""
    out = y.copy()
    a1, a2 = arma.a
    for n in range(2, len(y)):
        out[n] = offset + a1 * (pred[n - 1] - offset) + a2 * (y[n - 2] - offset)
        out[n] += sum(arma.b[j] * w[n - j] for j in range(3))
    return out


def test_noise_free_data_are_predicted_exactly_at_every_horizon():
    """A noise-free record from a non-rest state (a window of a longer run): the free run from
    its initial conditions and every k-step prediction reproduce it."""
    w = np.random.default_rng(1).normal(size=900)
    y = (ARMA2.filter(w) + 1.0)[300:]
    w = w[300:]
    for steps in (None, 1, 3, 50):
        # w before the window is unknown, so the first q outputs after m use zeros for it;
        # with b's lags inside the initial conditions the recursion is exact from m + q on
        pred = predict_output(ARMA2, w, 1.0, y, steps, owner="t")
        np.testing.assert_allclose(pred[4:], y[4:], atol=1e-9, err_msg=str(steps))


def test_predict_keeps_the_free_run_from_rest_without_y():
    phi, arma = Saturation(1.0, 1.5), EXAMPLE_ARMA["order2"]
    rng = np.random.default_rng(2)
    u = rng.uniform(-2, 2, 4000)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    est = HammersteinIdentifier().fit(u, y)
    w = est.nonlinearity(u)
    np.testing.assert_array_equal(est.predict(u), est.arma_.filter(w) + est.offset_)
    k1 = est.predict(u, y, steps_ahead=1)
    np.testing.assert_allclose(k1, one_step(est.arma_, w, y, est.offset_), atol=1e-10)
    assert est.max_lag_ == max(est.arma_.order)
    # one step ahead beats the free run, which beats nothing
    assert est.fit_percent(u, y, steps_ahead=1) > est.fit_percent(u, y) > 0


def test_score_is_r2_and_fit_percent_its_own_method():
    from sklearn.metrics import r2_score as sk_r2

    u = ar1(3000, 3)
    y = EXAMPLE_ARMA["order1"].filter(u) + 0.1 * np.random.default_rng(3).normal(size=3000)
    for model in (LinearARX().fit(u, y), HammersteinIdentifier().fit(u, y)):
        y_hat = model.predict(u)
        assert model.score(u, y) == pytest.approx(sk_r2(y, y_hat), rel=1e-12)
        assert model.fit_percent(u, y) == pytest.approx(fit_percent(y, y_hat), rel=1e-12)
        y2 = model.predict(u, y, steps_ahead=2)
        assert model.score(u, y, steps_ahead=2) == pytest.approx(sk_r2(y, y2), rel=1e-12)
    assert r2_score([1.0, 2.0, 3.0], [1.0, 2.0, 4.0]) == pytest.approx(0.5)


# ----------------------------------------------------------------------------- whiteness


def test_whiteness_statistics_match_statsmodels():
    from statsmodels.stats.diagnostic import acorr_ljungbox

    x = ar1(3000, 4, c=0.2)
    rep = whiteness_test(x, n_lags=12)
    peer = acorr_ljungbox(x, lags=[12], return_df=True)
    assert rep.ljung_box == pytest.approx(float(peer["lb_stat"].iloc[0]), rel=1e-10)
    assert rep.ljung_box_p == pytest.approx(float(peer["lb_pvalue"].iloc[0]), rel=1e-8)
    sq = (x - x.mean()) ** 2
    peer2 = acorr_ljungbox(sq, lags=[12], return_df=True)
    assert rep.mcleod_li == pytest.approx(float(peer2["lb_stat"].iloc[0]), rel=1e-10)


@pytest.mark.parametrize(
    ("name", "make", "white", "which"),
    [
        ("uniform", lambda n, r: r.uniform(-1, 1, n), True, ""),
        ("gaussian", lambda n, r: r.normal(size=n), True, ""),
        ("ar1", lambda n, r: ar1(n, 5), False, "coloured"),
        (
            "moving-average",
            lambda n, r: np.convolve(r.normal(size=n), [1, 1])[:n],
            False,
            "coloured",
        ),
        # uncorrelated but dependent: the amplitude follows the previous sample (ARCH(1))
        ("arch", lambda n, r: arch(n, r), False, "dependent"),
    ],
)
def test_whiteness_on_white_and_coloured_inputs(name, make, white, which):
    x = make(5000, np.random.default_rng(6))
    rep = whiteness_test(x)
    assert rep.white is white, rep.reason
    assert rep.n_lags == 20 and rep.alpha == 0.001
    if white:
        assert "looks white" in rep.reason
    else:
        assert which in rep.reason and "not white" in rep.reason
    if name == "ar1":
        assert rep.lag1 == pytest.approx(0.9, abs=0.02)
    if name == "arch":
        assert rep.ljung_box_p > 0.005  # no linear correlation to see
    est_path = "white" if white else "correlated"
    y = 0.5 * x + np.random.default_rng(7).normal(size=x.shape[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        assert HammersteinIdentifier().fit(x, y).method_ == est_path


def arch(n, rng):
    x = np.zeros(n)
    e = rng.normal(size=n)
    for k in range(1, n):
        x[k] = e[k] * np.sqrt(0.2 + 0.7 * x[k - 1] ** 2)
    return x


# ----------------------------------------------------------------------------- the white path


def test_white_path_is_the_papers_pieces_bit_for_bit():
    """method="auto" on a white input is method="white", which is the correlation approach
    on lag regressions each fitted alone (eq. 14 in grid mode, sample k of lag k paired with
    y[k:]): the same floating-point operations, so the same bits."""
    phi, arma = Saturation(1.0, 1.5), EXAMPLE_ARMA["order2"]
    rng = np.random.default_rng(8)
    u = rng.uniform(-2, 2, 6000)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    auto = HammersteinIdentifier(n_lags=20).fit(u, y)
    white = HammersteinIdentifier(n_lags=20, method="white").fit(u, y)
    assert auto.method_ == "white" and auto.whiteness_.white
    for name in ("impulse_response_", "nonlinearity_", "grid_", "shape_", "singular_values_"):
        np.testing.assert_array_equal(getattr(auto, name), getattr(white, name))
    lo, hi = u[:256].min(), u[:256].max()  # the grid: the warmup inputs' range, +10 % a side
    full = np.linspace(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), 101)
    h1 = auto.bandwidth_
    regs = [
        SemiRecursiveKernelRegression("epanechnikov", h1, 0.2, grid=full).fit(u[: 6000 - k], y[k:])
        for k in range(20)
    ]
    num = np.array([r.numerator_ for r in regs])
    den = np.array([r.denominator_ for r in regs])
    mean_y = float(np.cumsum(y)[-1] / y.shape[0])  # summed in order, as the stream does
    sol = solve(num, den, full, instrument="auto", known_points=None, order="bic",
                max_order=4, mean_y=mean_y, owner="t")  # fmt: skip
    np.testing.assert_array_equal(sol.grid, auto.grid_)
    np.testing.assert_array_equal(sol.impulse, auto.impulse_response_)
    np.testing.assert_array_equal(sol.nonlinearity, auto.nonlinearity_)
    assert sol.arma.model == auto.arma_ and sol.offset == auto.offset_


# ----------------------------------------------------------------------------- LinearARX


def test_linear_arx_recovers_an_output_error_system():
    arma = ARMA((1.2, -0.5), (0.5, 0.3, 0.0))
    u = ar1(6000, 9, c=0.5)
    y = arma.filter(u) + 2.0 + 0.05 * np.random.default_rng(9).normal(size=6000)
    model = LinearARX().fit(u, y)
    assert model.fit(u, y) is model and model.order_ == 2
    np.testing.assert_allclose(model.arma_.a, arma.a, atol=0.01)
    np.testing.assert_allclose(model.arma_.b, arma.b, atol=0.01)
    np.testing.assert_allclose(model.impulse_response_, arma.impulse_response(40), atol=0.02)
    assert model.selection_.linear.order == 2 and model.n_samples_ == 6000


def test_linear_arx_follows_the_estimator_contract():
    from sklearn.base import clone

    model = LinearARX(order=3, validation_fraction=0.2)
    assert clone(model).get_params() == model.get_params()
    assert repr(model) == "LinearARX(order=3, validation_fraction=0.2)"
    with pytest.raises(NotFittedError):
        model.predict(np.zeros(5))
    with pytest.raises(NotFittedError):
        _ = model.arma_


# ----------------------------------------------------------------------------- persistence


def test_correlated_path_saves_and_loads(tmp_path):
    phi, arma = Saturation(1.0, 1.5), EXAMPLE_ARMA["order2"]
    rng = np.random.default_rng(10)
    u = ar1(6000, 10)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    est = HammersteinIdentifier(known_points=((0.0, 0.0), (1.5, 1.0))).fit(u, y)
    est.save(tmp_path / "h.npz")
    back = HammersteinIdentifier.load(tmp_path / "h.npz")
    assert back.method_ == "correlated" and back.get_params() == est.get_params()
    np.testing.assert_array_equal(back.predict(u[:500]), est.predict(u[:500]))
    np.testing.assert_array_equal(back.predict(u, y, 3), est.predict(u, y, 3))
    np.testing.assert_array_equal(back.nonlinearity_, est.nonlinearity_)
    assert back.report_ == est.report_ and back.n_samples_ == 6000
    assert back.whiteness_.lag1 == est.whiteness_.lag1
    np.testing.assert_array_equal(back.baseline_.predict(u), est.baseline_.predict(u))
    with pytest.raises(ValueError, match=r"'method' parameter .* partial_fit"):
        back.partial_fit(u, y)
    with pytest.raises(AttributeError, match="white-input path only"):
        _ = back.bandwidth_


# ----------------------------------------------------------------------------- bad input

GOOD_U = ar1(1000, 11)
GOOD_Y = np.convolve(GOOD_U, [1.0, 0.5])[:1000]


@pytest.mark.parametrize(
    ("kwargs", "u", "y", "exc", "match"),
    [
        ({}, GOOD_U[:60], GOOD_Y[:60], ValueError, r"'u' parameter .* at least 100 samples"),
        ({}, np.full(1000, 2.0), GOOD_Y, ValueError, "'u' parameter .* must vary"),
        ({}, GOOD_U, np.zeros(1000), ValueError, "'y' parameter .* must vary"),
        ({}, np.r_[GOOD_U[:-1], np.nan], GOOD_Y, ValueError, "'u' parameter .* finite"),
        ({}, GOOD_U, np.r_[np.nan, GOOD_Y[1:]], ValueError, "'y' parameter .* finite"),
        ({}, GOOD_U + 0j, GOOD_Y, TypeError, "'u' parameter .* real"),
        ({"method": "colour"}, GOOD_U, GOOD_Y, ValueError, "'method' parameter .* one of"),
        ({"n_knots": 1}, GOOD_U, GOOD_Y, ValueError, "'n_knots' parameter .* >= 2"),
        ({"n_knots": "many"}, GOOD_U, GOOD_Y, ValueError, "'n_knots' parameter"),
        ({"validation_fraction": 0.7}, GOOD_U, GOOD_Y, ValueError, "'validation_fraction'"),
        ({"alpha": 1.5}, GOOD_U, GOOD_Y, ValueError, "'alpha' parameter .* in \\(0, 1\\)"),
        ({"order": "bic"}, GOOD_U, GOOD_Y, ValueError, "'order' parameter .* correlated-input"),
        ({"order": "aicc"}, GOOD_U, GOOD_Y, ValueError, "'order' parameter"),
        ({"max_order": -1}, GOOD_U, GOOD_Y, ValueError, "'max_order' parameter"),
    ],
)
def test_bad_input_is_named(kwargs, u, y, exc, match):
    with pytest.raises(exc, match=match):
        HammersteinIdentifier(**kwargs).fit(u, y)


@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (lambda m: m.predict(GOOD_U, steps_ahead=2), ValueError, "'y' parameter .* steps_ahead"),
        (lambda m: m.predict(GOOD_U, GOOD_Y, steps_ahead=0), ValueError, "'steps_ahead'.*>= 1"),
        (lambda m: m.predict(GOOD_U, GOOD_Y[:10]), ValueError, "'y' parameter .* shape"),
        (lambda m: m.predict(GOOD_U, GOOD_Y, steps_ahead=1.5), TypeError, "'steps_ahead'"),
        (lambda m: m.bands(GOOD_U[:500], GOOD_Y[:500]), ValueError, "'u' parameter .* fitted"),
        (lambda m: m.bands(GOOD_U, GOOD_Y, n_boot=3), ValueError, "'n_boot' parameter"),
        (lambda m: m.bands(GOOD_U, GOOD_Y, level=1.0), ValueError, "'level' parameter"),
    ],
)
def test_bad_prediction_input_is_named(call, exc, match):
    model = HammersteinIdentifier().fit(GOOD_U, GOOD_Y)
    with pytest.raises(exc, match=match):
        call(model)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"u": GOOD_U[:50], "y": GOOD_Y[:50]}, "at least 100 samples"),
        ({"u": np.ones(500), "y": GOOD_Y[:500]}, "'u' parameter of LinearARX must vary"),
        ({"u": GOOD_U, "y": GOOD_Y, "order": 0}, "'order' parameter of LinearARX"),
    ],
)
def test_linear_arx_bad_input(kwargs, match):
    params = {k: kwargs.pop(k) for k in list(kwargs) if k not in ("u", "y")}
    with pytest.raises(ValueError, match=match):
        LinearARX(**params).fit(kwargs["u"], kwargs["y"])


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((np.arange(10.0),), "at least 20 samples"),
        ((np.ones(100),), "must vary"),
        ((GOOD_U, 600), "'n_lags' parameter .* < n / 2"),
        ((GOOD_U, 5, 0.0), "'alpha' parameter"),
    ],
)
def test_whiteness_test_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        whiteness_test(*args)
