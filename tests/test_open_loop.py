"""Input-driven simulation: analytic cases, an independent integrator, the closed-loop
path, every form of the torque input, bad input."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import flexarm as fa
from flexarm.control.controllers import JacobianTransposePD, JointPD
from flexarm.control.trajectories import Square
from flexarm.sim import SimulationError, simulate, simulate_open_loop

ROD = fa.Link(1.2, 10.0, 2.0, n_modes=0, hub_inertia=0.3)  # rigid: J = rho L^3/3 + hub


def rod_inertia(link):
    return link.linear_density * link.length**3 / 3.0 + link.hub_inertia


@pytest.fixture(scope="module")
def rod():
    return fa.FlexibleArm([ROD])


# ------------------------------------------------------------------ analytic oracles
def test_constant_torque_on_a_rigid_link_is_a_parabola(rod):
    """theta = tau t^2 / (2 J): RK4 integrates a quadratic exactly."""
    t = np.linspace(0.0, 2.0, 201)
    tau = 3.0
    res = simulate_open_loop(rod, t, np.full((t.size, 1), tau))
    J = rod_inertia(ROD)
    np.testing.assert_allclose(res.q[:, 0], tau * t**2 / (2 * J), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res.dq[:, 0], tau * t / J, rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(res.tau[:, 0], tau)
    assert res.info["status"] == "ok"
    assert np.all(np.isnan(res.metrics()["rms_error_m"]))  # no reference to track


def test_a_torque_ramp_interpolated_linearly_is_a_cubic(rod):
    """tau = a t between samples: theta = a t^3 / (6 J), exact under RK4 (Simpson)."""
    t = np.linspace(0.0, 1.0, 11)
    a = 5.0
    res = simulate_open_loop(rod, t, (a * t)[:, None], interpolation="linear", substeps=3)
    J = rod_inertia(ROD)
    np.testing.assert_allclose(res.q[:, 0], a * t**3 / (6 * J), rtol=1e-12, atol=1e-15)
    held = simulate_open_loop(rod, t, (a * t)[:, None], interpolation="zoh", substeps=3)
    # held: the torque lags the ramp by up to one interval, so theta falls behind
    assert np.all(held.q[1:, 0] < res.q[1:, 0])


def test_initial_state_and_time_offset(rod):
    t = np.linspace(10.0, 11.0, 51)  # starts at 10 s: only the spacing matters
    res = simulate_open_loop(rod, t, np.zeros((51, 1)), initial_state=[0.5, -2.0])
    np.testing.assert_allclose(res.q[:, 0], 0.5 - 2.0 * (t - 10.0), atol=1e-13)
    np.testing.assert_array_equal(res.t, t)


# ------------------------------------------------------------------ an independent integrator
def test_flexible_link_against_solve_ivp_on_the_numpy_model():
    """One flexible link, two modes, a smooth torque: the compiled RK4 against DOP853
    on the NumPy reference dynamics (an independent evaluation of the same ODE)."""
    arm = fa.FlexibleArm(
        [fa.Link(1.0, 20.0, 0.8, n_modes=2, hub_inertia=0.05)],
        boundary="clamped-free",
        geometric_stiffening=False,
    )

    def torque(time):
        return np.array([0.4 * np.sin(3.0 * time) * np.exp(-time)])

    t = np.linspace(0.0, 1.5, 1501)
    res = simulate_open_loop(arm, t, torque, substeps=2)
    n = arm.n_dof

    def rhs(time, x):
        return np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], torque(time))]

    ref = solve_ivp(
        rhs, (0.0, 1.5), np.zeros(2 * n), t_eval=t, method="DOP853", rtol=1e-11, atol=1e-13
    )
    # RK4 at h = 0.5 ms against a stiffest mode of ~550 rad/s: (h w)^4 ~ 6e-6 relative
    scale = np.abs(ref.y[:n].T).max(axis=0)
    np.testing.assert_allclose(res.q, ref.y[:n].T, atol=1e-5 * scale.max())


# ------------------------------------------------------------------ the closed-loop path
def test_zero_gain_closed_loop_equals_zero_torque_open_loop():
    arm = fa.FlexibleArm.paper()
    x0 = np.array([0.2, 0.4, 0.01, -0.02, 0.0, 0.0, 0.3, 0.0])
    closed = simulate(
        arm, JointPD(kp=0.0, kd=0.0), Square(), duration=0.2, dt=1e-3, initial_state=x0
    )
    opened = simulate_open_loop(arm, closed.t, np.zeros((closed.t.size, 2)), initial_state=x0)
    np.testing.assert_array_equal(opened.q, closed.q)
    np.testing.assert_array_equal(opened.dq, closed.dq)


@pytest.mark.parametrize("substeps", [1, 3])
def test_replaying_a_closed_loop_torque_record_reproduces_the_run(substeps):
    """The closed loop holds its torque over each period: fed back open loop, the
    record gives the same states bit for bit (same integrator, same order)."""
    arm = fa.FlexibleArm.paper(n_modes=2)  # the general kernel
    closed = simulate(
        arm, JacobianTransposePD.from_arm(arm), Square(), duration=0.1, dt=1e-4, substeps=substeps
    )
    opened = simulate_open_loop(
        arm,
        closed.t,
        closed.tau,
        initial_state=np.r_[closed.q[0], closed.dq[0]],
        substeps=substeps,
    )
    np.testing.assert_array_equal(opened.q, closed.q)
    np.testing.assert_array_equal(opened.tip, closed.tip)


def test_paper_structure_replay_is_bitwise_too():
    arm = fa.FlexibleArm.paper()  # the two-links-one-mode scalar kernel
    closed = simulate(arm, duration=0.05, dt=1e-4)
    opened = simulate_open_loop(
        arm, closed.t, closed.tau, initial_state=np.r_[closed.q[0], closed.dq[0]]
    )
    np.testing.assert_array_equal(opened.q, closed.q)


# ------------------------------------------------------------------ forms of the torque input
def test_python_function_equals_compiled_function_equals_linear_samples():
    arm = fa.FlexibleArm.paper()
    t = np.linspace(0.0, 0.2, 201)
    slope = np.array([2.0, -1.0])

    def python_ramp(time):
        return slope * time

    @numba.njit
    def compiled_ramp(time, tau):
        tau[0] = 2.0 * time
        tau[1] = -1.0 * time

    samples = simulate_open_loop(arm, t, t[:, None] * slope, interpolation="linear", substeps=2)
    by_python = simulate_open_loop(arm, t, python_ramp, substeps=2)
    by_numba = simulate_open_loop(arm, t, compiled_ramp, substeps=2)
    np.testing.assert_allclose(by_python.q, samples.q, rtol=0, atol=1e-14)
    np.testing.assert_allclose(by_numba.q, by_python.q, rtol=0, atol=1e-14)
    assert by_python.info["torque"] == "function"
    assert by_numba.info["torque"] == "compiled function"


def test_one_link_accepts_a_1d_torque(rod):
    t = np.linspace(0.0, 0.5, 6)
    a = simulate_open_loop(rod, t, np.ones(6))
    b = simulate_open_loop(rod, t, np.ones((6, 1)))
    np.testing.assert_array_equal(a.q, b.q)


def test_divergence_keeps_the_partial_run():
    arm = fa.FlexibleArm.paper()
    t = np.linspace(0.0, 1.0, 1001)
    with pytest.raises(SimulationError) as info:
        simulate_open_loop(arm, t, np.full((1001, 2), 1e4), max_deflection=0.5)
    err = info.value
    assert 0.0 < err.time < 1.0
    assert err.result.t[-1] == err.time and err.result.info["status"] == "diverged"


def test_result_table_and_save_round_trip(rod, tmp_path):
    t = np.linspace(0.0, 0.1, 11)
    res = simulate_open_loop(rod, t, np.ones((11, 1)))
    header, values = res.table()
    assert "x_ref" not in header and values.shape == (11, len(header))
    back = type(res).load(res.save(tmp_path / "run.npz"))
    np.testing.assert_array_equal(back.q, res.q)
    assert back.reference.shape == (11, 0)


# ------------------------------------------------------------------ bad input
BAD = [
    ({"t": [0.0]}, ValueError, "'t'.*at least 2"),
    ({"t": [0.0, 0.1, 0.3]}, ValueError, "'t'.*evenly spaced"),
    ({"t": [0.2, 0.1, 0.0]}, ValueError, "'t'.*increasing"),
    ({"t": [0.0, np.nan]}, ValueError, "'t'"),
    ({"torque": np.ones((3, 2))}, ValueError, r"'torque'.*\(4, 1\)"),
    ({"torque": np.full((4, 1), np.inf)}, ValueError, "'torque'"),
    ({"torque": "three"}, TypeError, "'torque'"),
    ({"torque": lambda time: [1.0, 2.0]}, ValueError, r"'torque'.*shape \(1,\)"),
    ({"torque": lambda time: [np.nan]}, ValueError, "'torque'.*finite"),
    ({"interpolation": "cubic"}, ValueError, "'interpolation'"),
    ({"substeps": 0}, ValueError, "'substeps'"),
    ({"initial_state": [0.0]}, ValueError, "'initial_state'"),
    ({"max_deflection": -1.0}, ValueError, "'max_deflection'"),
    ({"progress": "yes"}, TypeError, "'progress'"),
]


@pytest.mark.parametrize(("change", "exc", "match"), BAD)
def test_bad_input_is_named(rod, change, exc, match):
    kwargs = {"t": np.linspace(0.0, 0.3, 4), "torque": np.zeros((4, 1)), **change}
    with pytest.raises(exc, match=match):
        simulate_open_loop(rod, **kwargs)


def test_a_string_is_not_an_arm():
    with pytest.raises(TypeError, match="'arm' parameter of simulate_open_loop"):
        simulate_open_loop("paper", [0.0, 1.0], np.zeros((2, 2)))
    with pytest.raises(TypeError, match="'arm' parameter of simulate"):
        simulate("paper")
