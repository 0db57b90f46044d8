"""Geometric stiffening: closed forms, an independent continuum oracle, the off switch.

The foreshortening ``u(x) = 1/2 int_0^x w'^2`` in the kinematic map
(:mod:`flexarm.model.foreshortening`) must give

* Southwell's coefficient: a cantilever spinning at ``Omega`` about its clamp
  has ``d(omega_j**2)/d(Omega**2) = K_j = int rho (L**2 - x**2)/2 phi_j'**2 dx /
  int rho phi_j**2 dx`` at ``Omega = 0`` for motion out of the plane of rotation
  (first-order perturbation of the eigenvalue; K_1 = 1.1933 for the first mode,
  Wright, Smith, Thresher & Wang, J. Appl. Mech. 49:197, 1982). In the plane of
  rotation — flexarm's plane — the rotating frame's centrifugal softening takes
  ``Omega**2`` off: ``omega_1**2 = omega_0**2 + (K_1 - 1) Omega**2`` with one mode
  (a Rayleigh–Ritz estimate);
* with more modes, the in-plane frequencies of the continuum rotating beam,
  ``EI w'''' - (T w')' - rho Omega**2 w = rho omega**2 w`` with
  ``T = rho Omega**2 (L**2 - x**2) / 2``, computed here independently by a
  Rayleigh–Ritz method on polynomials (no beam mode in it);
* and with the switch off, the model as it was: ``omega_1**2 = omega_0**2 -
  Omega**2`` (the spinning link softens and buckles at ``Omega = omega_0``),
  the stiffening terms identically zero and the same code path.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexarm as fa
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.model import dynamics
from flexarm.model.arrays import pack_arm_arrays
from flexarm.model.beam import BeamModes
from flexarm.model.foreshortening import foreshortening_integrals, shortening_matrix
from flexarm.model.prescribed import prescribed_accelerations, prescribed_dynamics
from flexarm.sim import SimulationError
from flexarm.sim.prescribed import simulate_prescribed

BETA1 = 1.8751040687  # first cantilever root


def textbook_cantilever(x: np.ndarray, lam: float = BETA1) -> tuple[np.ndarray, np.ndarray]:
    """The first cantilever mode of a unit beam in the textbook form
    ``cosh - cos - sigma (sinh - sin)`` and its slope (an independent formula)."""
    sig = (math.cosh(lam) + math.cos(lam)) / (math.sinh(lam) + math.sin(lam))
    z = lam * x
    phi = np.cosh(z) - np.cos(z) - sig * (np.sinh(z) - np.sin(z))
    dphi = lam * (np.sinh(z) + np.sin(z) - sig * (np.cosh(z) - np.cos(z)))
    return phi, dphi


def spinning_frequencies(arm: fa.FlexibleArm, omega: float) -> np.ndarray:
    """Frequencies (rad/s) of small vibrations of a one-link arm whose joint turns at
    the constant rate ``omega``: the prescribed-motion dynamics (NumPy reference)
    linearised about straight by central differences."""
    n = arm.n_dof
    dq0 = np.zeros(n)
    dq0[0] = omega
    m = n - 1
    A = np.zeros((2 * m, 2 * m))
    A[:m, m:] = np.eye(m)
    eps = 1e-6

    def f(q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        return prescribed_accelerations(arm, q, dq, np.zeros(1))[0][1:]

    for j in range(m):
        e = np.zeros(n)
        e[1 + j] = eps
        A[m:, j] = (f(e, dq0) - f(-e, dq0)) / (2 * eps)
        A[m:, m + j] = (f(np.zeros(n), dq0 + e) - f(np.zeros(n), dq0 - e)) / (2 * eps)
    ev = np.linalg.eigvals(A)
    return np.sort(ev.imag[ev.imag > 0])


def continuum_in_plane_frequencies(omega: float, n_poly: int) -> np.ndarray:
    """The rotating clamped-free beam (L = EI = rho = 1) in its plane of rotation, by
    Rayleigh–Ritz on ``x**2 P_k(2x - 1)`` (Legendre): lowest three, rad/s."""
    import scipy.linalg
    from numpy.polynomial import legendre as lg

    t, wq = np.polynomial.legendre.leggauss(80)
    x, wq = 0.5 * (t + 1.0), 0.5 * wq
    B, B1, B2 = [], [], []
    for k in range(n_poly):
        c = np.zeros(k + 1)
        c[k] = 1.0
        p = lg.legval(2 * x - 1, c)
        dp = 2 * lg.legval(2 * x - 1, lg.legder(c))
        ddp = 4 * lg.legval(2 * x - 1, lg.legder(c, 2))
        B.append(x**2 * p)
        B1.append(2 * x * p + x**2 * dp)
        B2.append(2 * p + 4 * x * dp + x**2 * ddp)
    B, B1, B2 = np.array(B), np.array(B1), np.array(B2)
    tension = omega**2 * (1 - x**2) / 2
    K = (B2 * wq) @ B2.T + (B1 * tension * wq) @ B1.T - omega**2 * (B * wq) @ B.T
    M = (B * wq) @ B.T
    return np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)[:3])


def one_link(n_modes: int, stiffening: bool) -> fa.FlexibleArm:
    return fa.FlexibleArm(
        [fa.Link(1.0, 1.0, 1.0, n_modes=n_modes)],
        boundary="clamped-free",
        geometric_stiffening=stiffening,
    )


def southwell_k1() -> float:
    """K_1 from the textbook shape by Gauss–Legendre quadrature (no flexarm code)."""
    t, w = np.polynomial.legendre.leggauss(80)
    x, w = 0.5 * (t + 1), 0.5 * w
    phi, dphi = textbook_cantilever(x)
    return float((w @ ((1 - x**2) / 2 * dphi**2)) / (w @ phi**2))


# ------------------------------------------------------------------ closed forms
def test_southwell_coefficient_of_the_first_cantilever_mode():
    """K_1 from the textbook shape, the literature's 1.1933 and flexarm's
    foreshortening integrals agree."""
    k1 = southwell_k1()
    assert k1 == pytest.approx(1.1933, abs=5e-5)
    bm = BeamModes(1.0, 1.0, 1.0, n_modes=1)
    f = foreshortening_integrals(bm)
    assert f.moment[0, 0] / bm.modal_mass[0, 0] == pytest.approx(k1, rel=1e-12)


@pytest.mark.parametrize("ratio", [0.5, 1.5, 2.0, 4.0])
def test_spinning_link_frequency_rises_with_the_spin(ratio):
    """One mode: omega**2 = omega_0**2 + (K_1 - 1) Omega**2 with stiffening,
    omega_0**2 - Omega**2 without (the link buckles once Omega > omega_0)."""
    w0 = BETA1**2
    big_omega = ratio * w0
    k1 = southwell_k1()
    on = spinning_frequencies(one_link(1, True), big_omega)
    assert on[0] ** 2 == pytest.approx(w0**2 + (k1 - 1) * big_omega**2, rel=1e-6)
    off = spinning_frequencies(one_link(1, False), big_omega)
    if ratio < 1.0:
        assert off[0] ** 2 == pytest.approx(w0**2 - big_omega**2, rel=1e-6)
    else:
        assert off.size == 0  # no oscillation: omega_0**2 - Omega**2 <= 0, a buckled link


@pytest.mark.parametrize("ratio", [0.5, 1.0, 2.0])
def test_spinning_link_converges_to_the_continuum_in_plane_frequencies(ratio):
    """The error of the first in-plane frequency falls as modes are added, to the
    stated tolerance at five modes. Both are Rayleigh–Ritz estimates from above;
    the continuum's polynomial basis (16 terms) is converged far below the
    tolerance (12 terms agree to 1e-9)."""
    big_omega = ratio * BETA1**2
    exact = continuum_in_plane_frequencies(big_omega, 16)[0]
    assert continuum_in_plane_frequencies(big_omega, 12)[0] == pytest.approx(exact, rel=1e-9)
    errors = [spinning_frequencies(one_link(n, True), big_omega)[0] / exact - 1 for n in (1, 3, 5)]
    assert all(e > -1e-9 for e in errors)  # upper bounds
    assert errors[0] > errors[1] > errors[2]
    # cantilever modes describe the spinning beam's shape less well as the spin grows:
    # measured 1e-6, 2e-5, 3e-4 at 5 modes; the bound is 1e-3 (Omega/omega_0)**2
    assert errors[2] < 1e-3 * ratio**2


# ------------------------------------------------------- the foreshortening integrals
def test_foreshortening_integrals_against_single_integrals():
    """``int rho S dx = int rho (L - s) phi' phi' ds`` and ``int rho x S dx =
    int rho (L**2 - s**2)/2 phi' phi' ds`` (order of integration exchanged), on a
    clamped-mass beam; the tip's matrix is ``int_0^L phi' phi'``."""
    bm = BeamModes(1.7, 3.0, 0.6, n_modes=4, tip_mass=0.4, tip_inertia=0.05)
    f = foreshortening_integrals(bm)
    L, rho = bm.length, bm.linear_density
    t, w = np.polynomial.legendre.leggauss(120)
    s, w = 0.5 * L * (t + 1), 0.5 * L * w
    g = bm.slope(s)
    np.testing.assert_allclose(f.tip, (g * w) @ g.T, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f.mass, rho * (g * w * (L - s)) @ g.T, rtol=1e-12, atol=1e-11)
    moment = rho * (g * w * (L**2 - s**2) / 2) @ g.T
    np.testing.assert_allclose(f.moment, moment, rtol=1e-12, atol=1e-11)
    # symmetries of the cubic and quartic integrals
    np.testing.assert_allclose(f.cubic, f.cubic.transpose(0, 2, 1), atol=1e-12)
    np.testing.assert_allclose(f.quartic, f.quartic.transpose(1, 0, 2, 3), atol=1e-10)
    np.testing.assert_allclose(f.quartic, f.quartic.transpose(2, 3, 0, 1), atol=1e-10)


