"""Gravity through every door: ``flexarm simulate --gravity`` and
``--gravity-compensation``, sweeps over ``arm.gravity`` and its components, the
Gymnasium environment's ``gravity`` and ``gravity_compensation``, and the
sampled-data check linearised about the posture that carries the arm's weight.

Oracles: the library run of the same arm built by hand (the command line and the
sweep rows), the open-loop and closed-loop simulators (the environment), a rigid
pendulum's closed-form fall and moment balance, the horizontal arm's sampling
check (a compensated rigid arm's joint loop is the horizontal one's), and finite
differences of the NumPy statics (the holding torques' stiffness).
"""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.control import JacobianTransposePD, JointPD
from flexarm.control.sampling import check_sampling, holding_stiffness, linear_loop
from flexarm.control.trajectories import Square
from flexarm.errors import SweepError
from flexarm.sensing.sensors import JointSensor
from flexarm.sweeps.driver import sweep
from flexarm.sweeps.spec import SweepSpec
from helpers.cli import error_line, help_text, run, strict_json

VERTICAL = (0.0, -9.81)
TILTED = (2.0, -9.6)  # both components, to catch a swapped or dropped one
SHORT = 0.02  # s of the paper's arm per run


def _paper_run(gravity, duration=SHORT, **settings):
    arm = fa.FlexibleArm.paper(gravity=gravity)
    law = JacobianTransposePD.from_arm(arm)
    return fa.simulate(arm, law, Square(), duration=duration, **settings)


# ------------------------------------------------------------------ command line
def test_simulate_gravity_runs_the_arm_with_that_gravity(capsys):
    status, out, err = run(capsys, "simulate", "--gravity", *TILTED, "--duration", SHORT, "--json")
    assert status == 0, err
    summary = strict_json(out)
    assert summary["settings"]["arm"]["gravity"] == list(TILTED)
    assert summary["run"]["gravity_compensation"] is True  # the built-in laws' choice
    alone = _paper_run(TILTED).metrics()
    assert summary["rms_error_m"] == alone["rms_error_m"]
    assert summary["max_torque_Nm"] == alone["max_torque_Nm"]
    flat = _paper_run(None).metrics()
    assert summary["max_torque_Nm"] != flat["max_torque_Nm"]


def test_simulate_gravity_overrides_the_scenario_and_compensation_can_be_switched_off(
    capsys, tmp_path
):
    path = tmp_path / "s.toml"
    path.write_text(f"[arm]\ngravity = [0.0, -1.0]\n[simulation]\nduration = {SHORT}\n")
    status, out, err = run(
        capsys,
        "simulate",
        "--scenario",
        path,
        "--gravity",
        *VERTICAL,
        "--no-gravity-compensation",
        "--json",
    )
    assert status == 0, err
    summary = strict_json(out)
    assert summary["settings"]["arm"]["gravity"] == list(VERTICAL)
    assert summary["run"]["gravity_compensation"] is False
    alone = _paper_run(VERTICAL, gravity_compensation=False).metrics()
    assert summary["max_torque_Nm"] == alone["max_torque_Nm"]
    assert summary["rms_error_m"] == alone["rms_error_m"]


@pytest.mark.parametrize(
    ("values", "needle"),
    [
        (["0", "nan"], "must be finite"),
        (["inf", "0"], "must be finite"),
        (["0"], "expected 2 numbers"),
        (["0", "1", "2"], "expected 2 numbers"),
        (["0", "down"], "must be a number"),
    ],
)
def test_bad_gravity_is_one_line_naming_the_option(capsys, tmp_path, values, needle):
    out_dir = tmp_path / "out"
    status, out, err = run(capsys, "simulate", "--gravity", *values, "--out", out_dir)
    assert status == 2 and out == ""
    line = error_line(err)
    assert "argument --gravity" in line and needle in line
    assert not out_dir.exists()


