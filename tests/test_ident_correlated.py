"""Hammerstein identification for correlated inputs against the truth.

Simulated Hammerstein systems in the paper's noise model (``W_n = phi(X_n) + xi_n``)
driven by a sine sweep over 0.001-0.4 cycles/sample, a random-phase multisine
and AR(1) noise with coefficient 0.9; the identifier chooses its path, order and
knots from the data. The accuracy asked of it: phi within 0.06 after an
affine fit for a saturation (0.1 for the others, the white path's own test bar
in ``test_ident_hammerstein.py``) and an impulse-response cosine of at least 0.99.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from flexarm.ident import (
    EXAMPLE_ARMA,
    Cubic,
    DeadZone,
    HammersteinIdentifier,
    IdentificationWarning,
    Quantizer,
    Saturation,
    simulate_hammerstein,
)
from helpers.ident import ar1, multisine, scaled, sweep

N = 20_000


INPUTS = {"sweep": sweep, "multisine": multisine, "ar1": ar1}
PHIS = {
    "saturation": (Saturation(1.0, 1.5), 0.06),
    "deadzone-jump": (DeadZone(0.5, 1.0, jump=0.3), 0.1),
    "quantizer": (Quantizer(0.5), 0.1),
    "even-square": (Cubic(0.0, 0.0, 1.0, 0.0), 0.1),
}
ARMAS = {"saturation": "order1", "deadzone-jump": "order2", "quantizer": "order3"}


def errors(est, phi, arma, u):
    """phi's RMS error on the central 98 % of the inputs after the best affine map, and the
    cosine between the impulse responses (the map's scale divided out of lambda)."""
    x = np.linspace(*np.quantile(u, [0.01, 0.99]), 200)
    est_phi = est.nonlinearity(x)
    s, t = np.linalg.lstsq(np.c_[est_phi, np.ones_like(x)], phi(x), rcond=None)[0]
    lam = est.impulse_response_ / s
    true = arma.impulse_response(lam.shape[0])
    cosine = float(lam @ true / np.linalg.norm(lam) / np.linalg.norm(true))
    return float(np.sqrt(np.mean((s * est_phi + t - phi(x)) ** 2))), cosine


@pytest.mark.parametrize("colour", sorted(INPUTS))
@pytest.mark.parametrize("phi_name", sorted(PHIS))
def test_recovery_on_correlated_inputs(phi_name, colour):
    phi, bar = PHIS[phi_name]
    arma = EXAMPLE_ARMA[ARMAS.get(phi_name, "order2")]
    rng = np.random.default_rng(17)
    u = INPUTS[colour](N, rng)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    est = HammersteinIdentifier().fit(u, y)
    assert est.method_ == "correlated" and not est.whiteness_.white
    e_phi, cosine = errors(est, phi, arma, u)
    assert e_phi <= bar, (e_phi, est.report_.structure["order"], est.report_.structure["n_knots"])
    assert cosine >= 0.99, cosine
    # chosen from the data, and reported: the order and knots, on held-out blocks
    st = est.report_.structure
    assert st["chosen_by"] == "held-out" and st["n_knots"] == est.grid_.shape[0] > 2
    assert st["selection"]["nonlinear_helps"] and est.report_.nonlinear_helps
    assert est.report_.fit_percent > est.report_.baseline["fit_percent"]


def test_sign_is_fixed_by_the_impulse_response():
    """phi and lambda share a sign: the largest impulse-response entry is +1, whatever the
    sign of the data (y -> -y flips phi, not lambda)."""
    phi, arma = Saturation(1.0, 1.5), EXAMPLE_ARMA["order2"]
    rng = np.random.default_rng(3)
    u = ar1(8000, rng)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.1, rng=rng)
    a = HammersteinIdentifier(n_knots=8, order=2).fit(u, y)
    b = HammersteinIdentifier(n_knots=8, order=2).fit(u, -y)
    assert np.max(np.abs(a.impulse_response_)) == pytest.approx(1.0)
    assert a.impulse_response_[np.argmax(np.abs(a.impulse_response_))] == pytest.approx(1.0)
    np.testing.assert_allclose(b.impulse_response_, a.impulse_response_, atol=1e-9)
    np.testing.assert_allclose(b.nonlinearity_, -a.nonlinearity_, atol=1e-9)
    assert np.corrcoef(a.nonlinearity(u[:500]), phi(u[:500]))[0, 1] > 0.99


