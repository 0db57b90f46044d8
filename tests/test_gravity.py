"""Gravity in the plane of motion (flexarm.model.gravity, flexarm.model.statics).

Oracles, none of them the code under test:

* the potential against a quadrature of ``-g . p dm`` over the deflected points
  (``point_position``), and the forces against its central differences;
* every compiled kernel against the NumPy reference;
* the static sag of a cantilever against the closed forms ``q L**4 / (8 EI)``
  (own weight) and ``P L**3 / (3 EI)`` (tip load);
* a hanging and a standing link's frequencies against a finite-element beam
  written here (Hermite elements with the geometric stiffness of the axial load
  ``N(x) = +- rho g (L - x)``), and the standing link's buckling at Greenhill's
  ``(rho g L**3)_cr = 7.837 EI``;
* conservation of kinetic plus potential energy in a free swing;
* holding torques against moment sums by hand; the rigid limit against a
  textbook rigid two-link arm (and Pinocchio, where installed);
* a flexible two-link arm released from rest against Exudyn's ANCF cables.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

import flexarm as fa
from exudyn_models import EXUDYN_MISSING, TorquePulses, run_exudyn
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.model import dynamics
from flexarm.model.gravity import gravity_forces
from flexarm.model.prescribed import prescribed_accelerations, prescribed_dynamics
from flexarm.model.statics import UnstableEquilibriumError
from helpers.arms import random_state, three_links, two_short_links

G = 9.81
DOWN = (0.0, -G)
TILTED = (2.0, -9.6)  # both components, to catch a swapped or dropped one
GREENHILL = 7.8373  # (rho g L**3 / EI) at which a uniform column buckles under its weight


def cantilever(n_modes: int, **kwargs) -> fa.FlexibleArm:
    """One link, 1 m, EI = 100 N m**2, rho = 1 kg/m, under gravity ``DOWN``."""
    kwargs.setdefault("gravity", DOWN)
    return fa.FlexibleArm([fa.Link(1.0, 100.0, 1.0, n_modes=n_modes)], **kwargs)


ARMS = {
    "one-link": lambda: cantilever(3, payload_mass=0.2),
    "paper-scalar": lambda: fa.FlexibleArm.paper(gravity=TILTED, payload_mass=0.3),
    "two-stiffened": lambda: two_short_links(2, gravity=TILTED),
    "two-linear": lambda: two_short_links(
        2, gravity=TILTED, geometric_stiffening=False, boundary="clamped-free"
    ),
    "three-recursive": lambda: three_links(gravity=TILTED),
    "two-stiff": lambda: fa.FlexibleArm(
        [fa.Link(1.0, 60.0, 1.0, n_modes=2), fa.Link(0.8, 40.0, 0.8, n_modes=2, hub_mass=0.3)],
        payload_mass=0.2,
        payload_inertia=0.01,
        gravity=TILTED,
    ),
    "flexible-joints": lambda: fa.FlexibleArm.paper(
        gravity=TILTED, joints=[fa.LinearJoint(200.0, 0.05)] * 2, geometric_stiffening=True
    ),
}


# ------------------------------------------------------------------ the parameter
@pytest.mark.parametrize(
    ("value", "error"),
    [
        ("down", InvalidTypeError),
        (9.81, InvalidTypeError),
        ((0.0,), InvalidValueError),
        ((0.0, -9.81, 0.0), InvalidValueError),
        ((0.0, float("nan")), InvalidValueError),
        ((0.0, float("inf")), InvalidValueError),
        ((True, -9.81), InvalidTypeError),
        ((0.0, "g"), InvalidTypeError),
    ],
)
def test_bad_gravity_is_named(value, error):
    with pytest.raises(error, match="'gravity'"):
        cantilever(1, gravity=value)


def test_gravity_is_stored_as_two_floats():
    arm = cantilever(1, gravity=np.array([0, -10]))
    assert arm.gravity == (0.0, -10.0)
    assert cantilever(1, gravity=None).gravity is None
    np.testing.assert_array_equal(cantilever(1, gravity=None).arrays.gravity, [0.0, 0.0])


def test_zero_gravity_is_the_arm_without_it_bit_for_bit():
    """(0, 0) skips the terms as None does: the same accelerations to the bit."""
    rng = np.random.default_rng(3)
    for make in (lambda g: two_short_links(2, gravity=g), lambda g: three_links(gravity=g)):
        off, zero = make(None), make((0.0, 0.0))
        q, dq = random_state(off, rng)
        tau = rng.normal(size=off.n_links)
        assert np.array_equal(off.forward_dynamics(q, dq, tau), zero.forward_dynamics(q, dq, tau))


# ------------------------------------------------------- potential and its forces
def _quadrature_potential(arm: fa.FlexibleArm, q: np.ndarray, nodes: int = 20) -> np.ndarray:
    """``-g . (int p dm + hubs + payload)`` from the deflected points (Gauss-Legendre),
    for each row of ``q`` (m, n_dof)."""
    g = np.asarray(arm.gravity)
    x, w = np.polynomial.legendre.leggauss(nodes)
    total = np.zeros(q.shape[0])
    for i, lk in enumerate(arm.links):
        L = lk.length
        for xi, wi in zip(x, w, strict=True):
            p = arm.point_position(q, i, 0.5 * L * (1 + xi))
            total += lk.linear_density * 0.5 * L * wi * (p @ g)
        if i > 0:
            total += lk.hub_mass * (arm.point_position(q, i, 0.0) @ g)
    last = arm.n_links - 1
    tip = arm.point_position(q, last, arm.links[last].length)
    return -(total + arm.payload_mass * (tip @ g))


@pytest.mark.parametrize("name", ["one-link", "two-stiffened", "two-linear", "three-recursive"])
def test_potential_and_forces_match_the_deflected_points(name):
    arm = ARMS[name]()
    rng = np.random.default_rng(5)
    for _ in range(3):
        q, dq = random_state(arm, rng)
        h = 1e-6 * np.eye(arm.n_dof)
        v = _quadrature_potential(arm, np.vstack([q, q + h, q - h]))
        kinetic, potential = arm.energy(q, dq)
        elastic = 0.5 * q @ (arm.arrays.stiffness * q)
        assert potential - elastic == pytest.approx(v[0], rel=1e-11, abs=1e-12)
        fd = -(v[1 : arm.n_dof + 1] - v[arm.n_dof + 1 :]) / 2e-6
        np.testing.assert_allclose(gravity_forces(arm, q), fd, rtol=1e-7, atol=1e-7)
        assert kinetic == pytest.approx(0.5 * dq @ arm.mass_matrix(q) @ dq)


# --------------------------------------------------------------- every backend
def _kernel(kernel, arm, q, dq, tau):
    ddq = np.empty(arm.n_dof)
    if kernel is dynamics.forward_dynamics_two_links_one_mode:
        kernel(q, dq, tau, arm.arrays, ddq)
    else:
        kernel(q, dq, tau, arm.arrays, dynamics.make_workspace(arm.n_dof), ddq)
    return ddq


@pytest.mark.parametrize("name", sorted(ARMS))
def test_every_backend_agrees_with_the_numpy_reference(name):
    arm = ARMS[name]()
    kernels = [
        dynamics.forward_dynamics,
        dynamics.forward_dynamics_dense,
        dynamics.forward_dynamics_recursive,
    ]
    if dynamics.is_two_links_one_mode(arm.arrays):
        kernels.append(dynamics.forward_dynamics_two_links_one_mode)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, dq = random_state(arm, rng)
        tau = rng.normal(size=arm.n_links)
        ref = arm.forward_dynamics(q, dq, tau, backend="numpy")
        for kernel in kernels:
            got = _kernel(kernel, arm, q, dq, tau)
            np.testing.assert_allclose(
                got, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max(), err_msg=kernel.__name__
            )
        fast = arm.forward_dynamics(q, dq, tau)
        np.testing.assert_array_equal(fast, _kernel(dynamics.forward_dynamics, arm, q, dq, tau))
        # gravity moves the answer far beyond the tolerance: the checks are not vacuous
        free = fa.FlexibleArm(**{**_fields(arm), "gravity": None})
        assert np.abs(free.forward_dynamics(q, dq, tau) - ref).max() > 1e-6 * np.abs(ref).max()
        acc = rng.normal(size=arm.n_links)
        want_ddq, want_tau = prescribed_accelerations(arm, q, dq, acc)
        ddq, t = np.empty(arm.n_dof), np.empty(arm.n_links)
        prescribed_dynamics(q, dq, acc, arm.arrays, dynamics.make_workspace(arm.n_dof), ddq, t)
        np.testing.assert_allclose(ddq, want_ddq, rtol=1e-10, atol=1e-10 * np.abs(want_ddq).max())
        np.testing.assert_allclose(t, want_tau, rtol=1e-10, atol=1e-10 * np.abs(want_tau).max())


def _fields(arm: fa.FlexibleArm) -> dict:
    import dataclasses

    return {f.name: getattr(arm, f.name) for f in dataclasses.fields(arm) if f.init}


# ------------------------------------------------------------------ static sag
def test_own_weight_sag_converges_to_the_closed_form():
    """Horizontal cantilever: tip sag q L**4 / (8 EI), holding torque q L**2 / 2 (the
    linear theory's; with geometric stiffening the sag is the same and the torque
    less by the weight times the points' pull-in, a relative 6e-5)."""
    exact = G * 1.0 / (8 * 100.0)  # rho g L**4 / (8 EI), m
    errs = []
    for n in (1, 2, 3, 4, 6):
        eq = cantilever(n, geometric_stiffening=False).equilibrium([0.0])
        errs.append(abs(-eq.tip[1] - exact) / exact)
        assert eq.torques[0] == pytest.approx(G / 2, rel=1e-12)  # the link's own
        assert eq.stable and eq.residual < 1e-10
        stiffened = cantilever(n).equilibrium([0.0])
        assert stiffened.tip[1] == pytest.approx(eq.tip[1], rel=1e-12)
        assert stiffened.torques[0] == pytest.approx(G / 2, rel=1e-4)
        assert stiffened.torques[0] < G / 2
    assert np.all(np.diff(errs) < 0), errs
    assert errs[0] > 1e-3  # one mode is visibly off ...
    assert errs[-1] < 2e-5  # ... six are on the closed form


def test_tip_load_sag_converges_to_the_closed_form():
    """A payload P = m g at the tip adds P L**3 / (3 EI) to the own-weight sag
    (superposition; clamped-mass modes carry the tip mass)."""
    mp = 0.8
    exact = G / (8 * 100.0) + mp * G / (3 * 100.0)
    errs = []
    for n in (1, 2, 3, 5):
        eq = cantilever(n, payload_mass=mp, geometric_stiffening=False).equilibrium([0.0])
        errs.append(abs(-eq.tip[1] - exact) / exact)
        assert eq.torques[0] == pytest.approx(G / 2 + mp * G, rel=1e-12)
    assert np.all(np.diff(errs) < 0), errs
    assert errs[-1] < 2e-5


def test_sag_shortens_the_link_by_half_the_integral_of_its_slope_squared():
    """With geometric stiffening the sagging tip moves in by 1/2 int w'**2 of the
    closed-form deflection w = q x**2 (6 L**2 - 4 L x + x**2) / (24 EI)."""
    eq = cantilever(6).equilibrium([0.0])
    x, w = np.polynomial.legendre.leggauss(20)
    x = 0.5 * (x + 1)
    slope = G / (24 * 100.0) * (12 * x - 12 * x**2 + 4 * x**3)
    pull_in = 0.5 * 0.5 * np.sum(w * slope**2)
    assert 1.0 - eq.tip[0] == pytest.approx(pull_in, rel=1e-3)
    linear = cantilever(6, geometric_stiffening=False).equilibrium([0.0])
    assert linear.tip[0] == 1.0


# ------------------------------------------- hanging and standing: frequencies, buckling
def _fe_frequencies(load: float, n_el: int = 40, count: int = 3) -> np.ndarray:
    """First ``count`` frequencies (rad/s) of a clamped-free beam (L = EI = rho = 1)
    under the axial force ``N(x) = load (1 - x)`` (tension > 0): Hermite cubic
    elements, consistent mass, geometric stiffness ``int N H' H'^T``."""
    h = 1.0 / n_el
    ke = np.array(
        [[12, 6 * h, -12, 6 * h], [6 * h, 4 * h**2, -6 * h, 2 * h**2],
         [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h**2, -6 * h, 4 * h**2]]
    ) / h**3  # fmt: skip
    me = h / 420 * np.array(
        [[156, 22 * h, 54, -13 * h], [22 * h, 4 * h**2, 13 * h, -3 * h**2],
         [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h**2, -22 * h, 4 * h**2]]
    )  # fmt: skip
    gp, gw = np.polynomial.legendre.leggauss(4)
    n = 2 * (n_el + 1)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for e in range(n_el):
        kg = np.zeros((4, 4))
        for xi, wi in zip(gp, gw, strict=True):
            s = 0.5 * (xi + 1)  # local coordinate in [0, 1]
            # slopes of the Hermite shape functions (w1, w1', w2, w2') along the element
            dH = np.array([(6 * s**2 - 6 * s) / h, 1 - 4 * s + 3 * s**2, (6 * s - 6 * s**2) / h])
            dH = np.append(dH, 3 * s**2 - 2 * s)
            N = load * (1.0 - (e + s) * h)
            kg += 0.5 * h * wi * N * np.outer(dH, dH)
        dofs = slice(2 * e, 2 * e + 4)
        K[dofs, dofs] += ke + kg
        M[dofs, dofs] += me
    lam = scipy.linalg.eigh(K[2:, 2:], M[2:, 2:], eigvals_only=True)
    return np.sqrt(lam[:count])


@pytest.mark.parametrize(("posture", "sign"), [(-np.pi / 2, 1.0), (np.pi / 2, -1.0)])
def test_hanging_and_standing_frequencies_match_a_finite_element_beam(posture, sign):
    """Load rho g L**3 / EI = 4 (about half Greenhill's): the first frequency moves by
    about a quarter, down for the standing link, up for the hanging one."""
    load = 4.0
    arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=6)], gravity=(0.0, -load))
    eq = arm.equilibrium([posture])
    fe = _fe_frequencies(sign * load)
    np.testing.assert_allclose(eq.frequencies[:3], fe, rtol=2e-5)
    unloaded = _fe_frequencies(0.0)
    assert sign * (eq.frequencies[0] - unloaded[0]) > 0.1 * unloaded[0]
    np.testing.assert_allclose(eq.deflections[0], 0.0, atol=1e-14)  # gravity along the link
    assert eq.torques[0] == pytest.approx(0.0, abs=1e-12)


