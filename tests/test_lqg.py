"""LQR and Kalman designs against python-control, the separation principle, the
compiled LQG step against NumPy, the reflected-tip law and its limit, bad input."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.control._lqg_layout import FUZZY, GAIN, POINT, LQGLayout
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.design import kalman, lqr
from flexarm.control.linearize import closed_loop_matrix, linearize
from flexarm.control.lqg import LQG
from flexarm.control.reflected import ReflectedTipPD, reflection_limit
from flexarm.control.signals import measurement_size, reference_size
from flexarm.control.statespace import StateSpace
from flexarm.control.trajectories import Square
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor
from flexarm.sim import simulate

control = pytest.importorskip("control")

ARM = fa.FlexibleArm.paper()
THETA = np.array([0.2, 1.4])


@pytest.fixture(scope="module")
def tip_model():
    return linearize(ARM, THETA, sensor=TipSensor(), rates=True)


def weights(sys):
    q = np.diag(np.linspace(1.0, 3.0, sys.n_states))
    return q, np.diag([0.5, 2.0])


# ------------------------------------------------------------------ designs vs python-control
def test_lqr_matches_python_control(tip_model):
    q, r = weights(tip_model)
    ours = lqr(tip_model, q, r)
    k, s, e = control.lqr(tip_model.A, tip_model.B, q, r)
    np.testing.assert_allclose(ours.K, k, rtol=1e-6, atol=1e-8 * np.abs(k).max())
    np.testing.assert_allclose(ours.S, s, rtol=1e-6, atol=1e-8 * np.abs(s).max())
    np.testing.assert_allclose(np.sort_complex(ours.poles), np.sort_complex(e), rtol=1e-6)


def test_dlqr_matches_python_control(tip_model):
    sys = tip_model.discretize(2e-3)
    q, r = weights(sys)
    ours = lqr(sys, q, r)
    k, _, _ = control.dlqr(sys.A, sys.B, q, r)
    np.testing.assert_allclose(ours.K, k, rtol=1e-6, atol=1e-8 * np.abs(k).max())
    assert np.all(np.abs(ours.poles) < 1)


def test_kalman_matches_lqe_and_dlqe(tip_model):
    qn, rn = np.diag([0.3, 0.7]), np.diag([1e-4, 2e-4, 1e-3, 3e-3])
    ours = kalman(tip_model, tip_model.B, qn, rn)

    def covariance(g):  # G Qn G', made exactly symmetric (python-control checks it)
        w = g @ qn @ g.T
        return 0.5 * (w + w.T)

    eye = np.eye(tip_model.n_states)
    gain, _, _ = control.lqe(tip_model.A, eye, tip_model.C, covariance(tip_model.B), rn)
    np.testing.assert_allclose(ours.L, gain, rtol=1e-6, atol=1e-8 * np.abs(gain).max())
    sys = tip_model.discretize(1e-3)
    ours_d = kalman(sys, sys.B, qn, rn)
    gain_d, p_d, _ = control.dlqe(sys.A, eye, sys.C, covariance(sys.B), rn)
    np.testing.assert_allclose(ours_d.L, gain_d, rtol=1e-6, atol=1e-8 * np.abs(gain_d).max())
    np.testing.assert_allclose(ours_d.P, p_d, rtol=1e-6, atol=1e-10 * np.abs(p_d).max())
    np.testing.assert_allclose(sys.A @ ours_d.M, ours_d.L, rtol=1e-10, atol=1e-14)  # L = A M


def test_separation_principle(tip_model):
    """Plant + LQG (current-estimate form) on the linear model: the closed loop's
    eigenvalues are the regulator's and the estimator's."""
    sys = tip_model.discretize(1e-3)
    q, r = weights(sys)
    k = lqr(sys, q, r).K
    m = kalman(sys, sys.B, np.eye(2), 1e-3 * np.eye(4)).M
    phi, gam, c = sys.A, sys.B, sys.C
    n = phi.shape[0]
    eye = np.eye(n)
    # x+ = Phi x - Gamma K xh ;  xh+ = (I - M C)(Phi xh - Gamma K xh) + M C x+
    top = np.hstack([phi, -gam @ k])
    bottom = np.hstack([m @ c @ phi, (eye - m @ c) @ (phi - gam @ k) - m @ c @ gam @ k])
    closed = np.linalg.eigvals(np.vstack([top, bottom]))
    parts = np.r_[np.linalg.eigvals(phi - gam @ k), np.linalg.eigvals((eye - m @ c) @ phi)]
    np.testing.assert_allclose(np.sort_complex(closed), np.sort_complex(parts), atol=1e-9)


# ------------------------------------------------------------------ bad designs
@pytest.mark.parametrize(
    ("q", "r", "match"),
    [
        (-np.eye(8), np.eye(2), r"'Q'.*semidefinite"),
        (np.eye(8), np.zeros((2, 2)), r"'R'.*positive definite"),
        (np.eye(8), np.array([[1.0, 2.0], [0.0, 1.0]]), r"'R'.*symmetric"),
        (np.eye(3), np.eye(2), r"'Q'.*shape"),
    ],
)
def test_bad_weights(tip_model, q, r, match):
    with pytest.raises(ValueError, match=match):
        lqr(tip_model, q, r)


def test_a_sensor_blind_to_a_rigid_motion_is_refused(tip_model):
    rates_only = StateSpace(
        tip_model.A,
        tip_model.B,
        tip_model.C[2:],
        None,
        None,
        tip_model.state_names,
        None,
        ["dx", "dy"],
    )
    with pytest.raises(ValueError, match=r"'sensor'.*unobservable from dx, dy"):
        kalman(rates_only, rates_only.B, np.eye(2), 1e-4 * np.eye(2))
    # a "sensor" at the base joint sees nothing of the arm
    with pytest.raises(ValueError, match=r"'sensor'.*unobservable"):
        simulate(ARM, LQG(), sensor=PointSensor(0, 0.0), duration=0.1)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"torque_weight": 0.0}, ValueError, "'torque_weight'"),
        ({"position_noise": -1.0}, ValueError, "'position_noise'"),
        ({"schedule_points": 0}, ValueError, "'schedule_points'"),
        ({"gain": 0.0}, ValueError, "'gain'"),
        ({"ks": -1.0}, ValueError, "'ks'"),
        ({"model": "paper"}, TypeError, "'model'"),
        ({"fls": "paper"}, TypeError, "'fls'"),
    ],
)
def test_bad_lqg_parameters(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        LQG(**kwargs)


# ------------------------------------------------------------------ the compiled step
def lqg_step(p, y, r, s, n_links=2):
    """The LQG step written again in NumPy, reading the parameter vector through the
    layout (the offsets of the parts are the layout's; the step's arithmetic is here)."""
    layout = LQGLayout.of(p, n_links)
    grid = layout.grid(p)
    ng = grid.shape[0]
    th1, th2 = r[6], r[7]
    j = int(np.clip(np.searchsorted(grid, th2) - 1, 0, ng - 2))
    w = float(np.clip((th2 - grid[j]) / (grid[j + 1] - grid[j]), 0.0, 1.0))
    mats = [layout.matrices(p, g) for g in (j, j + 1)]
    phi, gam, c, k, m = ((1 - w) * a + w * b for a, b in zip(*mats, strict=True))
    xh, du = layout.state(s)
    xp = phi @ xh + gam @ du
    rot = np.array([[np.cos(th1), np.sin(th1)], [-np.sin(th1), np.cos(th1)]])
    dy = np.r_[rot @ (y[4:6] - r[0:2]), rot @ (y[6:8] - r[2:4])]
    xh_new = xp + m @ (dy - c @ xp)
    return -k @ xh_new, xh_new


def test_the_layout_holds_the_design_where_it_says():
    """The parameter vector read through the layout gives back the design's own
    matrices (the discretised model, the regulator's K and the filter's M at a grid
    point) and the header the law was built with."""
    law = LQG(gain=1.5, schedule_points=3)
    reference = np.zeros((2, reference_size(2)))
    reference[:, 7] = [1.0, 2.0]  # theta_2: the grid spans [0.95, 2.05]
    params = law.design(ARM, TipSensor(), 2e-4, reference)
    layout = LQGLayout.of(params, 2)
    assert layout == (2 * ARM.n_dof, 2, 4, 3, 1)  # one shoulder angle: no gravity
    np.testing.assert_allclose(layout.grid(params), [0.95, 1.5, 2.05], rtol=1e-15)
    assert params[GAIN] == 1.5 and params[POINT] == 1.0
    sys = linearize(ARM, np.array([0.0, 1.5]), sensor=TipSensor(), rates=True).discretize(2e-4)
    phi, gam, c, k, m = layout.matrices(params, 1)
    np.testing.assert_array_equal(phi, sys.A)
    np.testing.assert_array_equal(gam, sys.B)
    np.testing.assert_array_equal(c, sys.C)
    tip = linearize(ARM, np.array([0.0, 1.5]), output="tip", rates=True)
    q = tip.C.T @ np.diag([1e4, 1e4, 10.0, 10.0]) @ tip.C
    q += 1e-9 * np.trace(q) / layout.nx * np.eye(layout.nx)
    np.testing.assert_allclose(k, lqr(sys, q, np.eye(2)).K, rtol=1e-9, atol=1e-12)
    # the filter distrusts the measurement by 1 cm and 1 cm/s (the sensor is noiseless)
    est = kalman(sys, sys.B, 0.3**2 * np.eye(2), np.diag([1e-4, 1e-4, 1e-4, 1e-4]))
    np.testing.assert_allclose(m, est.M, rtol=1e-9, atol=1e-12)
    assert params.shape == (int(params[FUZZY]),)  # no fuzzy part: the blocks end the vector


def test_compiled_step_matches_numpy():
    square = Square()
    res = simulate(ARM, LQG(), square, sensor=TipSensor(), duration=0.01)
    law = LQG()
    params = law.design(ARM, TipSensor(), 2e-4, res.reference)
    layout = LQGLayout.of(params, 2)
    rng = np.random.default_rng(3)
    state = law.initial_state(ARM)
    xh, du = layout.state(state)
    xh[:] = rng.normal(size=layout.nx) * 1e-3
    du[:] = rng.normal(size=layout.nu)
    for _ in range(3):
        y = rng.normal(size=measurement_size(2, 2))
        r = np.zeros(reference_size(2))
        r[:4], r[6:8] = rng.normal(size=4), [0.3, 1.2 + 0.5 * rng.random()]
        expected_tau, expected_xh = lqg_step(params, y, r, state.copy())
        tau = law(0.0, y, r, params, state)
        np.testing.assert_allclose(tau, expected_tau, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(xh, expected_xh, rtol=1e-10, atol=1e-15)
        np.testing.assert_array_equal(du, tau)  # the applied du, for the prediction


def test_fuzzy_adaptation_off_is_the_plain_law_and_gain_scales():
    square = Square()
    ref = simulate(ARM, LQG(), square, sensor=TipSensor(), duration=0.01).reference
    y = np.random.default_rng(0).normal(size=measurement_size(2, 2))
    r = ref[10]
    outs = {}
    for name, law in {"plain": LQG(), "gain2": LQG(gain=2.0), "fuzzy": LQG(ks=100.0)}.items():
        p = law.design(ARM, TipSensor(), 2e-4, ref)
        outs[name] = law(0.0, y, r, p, law.initial_state(ARM))
    np.testing.assert_allclose(outs["gain2"], 2 * outs["plain"], rtol=1e-14)
    ratio = outs["fuzzy"] / outs["plain"]
    assert np.allclose(ratio, ratio[0]) and 1.0 <= ratio[0] <= 5.0  # lambda / lambda0


def test_lqg_tracks_with_the_tip_sensor_alone():
    res = simulate(ARM, LQG(), Square(), sensor=TipSensor(), smoothing=0.1, duration=6.0)
    m = res.metrics()
    # regression bounds: these 6 s (of the square's 20) reach 3.42 cm rms, 10.1 cm at
    # most and 25.0 N m at most; each bound is 1.25 times that
    assert m["rms_error_m"] < 1.25 * 0.0342
    assert m["max_error_m"] < 1.25 * 0.101
    assert m["max_torque_Nm"] < 1.25 * 25.0
    assert res.info["feedforward"] is True
    jt = JacobianTransposePD.from_arm(ARM)
    with pytest.raises(fa.SimulationError):  # what the paper's law does with it
        simulate(ARM, jt, Square(), sensor=TipSensor(), smoothing=0.1, duration=6.0)


# ------------------------------------------------------------------ output redefinition
def test_reflection_limits_agree_with_an_eigenvalue_scan():
    points = [(3.0, -2.0), (7.0, 2.0)]
    limit = reflection_limit(ARM, TipSensor(), points, tolerance=1e-3)
    alphas = np.arange(0.0, 1.0001, 0.02)

    def worst(alpha):
        law = ReflectedTipPD(alpha=alpha)
        return max(
            np.linalg.eigvals(closed_loop_matrix(ARM, law, pt, TipSensor())).real.max()
            for pt in points
        )

    growth = np.array([worst(a) for a in alphas])
    first_unstable = alphas[np.argmax(growth >= 0)]
    assert np.all(growth[alphas < first_unstable] < 0)
    assert first_unstable - 0.02 - 1e-3 <= limit <= first_unstable  # scan step, tolerance
    assert 0.5 < limit < 1.0  # the physical tip itself (alpha = 1) is unstable


def test_reflected_law_at_its_ends():
    """alpha = 0: PD on the rigid kinematics of the encoders; alpha = 1: on the point."""
    rng = np.random.default_rng(2)
    y = rng.normal(size=measurement_size(2, 2))
    r = rng.normal(size=reference_size(2))
    jt = JacobianTransposePD()
    p_jt = jt.parameters_for(ARM, TipSensor())
    for alpha in (0.0, 1.0):
        law = ReflectedTipPD(alpha=alpha)
        tau = law(0.0, y, r, law.parameters_for(ARM, TipSensor()), law.initial_state(ARM))
        yy = y.copy()
        if alpha == 0.0:
            phi = np.cumsum(y[:2])
            lengths = ARM.link_lengths
            yy[4:6] = [lengths @ np.cos(phi), lengths @ np.sin(phi)]
            yy[6:8] = [
                -(lengths * np.sin(phi)) @ np.cumsum(y[2:4]),
                (lengths * np.cos(phi)) @ np.cumsum(y[2:4]),
            ]
        np.testing.assert_allclose(tau, jt(0.0, yy, r, p_jt, np.zeros(0)), rtol=1e-12)


def test_reflected_needs_a_point_and_alpha_in_range():
    with pytest.raises(ValueError, match="'alpha'"):
        ReflectedTipPD(alpha=1.5)
    with pytest.raises(ValueError, match=r"'sensor'.*point"):
        ReflectedTipPD().parameters_for(ARM, JointSensor())


def test_closed_loop_growth_is_negative_on_the_design_model_and_matches_a_held_run():
    """The linear test of the robustness rows: decaying on the design model itself;
    on a plant where it says "grows", a run held at that configuration grows too."""
    from flexarm.control.lqg import closed_loop_growth
    from flexarm.control.trajectories import Line

    law = LQG(torque_weight=0.1, position_noise=1e-3, velocity_noise=1e-2)
    sensor = PointSensor(1, 0.5)
    assert closed_loop_growth(ARM, law, sensor, 2e-4, [1.5, 2.5]) < 0
    plant = fa.FlexibleArm.paper(n_modes=3, boundary="clamped-mass")
    design_law = LQG(model=ARM, torque_weight=0.1, position_noise=1e-3, velocity_noise=1e-2)
    rate = closed_loop_growth(plant, design_law, sensor, 2e-4, [2.5])
    assert rate > 1.0  # per second
    theta = np.array([0.0, 2.5])
    p0 = tuple(plant.forward_kinematics(theta))
    x0 = np.zeros(2 * plant.n_dof)
    x0[:2], x0[2] = theta, 1e-5
    res = simulate(
        plant, design_law, Line(p0, p0, 3.0), sensor=sensor, duration=3.0, initial_state=x0
    )
    d = np.abs(res.link_deflections).max(axis=1)
    early, late = d[(res.t > 0.5) & (res.t < 1.0)].max(), d[(res.t > 2.5)].max()
    assert late / early > np.exp(0.5 * rate * 1.5)  # grows at (at least half) that rate