def test_simulate_help_explains_gravity(capsys):
    text = help_text(capsys, "simulate")
    assert "--gravity GX GY" in text and "--gravity-compensation" in text
    assert "none without" in text


# ------------------------------------------------------------------ sweeps
def test_a_sweep_over_gravity_gives_each_point_the_single_run():
    points = [[0.0, -9.81], [0.0, -2.0], list(TILTED)]
    spec = SweepSpec.from_dict(
        {"base": {"simulation": {"duration": SHORT}}, "grid": {"arm.gravity": points}}
    )
    table = sweep(spec, workers=1, processes=False, progress=False)
    rows = table.rows()
    torques = [row["max_torque_Nm"] for row in rows]
    assert len(set(torques)) == len(points)  # every point its own run
    for row, g in zip(rows, points, strict=True):
        alone = _paper_run(tuple(g)).metrics()
        assert row["status"] == "ok"
        for name in ("rms_error_m", "max_error_m", "max_torque_Nm", "control_effort_N2m2s"):
            assert row[name] == alone[name]


def test_a_sweep_over_one_component_sets_that_item_of_the_base_gravity():
    base = {"arm": {"gravity": [0.0, -9.81]}, "simulation": {"duration": SHORT}}
    spec = SweepSpec.from_dict({"base": base, "grid": {"arm.gravity[0]": [0.0, 2.0]}})
    assert [spec.scenario(r.params)["arm"]["gravity"] for r in spec.runs] == [
        [0.0, -9.81],
        [2.0, -9.81],
    ]
    assert base["arm"]["gravity"] == [0.0, -9.81]  # the base is not changed
    table = sweep(spec, workers=1, processes=False, progress=False)
    for row, gx in zip(table.rows(), (0.0, 2.0), strict=True):
        assert row["max_torque_Nm"] == _paper_run((gx, -9.81)).metrics()["max_torque_Nm"]


@pytest.mark.parametrize(
    ("base", "key", "match"),
    [
        ({}, "arm.gravity[1]", r"grid\.arm\.gravity\[1\].*not an array of numbers"),
        ({"arm": {"gravity": [0.0, -9.81]}}, "arm.gravity[2]", "the array has 2 items"),
    ],
)
def test_a_component_of_gravity_the_base_does_not_hold_is_named(base, key, match):
    spec = SweepSpec.from_dict({"base": base, "grid": {key: [1.0]}})
    with pytest.raises(SweepError, match=match):
        spec.runs  # noqa: B018 - expanding the runs sets the keys


# ------------------------------------------------------------------ environment
gym = pytest.importorskip("gymnasium")
from flexarm.envs import EnvConfig, FlexibleArmEnv  # noqa: E402


def _pendulum() -> fa.FlexibleArm:
    """One rigid rod: 1 m, 2 kg/m, no hub: ``I = m L**2 / 3`` about the joint."""
    return fa.FlexibleArm([fa.Link(1.0, 1.0, 2.0, n_modes=0)])


ONE_JOINT = {"torque_limit": 100.0}  # (the default config's limits are the paper arm's two)


def test_env_gravity_option_builds_the_arm_with_it():
    config = EnvConfig(gravity=VERTICAL, duration=0.05)
    assert config.arm.gravity == VERTICAL
    assert config.arm == fa.FlexibleArm.paper(gravity=VERTICAL)
    assert EnvConfig(duration=0.05).arm.gravity is None
    assert not config.compensates_gravity
    assert EnvConfig(gravity_compensation=True, duration=0.05).compensates_gravity is False


def test_env_with_gravity_steps_as_the_open_loop_simulator():
    dt, substeps, n = 2.0**-7, 4, 30
    env = FlexibleArmEnv(gravity=TILTED, dt=dt, substeps=substeps, duration=n * dt)
    env.reset(seed=0)
    x0 = np.r_[env._batch.state.q[0], env._batch.state.dq[0]]
    tau = np.cumsum(np.random.default_rng(3).normal(0.0, 2.0, size=(n + 1, 2)), axis=0)
    q = [env._batch.state.q[0].copy()]
    for k in range(n):
        env.step(tau[k])
        q.append(env._batch.state.q[0].copy())
    arm = fa.FlexibleArm.paper(gravity=TILTED)
    t = np.arange(n + 1) * dt
    res = fa.simulate_open_loop(arm, t, tau, initial_state=x0, substeps=substeps)
    np.testing.assert_array_equal(np.array(q), res.q)  # the same compiled step