def test_standing_link_buckles_at_greenhills_load():
    def standing(load: float, **kwargs):
        arm = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=6)], gravity=(0.0, -load))
        return arm.equilibrium([np.pi / 2], **kwargs)

    # six modes put the critical load within 2e-5 of Greenhill's (from above: 7.8375)
    below = standing(0.999 * GREENHILL)
    assert below.stable and below.eigenvalues[0] > 0
    with pytest.raises(UnstableEquilibriumError, match="buckling") as info:
        standing(1.001 * GREENHILL)
    flagged = info.value.equilibrium
    assert not flagged.stable and flagged.eigenvalues[0] < 0
    assert np.isnan(flagged.frequencies[0])
    again = standing(1.001 * GREENHILL, require_stable=False)
    assert not again.stable
    # the hanging link under the same load is stiffened, not buckled
    hanging = fa.FlexibleArm([fa.Link(1.0, 1.0, 1.0, n_modes=6)], gravity=(0.0, -1.01 * GREENHILL))
    assert hanging.equilibrium([-np.pi / 2]).stable


# ------------------------------------------------------------------- free swing
def test_free_swing_conserves_kinetic_plus_potential_energy():
    """Released at rest from the horizontal (no damping, no torque): T + V stays
    put while some 20 J change between the two."""
    arm = two_short_links(2, gravity=TILTED)
    n = arm.n_dof
    zero = np.zeros(arm.n_links)

    def rhs(t, x):
        return np.concatenate([x[n:], arm.forward_dynamics(x[:n], x[n:], zero)])

    x0 = np.zeros(2 * n)
    sol = scipy.integrate.solve_ivp(rhs, (0.0, 1.0), x0, method="DOP853", rtol=1e-10, atol=1e-12,
                                    t_eval=np.linspace(0.0, 1.0, 21))  # fmt: skip
    energies = np.array([sum(arm.energy(x[:n], x[n:])) for x in sol.y.T])
    kinetic = np.array([arm.energy(x[:n], x[n:])[0] for x in sol.y.T])
    assert kinetic.max() > 10.0
    assert np.abs(energies - energies[0]).max() < 1e-7 * kinetic.max()


