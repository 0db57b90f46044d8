"""The Hammerstein identifier against the best linear model on a validation part.

A truly Hammerstein system (a dead zone) must be identified as one, beating every
linear ARX model; a linear system must leave the linear model the winner, returned
(correlated path) or recommended by a warning (a given order, the white path). The
comparison's claims are checked on fresh data against least-squares ARX models of
every order written out in NumPy (``helpers.ident.arx_free_run``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from flexarm.ident import (
    EXAMPLE_ARMA,
    Comparison,
    DeadZone,
    HammersteinIdentifier,
    IdentificationWarning,
    LinearARX,
    simulate_hammerstein,
)
from flexarm.ident.hammerstein.comparison import WINNERS
from helpers.ident import ar1, arx_free_run

ARMA2 = EXAMPLE_ARMA["order2"]
DEAD_ZONE = DeadZone(0.5, 1.0)
DOES_NOT_BEAT = "does not beat the best linear model"


def record(phi, n, seed, white):
    """``(u, y)``: an i.i.d. uniform input on [-2, 2] or AR(1) noise through ``phi`` and
    the order-2 example ARMA, noise 0.2 in the paper's model."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-2.0, 2.0, n) if white else ar1(n, rng)
    return u, simulate_hammerstein(phi, ARMA2.a, ARMA2.b, u, noise_std=0.2, rng=rng)


def best_arx_mse(u_fit, y_fit, u_new, y_new, orders=range(1, 11)):
    """The smallest free-run mean square error on fresh data of least-squares ARX models
    of every order (NumPy), and its order."""
    mse = {o: float(np.mean((y_new - arx_free_run(u_fit, y_fit, o, u_new)) ** 2)) for o in orders}
    best = min(mse, key=mse.get)
    return mse[best], best


def fit_quietly(est, u, y):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", IdentificationWarning)
        est.fit(u, y)
    return est, [str(w.message) for w in caught]


@pytest.mark.parametrize("white", [False, True], ids=["correlated", "white"])
def test_a_dead_zone_beats_every_linear_model(white):
    u, y = record(DEAD_ZONE, 20_000, 1, white)
    est, said = fit_quietly(HammersteinIdentifier(), u, y)
    assert est.method_ == ("white" if white else "correlated")
    comp = est.report_.comparison
    assert comp.winner == "hammerstein" and est.report_.winner == "hammerstein"
    assert comp.margin > comp.standard_error > 0 and comp.relative > 0.2
    assert comp.model_fit_percent > comp.linear_fit_percent
    assert comp.orders == tuple(range(1, 11))  # the best linear model over every order
    assert est.report_.nonlinear_helps and est.recommended_ is est
    assert comp.recommended == "identifier" and not any(DOES_NOT_BEAT in w for w in said)
    # on fresh data the identifier beats the best least-squares ARX of any order
    u_new, y_new = record(DEAD_ZONE, 10_000, 2, white)
    mse = float(np.mean((y_new - est.predict(u_new)) ** 2))
    linear_mse, _ = best_arx_mse(u, y, u_new, y_new)
    assert mse < 0.8 * linear_mse, (mse, linear_mse)
    fresh = est.compare(u_new, y_new)
    assert fresh.winner == "hammerstein" and fresh.n_validation == 10_000
    assert fresh.model_mse == pytest.approx(mse, rel=0.01)  # batch means of equal batches


def test_a_linear_system_keeps_the_linear_model_on_the_correlated_path():
    u, y = record(lambda v: 1.5 * v, 8000, 3, white=False)
    est, said = fit_quietly(HammersteinIdentifier(), u, y)
    comp = est.report_.comparison
    assert est.method_ == "correlated" and comp.winner == "linear"
    assert not est.report_.nonlinear_helps and comp.margin <= comp.standard_error
    # returned: the identifier's model is the baseline's linear model
    assert comp.recommended == "identifier" and est.recommended_ is est
    assert est.grid_.shape[0] == 2 and est.order_ == est.baseline_.order_ == comp.baseline_order
    u_new, _ = record(lambda v: 1.5 * v, 3000, 4, white=False)
    np.testing.assert_allclose(est.predict(u_new), est.baseline_.predict(u_new), atol=1e-9)
    assert not any(DOES_NOT_BEAT in w for w in said)
    assert "the linear ARX" in comp.statement() and "of its baseline" in comp.statement()


def test_a_linear_system_on_the_white_path_recommends_the_baseline_loudly():
    u, y = record(lambda v: 1.5 * v, 20_000, 5, white=True)
    with pytest.warns(IdentificationWarning, match=f"{DOES_NOT_BEAT}.*baseline_"):
        est = HammersteinIdentifier().fit(u, y)
    comp = est.report_.comparison
    assert est.method_ == "white" and comp.winner == "linear" and comp.recommended == "baseline"
    assert est.recommended_ is est.baseline_ and not est.report_.nonlinear_helps
    assert comp.part.startswith("trailing part") and comp.n_validation == 5000
    # the recommendation holds on fresh data: the baseline is at least as good
    u_new, y_new = record(lambda v: 1.5 * v, 10_000, 6, white=True)
    base = float(np.mean((y_new - est.baseline_.predict(u_new)) ** 2))
    own = float(np.mean((y_new - est.predict(u_new)) ** 2))
    assert base <= own