def test_a_rigid_pendulum_falls_from_rest_as_gravity_says():
    h = 1e-3
    env = FlexibleArmEnv(
        arm=_pendulum(),
        gravity=VERTICAL,
        initial_state=(0.0, 0.0),
        dt=h,
        substeps=1,
        duration=0.1,
        **ONE_JOINT,
    )
    env.reset(seed=0)
    env.step(np.zeros(1))
    alpha = -1.5 * 9.81 / 1.0  # -m g L/2 / (m L**2 / 3) from the horizontal
    theta = env._batch.state.q[0, 0]
    assert theta == pytest.approx(0.5 * alpha * h**2, rel=1e-6)
    flat = FlexibleArmEnv(
        arm=_pendulum(), initial_state=(0.0, 0.0), dt=h, duration=0.1, **ONE_JOINT
    )
    flat.reset(seed=0)
    flat.step(np.zeros(1))
    assert flat._batch.state.q[0, 0] == 0.0  # no gravity: nothing moves


def test_the_paper_arm_with_gravity_falls_under_a_zero_action():
    env = FlexibleArmEnv(gravity=VERTICAL, duration=0.3)
    env.reset(seed=0)
    start = env.config.arm.tip_position(env._batch.state.q[0])
    for _ in range(30):
        env.step(np.zeros(2))
    tip = env.config.arm.tip_position(env._batch.state.q[0])
    assert tip[1] < start[1] - 0.1  # it fell
    assert abs(tip[0] - start[0]) < abs(tip[1] - start[1])


def test_compensation_holds_a_rigid_pendulum_at_any_angle():
    theta0 = 0.4
    env = FlexibleArmEnv(
        arm=_pendulum(),
        gravity=VERTICAL,
        gravity_compensation=True,
        initial_state=(theta0, 0.0),
        dt=0.01,
        duration=0.5,
        **ONE_JOINT,
    )
    env.reset(seed=0)
    for _ in range(50):
        obs, *_, info = env.step(np.zeros(1))
    hold = 2.0 * 9.81 * 0.5 * np.cos(theta0)  # m g L/2 cos(theta): the moment balance
    assert info["torque_Nm"][0] == pytest.approx(hold, rel=1e-12)
    assert env._batch.state.q[0, 0] == pytest.approx(theta0, abs=1e-12)
    assert obs[0] == pytest.approx(theta0, abs=1e-12)


def test_compensated_env_steps_as_the_closed_loop_with_compensation():
    """A zero law in the closed loop with gravity compensation, and the environment
    with zero actions and compensation: the same holding torques of the same measured
    angles, the same compiled step."""
    dt, substeps, n = 0.01, 10, 20
    options = {"gravity": TILTED, "dt": dt, "substeps": substeps, "duration": n * dt}
    env = FlexibleArmEnv(gravity_compensation=True, torque_limit=500.0, **options)
    env.reset(seed=0)
    x0 = np.r_[env._batch.state.q[0], env._batch.state.dq[0]]
    q = [env._batch.state.q[0].copy()]
    taus = []
    for _ in range(n):
        info = env.step(np.zeros(2))[-1]
        q.append(env._batch.state.q[0].copy())
        taus.append(info["torque_Nm"])
    res = fa.simulate(
        env.config.arm,
        JointPD(0.0, 0.0),
        Square(),
        dt=dt,
        substeps=substeps,
        duration=n * dt,
        initial_state=tuple(x0),
        torque_limit=500.0,
        gravity_compensation=True,
    )
    np.testing.assert_array_equal(np.array(q), res.q)
    np.testing.assert_array_equal(np.array(taus), res.tau[:-1])
    off = FlexibleArmEnv(torque_limit=500.0, **options)
    off.reset(seed=0)
    assert not np.array_equal(off.step(np.zeros(2))[-1]["torque_Nm"], taus[0])