# ------------------------------------------------------------ statics by hand
def _hand_torques(links, mh2, mp, theta, g):
    """Holding torques of a rigid two-link arm: minus the moment of every weight
    outboard of each joint about it (uniform rods, hub 2 at joint 2, payload at
    the tip)."""
    (L1, m1), (L2, m2) = links
    g = np.asarray(g)
    e1 = np.array([np.cos(theta[0]), np.sin(theta[0])])
    e2 = np.array([np.cos(theta[0] + theta[1]), np.sin(theta[0] + theta[1])])

    def moment(r, m):
        return r[0] * m * g[1] - r[1] * m * g[0]

    o2 = L1 * e1
    weights2 = [(0.5 * L2 * e2, m2), (L2 * e2, mp)]
    weights1 = [(0.5 * L1 * e1, m1), (o2, mh2)] + [(o2 + r, m) for r, m in weights2]
    return np.array([-sum(moment(r, m) for r, m in w) for w in (weights1, weights2)])


@pytest.mark.parametrize("n_modes", [0, 2])
def test_holding_torques_match_statics_by_hand(n_modes):
    """Rigid links (no modes), and stiff flexible ones (EI 1e9 N m**2: link 1's tip
    slope, some 1e-8 rad, turns link 2 and changes the torques by less than 1e-7)."""
    L1, L2, rho1, rho2, mh2, mp = 1.2, 0.9, 2.0, 1.5, 0.7, 0.4
    links = [
        fa.Link(L1, 1e9, rho1, n_modes=n_modes, hub_mass=3.0, hub_inertia=0.1),
        fa.Link(L2, 1e9, rho2, n_modes=n_modes, hub_mass=mh2, hub_inertia=0.05),
    ]
    arm = fa.FlexibleArm(links, payload_mass=mp, payload_inertia=0.02, gravity=TILTED)
    for theta in ([0.0, 0.0], [0.4, -1.1], [2.5, 0.7]):
        want = _hand_torques([(L1, rho1 * L1), (L2, rho2 * L2)], mh2, mp, theta, TILTED)
        eq = arm.equilibrium(theta)
        np.testing.assert_allclose(eq.torques, want, rtol=1e-6, atol=1e-9)
        # the torques hold the arm: released under them, it does not accelerate
        ddq = arm.forward_dynamics(eq.q, np.zeros(arm.n_dof), eq.torques)
        assert np.abs(ddq).max() < 1e-9


