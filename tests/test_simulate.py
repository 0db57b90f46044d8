"""The closed-loop simulator: integrator accuracy, sensors, delays, controllers,
divergence, results."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import flexarm as fa
from flexarm.control.controllers import CompiledController, JacobianTransposePD, JointPD
from flexarm.control.trajectories import Circle, Line, Square
from flexarm.sensing.delays import DelayModel
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor, parse_sensor
from flexarm.sim import SimulationError, simulate
from flexarm.sim.results import SimulationResult


@pytest.fixture(scope="module")
def paper():
    return fa.FlexibleArm.paper()


@pytest.fixture(scope="module")
def rigid():
    return fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=0, hub_inertia=0.05)] * 2)


@pytest.fixture(scope="module")
def short_square():
    return Square(center=(5.0, 0.0), side=2.0, time_per_side=0.5)


# ------------------------------------------------------------------ controllers
def test_jacobian_transpose_gains_from_the_paper(paper):
    c = JacobianTransposePD.from_arm(paper)
    w1 = paper.link_frequencies[0][0]
    assert c.kp == pytest.approx(w1**2) and c.kp == pytest.approx(150.8, abs=0.05)
    assert c.kd == pytest.approx(2 * 0.707 * w1) and c.kd == pytest.approx(17.364, abs=2e-3)


def test_compiled_jacobian_transpose_law_matches_numpy(paper):
    c = JacobianTransposePD(kp=[[120.0, 5.0], [-3.0, 90.0]], kd=[10.0, 14.0])
    rng = np.random.default_rng(0)
    p = c.parameters(paper)
    for _ in range(5):
        y = rng.normal(size=2 * 2 + 4 + 2)
        r = rng.normal(size=14)  # reference_size(2)
        kp = np.array([[120.0, 5.0], [-3.0, 90.0]])
        kd = np.diag([10.0, 14.0])
        expected = paper.jacobian(y[:2]).T @ (kp @ (r[:2] - y[4:6]) + kd @ (r[2:4] - y[6:8]))
        np.testing.assert_allclose(c(0.0, y, r, p, np.zeros(0)), expected, rtol=1e-12)


def test_compiled_joint_pd_matches_formula(paper):
    c = JointPD(kp=[50.0, 30.0], kd=4.0)
    y = np.array([0.1, -0.2, 0.3, 0.4, 0, 0, 0, 0, 0, 0])
    r = np.zeros(14)  # reference_size(2)
    r[6:8], r[8:10] = [0.5, 0.5], [1.0, -1.0]
    tau = c(0.0, y, r, c.parameters(paper), np.zeros(0))
    np.testing.assert_allclose(tau, [50 * 0.4 + 4 * 0.7, 30 * 0.7 + 4 * -1.4])


@numba.njit
def _damp_joints(t, y, r, params, state, tau):
    n = tau.shape[0]
    state[0] += 1.0  # counts the calls
    for i in range(n):
        tau[i] = params[0] * (r[6 + i] - y[i]) + params[1] * (r[6 + n + i] - y[n + i])


def test_user_compiled_controller_plugs_in(rigid):
    ctrl = CompiledController(_damp_joints, params=[400.0, 40.0], state=[0.0])
    res = simulate(rigid, ctrl, Line((1.2, 0.3), (1.0, 0.8), 2.0), dt=1e-3, duration=3.0)
    assert res.metrics()["max_error_m"] < 0.01
    assert res.info["controller"] == "compiled"
    assert res.info["controller_state"] == [3000.0]  # one call per control period


def test_compiled_controller_rejects_plain_functions():
    with pytest.raises(TypeError, match="'function'"):
        CompiledController(lambda *a: None)


# ------------------------------------------------------------------ tracking
def test_rigid_arm_tracks_a_slow_reference(rigid):
    traj = Circle(center=(1.2, 0.0), radius=0.3, period=8.0)
    res = simulate(rigid, JacobianTransposePD(kp=400.0, kd=60.0), traj, dt=1e-3)
    m = res.metrics()
    assert m["max_error_m"] < 0.02
    assert m["rms_error_m"] < 0.01
    assert res.info["status"] == "ok"


def test_rk4_matches_the_adaptive_reference(paper, short_square):
    kw = dict(trajectory=short_square, dt=2e-4, duration=0.6)
    fixed = simulate(paper, **kw)
    ref = simulate(paper, method="scipy", **kw)
    np.testing.assert_allclose(fixed.q, ref.q, atol=1e-6 * np.abs(ref.q).max())
    np.testing.assert_allclose(fixed.tau, ref.tau, rtol=1e-5, atol=1e-6 * np.abs(ref.tau).max())


def test_substeps_converge_at_fourth_order(rigid):
    traj = Circle(center=(1.2, 0.0), radius=0.3, period=2.0)
    ctrl = JacobianTransposePD(kp=400.0, kd=60.0)
    kw = dict(dt=5e-3, duration=0.5)
    q = [simulate(rigid, ctrl, traj, substeps=s, **kw).q[-1] for s in (1, 2, 4, 32)]
    e1, e2, e4 = (np.abs(x - q[-1]).max() for x in q[:3])
    assert e1 / e2 > 8 and e2 / e4 > 8  # 2**4 = 16 ideally


# ------------------------------------------------------------------ sensors
def test_joint_sensor_measurement_is_rigid_kinematics(paper, short_square):
    res = simulate(paper, trajectory=short_square, duration=0.2)
    th = res.q[:, :2]
    np.testing.assert_allclose(res.measurement[:, 0:2], th, atol=1e-15)
    np.testing.assert_allclose(res.measurement[:, 4:6], paper.forward_kinematics(th), atol=1e-12)
    np.testing.assert_allclose(res.measurement[:, 8:], res.q[:, 2:], atol=1e-15)


# Noncollocated PD feedback is unstable on this arm (tests below show it), so the
# sensor and delay tests close the loop on the encoders (JointPD reads the undelayed
# encoder angles with a noncollocated sensor) and only record the sensed signal.
COLLOCATED = JointPD(kp=2000.0, kd=300.0)


def test_point_sensor_measures_the_deflected_point(paper, short_square):
    ctrl = COLLOCATED
    res = simulate(paper, ctrl, short_square, sensor=PointSensor(1, 0.5), duration=0.3)
    expected = paper.point_position(res.q, 1, 0.5)
    np.testing.assert_allclose(res.measurement[:, 4:6], expected, atol=1e-12)


def test_tip_sensor_is_the_end_effector(paper, short_square):
    ctrl = COLLOCATED
    res = simulate(paper, ctrl, short_square, sensor=TipSensor(), duration=0.3)
    np.testing.assert_allclose(res.measurement[:, 4:6], res.tip, atol=1e-12)


def test_exact_delay_shifts_the_signal_by_exactly_the_delay(paper, short_square):
    ctrl = COLLOCATED
    dt, delay = 2e-4, 0.01  # 50 samples
    res = simulate(
        paper,
        ctrl,
        short_square,
        sensor=TipSensor(),
        delay=DelayModel(delay, "exact"),
        dt=dt,
        duration=0.3,
    )
    k = round(delay / dt)
    np.testing.assert_allclose(res.measurement[k:, 4:6], res.tip[:-k], atol=1e-12)
    np.testing.assert_allclose(res.measurement[:k, 4:6], np.repeat(res.tip[:1], k, 0), atol=1e-12)
    assert res.info["effective_delay_s"] == pytest.approx(delay)


def test_pade_delay_approximates_the_exact_delay(paper, short_square):
    ctrl = COLLOCATED
    kw = dict(sensor=TipSensor(), dt=2e-4, duration=0.4)
    exact = simulate(paper, ctrl, short_square, delay=DelayModel(0.01, "exact"), **kw)
    errs = []
    for order in (1, 2, 4):
        pade = simulate(paper, ctrl, short_square, delay=DelayModel(0.01, "pade", order), **kw)
        errs.append(np.abs(pade.measurement[:, 4:6] - exact.measurement[:, 4:6]).max())
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3


def test_delay_reference_shifts_the_command(paper, short_square):
    res = simulate(
        paper,
        COLLOCATED,
        short_square,
        sensor=TipSensor(),
        delay=DelayModel(0.02, "exact"),
        delay_reference=True,
        duration=0.3,
    )
    t = res.t
    np.testing.assert_allclose(
        res.reference[:, 0:2], short_square.evaluate(t - 0.02)[0], atol=1e-12
    )
    np.testing.assert_allclose(res.desired, short_square.evaluate(t)[0], atol=1e-12)


def test_noise_is_seeded_and_quantisation_rounds(paper, short_square):
    sensor = JointSensor(noise_std=1e-3, quantization=1e-3)
    a = simulate(paper, trajectory=short_square, sensor=sensor, duration=0.1, rng=3)
    b = simulate(paper, trajectory=short_square, sensor=sensor, duration=0.1, rng=3)
    c = simulate(paper, trajectory=short_square, sensor=sensor, duration=0.1, rng=4)
    np.testing.assert_array_equal(a.measurement, b.measurement)
    assert not np.array_equal(a.measurement, c.measurement)
    angles = a.measurement[:, :2] / 1e-3
    np.testing.assert_allclose(angles, np.round(angles), atol=1e-9)


def test_torque_saturation(paper, short_square):
    res = simulate(paper, trajectory=short_square, torque_limit=5.0, duration=0.5)
    assert np.nanmax(np.abs(res.tau)) <= 5.0
    assert np.isclose(np.nanmax(np.abs(res.tau)), 5.0)


@pytest.mark.parametrize(
    ("spec", "expected"),
    [("joint", JointSensor()), ("tip", TipSensor()), ("point:1:0.5", PointSensor(1, 0.5))],
)
def test_parse_sensor(spec, expected):
    assert parse_sensor(spec) == expected


@pytest.mark.parametrize("spec", ["elbow", "point:1", "point:x:0.5", "point:1:-2", "point:1:a"])
def test_parse_sensor_rejects(spec):
    with pytest.raises(ValueError, match=r"sensor|distance"):
        parse_sensor(spec)


# ------------------------------------------------------------------ divergence
def test_divergence_raises_with_time_state_and_partial_result(paper, short_square):
    # tip feedback with the paper's gains is unstable (linearised poles up to +116 rad/s)
    with pytest.raises(SimulationError) as info:
        simulate(paper, trajectory=short_square, sensor=TipSensor())
    err = info.value
    assert 0 < err.time < short_square.duration
    assert err.state.shape == (2 * paper.n_dof,)
    assert err.result.t[-1] == pytest.approx(err.time)
    assert np.all(np.isfinite(err.result.q))
    assert "diverged" in str(err)


def test_sampled_data_instability_at_one_kilohertz_is_detected(paper, short_square):
    """The hubless paper arm under the paper's JT gains needs dt well below 1 ms
    (its fastest closed-loop pole lies between about -1700 and -4500 rad/s along the square)."""
    with pytest.raises(SimulationError):
        simulate(paper, trajectory=Square(), dt=1e-3)


# ------------------------------------------------------------------ results
def test_result_save_load_round_trip(tmp_path, paper, short_square):
    res = simulate(paper, trajectory=short_square, duration=0.2)
    path = res.save(tmp_path / "run.npz")
    back = SimulationResult.load(path)
    for name in ("t", "q", "dq", "tau", "reference", "desired", "measurement", "tip"):
        np.testing.assert_array_equal(getattr(back, name), getattr(res, name))
    assert back.info == res.info and back.coordinate_names == res.coordinate_names
    assert list(tmp_path.iterdir()) == [path]  # no temporary files left behind


def test_result_load_rejects_malformed_files(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(ValueError, match="not a flexarm simulation result"):
        SimulationResult.load(bad)
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(ValueError, match="not a flexarm simulation result"):
        SimulationResult.load(other)


def test_result_metrics_and_series(paper):
    """Each metric against its definition written out here from the recorded series:
    the error is the end effector's distance from the desired point; corner errors
    the largest error within a second after each corner; the residual vibration the
    RMS elastic deflection after the motion ends (4 s of a 2 m square at 1 s a side)."""
    res = simulate(paper, trajectory=Square(side=2.0, time_per_side=1.0), duration=5.0)
    m = res.metrics()
    tip, desired, t = res.tip, res.desired, res.t
    error = np.hypot(tip[:, 0] - desired[:, 0], tip[:, 1] - desired[:, 1])
    np.testing.assert_allclose(res.error, error, rtol=0, atol=1e-15)
    assert m["rms_error_m"] == pytest.approx(np.sqrt(np.mean(error**2)), rel=1e-12)
    assert m["max_error_m"] == pytest.approx(error.max(), rel=1e-15)
    corners = [1.0, 2.0, 3.0, 4.0]  # the turns at the end of each 1 s side
    assert list(res.corner_times) == corners
    want = [error[(t >= c - 1e-12) & (t <= c + 1.0 + 1e-12)].max() for c in corners]
    np.testing.assert_allclose(m["corner_errors_m"], want, rtol=1e-15)
    assert m["sim_time_s"] == pytest.approx(5.0)
    # the elastic deflection: the tip against the rigid kinematics of the joint angles
    th1, th2 = res.q[:, 0], res.q[:, 1]
    rigid = np.column_stack(
        [
            4.5 * np.cos(th1) + 4.5 * np.cos(th1 + th2),
            4.5 * np.sin(th1) + 4.5 * np.sin(th1 + th2),
        ]
    )
    elastic = np.hypot(*(tip - rigid).T)
    after = t >= 4.0 - 1e-12
    assert m["residual_vibration_m"] == pytest.approx(np.sqrt(np.mean(elastic[after] ** 2)))
    # the links' tip deflections: each link's modal coordinates times its tip shape
    assert res.link_deflections.shape == (t.size, 2)
    for i in range(2):
        phi_tip = paper.modes[i].shape(4.5)[:, 0]
        np.testing.assert_allclose(
            res.link_deflections[:, i], res.q[:, 2 + i] * phi_tip[0], rtol=1e-13, atol=1e-15
        )


def test_the_rigid_tip_and_the_elastic_deflection_of_a_three_link_run():
    """Against the rigid kinematics of model.kinematics and NumPy's row norms."""
    from flexarm.model.kinematics import rigid_point

    arm = fa.FlexibleArm([fa.Link(1.5, 1676.0, 0.335, n_modes=2, hub_inertia=1.0)] * 3)
    t = np.linspace(0.0, 0.5, 501)
    res = fa.simulate_open_loop(arm, t, np.column_stack([np.sin(7 * t), -np.ones_like(t), t]))
    pos, _ = rigid_point(arm.link_lengths, res.q[:, :3])
    np.testing.assert_allclose(res.rigid_tip, pos, rtol=0, atol=1e-14)
    np.testing.assert_allclose(
        res.elastic_deflection, np.linalg.norm(res.tip - pos, axis=1), rtol=0, atol=1e-14
    )
    assert np.max(res.elastic_deflection) > 1e-4  # the links did bend


