"""Tests of :mod:`flexarm.sensing.delays` against hand-written coefficients and independent oracles.

Oracles (none calls the code under test to produce the expected value):

* the Padé coefficients of orders 1–3 written out by hand, and the paper's order-2
  formula (the paper's Sec. V);
* the Taylor series of ``e^{-sT}`` against a power-series division done in mpmath at
  40 digits; the leading phase-error term ``(n!)**2 / ((2n)! (2n+1)!) (wT)**(2n+1)``;
* the transfer function rebuilt from ``(A, B, C, D)`` by a linear solve, Gramians
  from scipy's Lyapunov solver;
* the analytic continuous step response ``D + C A^-1 (expm(A t) - I) B`` and
  scipy.signal.step for the discretisation;
* the Euler–Bernoulli dispersion relation ``EI beta**4 = rho w**2`` (phase speed
  ``w / beta``, group speed ``d w / d beta``) and the paper's link (its Sec. III).
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest
import scipy.linalg as sla
from scipy import signal

from flexarm.modes import BeamModes
from flexarm.sensing.delays import (
    SEED_WAVE_SPEED,
    DelayModel,
    bending_group_speed,
    bending_phase_speed,
    discretize,
    pade,
    pade_state_space,
    travel_delay,
    wave_delay,
)

EI_ARM, RHO_ARM, L_ARM = 1676.0, 0.335, 4.5  # the paper's link (Sec. III)
ORDERS = tuple(range(1, 9))


def freq_response(num, den, w):
    s = 1j * np.asarray(w)
    return np.polyval(num, s) / np.polyval(den, s)


def ss_response(A, B, C, D, s):
    n = A.shape[0]
    return np.array([(C @ np.linalg.solve(si * np.eye(n) - A, B))[0, 0] + D[0, 0] for si in s])


# ----------------------------------------------------------------------- Padé
@pytest.mark.parametrize("T", (1.0, 0.05, 3e-4))
def test_pade_coefficients_by_hand(T):
    num, den = pade(T, 1)
    np.testing.assert_allclose(num, [-T / 2, 1.0], rtol=1e-15)
    np.testing.assert_allclose(den, [T / 2, 1.0], rtol=1e-15)
    num, den = pade(T, 2)  # the paper: (1 - sT/2 + s²T²/12) / (1 + sT/2 + s²T²/12)
    np.testing.assert_allclose(num, [T**2 / 12, -T / 2, 1.0], rtol=1e-15)
    np.testing.assert_allclose(den, [T**2 / 12, T / 2, 1.0], rtol=1e-15)
    num, den = pade(T, 3)  # (1 - x/2 + x²/10 - x³/120) / (1 + x/2 + x²/10 + x³/120)
    np.testing.assert_allclose(num, [-(T**3) / 120, T**2 / 10, -T / 2, 1.0], rtol=1e-15)
    np.testing.assert_allclose(den, [T**3 / 120, T**2 / 10, T / 2, 1.0], rtol=1e-15)


def test_pade_order_2_is_the_papers_formula_as_a_function():
    T = 0.08
    s = np.array([0.3j, 2.0 + 5.0j, 40.0j, -1.0 + 0.5j])
    paper = (1 - s * T / 2 + s**2 * T**2 / 12) / (1 + s * T / 2 + s**2 * T**2 / 12)
    num, den = pade(T, 2)
    np.testing.assert_allclose(np.polyval(num, s) / np.polyval(den, s), paper, rtol=1e-14)


@pytest.mark.parametrize("n", ORDERS)
def test_pade_is_all_pass(n):
    T = 0.2
    w = np.logspace(-2, 3, 200) / T
    np.testing.assert_allclose(np.abs(freq_response(*pade(T, n), w)), 1.0, atol=1e-12)


PHASE_LIMITS = {1: 0.229, 2: 0.946, 3: 1.97, 4: 3.19, 5: 4.53, 6: 5.95}  # module docstring


def phase_error(num, den, T, x):
    """|arg H(i x / T) + x|, wrapped to [0, pi]."""
    ang = np.angle(freq_response(num, den, np.asarray(x) / T)) + x
    return np.abs((ang + np.pi) % (2 * np.pi) - np.pi)


@pytest.mark.parametrize("n", sorted(PHASE_LIMITS))
def test_pade_phase_error_below_1e3_up_to_the_documented_limit(n):
    T = 0.37
    num, den = pade(T, n)
    x_lim = PHASE_LIMITS[n]
    assert phase_error(num, den, T, np.linspace(0.0, x_lim, 2000)).max() < 1e-3
    assert phase_error(num, den, T, 1.02 * x_lim) > 1e-3  # the limit is sharp
    assert phase_error(num, den, T, 3.0 * n) > 0.1  # and beyond it the approximation fails


@pytest.mark.parametrize("n", (1, 2, 3, 4, 5))
def test_pade_phase_error_follows_its_leading_term(n):
    T = 0.37
    num, den = pade(T, n)
    c = math.factorial(n) ** 2 / (math.factorial(2 * n) * math.factorial(2 * n + 1))
    x = (1e-9 / c) ** (1 / (2 * n + 1))  # where the leading term is 1e-9 rad
    assert phase_error(num, den, T, x) / (c * x ** (2 * n + 1)) == pytest.approx(1.0, rel=0.05)


@pytest.mark.parametrize("n", ORDERS)
def test_pade_taylor_series_matches_the_exponential_to_order_2n(n):
    T = 0.7
    num, den = pade(T, n)
    with mp.workdps(40):
        q, exact, remainder = _series_check(num, den, n, T)
        rel = [float(abs(q[k] - exact[k]) / abs(exact[k])) for k in range(2 * n + 1)]
        first_miss = float(abs(q[2 * n + 1] - exact[2 * n + 1]) / remainder)
    # float coefficients (rounded to 1e-16) lose a few digits in the division
    assert max(rel) < 1e-11
    # the first mismatch is the known Padé remainder (n!)**2 / ((2n)! (2n+1)!) x**(2n+1)
    assert first_miss == pytest.approx(1.0, rel=1e-6)


def _series_check(num, den, n, T):
    """Power series of num/den and of exp(-sT) through s**(2n+1), and the Padé remainder."""
    a = [mp.mpf(float(c)) for c in num[::-1]]  # ascending powers
    d = [mp.mpf(float(c)) for c in den[::-1]]
    a += [mp.mpf(0)] * (2 * n + 2 - len(a))
    d += [mp.mpf(0)] * (2 * n + 2 - len(d))
    q = []
    for k in range(2 * n + 2):  # power-series division num / den
        q.append((a[k] - sum(d[j] * q[k - j] for j in range(1, k + 1))) / d[0])
    exact = [(-mp.mpf(T)) ** k / mp.factorial(k) for k in range(2 * n + 2)]
    f = math.factorial
    remainder = mp.mpf(f(n) ** 2) / (f(2 * n) * f(2 * n + 1)) * mp.mpf(T) ** (2 * n + 1)
    return q, exact, remainder


@pytest.mark.parametrize("n", ORDERS)
def test_pade_zeros_in_rhp_poles_in_lhp(n):
    num, den = pade(0.1, n)
    zeros, poles = np.roots(num), np.roots(den)
    assert np.all(zeros.real > 0)  # non-minimum phase
    assert np.all(poles.real < 0)
    np.testing.assert_allclose(np.sort_complex(zeros), np.sort_complex(-poles), rtol=1e-8)


# ---------------------------------------------------------------- state space
@pytest.mark.parametrize("n", (*ORDERS, 12, 20))
def test_state_space_realises_the_transfer_function(n):
    T = 0.045
    A, B, C, D = pade_state_space(T, n)
    assert A.shape == (n, n) and B.shape == (n, 1) and C.shape == (1, n) and D.shape == (1, 1)
    num, den = pade(T, n)
    s = np.array([0.0, 3.0j, 1.0 + 40.0j, -5.0 + 1.0j, 100.0, 2.0j * n / T])
    np.testing.assert_allclose(
        ss_response(A, B, C, D, s), np.polyval(num, s) / np.polyval(den, s), atol=1e-10
    )


@pytest.mark.parametrize("n", (*ORDERS, 15))
def test_state_space_is_balanced_lossless_and_well_scaled(n):
    T = 0.3
    A, B, C, D = pade_state_space(T, n)
    P = sla.solve_continuous_lyapunov(A, -B @ B.T)
    Q = sla.solve_continuous_lyapunov(A.T, -C.T @ C)
    np.testing.assert_allclose(P, np.eye(n), atol=1e-10)
    np.testing.assert_allclose(Q, np.eye(n), atol=1e-10)
    assert D[0, 0] == (-1) ** n
    np.testing.assert_allclose(C, -D[0, 0] * B.T, rtol=1e-15)
    assert np.abs(A * T).max() == pytest.approx(n * (n + 1), rel=1e-12)  # documented
    np.testing.assert_array_equal(np.triu(A, 2), 0.0)  # tridiagonal
    np.testing.assert_array_equal(np.tril(A, -2), 0.0)
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(A)), np.sort_complex(np.roots(pade(T, n)[1])), rtol=1e-8
    )


# -------------------------------------------------------------- discretisation
def continuous_step(A, B, C, D, t):
    """y(t) = D + C A^-1 (expm(A t) - I) B for a unit step from rest (A invertible)."""
    n = A.shape[0]
    Ainv_B = np.linalg.solve(A, B)
    return np.array([(D + C @ (sla.expm(A * tk) - np.eye(n)) @ Ainv_B)[0, 0] for tk in t])


def discrete_step(Ad, Bd, Cd, Dd, k):
    x = np.zeros((Ad.shape[0], 1))
    ys = []
    for _ in range(k):
        ys.append((Cd @ x + Dd)[0, 0])
        x = Ad @ x + Bd
    return np.array(ys)


@pytest.mark.parametrize("n", (1, 2, 4))
@pytest.mark.parametrize("dt_over_T", (0.1, 1.0, 7.0))
def test_discretization_is_exact_at_the_samples(n, dt_over_T):
    T = 0.05
    dt = dt_over_T * T
    A, B, C, D = pade_state_space(T, n)
    Ad, Bd, Cd, Dd = discretize(A, B, C, D, dt)
    np.testing.assert_allclose(Ad, sla.expm(A * dt), atol=1e-13)
    np.testing.assert_allclose(Bd, np.linalg.solve(A, (Ad - np.eye(n)) @ B), atol=1e-12)
    np.testing.assert_array_equal(Cd, C)
    np.testing.assert_array_equal(Dd, D)
    k = 40
    t = np.arange(k) * dt
    y_d = discrete_step(Ad, Bd, Cd, Dd, k)
    np.testing.assert_allclose(y_d, continuous_step(A, B, C, D, t), atol=1e-11)
    _, y_sp = signal.step((A, B, C, D), T=t)
    np.testing.assert_allclose(y_d, y_sp, atol=1e-9)
    # unit DC gain survives the discretisation
    gain = Cd @ np.linalg.solve(np.eye(n) - Ad, Bd) + Dd
    assert gain[0, 0] == pytest.approx(1.0, abs=1e-12)


def test_discretization_of_a_general_mimo_system():
    rng = np.random.default_rng(7)
    n, m, p = 4, 2, 3
    A = rng.normal(size=(n, n)) - 3 * np.eye(n)
    B, C, D = rng.normal(size=(n, m)), rng.normal(size=(p, n)), rng.normal(size=(p, m))
    dt = 0.13
    Ad, Bd, Cd, Dd = discretize(A, B, C, D, dt)
    assert Bd.shape == (n, m) and Cd.shape == (p, n) and Dd.shape == (p, m)
    np.testing.assert_allclose(Ad, sla.expm(A * dt), rtol=1e-12)
    # Bd = int_0^dt expm(A s) ds B by Gauss–Legendre quadrature
    nodes, weights = np.polynomial.legendre.leggauss(30)
    s = 0.5 * dt * (nodes + 1)
    integral = sum(0.5 * dt * w * sla.expm(A * si) for si, w in zip(s, weights, strict=True))
    np.testing.assert_allclose(Bd, integral @ B, rtol=1e-11, atol=1e-13)


@pytest.mark.parametrize("n", (1, 2, 3, 6, 10))
def test_long_steps_stay_stable(n):
    """dt = 100 T: the exact discretisation puts the poles at exp(p dt), deep inside."""
    T, dt = 1e-4, 1e-2
    A, B, C, D = pade_state_space(T, n)
    Ad, Bd, Cd, Dd = discretize(A, B, C, D, dt)
    assert np.all(np.isfinite(Ad)) and np.all(np.isfinite(Bd))
    assert np.abs(np.linalg.eigvals(Ad)).max() < 1e-6
    # after one long step a step input has passed through: y = 1
    y = discrete_step(Ad, Bd, Cd, Dd, 3)
    np.testing.assert_allclose(y, [(-1.0) ** n, 1.0, 1.0], atol=1e-9)


# ----------------------------------------------------------------- DelayModel
def test_delay_model_defaults_and_none():
    d = DelayModel(0.02)
    assert (d.delay, d.method, d.order) == (0.02, "pade", 2)
    none = DelayModel.none()
    assert none.delay == 0.0 and none == DelayModel(0.0)
    A, B, C, D = none.state_space()
    assert A.shape == (0, 0) and B.shape == (0, 1) and C.shape == (1, 0)
    np.testing.assert_array_equal(D, [[1.0]])
    Ad, Bd, Cd, Dd = discretize(A, B, C, D, 0.01)  # zero states discretise too
    assert Ad.shape == (0, 0) and Bd.shape == (0, 1) and Cd.shape == (1, 0)
    np.testing.assert_array_equal(Dd, [[1.0]])
    num, den = none.transfer_function()
    np.testing.assert_array_equal(num, [1.0]) and np.testing.assert_array_equal(den, [1.0])


def test_delay_model_realisations():
    d = DelayModel(0.03, "pade", 3)
    for got, want in zip(d.state_space(), pade_state_space(0.03, 3), strict=True):
        np.testing.assert_array_equal(got, want)
    for got, want in zip(d.transfer_function(), pade(0.03, 3), strict=True):
        np.testing.assert_array_equal(got, want)
    assert d.samples(0.01) == pytest.approx(3.0)
    with pytest.raises(ValueError, match="'method' parameter of DelayModel must be 'pade'"):
        DelayModel(0.03, "exact").state_space()
    assert DelayModel(1, "exact").delay == 1.0 and isinstance(DelayModel(1).delay, float)


def test_delay_model_is_frozen():
    with pytest.raises(AttributeError):
        DelayModel(0.1).delay = 0.2


# ----------------------------------------------------------------- wave speeds
def test_seed_wave_speed_is_the_papers_number():
    assert abs(SEED_WAVE_SPEED - 41783.17) < 0.01
    assert abs(SEED_WAVE_SPEED**2 / 1745833288.33 - 1) < 1e-14
    assert travel_delay(4.5, "seed") == pytest.approx(1.077e-4, rel=1e-3)  # about 0.1 ms
    assert wave_delay(9.0, SEED_WAVE_SPEED) == pytest.approx(2 * travel_delay(4.5, "seed"))


def test_dispersive_speeds_at_the_papers_first_mode():
    w1 = float(BeamModes(L_ARM, EI_ARM, RHO_ARM).frequencies[0])
    assert w1 == pytest.approx(12.281, abs=1e-3)
    cp = bending_phase_speed(w1, EI_ARM, RHO_ARM)
    cg = bending_group_speed(w1, EI_ARM, RHO_ARM)
    assert cp == pytest.approx(29.5, abs=0.05)
    assert cg == pytest.approx(59.0, abs=0.1)
    # the spec's 0.08–0.3 s: group over one link, phase over the whole arm
    kw = {"omega": w1, "flexural_rigidity": EI_ARM, "linear_density": RHO_ARM}
    assert travel_delay(L_ARM, "dispersive", **kw) == pytest.approx(0.08, abs=0.005)
    assert travel_delay(2 * L_ARM, "dispersive", speed="phase", **kw) == pytest.approx(
        0.3, abs=0.01
    )
    assert travel_delay(2 * L_ARM, "dispersive", **kw) == pytest.approx(2 * L_ARM / cg, rel=1e-15)


@pytest.mark.parametrize("w", (0.5, 12.281, 300.0))
def test_speeds_follow_the_dispersion_relation(w):
    """EI beta**4 = rho w**2: phase speed w / beta, group speed d w / d beta."""
    ei, rho = 250.0, 1.7
    beta = (rho * w**2 / ei) ** 0.25
    assert bending_phase_speed(w, ei, rho) == pytest.approx(w / beta, rel=1e-14)
    h = 1e-6 * beta
    omega = lambda b: math.sqrt(ei / rho) * b**2  # noqa: E731
    dw_db = (omega(beta + h) - omega(beta - h)) / (2 * h)
    assert bending_group_speed(w, ei, rho) == pytest.approx(dw_db, rel=1e-8)


# ----------------------------------------------------------------- bad input
@pytest.mark.parametrize("fn", [pade, pade_state_space])
@pytest.mark.parametrize(
    ("delay", "order", "exc", "match"),
    [
        (0.1, 0, ValueError, r"'order' parameter of \w+ must be >= 1. Got 0 instead."),
        (0.1, -2, ValueError, r"'order' parameter of \w+ must be >= 1"),
        (0.1, 1.5, TypeError, r"'order' parameter of \w+ must be an integer. Got 1.5"),
        (0.1, 2.0, TypeError, r"'order' parameter of \w+ must be an integer"),
        (0.1, True, TypeError, r"'order' parameter of \w+ must be an integer"),
        (0.0, 2, ValueError, r"'delay' parameter of \w+ must be > 0. Got 0.0"),
        (-0.1, 2, ValueError, r"'delay' parameter of \w+ must be > 0"),
        (math.nan, 2, ValueError, r"'delay' parameter of \w+ must be finite"),
        ("0.1", 2, TypeError, r"'delay' parameter of \w+ must be a real number"),
    ],
)
def test_pade_rejects_bad_input(fn, delay, order, exc, match):
    with pytest.raises(exc, match=match):
        fn(delay, order)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"delay": -1e-3}, ValueError, "'delay' parameter of DelayModel must be >= 0"),
        ({"delay": math.nan}, ValueError, "'delay' parameter of DelayModel must be finite"),
        ({"delay": math.inf}, ValueError, "'delay' parameter of DelayModel must be finite"),
        ({"method": "buffer"}, ValueError, "'method' parameter of DelayModel must be one of"),
        ({"method": None}, TypeError, "'method' parameter of DelayModel must be a str"),
        ({"order": 0}, ValueError, "'order' parameter of DelayModel must be >= 1. Got 0"),
        ({"order": 1.5}, TypeError, "'order' parameter of DelayModel must be an integer"),
    ],
)
def test_delay_model_rejects_bad_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        DelayModel(**({"delay": 0.01} | kwargs))


def test_discretize_rejects_bad_input():
    A, B, C, D = np.eye(2) * -1, np.ones((2, 1)), np.ones((1, 2)), np.zeros((1, 1))
    with pytest.raises(ValueError, match="'A' parameter of discretize must be square"):
        discretize(np.ones((2, 3)), B, C, D, 0.1)
    with pytest.raises(
        ValueError, match=r"'B' parameter of discretize must be of shape \(2, any\)"
    ):
        discretize(A, np.ones((3, 1)), C, D, 0.1)
    with pytest.raises(
        ValueError, match=r"'C' parameter of discretize must be of shape \(any, 2\)"
    ):
        discretize(A, B, np.ones(2), D, 0.1)
    with pytest.raises(ValueError, match=r"'D' parameter of discretize must be of shape \(1, 1\)"):
        discretize(A, B, C, np.zeros((2, 1)), 0.1)
    with pytest.raises(ValueError, match="'A' parameter of discretize must be finite"):
        discretize(A * np.nan, B, C, D, 0.1)
    with pytest.raises(TypeError, match="'A' parameter of discretize must be real"):
        discretize(A + 0j, B, C, D, 0.1)
    with pytest.raises(ValueError, match="'dt' parameter of discretize must be > 0"):
        discretize(A, B, C, D, 0.0)
    with pytest.raises(ValueError, match=r"'dt' parameter of DelayModel\.samples must be > 0"):
        DelayModel(0.1).samples(-1.0)


@pytest.mark.parametrize(
    ("args", "kwargs", "exc", "match"),
    [
        ((1.0, "fast"), {}, ValueError, "'model' parameter of travel_delay must be one of"),
        ((1.0, "dispersive"), {}, TypeError, "'omega' parameter of travel_delay must be a real"),
        (
            (1.0, "dispersive"),
            {"omega": 10.0, "flexural_rigidity": 1.0},
            TypeError,
            "'linear_density' parameter of travel_delay must be a real number > 0 when",
        ),
        (
            (1.0, "dispersive"),
            {"omega": -1.0, "flexural_rigidity": 1.0, "linear_density": 1.0},
            ValueError,
            "'omega' parameter of travel_delay must be > 0",
        ),
        (
            (1.0, "dispersive"),
            {"omega": 1.0, "flexural_rigidity": 1.0, "linear_density": 1.0, "speed": "energy"},
            ValueError,
            "'speed' parameter of travel_delay must be one of",
        ),
        (
            (1.0, "seed"),
            {"omega": 10.0},
            ValueError,
            "'omega' parameter of travel_delay must be None",
        ),
        ((-1.0, "seed"), {}, ValueError, "'distance' parameter of wave_delay must be >= 0"),
        ((math.nan, "seed"), {}, ValueError, "'distance' parameter of wave_delay must be finite"),
    ],
)
def test_travel_delay_rejects_bad_input(args, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        travel_delay(*args, **kwargs)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: wave_delay(1.0, 0.0), "'speed' parameter of wave_delay must be > 0"),
        (lambda: bending_phase_speed(0.0, 1.0, 1.0), "'omega' parameter of bending_phase_speed"),
        (
            lambda: bending_group_speed(1.0, -1.0, 1.0),
            "'flexural_rigidity' parameter of bending_group_speed must be > 0",
        ),
        (
            lambda: bending_phase_speed(1.0, 1.0, math.nan),
            "'linear_density' parameter of bending_phase_speed must be finite",
        ),
    ],
)
def test_speed_functions_reject_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()