# -------------------------------------------------------------- rigid limit
def _textbook(links, hubs, mp, jp, g, q, dq, tau):
    """``ddq`` of a rigid two-link arm from its textbook M, C and g(q): uniform rods
    ``(L, m)``, hubs ``(mass, inertia)`` (hub 1's mass on the fixed base), payload
    mass ``mp`` and inertia ``jp`` at the tip."""
    (L1, m1), (L2, m2) = links
    (_, J1), (mh2, J2) = hubs
    gx, gy = g
    s2 = m2 * L2 / 2 + mp * L2  # first moment of link 2's side about joint 2
    s1 = m1 * L1 / 2 + (m2 + mh2 + mp) * L1
    i2 = m2 * L2**2 / 3 + J2 + mp * L2**2 + jp
    c2 = np.cos(q[1])
    i1 = m1 * L1**2 / 3 + J1 + (m2 + mh2 + mp) * L1**2
    M = np.array([[i1 + i2 + 2 * s2 * L1 * c2, i2 + s2 * L1 * c2], [i2 + s2 * L1 * c2, i2]])
    h = s2 * L1 * np.sin(q[1])
    C = np.array([-h * (2 * dq[0] * dq[1] + dq[1] ** 2), h * dq[0] ** 2])
    a1, a12 = q[0], q[0] + q[1]

    def de(a):  # g . d/da (cos a, sin a)
        return -np.sin(a) * gx + np.cos(a) * gy

    gq = -np.array([s1 * de(a1) + s2 * de(a12), s2 * de(a12)])  # dV/dq
    return np.linalg.solve(M, tau - C - gq)