@pytest.mark.parametrize("n_links", [1, 2, 3])
def test_control_effort_is_the_trapezoid_of_the_squared_torques(n_links):
    """Against a sum written out interval by interval; rows with a NaN (the tail of a
    diverged run) are dropped and their neighbours joined."""
    import itertools
    from fractions import Fraction

    from flexarm.sim.metrics import control_effort

    rng = np.random.default_rng(n_links)
    t = np.cumsum(rng.uniform(0.5, 1.5, 40))
    tau = rng.normal(size=(40, n_links))
    tau[[5, 6, 30]] = np.nan
    ok = [k for k in range(40) if np.all(np.isfinite(tau[k]))]
    power = [sum(Fraction(float(v)) ** 2 for v in tau[k]) for k in ok]
    exact = sum(
        (Fraction(float(t[b])) - Fraction(float(t[a]))) * (power[i] + power[i + 1]) / 2
        for i, (a, b) in enumerate(itertools.pairwise(ok))
    )
    assert control_effort(t, tau) == pytest.approx(float(exact), rel=1e-13)
    full = tau[ok]
    assert control_effort(t[ok], full) == pytest.approx(float(exact), rel=1e-13)
    assert np.isnan(control_effort(t[:2], tau[5:7]))  # fewer than two finite rows