def test_a_given_order_is_kept_and_the_best_linear_order_recommended():
    """ARMA order 2 identified with order 1 given: every order-1 Hammerstein model loses
    to the linear ARX of the right order, which the baseline finds among orders 1-10."""
    u, y = record(lambda v: v, 8000, 7, white=False)
    with pytest.warns(IdentificationWarning, match=DOES_NOT_BEAT):
        est = HammersteinIdentifier(order=1).fit(u, y)
    comp = est.report_.comparison
    assert est.order_ == 1 and comp.winner == "linear" and comp.recommended == "baseline"
    assert comp.orders == tuple(range(1, 11)) and comp.linear_order >= 2
    assert est.baseline_.order_ >= 2 and est.recommended_ is est.baseline_
    assert comp.margin < 0  # the order-1 model is worse, not merely no better
    u_new, y_new = record(lambda v: v, 5000, 8, white=False)
    own = float(np.mean((y_new - est.predict(u_new)) ** 2))
    base = float(np.mean((y_new - est.recommended_.predict(u_new)) ** 2))
    linear_mse, order = best_arx_mse(u, y, u_new, y_new)
    assert base < 0.7 * own and base <= 1.05 * linear_mse, (base, own, linear_mse, order)


def test_the_comparison_is_the_selections_held_out_errors():
    u, y = record(DEAD_ZONE, 8000, 9, white=False)
    est = HammersteinIdentifier().fit(u, y)
    comp, sel = est.report_.comparison, est.selection_
    linear = [c for c in sel.candidates if c.linear and np.isfinite(c.validation_mse)]
    assert comp.linear_mse == min(c.validation_mse for c in linear)
    assert comp.linear_order == min(linear, key=lambda c: c.validation_mse).order
    assert comp.model_mse == sel.chosen.validation_mse and comp.n_validation == sel.n_validation
    assert (comp.winner == "hammerstein") == (comp.margin > comp.standard_error)
    # both fits are the same transform of the errors: 100 (1 - sqrt(mse / var))
    var_model = comp.model_mse / (1 - comp.model_fit_percent / 100) ** 2
    var_linear = comp.linear_mse / (1 - comp.linear_fit_percent / 100) ** 2
    assert var_model == pytest.approx(var_linear, rel=1e-12)
    assert "every 4th of 20 contiguous blocks" in comp.part
    assert est.report_.summary()["comparison"]["winner"] == comp.winner


@pytest.mark.parametrize("white", [False, True], ids=["correlated", "white"])
def test_the_comparison_is_saved_and_loaded(white, tmp_path):
    u, y = record(DEAD_ZONE, 6000, 10, white)
    est, _ = fit_quietly(HammersteinIdentifier(), u, y)
    est.save(tmp_path / "ham.npz")
    back = HammersteinIdentifier.load(tmp_path / "ham.npz")
    assert isinstance(back.report_.comparison, Comparison)
    assert back.report_.comparison == est.report_.comparison
    assert back.report_.winner in WINNERS
    assert type(back.recommended_) is type(est.recommended_)


def test_compare_scores_from_skip_on_and_refuses_bad_skips():
    u, y = record(DEAD_ZONE, 6000, 11, white=False)
    est = HammersteinIdentifier().fit(u, y)
    comp = est.compare(u, y, skip=4000)
    assert comp.n_validation == 2000 and "from sample 4000" in comp.part
    tail = float(np.mean((y[4000:] - est.predict(u)[4000:]) ** 2))
    assert comp.model_mse == pytest.approx(tail, rel=1e-12)  # 20 equal batches
    base = float(np.mean((y[4000:] - est.baseline_.predict(u)[4000:]) ** 2))
    assert comp.linear_mse == pytest.approx(base, rel=1e-12)
    assert comp.linear_order == est.baseline_.order_ and comp.orders == (comp.linear_order,)
    with pytest.raises(ValueError, match=r"'skip' parameter of HammersteinIdentifier.compare"):
        est.compare(u, y, skip=6000)
    with pytest.raises(ValueError, match="'skip'"):
        est.compare(u, y, skip=-1)
    with pytest.raises(TypeError, match="'skip'"):
        est.compare(u, y, skip=1.5)


def test_the_linear_baseline_alone_is_unchanged_by_a_given_order():
    """The baseline of an identifier with a given order is the one LinearARX chooses
    alone (orders 1-10 on the same held-out blocks), not the given order's."""
    u, y = record(lambda v: v, 8000, 7, white=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        est = HammersteinIdentifier(order=1).fit(u, y)
    alone = LinearARX().fit(u, y)
    assert est.baseline_.order_ == alone.order_
    np.testing.assert_array_equal(est.baseline_.predict(u), alone.predict(u))