RIGID = {
    "links": [(1.2, 2.4), (0.9, 1.35)],
    "hubs": [(3.0, 0.1), (0.7, 0.05)],
    "payload": (0.4, 0.02),
}


def _rigid_arm() -> fa.FlexibleArm:
    (L1, m1), (L2, m2) = RIGID["links"]
    (mh1, j1), (mh2, j2) = RIGID["hubs"]
    links = [
        fa.Link(L1, 1.0, m1 / L1, n_modes=0, hub_mass=mh1, hub_inertia=j1),
        fa.Link(L2, 1.0, m2 / L2, n_modes=0, hub_mass=mh2, hub_inertia=j2),
    ]
    mp, jp = RIGID["payload"]
    return fa.FlexibleArm(links, payload_mass=mp, payload_inertia=jp, gravity=TILTED)


def test_rigid_limit_matches_the_textbook_two_link_arm():
    arm = _rigid_arm()
    rng = np.random.default_rng(17)
    for _ in range(5):
        q, dq, tau = rng.uniform(-np.pi, np.pi, 2), rng.normal(size=2), rng.normal(size=2)
        want = _textbook(RIGID["links"], RIGID["hubs"], *RIGID["payload"], TILTED, q, dq, tau)
        for backend in ("compiled", "numpy"):
            np.testing.assert_allclose(arm.forward_dynamics(q, dq, tau, backend=backend), want,
                                       rtol=1e-12, atol=1e-12)  # fmt: skip