def test_shortening_is_half_the_integral_of_the_squared_slope():
    bm = BeamModes(2.0, 1.0, 1.0, n_modes=3)
    delta = np.array([0.3, -0.1, 0.05])
    x = np.linspace(0.0, 2.0, 7)
    u = 0.5 * np.einsum("j,jkm,k->m", delta, shortening_matrix(bm, x), delta)
    fine = np.linspace(0.0, 2.0, 200_001)
    slope2 = (delta @ bm.slope(fine)) ** 2
    cumulative = np.concatenate(
        [[0.0], np.cumsum(0.5 * (slope2[1:] + slope2[:-1]) * np.diff(fine))]
    )
    np.testing.assert_allclose(u, 0.5 * np.interp(x, fine, cumulative), rtol=1e-9, atol=1e-12)
    assert u[0] == 0.0


def test_point_of_a_bent_link_keeps_its_arc_length():
    """The deflected link is inextensible to second order: the chord from the joint
    to each point shortens by u(x), so |p(x)|**2 = (x - u)**2 + w**2."""
    arm = fa.FlexibleArm([fa.Link(2.0, 3.0, 0.5, n_modes=2)], geometric_stiffening=True)
    q = np.array([0.7, 0.2, -0.05])
    bm = arm.modes[0]
    for x in (0.5, 1.3, 2.0):
        p = arm.point_position(q, 0, x)
        w = q[1:] @ bm.shape(x)[:, 0]
        u = 0.5 * q[1:] @ shortening_matrix(bm, x)[:, :, 0] @ q[1:]
        assert p @ p == pytest.approx((x - u) ** 2 + w**2, rel=1e-13)
        assert u > 0


