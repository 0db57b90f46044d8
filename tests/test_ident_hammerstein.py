"""Hammerstein systems and their identification (paper §5) against closed forms and truth."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from flexarm.ident import (
    ARMA,
    EXAMPLE_ARMA,
    Cubic,
    DeadZone,
    HammersteinIdentifier,
    HardLimiter,
    NotFittedError,
    PiecewiseLinear,
    Quantizer,
    Saturation,
    Sign,
    arma_from_impulse_response,
    fit_percent,
    simulate_hammerstein,
    two_point_normalisation,
)

# ----------------------------------------------------------------------------- nonlinearities


def test_nonlinearities_closed_forms():
    x = np.array([-2.0, -0.6, -0.5, -0.2, 0.0, 0.24, 0.25, 0.5, 0.7, 3.0])
    np.testing.assert_array_equal(
        Saturation(1.0, 2.0)(x), [-1, -1, -1, -0.4, 0, 0.48, 0.5, 1, 1, 1]
    )
    dz = DeadZone(0.5, 2.0, jump=0.1)(x)
    np.testing.assert_allclose(dz, [-3.1, -0.3, 0, 0, 0, 0, 0, 0, 0.5, 5.1], atol=1e-15)
    np.testing.assert_array_equal(Quantizer(0.5)(x), [-2, -0.5, -0.5, 0, 0, 0, 0.5, 0.5, 0.5, 3])
    np.testing.assert_array_equal(HardLimiter(-1, 3, 0.25)(x), [-1] * 6 + [3] * 4)
    np.testing.assert_array_equal(Sign(2.0)(x), [-2] * 4 + [0] + [2] * 5)
    np.testing.assert_allclose(Cubic(1.0, -1.0, 0.5, 2.0)(x), 1 - x + 0.5 * x**2 + 2 * x**3)
    pw = PiecewiseLinear((-1.0, 0.0, 2.0), (2.0, 0.0, 1.0))
    np.testing.assert_allclose(pw([-3.0, -0.5, 1.0, 4.0]), [6.0, 1.0, 0.5, 2.0])


@pytest.mark.parametrize(
    "phi",
    [Saturation(), DeadZone(), Quantizer(), HardLimiter(), Sign(), Cubic(), PiecewiseLinear()],
    ids=lambda p: type(p).__name__,
)
def test_nonlinearities_are_vectorised_and_frozen(phi):
    x = np.linspace(-2, 2, 12).reshape(3, 4)
    out = phi(x)
    assert out.shape == x.shape and out.dtype == np.float64
    np.testing.assert_array_equal(out.ravel(), [float(phi(v)) for v in x.ravel()])
    with pytest.raises(AttributeError):
        phi.foo = 1  # frozen dataclass


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: Saturation(limit=-1.0), "'limit' parameter of Saturation must be > 0"),
        (lambda: DeadZone(width=-0.1), "'width' parameter of DeadZone must be >= 0"),
        (lambda: Quantizer(step=0.0), "'step' parameter of Quantizer must be > 0"),
        (lambda: HardLimiter(1.0, 0.0), "'high' parameter of HardLimiter"),
        (lambda: PiecewiseLinear((0.0, 0.0), (1.0, 2.0)), "'breakpoints' parameter"),
        (lambda: PiecewiseLinear((0.0, 1.0), (1.0,)), "'values' parameter"),
    ],
)
def test_nonlinearity_parameters_checked(make, match):
    with pytest.raises(ValueError, match=match):
        make()


# ----------------------------------------------------------------------------- ARMA / simulation


def direct_hammerstein(phi, a, b, u, xi):
    """The difference equation written out, one sample at a time."""
    w = phi(u) + xi
    y = np.zeros(len(u))
    for n in range(len(u)):
        acc = sum(a[i - 1] * y[n - i] for i in range(1, len(a) + 1) if n - i >= 0)
        acc += sum(b[j] * w[n - j] for j in range(len(b)) if n - j >= 0)
        y[n] = acc
    return y


@pytest.mark.parametrize("name", sorted(EXAMPLE_ARMA))
def test_simulate_hammerstein_matches_difference_equation(name):
    arma = EXAMPLE_ARMA[name]
    u = np.random.default_rng(0).normal(size=300)
    phi = DeadZone(0.3, 1.5, jump=0.2)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.3, rng=7)
    xi = 0.3 * np.random.default_rng(7).standard_normal(300)
    np.testing.assert_allclose(y, direct_hammerstein(phi, arma.a, arma.b, u, xi), atol=1e-12)
    np.testing.assert_array_equal(y, simulate_hammerstein(phi, arma.a, arma.b, u, 0.3, rng=7))


def test_arma_closed_forms():
    k = np.arange(10)
    np.testing.assert_allclose(ARMA((0.6,), (2.0,)).impulse_response(10), 2 * 0.6**k)
    # two real poles 0.5 and 0.2: lambda_k = (0.5**(k+1) - 0.2**(k+1)) / 0.3
    arma = ARMA((0.7, -0.1), (1.0,))
    np.testing.assert_allclose(arma.impulse_response(10), (0.5 ** (k + 1) - 0.2 ** (k + 1)) / 0.3)
    assert arma.dc_gain == pytest.approx(1 / (1 - 0.7 + 0.1))
    np.testing.assert_allclose(sorted(arma.poles.real), [0.2, 0.5])
    assert arma.order == (2, 0)


@pytest.mark.parametrize("a", [(1.0,), (1.2,), (0.5, 0.6), (0.0, 0.0, 1.0)])
def test_unstable_arma_rejected(a):
    with pytest.raises(ValueError, match=r"'a' parameter of ARMA must give a stable"):
        ARMA(a, (1.0,))
    with pytest.raises(ValueError, match=r"'a' parameter of simulate_hammerstein must give"):
        simulate_hammerstein(Saturation(), a, (1.0,), np.zeros(10))


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"b": (0.0, 0.0)}, ValueError, "'b' parameter of simulate_hammerstein must not be all"),
        ({"u": [1.0, np.nan]}, ValueError, "'u' parameter of simulate_hammerstein must be finite"),
        ({"u": []}, ValueError, "'u' parameter of simulate_hammerstein must hold at least 1"),
        ({"noise_std": -1.0}, ValueError, "'noise_std' parameter of simulate_hammerstein"),
        ({"phi": 3.0}, TypeError, "'phi' parameter of simulate_hammerstein must be a callable"),
        ({"phi": lambda x: x[:1]}, ValueError, "'phi' parameter .* must return an array"),
        ({"rng": "seed"}, TypeError, "'rng' parameter of simulate_hammerstein"),
    ],
)
def test_simulate_hammerstein_bad_input(kwargs, exc, match):
    args = {"phi": Saturation(), "a": (0.5,), "b": (1.0,), "u": np.ones(5)}
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        simulate_hammerstein(**args)


# ----------------------------------------------------------------------------- ARMA from lambda


@pytest.mark.parametrize(
    ("a", "b"),
    [((0.6,), (1.0, 0.5)), ((1.2, -0.5), (1.0, 0.4, -0.2)), ((0.9, -0.5, 0.2), (0.5, 0, 0, 0.3))],
)
def test_arma_from_exact_impulse_response(a, b):
    h = ARMA(a, b).impulse_response(40)
    fit = arma_from_impulse_response(h, max_order=4)
    assert fit.order == len(a)
    np.testing.assert_allclose(fit.model.a, a, atol=1e-6)
    np.testing.assert_allclose(fit.model.b, b, atol=1e-6)


def test_arma_from_impulse_response_bad_input():
    with pytest.raises(ValueError, match="'h' parameter of arma_from_impulse_response must hold"):
        arma_from_impulse_response(np.ones(5), max_order=4)
    with pytest.raises(ValueError, match="'order' parameter of arma_from_impulse_response"):
        arma_from_impulse_response(np.ones(20), order="aicc")


# ----------------------------------------------------------------------------- identification


def hammerstein_data(phi, arma, n, seed, noise=0.2):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-2.0, 2.0, n)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=noise, rng=rng)
    return u, y


def errors(est, phi, arma, known):
    """RMS error of phi on [-1.9, 1.9] and relative error of lambda (affine-aligned if unknown)."""
    x = np.linspace(-1.9, 1.9, 200)
    est_phi = est.nonlinearity(x)
    lam = est.impulse_response_
    if not known:  # best affine map s * phi_hat + t onto the truth, lambda / s
        s, t = np.linalg.lstsq(np.c_[est_phi, np.ones_like(x)], phi(x), rcond=None)[0]
        est_phi, lam = s * est_phi + t, lam / s
    true_lam = arma.impulse_response(lam.shape[0])
    e_phi = float(np.sqrt(np.mean((est_phi - phi(x)) ** 2)))
    e_lam = float(np.linalg.norm(lam - true_lam) / np.linalg.norm(true_lam))
    return e_phi, e_lam


PHIS = {
    "saturation": Saturation(1.0, 1.5),
    "deadzone-jump": DeadZone(0.5, 1.0, jump=0.3),
    "quantizer": Quantizer(0.5),
    "even-square": Cubic(0.0, 0.0, 1.0, 0.0),
}


@pytest.mark.parametrize("order", [1, 2, 3])
@pytest.mark.parametrize("phi_name", sorted(PHIS))
def test_recovery_improves_with_n(phi_name, order):
    phi, arma = PHIS[phi_name], EXAMPLE_ARMA[f"order{order}"]
    u, y = hammerstein_data(phi, arma, 16000, seed=order)
    small = errors(HammersteinIdentifier().fit(u[:1000], y[:1000]), phi, arma, False)
    large = errors(HammersteinIdentifier().fit(u, y), phi, arma, False)
    assert large[0] < 0.6 * small[0], (small, large)
    assert large[1] < 0.6 * small[1], (small, large)
    assert large[0] < 0.1 and large[1] < 0.1, large


@pytest.mark.parametrize("phi_name", ["saturation", "deadzone-jump"])
def test_known_points_give_absolute_phi_and_lambda(phi_name):
    phi, arma = PHIS[phi_name], EXAMPLE_ARMA["order2"]
    x2 = 1.8
    known = ((0.0, 0.0), (x2, float(phi(x2))))
    u, y = hammerstein_data(phi, arma, 16000, seed=5)
    e_phi, e_lam = errors(HammersteinIdentifier(known_points=known).fit(u, y), phi, arma, True)
    assert e_phi < 0.1 and e_lam < 0.1, (e_phi, e_lam)


@pytest.mark.parametrize(("phi_name", "order"), [("deadzone-jump", 3), ("even-square", 2)])
def test_prediction_on_fresh_data(phi_name, order):
    phi, arma = PHIS[phi_name], EXAMPLE_ARMA[f"order{order}"]
    u, y = hammerstein_data(phi, arma, 16000, seed=11)
    est = HammersteinIdentifier().fit(u, y)
    u_new, _ = hammerstein_data(phi, arma, 3000, seed=12)
    y_new = simulate_hammerstein(phi, arma.a, arma.b, u_new)  # noise-free truth
    y_hat = est.predict(u_new)
    nrmse = np.linalg.norm(y_new - y_hat) / np.linalg.norm(y_new - y_new.mean())
    assert nrmse < 0.1, nrmse
    assert est.fit_percent(u_new, y_new) == pytest.approx(100 * (1 - nrmse))
    assert est.score(u_new, y_new) == pytest.approx(1 - nrmse**2)  # R², scikit-learn's score


def test_linear_model_fails_where_the_hammerstein_model_fits():
    phi, arma = PHIS["even-square"], EXAMPLE_ARMA["order2"]
    u, y = hammerstein_data(phi, arma, 16000, seed=11)
    u_new, _ = hammerstein_data(phi, arma, 3000, seed=12)
    y_new = simulate_hammerstein(phi, arma.a, arma.b, u_new)

    def lagged(v):
        return np.c_[
            np.array([np.r_[np.zeros(k), v[: len(v) - k]] for k in range(40)]).T, np.ones(len(v))
        ]

    coef = np.linalg.lstsq(lagged(u), y, rcond=None)[0]  # least-squares FIR on u
    assert fit_percent(y_new, lagged(u_new) @ coef) < 10
    assert HammersteinIdentifier().fit(u, y).fit_percent(u_new, y_new) > 90


def test_two_point_normalisation_closed_form():
    assert two_point_normalisation(5.0, -1.0, 2.0, -1.0) == (2.0, 1.0)
    phi, arma = PHIS["saturation"], EXAMPLE_ARMA["order1"]
    u, y = hammerstein_data(phi, arma, 4000, seed=2)
    x1, f1, x2, f2 = -0.4, -0.6, 1.2, 1.0
    est = HammersteinIdentifier(known_points=((x1, f1), (x2, f2))).fit(u, y)
    raw = HammersteinIdentifier().fit(u, y)
    grid, shape = est.grid_, est.shape_
    m1, m2 = np.interp([x1, x2], grid, shape)
    d1 = (m1 - m2) / (f1 - f2)  # paper §5
    alpha = m1 - d1 * f1
    np.testing.assert_allclose(est.nonlinearity_, (shape - alpha) / d1, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(est.nonlinearity([x1, x2]), [f1, f2], atol=1e-12)
    # the same data without known points: phi up to an affine map, lambda scaled inversely
    np.testing.assert_array_equal(raw.shape_, shape)
    c = est.impulse_response_[0] / raw.impulse_response_[0]
    np.testing.assert_allclose(est.impulse_response_, c * raw.impulse_response_, rtol=1e-12)
    np.testing.assert_allclose(
        est.nonlinearity_, raw.nonlinearity_ / c - alpha / d1, rtol=1e-10, atol=1e-10
    )
    assert np.max(np.abs(raw.impulse_response_)) == pytest.approx(1.0)


def test_even_nonlinearity_needs_a_nonlinear_instrument():
    phi, arma = PHIS["even-square"], EXAMPLE_ARMA["order1"]
    u, y = hammerstein_data(phi, arma, 16000, seed=3)
    good = errors(HammersteinIdentifier(instrument="auto").fit(u, y), phi, arma, False)
    paper = errors(HammersteinIdentifier(instrument="regression").fit(u, y), phi, arma, False)
    bad = errors(HammersteinIdentifier(instrument="input").fit(u, y), phi, arma, False)
    assert good[1] < 0.1 and paper[1] < 0.1
    assert bad[1] > 0.5  # cov(phi(X), X) = 0: the input is no instrument here


def test_delayed_linear_part_needs_the_joint_instrument():
    phi, arma = PHIS["saturation"], ARMA((0.5,), (0.0, 1.0))  # b0 = 0: m_0 is constant
    u, y = hammerstein_data(phi, arma, 16000, seed=4)
    good = errors(HammersteinIdentifier().fit(u, y), phi, arma, False)
    paper = errors(HammersteinIdentifier(instrument="regression").fit(u, y), phi, arma, False)
    assert good[0] < 0.1 and good[1] < 0.1
    assert paper[1] > 2 * good[1]


def test_scale_free_defaults():
    phi, arma = PHIS["deadzone-jump"], EXAMPLE_ARMA["order2"]
    u, y = hammerstein_data(phi, arma, 8000, seed=6)
    a = HammersteinIdentifier().fit(u, y)
    b = HammersteinIdentifier().fit(1e-3 * u, 1e4 * y)  # other units
    np.testing.assert_allclose(b.grid_, 1e-3 * a.grid_, rtol=1e-12)
    np.testing.assert_allclose(b.nonlinearity_, 1e4 * a.nonlinearity_, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(b.impulse_response_, a.impulse_response_, rtol=1e-6, atol=1e-9)


def test_streaming_equals_batch():
    phi, arma = PHIS["quantizer"], EXAMPLE_ARMA["order2"]
    u, y = hammerstein_data(phi, arma, 6000, seed=8)
    batch = HammersteinIdentifier(n_lags=20).fit(u, y)
    stream = HammersteinIdentifier(n_lags=20)
    cuts = np.r_[0, 3, 3, 90, 250, 251, 270, 1000, 4321, 6000]
    for lo, hi in itertools.pairwise(cuts):
        stream.partial_fit(u[lo:hi], y[lo:hi])
    assert stream.n_samples_ == batch.n_samples_ == 6000
    for name in ("impulse_response_", "nonlinearity_", "shape_", "grid_", "singular_values_"):
        np.testing.assert_array_equal(getattr(stream, name), getattr(batch, name))
    assert stream.arma_ == batch.arma_ and stream.offset_ == batch.offset_
    np.testing.assert_array_equal(stream.predict(u[:500]), batch.predict(u[:500]))


def test_not_fitted_and_warmup():
    est = HammersteinIdentifier()
    with pytest.raises(NotFittedError):
        est.predict(np.zeros(3))
    est.partial_fit(np.random.default_rng(0).normal(size=100), np.ones(100))
    with pytest.raises(NotFittedError, match="not fitted yet"):
        _ = est.impulse_response_
    assert est.n_samples_ == 100


def test_params_contract():
    est = HammersteinIdentifier(n_lags=30, instrument="input")
    assert est.get_params()["n_lags"] == 30
    assert repr(est) == "HammersteinIdentifier(instrument='input', n_lags=30)"
    assert est.set_params(decay=0.3) is est and est.decay == 0.3
    with pytest.raises(ValueError, match="Invalid parameter 'foo'"):
        est.set_params(foo=1)
    with pytest.raises(TypeError, match="foo"):
        HammersteinIdentifier(foo=1)  # type: ignore[call-arg]
    u, y = hammerstein_data(PHIS["saturation"], EXAMPLE_ARMA["order1"], 600, seed=1)
    est.partial_fit(u, y)
    est.set_params(n_lags=10)
    with pytest.raises(ValueError, match=r"\['n_lags'\] parameter\(s\) of HammersteinIdentifier"):
        est.partial_fit(u, y)


GOOD_U = np.random.default_rng(0).uniform(-1, 1, 1000)
GOOD_Y = np.convolve(GOOD_U, [1.0, 0.5])[:1000]


@pytest.mark.parametrize(
    ("kwargs", "u", "y", "exc", "match"),
    [
        ({}, GOOD_U, GOOD_Y[:999], ValueError, r"'y' parameter .* length of u \(1000\)"),
        (
            {"method": "white"},
            GOOD_U[:200],
            GOOD_Y[:200],
            ValueError,
            r"'u' parameter .* at least 256 samples \(max\(warmup, 4 \* n_lags\)\)",
        ),
        ({}, GOOD_U[:99], GOOD_Y[:99], ValueError, "'u' parameter .* at least 100 samples"),
        ({}, np.ones(1000), GOOD_Y, ValueError, "'u' parameter of HammersteinIdentifier must vary"),
        ({}, GOOD_U, np.ones(1000), ValueError, "'y' parameter of HammersteinIdentifier must vary"),
        ({}, np.r_[np.nan, GOOD_U[1:]], GOOD_Y, ValueError, "'u' parameter .* finite"),
        ({}, GOOD_U, np.r_[GOOD_Y[:-1], np.inf], ValueError, "'y' parameter .* finite"),
        ({}, GOOD_U.reshape(2, 500), GOOD_Y, ValueError, r"'u' parameter .* shape \(n,\)"),
        ({"instrument": "x"}, GOOD_U, GOOD_Y, ValueError, "'instrument' parameter .* one of"),
        ({"order": "aicc"}, GOOD_U, GOOD_Y, ValueError, "'order' parameter"),
        ({"order": 30}, GOOD_U, GOOD_Y, ValueError, "'n_lags' parameter .* >= 2 \\* order"),
        ({"kernel": "cosine"}, GOOD_U, GOOD_Y, ValueError, "'kernel' parameter"),
        ({"bandwidth": -1.0}, GOOD_U, GOOD_Y, ValueError, "'bandwidth' parameter .* > 0"),
        ({"bandwidth": "scott"}, GOOD_U, GOOD_Y, ValueError, "'bandwidth' parameter.*silverman"),
        ({"bandwidth": None}, GOOD_U, GOOD_Y, TypeError, "'bandwidth' parameter"),
        ({"decay": 2.0}, GOOD_U, GOOD_Y, ValueError, "'decay' parameter .* <= 1"),
        ({"n_lags": 0}, GOOD_U, GOOD_Y, ValueError, "'n_lags' parameter .* >= 1"),
        ({"n_lags": 2.5}, GOOD_U, GOOD_Y, TypeError, "'n_lags' parameter .* integer"),
        ({"known_points": (1, 2)}, GOOD_U, GOOD_Y, ValueError, "'known_points' parameter"),
        ({"known_points": ((0, 0), (0, 1))}, GOOD_U, GOOD_Y, ValueError, "x1 != x2"),
        ({"known_points": ((0, 0), (9, 1))}, GOOD_U, GOOD_Y, ValueError, "within the input"),
    ],
)
def test_bad_input_rejected(kwargs, u, y, exc, match):
    with pytest.raises(exc, match=match):
        HammersteinIdentifier(**kwargs).fit(u, y)


@pytest.mark.parametrize("stop", [100, 255, 256, 3001], ids=lambda n: f"after{n}")
def test_save_load_resumes_bit_for_bit(tmp_path, stop):
    """Saved during the warmup (100, 255 samples) or after it, resumed from the file: the
    same model as never stopping (the lag regressions go through their state description)."""
    phi, arma = PHIS["saturation"], EXAMPLE_ARMA["order2"]
    u, y = hammerstein_data(phi, arma, 6000, seed=9)
    kw = {"n_lags": 20, "known_points": ((0.0, 0.0), (1.5, float(phi(1.5)))), "order": "aic"}
    never_stopped = HammersteinIdentifier(**kw).fit(u, y)
    first = HammersteinIdentifier(**kw).partial_fit(u[:stop], y[:stop])
    first.save(tmp_path / "h.npz")
    resumed = HammersteinIdentifier.load(tmp_path / "h.npz")
    assert resumed.get_params() == first.get_params() and resumed.n_samples_ == stop
    resumed.partial_fit(u[stop:], y[stop:])
    for name in ("impulse_response_", "nonlinearity_", "grid_", "singular_values_"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(never_stopped, name))
    assert resumed.arma_ == never_stopped.arma_ and resumed.offset_ == never_stopped.offset_
    assert resumed.bandwidth_ == never_stopped.bandwidth_


def test_save_load_keeps_a_bandwidth_rule_and_refuses_other_files(tmp_path):
    from flexarm.ident import Silverman

    u, y = hammerstein_data(PHIS["quantizer"], EXAMPLE_ARMA["order1"], 2000, seed=2)
    est = HammersteinIdentifier(n_lags=12, bandwidth=Silverman(0.4)).fit(u, y)
    est.save(tmp_path / "h.npz")
    back = HammersteinIdentifier.load(tmp_path / "h.npz")
    assert back.bandwidth == Silverman(0.4) and back.bandwidth_ == est.bandwidth_
    np.testing.assert_array_equal(back.predict(u[:50]), est.predict(u[:50]))
    with pytest.raises(NotFittedError):
        HammersteinIdentifier().save(tmp_path / "none.npz")
    from flexarm.ident import SemiRecursiveKernelRegression

    SemiRecursiveKernelRegression().fit(u, y).save(tmp_path / "other.npz")
    with pytest.raises(ValueError, match=r"'path'.*HammersteinIdentifier\.save"):
        HammersteinIdentifier.load(tmp_path / "other.npz")