def test_rigid_limit_matches_pinocchio():
    pin = pytest.importorskip("pinocchio", reason="Pinocchio is not installed (pip install pin)")
    (L1, m1), (L2, m2) = RIGID["links"]
    (_, j1), (mh2, j2) = RIGID["hubs"]
    mp, jp = RIGID["payload"]
    model = pin.Model()
    model.gravity.linear = np.array([TILTED[0], TILTED[1], 0.0])

    def rod(m, L, extra):  # a uniform rod along x from the joint, plus a rotary inertia
        inertia = np.diag([0.0, m * L**2 / 12, m * L**2 / 12 + extra])
        return pin.Inertia(m, np.array([L / 2, 0.0, 0.0]), inertia)

    j = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "joint1")
    model.appendBodyToJoint(j, rod(m1, L1, j1), pin.SE3.Identity())
    hub = pin.Inertia(mh2, np.zeros(3), np.zeros((3, 3)))
    at_tip = pin.SE3(np.eye(3), np.array([L1, 0.0, 0.0]))
    model.appendBodyToJoint(j, hub, at_tip)
    j = model.addJoint(j, pin.JointModelRZ(), at_tip, "joint2")
    model.appendBodyToJoint(j, rod(m2, L2, j2), pin.SE3.Identity())
    payload = pin.Inertia(mp, np.zeros(3), np.diag([0.0, 0.0, jp]))
    model.appendBodyToJoint(j, payload, pin.SE3(np.eye(3), np.array([L2, 0.0, 0.0])))
    data = model.createData()
    arm = _rigid_arm()
    rng = np.random.default_rng(19)
    for _ in range(5):
        q, dq, tau = rng.uniform(-np.pi, np.pi, 2), rng.normal(size=2), rng.normal(size=2)
        want = pin.aba(model, data, q, dq, tau)
        np.testing.assert_allclose(arm.forward_dynamics(q, dq, tau), want, rtol=1e-10, atol=1e-10)
        static = pin.computeGeneralizedGravity(model, data, q)
        np.testing.assert_allclose(arm.equilibrium(q).torques, static, rtol=1e-10, atol=1e-10)


# --------------------------------------------------------------- against Exudyn
@pytest.mark.skipif(bool(EXUDYN_MISSING), reason=EXUDYN_MISSING or "")
def test_two_link_arm_released_from_rest_matches_exudyn():
    """Straight and horizontal at rest, then let go: 0.6 s of the fall (the tip travels
    some 2 m; the links bend by up to 8 mm and ring). The tip path is within 1 % of
    its travel (measured: 2e-4 with one mode per link, 1.5e-5 with three) and the
    errors of the tip and of the link deflections fall with modes."""
    links = [fa.Link(1.0, 60.0, 1.0), fa.Link(0.8, 40.0, 0.8, hub_mass=0.3)]
    arm = fa.FlexibleArm(links, payload_mass=0.2, gravity=DOWN)
    none = TorquePulses((0.0, 0.0), (1.0, 1.0))
    ref = run_exudyn(arm, none, t_end=0.6, dt_out=0.01, n_elements=8, step=5e-4, gravity=DOWN)
    travel = np.linalg.norm(ref.tip - ref.tip[0], axis=1).max()
    peak = np.abs(ref.deflection).max(axis=0)
    tip, bend = [], []
    for k in (1, 3):
        torque = np.zeros((ref.t.shape[0], 2))
        res = fa.simulate_open_loop(arm.with_modes(k), ref.t, torque, substeps="auto")
        tip.append(np.linalg.norm(res.tip - ref.tip, axis=1).max() / travel)
        bend.append(np.abs(res.link_deflections - ref.deflection).max(axis=0) / peak)
    assert travel > 1.0
    assert tip[1] < tip[0] and np.all(bend[1] < bend[0]), (tip, bend)
    assert tip[1] < 0.01, tip


