"""Linear analysis: the open-loop state-space model against finite differences and
closed forms, transmission zeros against the Euler-Bernoulli continuum, ZOH
discretisation against SciPy, export to python-control, bad input."""

from __future__ import annotations

import itertools

import mpmath as mp
import numpy as np
import pytest
from scipy.signal import cont2discrete

import flexarm as fa
from flexarm.control.linearize import linearize
from flexarm.control.statespace import StateSpace
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor

PAPER_LINK = (4.5, 1676.0, 0.335)


def one_link(n_modes, **kw):
    return fa.FlexibleArm([fa.Link(*PAPER_LINK, n_modes=n_modes, **kw)])


# ------------------------------------------------------------------ the model itself
@pytest.mark.parametrize(
    "arm",
    [
        fa.FlexibleArm.paper(),
        fa.FlexibleArm.paper(n_modes=2, boundary="clamped-mass", payload_mass=0.4),
        fa.FlexibleArm.paper(joints=[fa.NonlinearJoint.default(fa.MakkarFriction.default())] * 2),
        fa.FlexibleArm([fa.Link(1.0, 5.0, 1.1, n_modes=2, hub_inertia=0.2, modal_damping=0.02)]),
    ],
    ids=["paper", "clamped-mass", "flexible-joints", "damped-hub"],
)
def test_state_matrix_is_the_jacobian_of_the_dynamics(arm):
    """A and B against central differences of the NumPy forward dynamics at rest."""
    theta = np.linspace(0.3, -0.4, arm.n_links)
    sys = linearize(arm, theta)
    n = arm.n_dof
    q0 = np.zeros(n)
    q0[: arm.n_links] = theta
    if arm.has_flexible_joints:
        q0[arm.motor_slice] = theta
    tau0 = np.zeros(arm.n_links)

    def f(x, tau):
        return np.r_[x[n:], arm.forward_dynamics(x[:n], x[n:], tau)]

    x0 = np.r_[q0, np.zeros(n)]
    a_fd = np.empty((2 * n, 2 * n))
    h = 1e-8  # the soft windup varies on the scale 1/sqrt(asw) = 2.5e-4 rad
    for j in range(2 * n):
        e = np.zeros(2 * n)
        e[j] = h
        a_fd[:, j] = (f(x0 + e, tau0) - f(x0 - e, tau0)) / (2 * h)
    b_fd = np.stack(
        [(f(x0, tau0 + 1e-3 * e) - f(x0, tau0 - 1e-3 * e)) / 2e-3 for e in np.eye(arm.n_links)], 1
    )
    scale = np.abs(a_fd).max()
    np.testing.assert_allclose(sys.A, a_fd, atol=1e-6 * scale)
    np.testing.assert_allclose(sys.B, b_fd, rtol=1e-7, atol=1e-9 * np.abs(b_fd).max())


def test_outputs_are_positions_and_rates_of_what_is_asked():
    arm = fa.FlexibleArm.paper(n_modes=2)
    theta = np.array([0.4, 0.9])
    tip = linearize(arm, theta, output="tip", rates=True)
    assert tip.output_names == ("x_tip", "y_tip", "dx_tip", "dy_tip")
    n = arm.n_dof
    q0 = np.r_[theta, np.zeros(n - 2)]
    dq = np.random.default_rng(0).normal(size=n)
    h = 1e-6  # d tip/dt = (d tip/d q) dq
    velocity = (arm.tip_position(q0 + h * dq) - arm.tip_position(q0 - h * dq)) / (2 * h)
    np.testing.assert_allclose(tip.C[2:] @ np.r_[np.zeros(n), dq], velocity, rtol=1e-7)
    joints = linearize(arm, theta, output="joints")
    np.testing.assert_array_equal(joints.C[:, :2], np.eye(2))
    enc = linearize(arm, theta, sensor=JointSensor())
    np.testing.assert_array_equal(enc.C, joints.C)
    # the paper's sensor model at 0.5 m from the elbow: rigid kinematics of theta only
    paper = linearize(arm, theta, sensor=PointSensor(1, 0.5, model="paper"))
    assert not np.any(paper.C[:, 2:])
    physical = linearize(arm, theta, sensor=PointSensor(1, 0.5))
    np.testing.assert_allclose(physical.C[:, :2], paper.C[:, :2], atol=1e-8)
    assert np.any(physical.C[:, 2:4])  # the deflection moves the physical point