def test_compiled_point_kinematics_carries_the_foreshortening():
    links = [fa.Link(1.3, 4.0, 0.9, n_modes=2), fa.Link(0.9, 2.5, 0.5, n_modes=3)]
    arm = fa.FlexibleArm(links, geometric_stiffening=True)
    rng = np.random.default_rng(3)
    q, dq = rng.normal(size=arm.n_dof) * 0.3, rng.normal(size=arm.n_dof)
    for link, d in ((0, 0.4), (1, 0.5), (1, 0.9)):
        out = np.empty(4)
        dynamics.point_kinematics(q, dq, arm.arrays, link, d, arm.point_basis(link, d), out)
        np.testing.assert_allclose(out[:2], arm.point_position(q, link, d), rtol=1e-13)
        eps = 1e-6
        fd = arm.point_position(q + eps * dq, link, d) - arm.point_position(q - eps * dq, link, d)
        np.testing.assert_allclose(out[2:], fd / (2 * eps), rtol=1e-7, atol=1e-9)


# --------------------------------------------------------------------- off switch
def test_off_switch_packs_no_stiffening_terms():
    arm = fa.FlexibleArm.paper(n_modes=2, boundary="clamped-mass")
    a = arm.arrays
    assert not arm.geometric_stiffening
    assert a.shortening_cubic.shape == (arm.n_dof, 0, 0)
    assert a.shortening_quartic.shape == (arm.n_dof, 0, 0, 0)
    for name in ("shortening_tip", "shortening_mass", "shortening_moment"):
        assert not np.any(getattr(a, name))
    on = arm.with_modes(2, geometric_stiffening=True).arrays
    assert on.shortening_quartic.shape == (arm.n_dof, 2, 2, 2)
    assert np.all(np.diag(on.shortening_tip)[2:] > 0)


