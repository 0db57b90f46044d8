"""python-control interop: the nlsys against flexarm's simulator and linearisation."""

from __future__ import annotations

import numpy as np
import pytest

control = pytest.importorskip("control")

import flexarm as fa  # noqa: E402
from flexarm.control.interop import signal_names, to_nlsys  # noqa: E402
from flexarm.control.linearize import linearize  # noqa: E402


def test_input_output_response_matches_simulate_open_loop():
    """Both integrate x' = f(x, u) with u linear between the samples: python-control
    with DOP853, flexarm with fixed-step RK4. Each side's error is measured, not
    assumed: RK4's falls 16-fold per halving of the step (checked), so at 64 substeps
    it is the 32-to-64 difference / 15 (Richardson); DOP853 steps across the kinks of
    the interpolated input, where its order drops, so its error is bounded by how far
    its answer moves from rtol 1e-12 to 1e-13 (about 2e-8 at rtol 1e-11: no tighter
    than that on this input). The two agree to the sum of the two errors."""
    arm = fa.FlexibleArm.paper()
    t = np.linspace(0.0, 0.3, 31)
    u = np.cumsum(np.random.default_rng(0).normal(0.0, 2.0, size=(31, 2)), axis=0)
    x0 = np.r_[0.3, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    plant = to_nlsys(arm)

    def response(rtol: float) -> control.TimeResponseData:
        return control.input_output_response(
            plant,
            t,
            u.T,
            x0,
            solve_ivp_method="DOP853",
            solve_ivp_kwargs={"rtol": rtol, "atol": 1e-14, "max_step": 0.01},
        )

    resp, coarser = response(1e-13), response(1e-12)
    dop = np.abs(resp.states - coarser.states).max()
    runs = {
        s: fa.simulate_open_loop(arm, t, u, initial_state=x0, interpolation="linear", substeps=s)
        for s in (16, 32, 64)
    }
    x = {s: np.c_[r.q, r.dq] for s, r in runs.items()}
    d16, d32 = np.abs(x[16] - x[32]).max(), np.abs(x[32] - x[64]).max()
    assert 12 < d16 / d32 < 20  # fourth order
    tol = 1.5 * d32 / 15 + 2.0 * dop + 1e-10
    np.testing.assert_allclose(resp.states.T, x[64], rtol=0, atol=tol)
    np.testing.assert_allclose(resp.outputs.T, x[64], rtol=0, atol=tol)


@pytest.mark.parametrize("output", ["state", "joints", "tip"])
def test_linearize_of_the_nlsys_matches_flexarm_linearize(output):
    """control.linearize takes forward differences with a step of 1e-6: an error of
    about 1e-6 relative to the entries (half the step times the second derivative)."""
    arm = fa.FlexibleArm.paper(joints=[fa.LinearJoint(2e4, 0.5)] * 2)
    theta = np.array([0.3, 0.5])
    x0 = np.zeros(2 * arm.n_dof)
    x0[:2] = theta
    x0[arm.motor_slice] = theta
    nl = control.linearize(to_nlsys(arm, output=output), x0, np.zeros(2), copy_names=True)
    ours = linearize(arm, theta, output="tip" if output == "tip" else "joints")
    scale = np.abs(ours.A).max()
    np.testing.assert_allclose(nl.A, ours.A, rtol=0, atol=1e-5 * scale)
    np.testing.assert_allclose(nl.B, ours.B, rtol=0, atol=1e-5 * np.abs(ours.B).max())
    if output == "state":
        # (x0 + eps - x0) / eps: exact up to the rounding of x0 + eps
        np.testing.assert_allclose(nl.C, np.eye(2 * arm.n_dof), rtol=0, atol=1e-9)
    else:
        np.testing.assert_allclose(nl.C, ours.C, rtol=0, atol=1e-5 * np.abs(ours.C).max())
        assert nl.output_labels == list(ours.output_names)
    lin = ours.to_control()
    assert nl.state_labels == lin.state_labels == list(ours.state_names)
    assert nl.input_labels == lin.input_labels == ["tau1", "tau2"]


def test_signal_names():
    arm = fa.FlexibleArm.paper()
    states, inputs, outputs = signal_names(arm, "joints")
    assert states[:4] == ["theta1", "theta2", "delta1_1", "delta2_1"]
    assert states[4] == "dtheta1" and inputs == ["tau1", "tau2"]
    assert outputs == ["theta1", "theta2"]


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"arm": "paper"}, TypeError, "'arm' parameter of to_nlsys"),
        ({"output": "sensor"}, ValueError, "'output' parameter of to_nlsys"),
        ({"name": 3}, TypeError, "'name' parameter of to_nlsys"),
    ],
)
def test_bad_input_is_named(kwargs, exc, match):
    args = {"arm": fa.FlexibleArm.paper(), **kwargs}
    with pytest.raises(exc, match=match):
        to_nlsys(args.pop("arm"), **args)