def test_position_given_by_the_tip_point():
    arm = fa.FlexibleArm.paper()
    by_position = linearize(arm, position=[6.0, 2.0], elbow="negative")
    theta = arm.inverse_kinematics([6.0, 2.0], elbow="negative")
    np.testing.assert_array_equal(by_position.A, linearize(arm, theta).A)


# ------------------------------------------------------------------ transmission zeros
def test_single_mode_zeros_match_the_closed_form():
    """q = (theta, delta): M = [[I, w], [w, m]], K = diag(0, k), y = L theta + phi(L) delta.
    Torque to tip: numerator (L m - phi(L) w) s^2 + L k, a real zero pair when
    phi(L) w > L m: s = +-sqrt(L k / (phi(L) w - L m))."""
    arm = one_link(1)
    bm = arm.modes[0]
    length = PAPER_LINK[0]
    m = bm.modal_mass[0, 0]
    k = bm.modal_stiffness[0, 0]
    w, phi_l = bm.moment_integral[0], bm.tip_deflection[0]
    expected = np.sqrt(length * k / (phi_l * w - length * m))
    zeros = linearize(arm, output="tip").transmission_zeros(inputs=[0], outputs=[1])
    np.testing.assert_allclose(np.sort(zeros.real), [-expected, expected], rtol=1e-8)
    np.testing.assert_allclose(zeros.imag, 0.0, atol=1e-8 * expected)
    assert expected == pytest.approx(33.1, abs=0.05)  # the figure the guide states, rad/s


def continuum_zero():
    """The pinned Euler-Bernoulli beam (no hub) driven by a root torque: its tip
    displacement has zeros where the zero dynamics (tip held, root moment free)
    have a solution: W(L) = W''(L) = W'''(L) = 0 and W(0) = 0 give
    W = sinh b(L - x) + sin b(L - x) with sinh bL + sin bL = 0; for real s,
    b = kappa e^{i pi/4}, kappa^4 = rho s^2 / EI."""
    r = mp.findroot(lambda r: mp.sinh(r * mp.expjpi(0.25)) + mp.sin(r * mp.expjpi(0.25)), 3.3)
    length, ei, rho = PAPER_LINK
    return float(mp.re(r) / length) ** 2 * np.sqrt(ei / rho)


def test_zeros_converge_to_the_continuum_value():
    sigma = continuum_zero()
    assert sigma == pytest.approx(39.07, abs=0.01)
    errors = []
    for n in (1, 3, 5, 8, 12):
        z = linearize(one_link(n), output="tip").transmission_zeros(inputs=[0], outputs=[1])
        real = z[(np.abs(z.imag) < 1e-6 * np.abs(z)) & (z.real > 0)]
        errors.append(abs(real.min() - sigma) / sigma)
    assert errors[0] > 0.1  # one mode: 33.1 vs 39.07
    assert all(b <= a for a, b in itertools.pairwise(errors[1:]))
    assert errors[-1] < 1e-5


def test_collocated_output_has_no_right_half_plane_zero():
    z = linearize(one_link(3), output="joints").transmission_zeros()
    assert np.all(z.real <= 1e-9 * np.abs(z).max())