@pytest.mark.parametrize("joints", [False, True], ids=["rigid-joints", "flexible-joints"])
def test_stiffening_path_with_zero_terms_is_the_off_path_bit_for_bit(joints):
    """The stiffening code only adds terms: fed all-zero foreshortening integrals
    (K > 0, so the stiffening branch runs), the kernels return exactly what the
    arm without stiffening returns."""
    joint = [fa.NonlinearJoint.default(fa.MakkarFriction.default())] * 2 if joints else None
    links = [fa.Link(1.3, 4.0, 0.9, n_modes=2, hub_mass=0.3), fa.Link(0.9, 2.5, 0.5, n_modes=3)]
    arm = fa.FlexibleArm(
        links, payload_mass=0.4, payload_inertia=0.05, joints=joint, geometric_stiffening=False
    )
    off = arm.arrays
    n, k = arm.n_dof, 3
    fields = {f: getattr(off, f) for f in off._fields if not f.startswith("shortening")}
    zeros = pack_arm_arrays(
        **fields,
        shortening_tip=np.zeros((n, n)),
        shortening_mass=np.zeros((n, n)),
        shortening_moment=np.zeros((n, n)),
        shortening_cubic=np.zeros((n, k, k)),
        shortening_quartic=np.zeros((n, k, k, k)),
    )
    rng = np.random.default_rng(4)
    for _ in range(5):
        q, dq = rng.normal(size=n) * 0.3, rng.normal(size=n)
        tau = rng.normal(size=2)
        got = []
        for model in (off, zeros):
            ws, ddq = dynamics.make_workspace(n), np.empty(n)
            dynamics.forward_dynamics(q, dq, tau, model, ws, ddq)
            dynamics.mass_and_bias(q, dq, model, ws)
            out = np.empty(4)
            dynamics.point_kinematics(q, dq, model, 1, 0.9, arm.point_basis(1, 0.9), out)
            got.append(np.concatenate([ddq, ws.mass.ravel(), ws.bias, out]))
        np.testing.assert_array_equal(got[1], got[0])