def test_to_pandas(paper, short_square):
    """The frame holds the result's own series, indexed by time."""
    pd = pytest.importorskip("pandas")
    res = simulate(paper, trajectory=short_square, duration=0.1)
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame)
    np.testing.assert_array_equal(df.index.to_numpy(), res.t)
    np.testing.assert_array_equal(df["theta1"].to_numpy(), res.q[:, 0])
    np.testing.assert_array_equal(df["dtheta1"].to_numpy(), res.dq[:, 0])
    np.testing.assert_array_equal(df["tau1"].to_numpy(), res.tau[:, 0])
    np.testing.assert_array_equal(df["x_tip"].to_numpy(), res.tip[:, 0])
    np.testing.assert_array_equal(df["error"].to_numpy(), res.error)


def test_plot_draws_the_results_series(paper, short_square):
    """The figure's lines are the result's path, desired path, error (mm) and link
    deflections (mm), on labelled axes."""
    res = simulate(paper, trajectory=short_square, duration=0.2)
    fig = res.plot()
    ax_xy, ax_err, ax_def = fig.axes
    desired, tip = ax_xy.get_lines()[:2]
    np.testing.assert_array_equal(desired.get_xydata(), res.desired)
    np.testing.assert_array_equal(tip.get_xydata(), res.tip)
    np.testing.assert_allclose(ax_err.get_lines()[0].get_ydata(), 1e3 * res.error)
    for i, line in enumerate(ax_def.get_lines()):
        np.testing.assert_allclose(line.get_ydata(), 1e3 * res.link_deflections[:, i])
    assert (ax_xy.get_xlabel(), ax_err.get_ylabel(), ax_def.get_xlabel()) == (
        "x (m)",
        "error (mm)",
        "t (s)",
    )
    import matplotlib.pyplot as plt

    plt.close(fig)