@pytest.mark.parametrize(
    ("options", "exc", "match"),
    [
        ({"gravity": (0.0, float("nan"))}, ValueError, "'gravity' parameter of EnvConfig"),
        ({"gravity": (0.0,)}, ValueError, "'gravity' parameter of EnvConfig"),
        ({"gravity_compensation": 1}, TypeError, "'gravity_compensation' parameter of EnvConfig"),
    ],
)
def test_bad_env_gravity_is_named(options, exc, match):
    with pytest.raises(exc, match=match):
        EnvConfig(duration=0.05, **options)


# ------------------------------------------------------------------ sampling check
def _rigid_two_links(gravity=None) -> fa.FlexibleArm:
    links = [
        fa.Link(1.0, 1.0, 2.0, n_modes=0, hub_mass=1.0, hub_inertia=0.05),
        fa.Link(0.8, 1.0, 1.5, n_modes=0, hub_mass=0.5, hub_inertia=0.02),
    ]
    return fa.FlexibleArm(links, payload_mass=0.3, gravity=gravity)


def _pieces(arm, law, theta, dt):
    from flexarm.control.signals import reference_size

    sensor = JointSensor()
    rows = np.zeros((1, reference_size(arm.n_links)))
    rows[0, : arm.n_links] = theta
    params = np.asarray(law.design(arm, sensor, dt, rows), dtype=float)
    state = np.asarray(law.initial_state(arm), dtype=float)
    return (arm, law, sensor, np.asarray(theta, dtype=float), rows[0], params, state)


def test_a_compensated_rigid_arm_loop_is_the_horizontal_ones():
    """On rigid links the holding torques' stiffness is gravity's whole tangent
    stiffness: the compensated loop applied continuously, linearised about any
    posture, is the horizontal arm's (sampled, the held compensation lags the plant's
    gravity by a period), and the check's verdict with it."""
    theta, dt = np.array([0.3, 0.7]), 2e-3
    law = JointPD(4000.0, 60.0)
    flat = linear_loop(*_pieces(_rigid_two_links(), law, theta, dt))
    vertical = _pieces(_rigid_two_links(TILTED), law, theta, dt)
    on = linear_loop(*vertical, gravity_compensation=True)
    off = linear_loop(*vertical, gravity_compensation=False)
    scale = np.max(np.abs(flat.continuous()))
    np.testing.assert_allclose(on.continuous(), flat.continuous(), rtol=0, atol=1e-9 * scale)
    assert np.max(np.abs(off.continuous() - flat.continuous())) > 1e-4 * scale  # gravity
    checked = check_sampling(*vertical, dt, gravity_compensation=True)
    assert checked.stable == check_sampling(*_pieces(_rigid_two_links(), law, theta, dt), dt).stable


def test_holding_stiffness_is_the_derivative_of_the_statics_torques():
    arm = fa.FlexibleArm(
        [
            fa.Link(1.0, 400.0, 1.0, n_modes=2, hub_mass=1.0, hub_inertia=0.5),
            fa.Link(0.8, 200.0, 0.8, n_modes=2, hub_mass=0.5, hub_inertia=0.2),
        ],
        payload_mass=0.3,
        gravity=TILTED,
    )
    theta, h = np.array([0.3, -0.9]), 1e-5
    got = holding_stiffness(arm, arm.equilibrium(theta).q)
    cols = []
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        up, down = arm.equilibrium(theta + e).torques, arm.equilibrium(theta - e).torques
        cols.append((up - down) / (2 * h))
    np.testing.assert_allclose(got, np.column_stack(cols), rtol=1e-6, atol=1e-9)
