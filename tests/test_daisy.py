"""The DaISy flexible robot arm (real data): examples/identify_daisy.py on the shared record.

The record is read from ``$FLEXARM_DATA/robot_arm.dat`` when the environment
variable names the data directory, else from ``<repository>/../shared/data``;
the tests that need it are skipped where it is absent (the data are never
copied into the project).
"""

from __future__ import annotations

import importlib.util
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from flexarm.ident import ARMA, HammersteinIdentifier, IdentificationWarning, fit_percent

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "identify_daisy.py"
DATA_DIR = os.environ.get("FLEXARM_DATA") or ROOT.parent / "shared" / "data"
DATA = pathlib.Path(DATA_DIR) / "robot_arm.dat"


def _example():
    spec = importlib.util.spec_from_file_location("identify_daisy", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ex = _example()
needs_data = pytest.mark.skipif(
    not DATA.is_file(),
    reason=f"DaISy robot_arm.dat not found at {DATA} (shared/data absent; set FLEXARM_DATA)",
)


def test_arx_recovers_a_known_arma_exactly():
    true = ARMA((1.5, -0.7), (0.0, 1.0, 0.5))
    u = np.random.default_rng(0).normal(size=400)
    model = ex.arx(u, true.filter(u), 2)
    np.testing.assert_allclose(model.a, true.a, atol=1e-10)
    np.testing.assert_allclose(model.b, true.b, atol=1e-10)


def test_cross_covariance_is_the_impulse_response_for_white_input_only():
    true = ARMA((0.8,), (1.0,))
    rng = np.random.default_rng(1)
    white = rng.normal(size=200_000)
    lam = ex.cross_covariance(white, true.filter(white), 10)
    # standard error sqrt(sum lambda**2 / n) = 0.004: allow five
    np.testing.assert_allclose(lam, 0.8 ** np.arange(10), atol=0.02)
    coloured = np.convolve(white, np.ones(5) / 5)[: white.shape[0]]  # lag-1 correlation 0.8
    lam_c = ex.cross_covariance(coloured, true.filter(coloured), 10)
    # closed form: sum_j lambda_j rho(k - j), rho the triangle autocorrelation of the average
    rho = {d: (5 - abs(d)) / 5 for d in range(-4, 5)}
    expected = [sum(0.8**j * rho.get(k - j, 0.0) for j in range(60)) for k in range(10)]
    np.testing.assert_allclose(lam_c, expected, atol=0.03)
    assert np.max(np.abs(lam_c - 0.8 ** np.arange(10))) > 1.0


def test_missing_file_is_reported(tmp_path):
    res = subprocess.run(
        [sys.executable, str(EXAMPLE), str(tmp_path / "none.dat")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert res.returncode == 2
    assert "not found" in res.stderr and "Traceback" not in res.stderr


@needs_data
def test_daisy_linear_part_and_free_run_fit():
    u, y = ex.load_daisy(DATA)
    assert u.shape == y.shape == (1024,)
    res = ex.identify(u, y)
    assert res["input_lag1_autocorrelation"] > 0.7  # a sweep, not white noise
    arx_fit, model = res["arx"]
    assert arx_fit > 90.0  # free run on the held-out third
    assert np.max(np.abs(model.poles)) < 1.0
    # the same model, scored independently of identify()
    n_fit = res["n_fit"]
    assert fit_percent(y[n_fit:], model.filter(u)[n_fit:]) == pytest.approx(arx_fit)
    # the white-input correlation formula is far off on a sine sweep, and so is the
    # identifier forced onto the paper's (white-input) path
    assert res["correlation"][0] < arx_fit - 40
    assert res["hammerstein_white"][0] < arx_fit - 40
    white = res["hammerstein_white"][1]
    assert any("not white" in w for w in white.report_.warnings)


@needs_data
def test_daisy_hammerstein_identifier_matches_the_arx_baseline():
    """On the same split, the identifier's free-run fit is within 2 points of
    least-squares ARX with the order by BIC (this arm is nearly linear)."""
    u, y = ex.load_daisy(DATA)
    res = ex.identify(u, y)
    arx_fit = res["arx"][0]
    ham_fit, ham = res["hammerstein"]
    assert ham.method_ == "correlated" and not ham.whiteness_.white
    assert ham.whiteness_.lag1 > 0.7
    assert ham_fit >= arx_fit - 2.0, (ham_fit, arx_fit)
    # the same model, scored independently: the free run of its own ARMA on phi(u)
    n_fit = res["n_fit"]
    y_hat = ham.arma_.filter(ham.nonlinearity(u)) + ham.offset_
    assert fit_percent(y[n_fit:], y_hat[n_fit:]) == pytest.approx(ham_fit, rel=1e-9)
    # its linear baseline is reported beside it, fitted to the same estimation data
    base_fit = res["baseline"][0]
    assert ham.report_.baseline["order"] == ham.baseline_.order_
    assert base_fit >= arx_fit - 2.0, (base_fit, arx_fit)


def best_arx_fit(u, y, n_fit):
    """The best free-run fit on ``y[n_fit:]`` of least-squares ARX over orders 1-10 fitted
    on the first ``n_fit`` samples (the example's NumPy ARX; unstable orders skipped)."""
    fits = []
    for order in range(1, 11):
        try:
            model = ex.arx(u[:n_fit], y[:n_fit], order)
        except ValueError:
            continue
        fits.append(fit_percent(y[n_fit:], model.filter(u)[n_fit:]))
    return max(fits)


@needs_data
def test_daisy_the_linear_model_wins_and_is_returned():
    """This arm's nonlinearity is not a static input map: on its held-out blocks no
    Hammerstein structure beats the best linear ARX over orders 1-10; the identifier
    returns the linear model, whose free run on the unseen last third is as good as the
    best least-squares ARX of any order there."""
    u, y = ex.load_daisy(DATA)
    res = ex.identify(u, y)
    ham = res["hammerstein"][1]
    comp = ham.report_.comparison
    assert comp.winner == "linear" and comp.recommended == "identifier"
    assert comp.orders == tuple(range(1, 11)) and not ham.report_.nonlinear_helps
    assert ham.grid_.shape[0] == 2 and ham.recommended_ is ham  # the linear model
    assert res["hammerstein"][0] >= best_arx_fit(u, y, res["n_fit"]) - 0.5


@needs_data
def test_daisy_a_given_order_recommends_the_best_linear_model_loudly():
    """order=4 is too low for this arm: the Hammerstein model of that order is 20 points
    worse on the last third than the best ARX; the identifier must compare it with every
    linear order (not ARX(4) alone), warn, and recommend a baseline that is not worse."""
    u, y = ex.load_daisy(DATA)
    n_fit = 683
    with pytest.warns(IdentificationWarning, match="does not beat the best linear model"):
        low = HammersteinIdentifier(order=4).fit(u[:n_fit], y[:n_fit])
    comp = low.report_.comparison
    assert comp.winner == "linear" and comp.recommended == "baseline"
    assert comp.orders == tuple(range(1, 11)) and comp.linear_order >= 6
    assert comp.margin < -comp.standard_error  # worse, by more than a standard error
    best = best_arx_fit(u, y, n_fit)
    own = fit_percent(y[n_fit:], low.predict(u)[n_fit:])
    rec = low.recommended_
    assert rec is low.baseline_ and rec.order_ >= 6
    assert own < best - 15.0
    assert fit_percent(y[n_fit:], rec.predict(u)[n_fit:]) >= best - 0.5


@needs_data
def test_daisy_script_runs(tmp_path):
    png = tmp_path / "daisy.png"
    res = subprocess.run(
        [sys.executable, str(EXAMPLE), str(DATA), "--plot", str(png)],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert res.returncode == 0, res.stderr
    assert "least-squares ARX" in res.stdout and "sine sweep" in res.stdout
    assert "correlated path" in res.stdout and "linear baseline" in res.stdout
    assert "does not beat the best linear model" in res.stdout
    assert png.stat().st_size > 0