def test_the_paper_arm_keeps_the_paper_model():
    arm = fa.FlexibleArm.paper()
    assert arm.boundary == "clamped-free" and not arm.geometric_stiffening
    assert arm.n_modes == (1, 1)
    assert dynamics.is_two_links_one_mode(arm.arrays)
    assert not dynamics.is_two_links_one_mode(
        fa.FlexibleArm.paper(geometric_stiffening=True).arrays
    )
    assert "1.2x" in fa.model.validity.PAPER_MODEL_NOTE
    user = fa.FlexibleArm([fa.Link(4.5, 1676.0, 0.335)] * 2)
    assert user.boundary == "clamped-mass" and user.geometric_stiffening
    assert user.n_modes == (3, 3)


# --------------------------------------------------------------- prescribed motion
@pytest.mark.parametrize("stiffening", [False, True])
@pytest.mark.parametrize("joints", [False, True], ids=["rigid-joints", "flexible-joints"])
def test_prescribed_motion_kernel_matches_numpy_and_forward_dynamics(joints, stiffening):
    """The compiled kernel equals the NumPy reference, and the servo torque it
    returns, fed to the forward dynamics, gives back the prescribed accelerations."""
    joint = [fa.LinearJoint(400.0, 0.05)] * 2 if joints else None
    links = [fa.Link(1.3, 4.0, 0.9, n_modes=2, hub_mass=0.3), fa.Link(0.9, 2.5, 0.5)]
    arm = fa.FlexibleArm(links, payload_mass=0.2, joints=joint, geometric_stiffening=stiffening)
    rng = np.random.default_rng(5)
    n = arm.n_dof
    for _ in range(4):
        q, dq, acc = rng.normal(size=n) * 0.2, rng.normal(size=n), rng.normal(size=2)
        ddq, tau = prescribed_accelerations(arm, q, dq, acc)
        np.testing.assert_allclose(ddq[arm.actuated_slice], acc, rtol=0, atol=0)
        d2, t2 = np.empty(n), np.empty(2)
        prescribed_dynamics(q, dq, acc, arm.arrays, dynamics.make_workspace(n), d2, t2)
        scale = np.abs(ddq).max()
        np.testing.assert_allclose(d2, ddq, rtol=1e-10, atol=1e-10 * scale)
        np.testing.assert_allclose(t2, tau, rtol=1e-10, atol=1e-10 * np.abs(tau).max())
        back = arm.forward_dynamics(q, dq, tau)
        np.testing.assert_allclose(back, ddq, rtol=1e-8, atol=1e-8 * scale)


def kane(omega: float, ramp: float = 15.0):
    """Kane, Ryan & Banerjee's spin-up: theta(t) for t < T, then omega t - omega T / 2."""

    def motion(t: np.ndarray):
        c = ramp / (2 * np.pi)
        on = t < ramp
        th = np.where(
            on, omega / ramp * (t**2 / 2 + c**2 * (np.cos(t / c) - 1)), omega * (t - ramp / 2)
        )
        dth = np.where(on, omega / ramp * (t - c * np.sin(t / c)), omega)
        ddth = np.where(on, omega / ramp * (1 - np.cos(t / c)), 0.0)
        return th, dth, ddth

    return motion


KANE_BEAM = fa.Link(10.0, 1.4e4, 1.2, n_modes=3)  # L (m), EI (N m^2), rho A (kg/m)


def test_spin_up_stays_bounded_with_stiffening_and_diverges_without():
    """Omega = 6 rad/s, above the first bending frequency (3.80 rad/s). The tip
    deflection stays below the quasi-static deflection under the peak angular
    acceleration 2 Omega / T of a beam without stiffening,
    11 rho alpha L**5 / (120 EI) = 0.63 m (stiffening only lowers it; the ramp is
    slow against the bending period, so dynamic amplification is small), and the
    residual vibration at constant spin is a small fraction of it. Without
    stiffening the link diverges once Omega passes 3.8 rad/s (t = 11 s)."""
    t = np.linspace(0.0, 20.0, 2001)
    arm = fa.FlexibleArm([KANE_BEAM], geometric_stiffening=True)
    res = simulate_prescribed(arm, t, kane(6.0), substeps=5)
    w = res.link_deflections[:, 0]
    alpha = 2 * 6.0 / 15.0
    bound = 11 * 1.2 * alpha * 10.0**5 / (120 * 1.4e4)
    assert np.abs(w).max() < bound
    assert np.abs(w[t > 16.0]).max() < 0.05 * np.abs(w).max()
    with pytest.raises(SimulationError) as err:
        simulate_prescribed(
            fa.FlexibleArm([KANE_BEAM], geometric_stiffening=False), t, kane(6.0), substeps=5
        )
    assert 9.0 < err.value.time < 12.0


