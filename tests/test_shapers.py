"""Tests of :mod:`flexarm.control.shapers` against closed forms, simulations and the literature.

Oracles (none calls the code under test to produce the expected value):

* the closed-form sensitivity curves of undamped shapers: ZV ``|cos(pi w / (2 w0))|``,
  ZVD ``cos(pi w / (2 w0))**2``, EI ``|(1+V)/2 cos(pi w / w0) + (1-V)/2|`` and the
  EI band edges ``cos(pi w / w0) = (3V - 1) / (1 + V)`` derived from it;
* scipy.signal.lsim of the oscillator ``x'' + 2 zeta w x' + w**2 x = w**2 u`` driven by
  a shaped step (zero-order hold on a grid containing every impulse time, so the
  input is exact), its residual amplitude read from the state;
* the published polynomial fit of damped EI shapers (Singhose, Seering & Singer; the
  coefficients below), approximate by construction;
* algebra: ZV * ZV = ZVD, the residual vibration of a convolution is the product of
  the factors'.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
import pytest
from scipy import signal

from flexarm.control.shapers import (
    KINDS,
    Shaper,
    design,
    ei,
    for_modes,
    residual_vibration,
    zv,
    zvd,
)

W0 = 12.281  # rad/s, the paper's first clamped mode of a link (its Sec. III)
DAMPINGS = (0.0, 0.02, 0.1, 0.3)


def damped_period(w, z):
    return 2 * math.pi / (w * math.sqrt(1 - z * z))


def oscillator_states(w, z, t, u):
    """lsim of x'' + 2 z w x' + w**2 x = w**2 u from rest, zero-order hold. Returns (x, x')."""
    sys = signal.StateSpace(
        [[0.0, 1.0], [-w * w, -2 * z * w]], [[0.0], [w * w]], np.eye(2), np.zeros((2, 1))
    )
    _, y, _ = signal.lsim(sys, u, t - t[0], interp=False)
    return y[:, 0], y[:, 1]


def envelope(w, z, x, v):
    """Amplitude of the free oscillation of e = x - 1 at each sample (decays as exp(-z w t))."""
    e = x - 1.0
    wd = w * math.sqrt(1 - z * z)
    return np.sqrt(e**2 + ((v + z * w * e) / wd) ** 2)


def step_grid(step_of_impulses, duration, per_step=40, lead=5):
    """A uniform grid starting before 0 whose step divides ``step_of_impulses``."""
    dt = step_of_impulses / per_step
    k0 = -lead
    k1 = math.ceil(duration / dt)
    return np.arange(k0, k1 + 1) * dt


# ------------------------------------------------------------------ designers
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("z", DAMPINGS)
def test_amplitudes_positive_sum_to_one_times_increasing(kind, z):
    s = design(kind, W0, z)
    assert np.all(s.amplitudes > 0)
    assert s.amplitudes.sum() == pytest.approx(1.0, abs=1e-14)
    assert s.times[0] == 0.0
    assert np.all(np.diff(s.times) > 0)
    assert s.duration == s.times[-1]
    assert s.n_impulses == (2 if kind == "zv" else 3)


@pytest.mark.parametrize("z", DAMPINGS)
def test_zv_zvd_closed_forms(z):
    k = math.exp(-z * math.pi / math.sqrt(1 - z * z))
    td = damped_period(W0, z)
    s1, s2 = zv(W0, z), zvd(W0, z)
    np.testing.assert_allclose(s1.amplitudes, np.array([1, k]) / (1 + k), rtol=1e-15)
    np.testing.assert_allclose(s1.times, [0, td / 2], rtol=1e-15)
    np.testing.assert_allclose(
        s2.amplitudes, np.array([1, 2 * k, k * k]) / (1 + k) ** 2, rtol=1e-15
    )
    np.testing.assert_allclose(s2.times, [0, td / 2, td], rtol=1e-15)


@pytest.mark.parametrize("maker", [zv, zvd], ids=["zv", "zvd"])
@pytest.mark.parametrize("z", DAMPINGS)
def test_zero_vibration_at_the_design_point(maker, z):
    for w in (0.3, W0, 250.0):
        assert residual_vibration(maker(w, z), w, z) < 1e-12


@pytest.mark.parametrize("z", DAMPINGS)
def test_zvd_has_zero_slope_at_the_design_frequency_and_zv_does_not(z):
    h = 1e-5
    v_zvd = residual_vibration(zvd(W0, z), W0 * np.array([1 - h, 1 + h]), z)
    v_zv = residual_vibration(zv(W0, z), W0 * np.array([1 - h, 1 + h]), z)
    # one-sided difference quotients (V >= 0 has a minimum 0 at w0)
    slope_zvd = v_zvd / (h * W0)
    slope_zv = v_zv / (h * W0)
    assert np.all(slope_zvd < 1e-4 / W0)  # O(h): a double zero
    assert np.all(slope_zv > 0.5 / W0)  # a simple zero: |dV/dw| = pi/(2 w0) when undamped


def test_zv_slope_matches_the_closed_form_undamped():
    h = 1e-7
    v = residual_vibration(zv(W0), W0 * (1 + h))
    assert v / (h * W0) == pytest.approx(math.pi / (2 * W0), rel=1e-5)


def test_undamped_sensitivity_curves_match_closed_forms():
    w = np.linspace(0.0, 4.0, 801) * W0
    x = math.pi * w / (2 * W0)
    np.testing.assert_allclose(residual_vibration(zv(W0), w), np.abs(np.cos(x)), atol=1e-14)
    np.testing.assert_allclose(residual_vibration(zvd(W0), w), np.cos(x) ** 2, atol=1e-14)
    for tol in (0.02, 0.05, 0.15):
        expected = np.abs((1 + tol) / 2 * np.cos(2 * x) + (1 - tol) / 2)
        np.testing.assert_allclose(
            residual_vibration(ei(W0, tolerance=tol), w), expected, atol=1e-14
        )


def test_residual_vibration_is_vectorised_over_any_shape():
    w = np.linspace(1.0, 30.0, 12).reshape(3, 4)
    v = residual_vibration(zvd(W0, 0.05), w, 0.05)
    assert v.shape == (3, 4)
    flat = [float(residual_vibration(zvd(W0, 0.05), wi, 0.05)) for wi in w.ravel()]
    np.testing.assert_allclose(v.ravel(), flat, rtol=1e-15)
    assert residual_vibration(zv(W0), 0.0) == pytest.approx(1.0)  # a static load is not shaped


# ------------------------------------------------------------------------- EI
@pytest.mark.parametrize(
    ("z", "tol"),
    # (0.6, 0.1) has no EI solution (tested below)
    [
        (z, v)
        for z in (0.0, 1e-3, 0.05, 0.1, 0.3, 0.6)
        for v in (0.02, 0.05, 0.1)
        if z < 0.6 or v < 0.1
    ],
)
def test_ei_hits_the_tolerance_with_a_hump_at_the_design_frequency(z, tol):
    s = ei(W0, z, tol)
    assert residual_vibration(s, W0, z) == pytest.approx(tol, abs=1e-10)
    h = 1e-5
    lo, hi = residual_vibration(s, W0 * np.array([1 - h, 1 + h]), z)
    assert abs(hi - lo) / (2 * h * W0) < 1e-6  # dV/dw = 0
    assert lo < tol and hi < tol  # a local maximum: a hump, not a dip


@pytest.mark.parametrize("z", (0.0, 0.05, 0.2))
def test_ei_has_two_zeros_bracketing_the_design_frequency(z):
    s = ei(W0, z)
    w = np.linspace(0.5, 2.0, 30001) * W0
    v = residual_vibration(s, w, z)
    below, above = w < W0, w > W0
    assert v[below].min() < 1e-3 and v[above].min() < 1e-3  # grid-limited zeros


def ei_band(s, z, tol, w0):
    """Edges of the connected set {V <= tol} around w0, by bisection on V - tol."""

    def edge(a, b):  # V(a) <= tol < V(b)
        for _ in range(80):
            m = 0.5 * (a + b)
            if residual_vibration(s, m, z) <= tol:
                a = m
            else:
                b = m
        return a

    v = lambda w: float(residual_vibration(s, w, z))  # noqa: E731
    lo = w0
    while v(lo) <= tol * (1 + 1e-9):
        lo *= 0.99
    hi = w0
    while v(hi) <= tol * (1 + 1e-9):
        hi *= 1.01
    return edge(lo / 0.99, lo), edge(hi / 1.01, hi)


def test_ei_band_matches_the_undamped_closed_form():
    tol = 0.05
    s = ei(W0, 0.0, tol)
    half = math.acos((1 - 3 * tol) / (1 + tol)) / math.pi  # cos(pi w/w0) = (3V-1)/(1+V)
    lo, hi = ei_band(s, 0.0, tol, W0 * 0.9)  # start inside the band but off the hump
    assert lo / W0 == pytest.approx(1 - half, abs=1e-9)
    assert hi / W0 == pytest.approx(1 + half, abs=1e-9)
    assert half == pytest.approx(0.2, abs=1e-3)  # the published +-20 % at 5 %
    inside = np.linspace(lo, hi, 2001)
    assert residual_vibration(s, inside).max() <= tol + 1e-12


@pytest.mark.parametrize("z", (0.0, 0.05, 0.2))
def test_ei_band_is_wider_than_zvd_band(z):
    tol = 0.05
    lo_e, hi_e = ei_band(ei(W0, z, tol), z, tol, W0 * 0.95)
    lo_z, hi_z = ei_band(zvd(W0, z), z, tol, W0)
    assert lo_e < lo_z and hi_e > hi_z
    assert (hi_e - lo_e) > 1.35 * (hi_z - lo_z)  # undamped: 0.400 w0 against 0.287 w0
    inside = np.linspace(lo_e, hi_e, 2001)
    assert residual_vibration(ei(W0, z, tol), inside, z).max() <= tol * (1 + 1e-9)


def singhose_fit(z, v):
    """Published polynomial fit of damped EI shapers (times in units of T_d)."""
    a1 = 0.24968 + 0.24961 * v + (0.80008 + 1.23328 * v) * z + (0.49599 + 3.17316 * v) * z * z
    a3 = 0.25149 + 0.21474 * v + (-0.83249 + 1.41498 * v) * z + (0.85181 - 4.90094 * v) * z * z
    t2 = (
        0.49990
        + (0.46159 * v + 8.57843 * v * v) * z
        + (4.26169 * v - 108.644 * v * v) * z * z
        + (1.75601 * v + 336.989 * v * v) * z**3
    )
    return np.array([a1, 1 - a1 - a3, a3]), np.array([0.0, t2, 1.0])


@pytest.mark.parametrize("z", (0.0, 0.02, 0.1, 0.2))
def test_damped_ei_agrees_with_the_published_fit(z):
    a_fit, t_fit = singhose_fit(z, 0.05)
    s = ei(W0, z, 0.05)
    np.testing.assert_allclose(s.amplitudes, a_fit, atol=2e-3)
    np.testing.assert_allclose(s.times / damped_period(W0, z), t_fit, rtol=0.015, atol=0)


def test_damped_ei_tends_to_the_undamped_closed_form():
    s0, s1 = ei(W0, 0.0), ei(W0, 1e-9)
    np.testing.assert_allclose(s1.amplitudes, s0.amplitudes, atol=1e-7)
    np.testing.assert_allclose(s1.times, s0.times, rtol=1e-7)


def test_ei_scales_with_frequency():
    a, b = ei(1.0, 0.1), ei(W0, 0.1)
    np.testing.assert_allclose(b.amplitudes, a.amplitudes, rtol=1e-12)
    np.testing.assert_allclose(b.times * W0, a.times, rtol=1e-12)


@pytest.mark.parametrize(("z", "tol"), [(0.8, 0.05), (0.3, 0.5)])
def test_ei_without_a_solution_raises(z, tol):
    with pytest.raises(ValueError, match="'damping' parameter of ei"):
        ei(W0, z, tol)


# ------------------------------------------------------------------ simulation
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("ratio", (1.0, 0.8, 1.3))
def test_shaped_step_on_an_undamped_oscillator(kind, ratio):
    """Residual amplitude 0 at the design frequency, V(w) off it (unshaped amplitude is 1)."""
    s = design(kind, W0)
    t = step_grid(s.times[1], s.duration + 3 * damped_period(W0 * ratio, 0.0))
    u = s.apply(t, (t >= 0).astype(float))
    x, v = oscillator_states(W0 * ratio, 0.0, t, u)
    after = t >= s.duration
    amp = envelope(W0 * ratio, 0.0, x, v)[after]
    expected = float(residual_vibration(s, W0 * ratio))
    np.testing.assert_allclose(amp, expected, atol=1e-9)
    if ratio == 1.0:
        assert expected == pytest.approx(0.05 if kind == "ei" else 0.0, abs=1e-12)


@pytest.mark.parametrize("kind", ("zv", "zvd"))
@pytest.mark.parametrize("ratio", (1.0, 0.85, 1.2))
def test_shaped_step_on_a_damped_oscillator(kind, ratio):
    """Shaped over unshaped residual amplitude at the same time is V(w, zeta) exp(zeta w t_n).

    V compares with one unit impulse at the last impulse time t_n, which has decayed
    by exp(-zeta w t_n) less than the unshaped step that starts at 0.
    """
    z = 0.08
    s = design(kind, W0, z)
    w = W0 * ratio
    t = step_grid(s.times[1], s.duration + 2 * damped_period(w, z))
    step = (t >= 0).astype(float)
    xs, vs = oscillator_states(w, z, t, s.apply(t, step))
    xu, vu = oscillator_states(w, z, t, step)
    after = t >= s.duration
    ratio_amp = envelope(w, z, xs, vs)[after] / envelope(w, z, xu, vu)[after]
    expected = residual_vibration(s, w, z) * math.exp(z * w * s.duration)
    np.testing.assert_allclose(ratio_amp, expected, atol=1e-8)
    if ratio != 1.0:
        assert expected > 0.05  # off design the test has something to compare


def test_multi_mode_shaper_cancels_both_modes():
    w1, w2 = W0, 2.5 * W0  # impulse times on one grid: pi/w1 * [0, 0.4, 1, 1.4]
    s = for_modes([w1, w2])
    np.testing.assert_allclose(s.times * w1 / math.pi, [0, 0.4, 1.0, 1.4], atol=1e-14)
    np.testing.assert_allclose(residual_vibration(s, [w1, w2]), 0.0, atol=1e-12)
    t = step_grid(0.2 * math.pi / w1, s.duration + 2 * damped_period(w1, 0.0))
    u = s.apply(t, (t >= 0).astype(float))
    after = t >= s.duration
    for w in (w1, w2):
        x, v = oscillator_states(w, 0.0, t, u)
        assert envelope(w, 0.0, x, v)[after].max() < 1e-9
    # a single-mode shaper leaves the other mode ringing
    assert residual_vibration(zv(w1), w2) > 0.5


# ------------------------------------------------------------------- algebra
@pytest.mark.parametrize("z", DAMPINGS)
def test_zv_convolved_with_itself_is_zvd(z):
    s = zv(W0, z).convolve(zv(W0, z))
    ref = zvd(W0, z)
    np.testing.assert_allclose(s.amplitudes, ref.amplitudes, rtol=1e-14)
    np.testing.assert_allclose(s.times, ref.times, rtol=1e-14)
    assert for_modes([W0, W0], z).n_impulses == 3


def test_residual_vibration_of_a_convolution_is_the_product():
    z = 0.07
    a, b = ei(W0, z), zvd(3.1 * W0, z)
    w = np.linspace(0.1, 5.0, 400) * W0
    np.testing.assert_allclose(
        residual_vibration(a.convolve(b), w, z),
        residual_vibration(a, w, z) * residual_vibration(b, w, z),
        atol=1e-14,
    )
    assert a.convolve(b).duration == pytest.approx(a.duration + b.duration, rel=1e-15)


def test_for_modes_with_per_mode_damping_and_kind():
    w, z = np.array([W0, 4 * W0]), np.array([0.02, 0.1])
    s = for_modes(w, z, kind="zvd")
    assert s.n_impulses == 9
    for wi, zi in zip(w, z, strict=True):
        assert residual_vibration(s, wi, zi) < 1e-12
    s_ei = for_modes(w, z, kind="ei", tolerance=0.03)
    for wi, zi in zip(w, z, strict=True):
        assert residual_vibration(s_ei, wi, zi) <= 0.03 + 1e-10


def test_design_dispatches():
    assert design("zv", W0, 0.1) == zv(W0, 0.1)
    assert design("zvd", W0) == zvd(W0)
    assert design("ei", W0, 0.05, tolerance=0.1) == ei(W0, 0.05, 0.1)


# ----------------------------------------------------------------- applying
def smooth_start(t):
    """0 before t = 0, 1 - cos(3 t) after: C1, |f''| <= 9."""
    t = np.asarray(t, dtype=float)
    return np.where(t > 0, 1 - np.cos(3 * t), 0.0)


def test_apply_equals_apply_function_on_a_grid_of_impulse_times():
    s = zvd(W0, 0.05)
    t = step_grid(s.times[1], 2.0, per_step=17)
    np.testing.assert_allclose(
        s.apply(t, smooth_start(t)), s.apply_function(smooth_start)(t), atol=1e-12
    )


def test_apply_interpolates_linearly_between_samples():
    s = ei(W0, 0.1)  # impulse times not on the grid
    t = np.linspace(-0.1, 2.0, 1001)
    dt = t[1] - t[0]
    err = np.abs(s.apply(t, smooth_start(t)) - s.apply_function(smooth_start)(t))
    assert err.max() <= 9 * dt**2 / 8  # linear interpolation error bound
    assert err.max() > 1e-8  # and it is an interpolation, not exact
    # a linear signal is shaped exactly
    lin = 2.0 * t + 1.0
    expected = sum(a * (2.0 * (t - ti) + 1.0) for a, ti in zip(s.amplitudes, s.times, strict=True))
    t_ok = t - s.duration >= t[0]
    np.testing.assert_allclose(s.apply(t, lin)[t_ok], expected[t_ok], atol=1e-12)


def test_apply_holds_the_first_sample_and_keeps_trailing_shape():
    s = zv(math.pi)  # impulses at 0 and 1 s
    t = np.arange(6) * 0.5
    vals = np.stack([np.full(6, 3.0), np.arange(6.0)], axis=1)  # (6, 2)
    out = s.apply(t, vals)
    assert out.shape == (6, 2)
    np.testing.assert_allclose(out[:, 0], 3.0)
    # second column: 0.5 (k + max(k - 2, 0))
    np.testing.assert_allclose(out[:, 1], 0.5 * (np.arange(6) + np.maximum(np.arange(6) - 2, 0)))
    single = s.apply([1.0], [[4.0, 5.0]])
    np.testing.assert_allclose(single, [[4.0, 5.0]])


Triple = namedtuple("Triple", "position velocity acceleration")


def test_apply_function_sums_tuple_members_separately():
    s = zv(2.0, 0.1)

    def evaluate(t):
        t = np.asarray(t, dtype=float)
        return Triple(np.stack([t**2, t], axis=-1), 2 * t, np.full_like(t, 2.0))

    g = s.apply_function(evaluate)
    t = np.linspace(0, 3, 7)
    out = g(t)
    assert isinstance(out, Triple)
    a, ti = s.amplitudes, s.times
    np.testing.assert_allclose(out.velocity, 2 * (t - a @ ti), rtol=1e-14)
    np.testing.assert_allclose(out.acceleration, 2.0)
    np.testing.assert_allclose(out.position[:, 1], t - a @ ti, rtol=1e-14)
    assert out.position.shape == (7, 2)
    plain = s.apply_function(lambda t: (t, 2 * t))(1.5)  # plain tuple, float time
    assert isinstance(plain, tuple) and not isinstance(plain, Triple)
    assert float(plain[0]) == pytest.approx(1.5 - a @ ti)


def test_apply_function_passes_floats_as_floats():
    seen = []

    def fn(t):
        seen.append(type(t))
        return np.asarray(t)

    zv(W0).apply_function(fn)(0.3)
    assert seen == [float, float]


def test_none_shaper_is_the_identity():
    s = Shaper.none()
    t = np.linspace(0, 1, 11)
    np.testing.assert_array_equal(s.apply(t, np.sin(t)), np.sin(t))
    assert s.duration == 0.0
    assert zvd(W0).convolve(s) == zvd(W0)
    np.testing.assert_allclose(residual_vibration(s, [1.0, 5.0]), 1.0)


def test_shaper_is_frozen_read_only_and_hashable():
    s = zv(W0)
    with pytest.raises(AttributeError):
        s.times = np.zeros(2)
    with pytest.raises(ValueError, match="read-only"):
        s.amplitudes[0] = 1.0
    assert s == zv(W0) and hash(s) == hash(zv(W0))
    assert s != zvd(W0)
    assert len({s, zv(W0), zvd(W0)}) == 2


# ----------------------------------------------------------------- bad input
@pytest.mark.parametrize("maker", [zv, zvd, ei], ids=["zv", "zvd", "ei"])
@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"frequency": 0.0}, ValueError, r"'frequency' parameter of \w+ must be > 0. Got 0.0"),
        ({"frequency": -3.0}, ValueError, r"'frequency' parameter of \w+ must be > 0"),
        ({"frequency": math.nan}, ValueError, r"'frequency' parameter of \w+ must be finite"),
        ({"frequency": math.inf}, ValueError, r"'frequency' parameter of \w+ must be finite"),
        ({"frequency": "12"}, TypeError, r"'frequency' parameter of \w+ must be a real number"),
        ({"damping": -0.1}, ValueError, r"'damping' parameter of \w+ must be >= 0"),
        ({"damping": 1.0}, ValueError, r"'damping' parameter of \w+ must be < 1. Got 1.0"),
        ({"damping": math.nan}, ValueError, r"'damping' parameter of \w+ must be finite"),
        ({"damping": True}, TypeError, r"'damping' parameter of \w+ must be a real number"),
    ],
)
def test_designers_reject_bad_input(maker, kwargs, exc, match):
    args = {"frequency": W0, "damping": 0.0} | kwargs
    with pytest.raises(exc, match=match):
        maker(**args)


@pytest.mark.parametrize(
    ("tol", "exc", "match"),
    [
        (0.0, ValueError, "must be > 0"),
        (-0.05, ValueError, "must be > 0"),
        (1.0, ValueError, "must be < 1"),
        (math.nan, ValueError, "must be finite"),
        (None, TypeError, "must be a real number"),
    ],
)
def test_ei_rejects_bad_tolerance(tol, exc, match):
    with pytest.raises(exc, match=r"'tolerance' parameter of ei " + match):
        ei(W0, tolerance=tol)


def test_design_rejects_unknown_kind_and_keywords():
    with pytest.raises(ValueError, match=r"'kind' parameter of design must be one of"):
        design("zvdd", W0)
    with pytest.raises(TypeError, match=r"'kind' parameter of design must be a str"):
        design(None, W0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'tolerance'"):
        design("zv", W0, tolerance=0.05)
    with pytest.raises(TypeError, match="unexpected keyword argument 'tol'"):
        design("ei", W0, tol=0.05)
    with pytest.raises(ValueError, match=r"'kind' parameter of for_modes"):
        for_modes([W0], kind="mzv")


@pytest.mark.parametrize(
    ("args", "exc", "match"),
    [
        (([],), ValueError, "'frequencies' parameter of for_modes must be non-empty"),
        (([W0, 0.0],), ValueError, "'frequencies' parameter of for_modes must be real and > 0"),
        (([W0, math.nan],), ValueError, "'frequencies' parameter of for_modes must be finite"),
        (([[W0]],), ValueError, "'frequencies' parameter of for_modes must be of shape"),
        (([W0], 1.0), ValueError, r"'damping' parameter of for_modes must be real, in \[0, 1\)"),
        (([W0, W0], [0.1]), ValueError, "'damping' parameter of for_modes must be a float or"),
    ],
)
def test_for_modes_rejects_bad_input(args, exc, match):
    with pytest.raises(exc, match=match):
        for_modes(*args)


@pytest.mark.parametrize(
    ("amplitudes", "times", "exc", "match"),
    [
        ([0.5, 0.6], [0.0, 1.0], ValueError, "'amplitudes' parameter of Shaper must sum to 1"),
        ([], [], ValueError, "'amplitudes' parameter of Shaper must be non-empty"),
        ([0.5, 0.5], [0.1, 1.0], ValueError, "'times' parameter of Shaper must start at 0"),
        ([0.5, 0.5], [0.0, 0.0], ValueError, "'times' parameter of Shaper must be strictly"),
        ([0.5, 0.5], [0.0, 1.0, 2.0], ValueError, r"'times' parameter of Shaper must be of shape"),
        (
            [0.5, math.nan],
            [0.0, 1.0],
            ValueError,
            "'amplitudes' parameter of Shaper must be finite",
        ),
        ([[1.0]], [[0.0]], ValueError, "'amplitudes' parameter of Shaper must be of shape"),
        (["a"], [0.0], TypeError, "'amplitudes' parameter of Shaper must be a numeric array"),
    ],
)
def test_shaper_rejects_bad_input(amplitudes, times, exc, match):
    with pytest.raises(exc, match=match):
        Shaper(amplitudes, times)


def test_negative_amplitudes_are_allowed():
    s = Shaper(np.array([1.2, -0.4, 0.2]), np.array([0.0, 0.1, 0.2]))
    assert s.n_impulses == 3


@pytest.mark.parametrize(
    ("t", "values", "match"),
    [
        ([0.0, 1.0, 1.0], [1.0, 2.0, 3.0], "'t' parameter of Shaper.apply must be strictly"),
        ([], [], "'t' parameter of Shaper.apply must be non-empty"),
        ([0.0, 1.0], [1.0, 2.0, 3.0], r"'values' parameter of Shaper.apply must be of shape \(2"),
        ([0.0, math.nan], [1.0, 2.0], "'t' parameter of Shaper.apply must be finite"),
        ([0.0, 1.0], [1.0, math.inf], "'values' parameter of Shaper.apply must be finite"),
    ],
)
def test_apply_rejects_bad_input(t, values, match):
    with pytest.raises(ValueError, match=match):
        zv(W0).apply(t, values)


def test_other_bad_arguments():
    with pytest.raises(TypeError, match=r"'fn' parameter of Shaper\.apply_function"):
        zv(W0).apply_function(3.0)
    with pytest.raises(TypeError, match=r"'other' parameter of Shaper\.convolve"):
        zv(W0).convolve([1.0])
    with pytest.raises(TypeError, match="'shaper' parameter of residual_vibration"):
        residual_vibration([1.0], W0)
    with pytest.raises(
        ValueError, match="'frequency' parameter of residual_vibration must be >= 0"
    ):
        residual_vibration(zv(W0), [-1.0, 2.0])
    with pytest.raises(ValueError, match="'damping' parameter of residual_vibration must be < 1"):
        residual_vibration(zv(W0), W0, 1.5)