# ------------------------------------------------------------------ discretisation, export
def test_zero_order_hold_against_scipy():
    sys = linearize(fa.FlexibleArm.paper(), [0.3, 0.7], output="tip")
    d = sys.discretize(2e-3)
    ad, bd, _, _, _ = cont2discrete((sys.A, sys.B, sys.C, sys.D), 2e-3, method="zoh")
    np.testing.assert_allclose(d.A, ad, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(d.B, bd, rtol=1e-9, atol=1e-15)
    assert d.dt == 2e-3 and d.state_names == sys.state_names


def test_export_to_python_control():
    control = pytest.importorskip("control")
    sys = linearize(fa.FlexibleArm.paper(), [0.3, 0.7], sensor=TipSensor(), rates=True)
    c = sys.to_control(name="arm")
    assert list(c.state_labels) == list(sys.state_names)
    assert list(c.input_labels) == ["tau1", "tau2"]
    assert list(c.output_labels) == ["x_sensor", "y_sensor", "dx_sensor", "dy_sensor"]
    np.testing.assert_allclose(
        np.sort_complex(control.poles(c)), np.sort_complex(sys.poles()), rtol=1e-9, atol=1e-9
    )
    cd = sys.discretize(1e-3).to_control()
    assert cd.dt == 1e-3


def test_static_feedback_closes_the_loop():
    sys = linearize(fa.FlexibleArm.paper(), [0.3, 0.7], output="joints", rates=True)
    k = np.hstack([150.0 * np.eye(2), 17.0 * np.eye(2)])
    closed = sys.feedback(k)
    np.testing.assert_allclose(
        np.sort_complex(closed.poles()),
        np.sort_complex(np.linalg.eigvals(sys.A - sys.B @ k @ sys.C)),
    )
    assert closed.is_stable()  # collocated PD on a flexible arm at rest


def test_dynamic_feedback_with_a_controller_system():
    """A first-order controller u = -K z, z' = -a z + y: the interconnection by hand."""
    sys = linearize(one_link(1, hub_inertia=1.0), output="joints")
    ctrl = StateSpace([[-5.0]], [[1.0]], [[2.0]], [[3.0]])
    closed = sys.feedback(ctrl)
    a, b, c = sys.A, sys.B, sys.C
    by_hand = np.block([[a - 3.0 * b @ c, -2.0 * b], [c, np.array([[-5.0]])]])
    np.testing.assert_allclose(closed.A, by_hand)


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("args", "exc", "match"),
    [
        (([[1.0, 2.0]], [[1.0]], [[1.0]]), ValueError, "'A'.*square"),
        (([[1.0]], [[1.0, 2.0], [3.0, 4.0]], [[1.0]]), ValueError, "'B'"),
        (([[1.0]], [[1.0]], [[1.0, 2.0]]), ValueError, "'C'"),
        (([[1j]], [[1.0]], [[1.0]]), TypeError, "'A'.*real"),
        (([[np.nan]], [[1.0]], [[1.0]]), ValueError, "'A'"),
    ],
)
def test_bad_state_space(args, exc, match):
    with pytest.raises(exc, match=match):
        StateSpace(*args)


def test_bad_requests():
    arm = fa.FlexibleArm.paper()
    sys = linearize(arm, output="tip")
    with pytest.raises(ValueError, match=r"'outputs'.*as many"):
        sys.transmission_zeros(inputs=[0], outputs=[0, 1])
    with pytest.raises(ValueError, match="'inputs'"):
        sys.transmission_zeros(inputs=[5], outputs=[0])
    with pytest.raises(ValueError, match="'output'"):
        linearize(arm, output="elbow")
    with pytest.raises(TypeError, match="'arm'"):
        linearize("paper")
    with pytest.raises(ValueError, match=r"'position'.*excludes"):
        linearize(arm, [0.0, 0.1], position=[5.0, 0.0])
    with pytest.raises(ValueError, match="continuous"):
        sys.discretize(1e-3).discretize(1e-3)
    with pytest.raises(ValueError, match="'controller'"):
        sys.feedback(np.ones((3, 3)))