# ------------------------------------------------------------------ flexible joints
def test_simulates_an_arm_with_flexible_joints():
    arm = fa.FlexibleArm.paper(joints=[fa.NonlinearJoint.default(fa.MakkarFriction.default())] * 2)
    res = simulate(arm, trajectory=Square(side=2.0, time_per_side=1.0), duration=1.0)
    assert res.q.shape[1] == arm.n_dof
    # the encoders read the motor angles
    np.testing.assert_allclose(res.measurement[:, :2], res.q[:, arm.motor_slice], atol=1e-15)


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"dt": 0.0}, ValueError, "'dt'"),
        ({"dt": float("nan")}, ValueError, "'dt'"),
        ({"duration": -1.0}, ValueError, "'duration'"),
        ({"substeps": 0}, ValueError, "'substeps'"),
        ({"method": "euler"}, ValueError, "'method'"),
        ({"elbow": "up"}, ValueError, "'elbow'"),
        ({"controller": "pd"}, TypeError, "'controller'"),
        ({"sensor": "tip"}, TypeError, "'sensor'"),
        ({"delay": 0.1}, TypeError, "'delay'"),
        ({"torque_limit": -1.0}, ValueError, "'torque_limit'"),
        ({"torque_limit": [1.0, 2.0, 3.0]}, ValueError, "'torque_limit'"),
        ({"initial_state": np.zeros(3)}, ValueError, "'initial_state'"),
        ({"rng": "seed"}, TypeError, "'rng'"),
        ({"sensor": PointSensor(2, 0.5)}, ValueError, "'link'"),
        ({"sensor": PointSensor(1, 5.0)}, ValueError, "'distance'"),
    ],
)
def test_simulate_rejects_bad_input(paper, kwargs, error, match):
    with pytest.raises(error, match=match):
        simulate(paper, **({"duration": 0.01} | kwargs))