# ------------------------------------------------------ linearised about the posture
@pytest.mark.parametrize("kind", ["hanging", "standing"])
def test_linearised_rigid_pendulum_has_its_closed_form_poles(kind):
    """A rigid rod with a hub inertia J, free at its joint: poles ``+-i w`` hanging,
    ``+-w`` standing, ``w**2 = m g L / 2 / (m L**2 / 3 + J)``."""
    from flexarm.control.linearize import linearize

    m, L, J = 1.5, 0.8, 0.05
    link = fa.Link(L, 1.0, m / L, n_modes=0, hub_inertia=J)
    arm = fa.FlexibleArm([link], gravity=TILTED)
    # TILTED is not along y: the posture is hanging or standing along gravity itself
    down = np.arctan2(TILTED[1], TILTED[0])
    theta = down if kind == "hanging" else down + np.pi
    poles = np.linalg.eigvals(linearize(arm, [theta]).A)
    w2 = m * np.hypot(*TILTED) * L / 2 / (m * L**2 / 3 + J)
    want = (
        [1j * np.sqrt(w2), -1j * np.sqrt(w2)] if kind == "hanging" else [np.sqrt(w2), -np.sqrt(w2)]
    )
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(np.array(want)), atol=1e-9)


@pytest.mark.parametrize("name", ["two-stiff", "flexible-joints"])
def test_linearisation_about_the_posture_is_the_jacobian_of_the_dynamics(name):
    """A and B about the equilibrium against central differences of the nonlinear
    forward dynamics at ``(q0, 0, tau0)``, where the arm is at rest under tau0."""
    from flexarm.control.linearize import linearize

    arm = ARMS[name]()
    theta = np.array([0.6, -0.9])
    eq = arm.equilibrium(theta)
    n = arm.n_dof
    zero = np.zeros(n)
    assert np.abs(arm.forward_dynamics(eq.q, zero, eq.torques)).max() < 1e-8
    sys = linearize(arm, theta)
    h = 1e-6
    cols = []
    for k in range(2 * n):
        e = np.zeros(2 * n)
        e[k] = h
        up = arm.forward_dynamics(eq.q + e[:n], e[n:], eq.torques)
        down = arm.forward_dynamics(eq.q - e[:n], -e[n:], eq.torques)
        cols.append((up - down) / (2 * h))
    jac = np.array(cols).T
    scale = np.abs(jac).max()
    np.testing.assert_allclose(sys.A[n:], jac, rtol=1e-5, atol=1e-6 * scale)
    bcols = []
    for i in range(arm.n_links):
        e = np.zeros(arm.n_links)
        e[i] = h
        up = arm.forward_dynamics(eq.q, zero, eq.torques + e)
        down = arm.forward_dynamics(eq.q, zero, eq.torques - e)
        bcols.append((up - down) / (2 * h))
    np.testing.assert_allclose(sys.B[n:], np.array(bcols).T, rtol=1e-6, atol=1e-9)


def test_a_scenario_file_sets_gravity():
    from flexarm.errors import ScenarioError
    from flexarm.sim.scenario import arm_from_tables

    arm = arm_from_tables({"arm": {"gravity": [0.0, -9.81]}})
    assert arm.gravity == (0.0, -9.81)
    assert arm_from_tables({"arm": {}}).gravity is None
    with pytest.raises(ScenarioError, match=r"arm\.gravity"):
        arm_from_tables({"arm": {"gravity": [0.0]}})