# ------------------------------------------------------------------ bad input
def test_arm_rejects_a_non_bool_switch():
    with pytest.raises(InvalidTypeError, match="'geometric_stiffening' parameter of FlexibleArm"):
        fa.FlexibleArm([KANE_BEAM], geometric_stiffening=1)


def test_with_modes_copies_and_checks():
    arm = fa.FlexibleArm([KANE_BEAM] * 2, payload_mass=0.3)
    five = arm.with_modes(5, boundary="clamped-free")
    assert five.n_modes == (5, 5) and five.boundary == "clamped-free" and five.payload_mass == 0.3
    assert arm.with_modes([1, 2]).n_modes == (1, 2) and arm.n_modes == (3, 3)
    with pytest.raises(InvalidValueError, match=r"'n_modes' parameter of FlexibleArm\.with_modes"):
        arm.with_modes([1, 2, 3])


@pytest.mark.parametrize(
    ("t", "motion", "error", "match"),
    [
        (np.array([0.0]), kane(1.0), InvalidValueError, "'t'"),
        (np.array([0.0, 0.1, 0.3]), kane(1.0), InvalidValueError, "evenly spaced"),
        (np.linspace(0, 1, 11), "spin", InvalidTypeError, "'motion'"),
        (np.linspace(0, 1, 11), lambda t: t, InvalidValueError, "'motion'"),
        (np.linspace(0, 1, 11), lambda t: (t, t, t[:3]), InvalidValueError, "ddtheta"),
        (np.linspace(0, 1, 11), lambda t: (t * np.nan, t, t), InvalidValueError, "finite theta"),
    ],
)
def test_simulate_prescribed_rejects_bad_input(t, motion, error, match):
    with pytest.raises(error, match=match):
        simulate_prescribed(fa.FlexibleArm([KANE_BEAM]), t, motion)


def test_shortening_matrix_rejects_points_off_the_link():
    with pytest.raises(InvalidValueError, match="'x' parameter of shortening_matrix"):
        shortening_matrix(BeamModes(1.0, 1.0, 1.0, 2), [0.5, 1.5])


@pytest.mark.parametrize("sensor", ["tip", "point"])
def test_physical_sensors_see_the_foreshortened_point(sensor):
    """In closed loop, a physical point sensor on an arm with stiffening measures the
    point where arm.point_position puts it, foreshortening included (the sensor
    carries the point's shortening matrix: FlexibleArm.point_basis)."""
    from flexarm.control.controllers import JointPD
    from flexarm.control.trajectories import Square
    from flexarm.sensing.sensors import PointSensor, TipSensor
    from flexarm.sim import simulate

    arm = fa.FlexibleArm.paper(n_modes=2, boundary="clamped-mass", geometric_stiffening=True)
    square = Square(center=(5.0, 0.0), side=2.0, time_per_side=0.5)
    link, d = (1, 4.5) if sensor == "tip" else (1, 0.5)
    sens = TipSensor() if sensor == "tip" else PointSensor(link, d)
    res = simulate(arm, JointPD(kp=2000.0, kd=300.0), square, sensor=sens, duration=0.5)
    expected = arm.point_position(res.q, link, d)
    np.testing.assert_allclose(res.measurement[:, 4:6], expected, rtol=0, atol=1e-12)
    linear = arm.with_modes(2, geometric_stiffening=False).point_position(res.q, link, d)
    assert np.abs(expected - linear).max() > 1e-9  # the foreshortening is in the signal