def test_known_points_fix_phi_absolutely_on_the_correlated_path():
    phi, arma = DeadZone(0.5, 1.0, jump=0.3), EXAMPLE_ARMA["order2"]
    rng = np.random.default_rng(5)
    u = multisine(N, rng)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    known = ((0.0, 0.0), (1.8, float(phi(1.8))))
    est = HammersteinIdentifier(known_points=known).fit(u, y)
    assert est.method_ == "correlated"
    np.testing.assert_allclose(est.nonlinearity([0.0, 1.8]), [0.0, float(phi(1.8))], atol=1e-9)
    x = np.linspace(-1.9, 1.9, 200)
    assert np.sqrt(np.mean((est.nonlinearity(x) - phi(x)) ** 2)) < 0.1
    lam = est.impulse_response_
    true = arma.impulse_response(lam.shape[0])
    assert np.linalg.norm(lam - true) / np.linalg.norm(true) < 0.05
    # the model reproduces noise-free fresh data
    u_new = multisine(5000, np.random.default_rng(6))
    y_new = simulate_hammerstein(phi, arma.a, arma.b, u_new)
    assert est.fit_percent(u_new, y_new) > 90


def test_wiener_system_does_not_fall_apart():
    """A Wiener system (the nonlinearity at the output) driven by a periodic sweep: the
    Hammerstein structure cannot help, so the identifier keeps the linear baseline's free-run
    error (within 10 %) on fresh data and says the nonlinear model does not help."""
    period = 2000
    k = np.arange(period)
    one = np.sin(2 * np.pi * (0.001 * k + 0.5 * (0.4 - 0.001) * k**2 / period))
    u = scaled(np.tile(one, 13))
    arma = EXAMPLE_ARMA["order2"]
    x = arma.filter(u)
    x /= np.std(x)
    rng = np.random.default_rng(8)
    y = Saturation(1.0)(x) + 0.05 * rng.standard_normal(u.shape[0])
    n = 20_000
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        est = HammersteinIdentifier().fit(u[:n], y[:n])
    err = np.sqrt(np.mean((y[n:] - est.predict(u)[n:]) ** 2))
    base = np.sqrt(np.mean((y[n:] - est.baseline_.predict(u)[n:]) ** 2))
    assert err <= 1.1 * base, (err, base)
    assert not est.report_.nonlinear_helps
    assert est.report_.structure["n_knots"] == 2  # the baseline's structure


def test_linear_system_keeps_the_linear_model():
    """No input nonlinearity: the chosen structure is the baseline's (two knots, same order)
    and its predictions equal the baseline's."""
    arma = EXAMPLE_ARMA["order2"]
    rng = np.random.default_rng(9)
    u = ar1(8000, rng)
    y = simulate_hammerstein(lambda v: 1.5 * v, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    est = HammersteinIdentifier().fit(u, y)
    assert est.grid_.shape[0] == 2 and not est.report_.nonlinear_helps
    assert est.order_ == est.baseline_.order_
    u_new = ar1(3000, np.random.default_rng(10))
    np.testing.assert_allclose(est.predict(u_new), est.baseline_.predict(u_new), atol=1e-9)


def test_white_path_forced_on_a_coloured_input_warns():
    phi, arma = Saturation(1.0, 1.5), EXAMPLE_ARMA["order1"]
    rng = np.random.default_rng(11)
    u = ar1(4000, rng)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.1, rng=rng)
    with pytest.warns(IdentificationWarning, match="forced on an input that is not white"):
        est = HammersteinIdentifier(method="white").fit(u, y)
    assert est.method_ == "white" and est.report_.requested == "white"
    assert "not white" in est.report_.reason and est.report_.warnings


def test_model_that_loses_to_its_baseline_is_flagged():
    """1000 white samples: the white path's kernel estimates are too rough to beat a linear
    ARX on this mildly nonlinear system; the report and a warning say so."""
    phi, arma = Quantizer(0.5), EXAMPLE_ARMA["order1"]
    rng = np.random.default_rng(1)
    u = rng.uniform(-2.0, 2.0, 1000)
    y = simulate_hammerstein(phi, arma.a, arma.b, u, noise_std=0.2, rng=rng)
    with pytest.warns(IdentificationWarning, match="below its linear baseline"):
        est = HammersteinIdentifier().fit(u, y)
    rep = est.report_
    assert est.method_ == "white" and rep.loses_to_baseline
    assert rep.fit_percent == pytest.approx(est.fit_percent(u, y))
    assert rep.baseline["fit_percent"] == pytest.approx(est.baseline_.fit_percent(u, y))
    assert rep.fit_percent < rep.baseline["fit_percent"] and not rep.nonlinear_helps
