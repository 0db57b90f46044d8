"""The Gymnasium environments: the checker, the open-loop simulator step for step,
the vector environment against the single one, seeds, autoreset, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import flexarm as fa  # noqa: E402
from flexarm.control.trajectories import Square  # noqa: E402
from flexarm.envs import ENV_ID, EnvConfig, FlexibleArmEnv, FlexibleArmVectorEnv  # noqa: E402
from flexarm.sensing.delays import DelayModel  # noqa: E402
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor  # noqa: E402

SHORT = {"duration": 0.1}


def _torques(n: int, n_links: int, seed: int = 3) -> np.ndarray:
    """A smooth-ish torque sequence, N m, shape (n, n_links)."""
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.normal(0.0, 2.0, size=(n, n_links)), axis=0)


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"sensor": TipSensor(noise_std=1e-3, rate_noise_std=1e-2)},
        {"sensor": PointSensor(1, 0.5, model="paper"), "delay": DelayModel(0.004, "pade", 2)},
        {"sensor": JointSensor(noise_std=1e-4), "delay": DelayModel(0.003, "exact")},
    ],
    ids=["joint", "tip-noise", "point-paper-pade", "joint-exact-delay"],
)
def test_passes_the_gymnasium_checker(options):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(ENV_ID, **SHORT, **options)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    # the one recommendation left: a [-1, 1] action (ours is the torque in N m, on purpose)
    others = [str(w.message) for w in caught if "normalized space" not in str(w.message)]
    assert not others


def test_steps_equal_the_open_loop_simulator_bit_for_bit():
    """One step is one control period with the action held: the same compiled RK4 step
    on the same operands as simulate_open_loop with a held torque, so equality is exact."""
    dt, substeps, n = 2.0**-7, 4, 40
    env = FlexibleArmEnv(dt=dt, substeps=substeps, duration=n * dt)
    env.reset(seed=0)
    x0 = np.r_[env._batch.state.q[0], env._batch.state.dq[0]]
    tau = _torques(n + 1, 2)
    q = [env._batch.state.q[0].copy()]
    for k in range(n):
        env.step(tau[k])
        q.append(env._batch.state.q[0].copy())
    t = np.arange(n + 1) * dt
    res = fa.simulate_open_loop(env.config.arm, t, tau, initial_state=x0, substeps=substeps)
    np.testing.assert_array_equal(np.array(q), res.q)


def test_the_general_kernel_path_equals_the_open_loop_simulator():
    """Two modes per link (the general RK4 step, not the paper's register form)."""
    arm = fa.FlexibleArm.paper(n_modes=2)
    dt, n = 2.0**-7, 20
    env = FlexibleArmEnv(arm=arm, dt=dt, substeps=8, duration=n * dt)
    env.reset(seed=0)
    x0 = np.r_[env._batch.state.q[0], env._batch.state.dq[0]]
    tau = _torques(n + 1, 2, seed=5)
    for k in range(n):
        env.step(tau[k])
    res = fa.simulate_open_loop(arm, np.arange(n + 1) * dt, tau, initial_state=x0, substeps=8)
    np.testing.assert_array_equal(env._batch.state.q[0], res.q[-1])
    np.testing.assert_array_equal(env._batch.state.dq[0], res.dq[-1])


def test_reward_and_observation_follow_their_definitions():
    env = FlexibleArmEnv(duration=0.05, tracking_weight=2.0, effort_weight=0.5)
    obs, info = env.reset(seed=0)
    assert info["tracking_error_m"] < 1e-12  # starts on the reference
    action = np.array([30.0, -250.0])  # the second beyond the limit: clipped to -100
    obs, reward, terminated, truncated, info = env.step(action)
    np.testing.assert_array_equal(info["torque_Nm"], [30.0, -100.0])
    q = env._batch.state.q[0]
    tip = env.config.arm.tip_position(q)
    p, v, _ = Square().evaluate(0.01)
    e = np.hypot(*(tip - p))
    assert info["tracking_error_m"] == pytest.approx(e, rel=1e-12, abs=1e-15)
    assert reward == pytest.approx(-(2.0 * e**2 + 0.5 * (0.3**2 + 1.0)), rel=1e-12)
    np.testing.assert_allclose(obs[:2], q[:2], rtol=0, atol=1e-15)  # undelayed encoders
    np.testing.assert_allclose(obs[4:], np.r_[p, v], rtol=0, atol=1e-15)
    assert not terminated and not truncated


def test_truncation_at_the_reference_end_and_termination_on_divergence():
    env = FlexibleArmEnv(duration=0.03)
    env.reset(seed=0)
    flags = [env.step(np.zeros(2))[2:4] for _ in range(3)]
    assert flags == [(False, False), (False, False), (False, True)]
    with pytest.raises(ValueError, match="call reset"):
        env.step(np.zeros(2))
    env = FlexibleArmEnv(duration=1.0, max_rate=0.5, divergence_penalty=7.0)
    env.reset(seed=0)
    for _ in range(100):
        obs, reward, terminated, truncated, _ = env.step(np.array([100.0, 100.0]))
        if terminated:
            break
    assert terminated and not truncated and reward == -7.0
    assert obs in env.observation_space


def test_reset_with_a_seed_is_reproducible():
    options = {
        "duration": 0.1,
        "sensor": TipSensor(noise_std=1e-3, rate_noise_std=1e-2),
        "initial_angle_std": 0.01,
    }
    runs = []
    for _ in range(2):
        env = FlexibleArmEnv(**options)
        obs = [env.reset(seed=42)[0]]
        obs += [env.step(np.array([5.0, -3.0]))[0] for _ in range(5)]
        runs.append(np.array(obs))
    np.testing.assert_array_equal(runs[0], runs[1])
    other = FlexibleArmEnv(**options).reset(seed=43)[0]
    assert not np.array_equal(other, runs[0][0])


@pytest.mark.parametrize("workers", [1, 2])
def test_the_vector_env_equals_single_envs_step_for_step(workers):
    options = {
        "duration": 0.06,
        "sensor": PointSensor(1, 0.5, noise_std=1e-3, rate_noise_std=1e-2),
        "delay": DelayModel(0.005, "exact"),
        "initial_angle_std": 0.02,
    }
    n, n_steps = 3, 9  # past the 6-step episodes: autoreset included
    vec = FlexibleArmVectorEnv(n, workers=workers, **options)
    singles = [FlexibleArmEnv(**options) for _ in range(n)]
    actions = _torques(n_steps * n, 2, seed=7).reshape(n_steps, n, 2)
    obs, _ = vec.reset(seed=10)
    expected = [env.reset(seed=10 + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.array(expected))
    done = np.zeros(n, dtype=bool)
    for k in range(n_steps):
        obs, rewards, term, trunc, info = vec.step(actions[k])
        for i, env in enumerate(singles):
            if done[i]:  # NEXT_STEP autoreset: a reset, reward 0, the action ignored
                o, r, te, tr = env.reset()[0], 0.0, False, False
            else:
                o, r, te, tr, _ = env.step(actions[k, i])
            np.testing.assert_array_equal(obs[i], o)
            assert (rewards[i], term[i], trunc[i]) == (r, te, tr)
        done = term | trunc
    assert info["_time_s"].all() and info["tracking_error_m"].shape == (n,)
    vec.close()


def test_same_step_autoreset_returns_the_final_observation():
    vec = FlexibleArmVectorEnv(2, autoreset_mode="SameStep", duration=0.02)
    first, _ = vec.reset(seed=0)
    vec.step(np.zeros((2, 2)))
    obs, _, term, trunc, info = vec.step(np.zeros((2, 2)))
    assert trunc.all() and not term.any()
    np.testing.assert_array_equal(obs, first)  # started again, at rest on the first point
    assert info["_final_obs"].all() and not np.array_equal(info["final_obs"], obs)


def test_make_vec_uses_the_compiled_vector_env():
    envs = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", **SHORT)
    assert isinstance(envs.unwrapped, FlexibleArmVectorEnv)
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (2, 8) and obs in envs.observation_space
    envs.close()


@pytest.mark.parametrize(
    ("build", "exc", "match"),
    [
        (lambda: FlexibleArmEnv(nonesuch=1), TypeError, "unexpected keyword argument 'nonesuch'"),
        (lambda: FlexibleArmEnv(dt=-1.0), ValueError, "'dt' parameter of EnvConfig"),
        (lambda: FlexibleArmEnv(torque_limit=(1.0,)), ValueError, "'torque_limit'"),
        (lambda: FlexibleArmEnv(sensor="tip"), TypeError, "'sensor' parameter of EnvConfig"),
        (lambda: FlexibleArmEnv(render_mode="human"), ValueError, "'render_mode'"),
        (lambda: FlexibleArmVectorEnv(0), ValueError, "'num_envs'"),
        (lambda: FlexibleArmVectorEnv(2, autoreset_mode="x"), ValueError, "'autoreset_mode'"),
        (
            lambda: EnvConfig(
                arm=fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0)] * 3)
            ).initial_rest_state(),
            ValueError,
            "'initial_state'",
        ),
    ],
)
def test_bad_input_is_named(build, exc, match):
    with pytest.raises(exc, match=match):
        build()


def test_bad_actions_are_named():
    env = FlexibleArmEnv(**SHORT)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"'action' parameter of FlexibleArmEnv\.step"):
        env.step(np.zeros(3))
    vec = FlexibleArmVectorEnv(2, **SHORT)
    vec.reset(seed=0)
    with pytest.raises(ValueError, match="'actions' parameter"):
        vec.step(np.zeros(2))