def test_unreachable_trajectory_is_rejected(paper):
    with pytest.raises(ValueError, match="reachable"):
        simulate(paper, trajectory=Square(center=(8.0, 0.0), side=4.0))


@pytest.mark.parametrize(("n_links", "n_modes"), [(1, 0), (2, 2), (3, 7)])
def test_signal_layout_tiles_the_vectors(n_links, n_modes):
    """Each signal has its own slice; together they cover y and r exactly once."""
    from flexarm.control import signals as s

    n = n_links
    y_parts = [
        (s.y_angles(n), n),
        (s.y_rates(n), n),
        (s.y_point(n), 2),
        (s.y_point_rate(n), 2),
        (s.y_modes(n), n_modes),
    ]
    r_parts = [
        (s.r_position(n), 2),
        (s.r_velocity(n), 2),
        (s.r_acceleration(n), 2),
        (s.r_angles(n), n),
        (s.r_rates(n), n),
        (s.r_angle_accelerations(n), n),
        (s.r_feedforward(n), n),
    ]
    for parts, size in ((y_parts, s.measurement_size(n, n_modes)), (r_parts, s.reference_size(n))):
        cover = np.zeros(size, dtype=int)
        for start, length in parts:
            cover[start : start + length] += 1
        assert np.all(cover == 1)


def test_recorded_measurement_follows_the_layout(paper, short_square):
    """What the loop writes at each offset is what the layout says: encoder angles and
    rates, the tip's position and velocity (tip sensor), the modal coordinates."""
    from flexarm.control import signals as s

    res = simulate(paper, COLLOCATED, short_square, sensor=TipSensor(), duration=0.05)
    y, n = res.measurement, 2
    np.testing.assert_array_equal(y[:, s.y_angles(n) : s.y_angles(n) + n], res.q[:, :2])
    np.testing.assert_array_equal(y[:, s.y_rates(n) : s.y_rates(n) + n], res.dq[:, :2])
    np.testing.assert_allclose(y[:, s.y_point(n) : s.y_point(n) + 2], res.tip, atol=1e-12)
    np.testing.assert_array_equal(y[:, s.y_modes(n) :], res.q[:, 2:])
    h = 1e-6  # d tip / dt = (d tip / d q) dq, by a central difference along dq
    tip_velocity = (
        paper.tip_position(res.q + h * res.dq) - paper.tip_position(res.q - h * res.dq)
    ) / (2 * h)
    np.testing.assert_allclose(
        y[:, s.y_point_rate(n) : s.y_point_rate(n) + 2], tip_velocity, atol=1e-7
    )


# ------------------------------------------------------- a point short of the tip
def _rigid_point(arm, theta, link, distance):
    """The point with straight links at joint angles ``theta`` (K, 2)."""
    q = np.zeros((theta.shape[0], arm.n_dof))
    q[:, :2] = theta
    return arm.point_position(q, link, distance)


def test_point_sensor_is_commanded_where_the_path_puts_it(paper, short_square):
    res = simulate(paper, COLLOCATED, short_square, sensor=PointSensor(1, 0.5), duration=0.3)
    theta_d = res.reference[:, 6:8]
    np.testing.assert_allclose(
        res.reference[:, 0:2], _rigid_point(paper, theta_d, 1, 0.5), atol=1e-12
    )
    # velocity: the derivative of that path (central differences of the positions)
    dt = res.t[1] - res.t[0]
    fd = (res.reference[2:, 0:2] - res.reference[:-2, 0:2]) / (2 * dt)
    np.testing.assert_allclose(res.reference[1:-1, 2:4], fd, atol=1e-5)
    np.testing.assert_allclose(res.desired, short_square.evaluate(res.t)[0], atol=1e-12)


def test_jacobian_transpose_law_uses_the_sensed_points_jacobian(paper):
    ctrl = JacobianTransposePD(kp=[[120.0, 5.0], [-3.0, 90.0]], kd=[[9.0, 1.0], [0.5, 7.0]])
    params = ctrl.parameters_for(paper, PointSensor(1, 0.5))
    rng = np.random.default_rng(11)
    y = rng.normal(size=2 * 2 + 4 + 2)
    r = rng.normal(size=14)  # reference_size(2)
    tau = ctrl(0.0, y, r, params, np.zeros(0))
    # the point's rigid Jacobian by central differences of its position
    theta = y[:2]
    eps = 1e-6
    jac = np.stack(
        [
            (
                _rigid_point(paper, (theta + eps * e)[None], 1, 0.5)[0]
                - _rigid_point(paper, (theta - eps * e)[None], 1, 0.5)[0]
            )
            / (2 * eps)
            for e in np.eye(2)
        ],
        axis=1,
    )
    force = np.array(ctrl.kp) @ (r[0:2] - y[4:6]) + np.array(ctrl.kd) @ (r[2:4] - y[6:8])
    np.testing.assert_allclose(tau, jac.T @ force, rtol=1e-8)
    # joint encoders and the tip: the end effector's Jacobian (the link lengths)
    for sensor in (JointSensor(), TipSensor(), None):
        np.testing.assert_array_equal(ctrl.parameters_for(paper, sensor)[8:], [4.5, 4.5])


def test_rigid_arm_settles_on_target_through_a_point_sensor(rigid):
    from flexarm.control.trajectories import PointToPoint

    move = PointToPoint((0.9, 0.6), (1.0, 0.8), 1.0)
    res = simulate(
        rigid,
        JacobianTransposePD(kp=400.0, kd=60.0),
        move,
        sensor=PointSensor(1, 0.3),
        duration=6.0,
        dt=1e-3,
    )
    assert np.linalg.norm(res.error[-1]) < 1e-4  # the end effector reaches the goal


def test_point_short_of_the_tip_needs_two_links():
    arm3 = fa.FlexibleArm([fa.Link(1.0, 5.0, 1.0, n_modes=0)] * 3)
    line = Line((1.5, 1.0), (1.6, 1.0), 1.0)
    with pytest.raises(ValueError, match="'sensor'"):
        simulate(arm3, JointPD(), line, sensor=PointSensor(1, 0.5), duration=0.1)
