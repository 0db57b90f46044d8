"""The packed arm (flexarm.model.packed): the public calls from Python equal the
compiled kernels bit for bit and the NumPy reference to rounding, batches equal
their rows, bad input is refused by name, threads share nothing writable.

Oracles: the kernels of flexarm.model.dynamics called on ``arm.arrays`` with a
fresh workspace (the code the packed entry points must reproduce exactly), and
the NumPy reference of flexarm.model.arm (an independent implementation).
"""

from __future__ import annotations

import pickle
import threading

import numba as nb
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import flexarm as fa
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.model import dynamics
from flexarm.model._buffer import scratch_size, unpacked, workspace
from flexarm.model.arrays import make_workspace, workspace_shapes, workspace_size
from helpers.arms import random_states, three_links

L, EI, RHO = 4.5, 1676.0, 0.335
JOINT = fa.NonlinearJoint.default(fa.MakkarFriction.default())

ARMS = {
    "paper": lambda: fa.FlexibleArm.paper(),
    "rigid": lambda: fa.FlexibleArm([fa.Link(L, EI, RHO, n_modes=0)] * 2),
    "paper-2modes": lambda: fa.FlexibleArm.paper(n_modes=2),
    "one-link-default": lambda: fa.FlexibleArm([fa.Link(L, EI, RHO)]),
    "three-links-stiffening": three_links,
    "paper-joints": lambda: fa.FlexibleArm.paper(joints=[JOINT, JOINT]),
    "joints-motor-friction-stiffening": lambda: fa.FlexibleArm(
        [fa.Link(L, EI, RHO, n_modes=2, hub_mass=1.0)] * 2,
        joints=[JOINT, fa.LinearJoint.default()],
        joint_friction="motor",
        payload_mass=0.5,
    ),
    "joints-rotor-uncoupled": lambda: fa.FlexibleArm(
        [fa.Link(L, EI, RHO, n_modes=1)] * 3,
        joints=[fa.LinearJoint.default()] * 3,
        rotor_coupling=False,
        geometric_stiffening=False,
    ),
}


@pytest.fixture(scope="module", params=list(ARMS))
def arm(request):
    return ARMS[request.param]()


def states(arm: fa.FlexibleArm, m: int, seed: int = 7):
    """``m`` random states (tip deflections of 3 % of the link) and torques."""
    return random_states(arm, m, seed)


def kernel(arm, q, dq, tau):
    """The compiled kernel called as the simulator calls it."""
    ddq = np.empty(arm.n_dof)
    dynamics.forward_dynamics(q, dq, tau, arm.arrays, make_workspace(arm.n_dof), ddq)
    return ddq


def close(a, b, tol=1e-12):
    """Norm-wise relative agreement: a small entry of a large result carries the
    rounding of the large ones."""
    return np.max(np.abs(a - b)) <= tol * max(1.0, np.max(np.abs(b)))


# --------------------------------------------------------------- the same numbers
def test_the_buffer_unpacks_to_the_arms_arrays(arm):
    got = unpacked(arm._packed().buf)
    for name in arm.arrays._fields:
        want = getattr(arm.arrays, name)
        assert getattr(got, name).dtype == want.dtype, name
        assert np.array_equal(getattr(got, name), want), name


@nb.njit
def _workspace_shapes(wbuf, n):  # pragma: no cover - compiled
    ws = workspace(wbuf, n, wbuf[: n * n].reshape((n, n)))
    return (
        ws.bias.shape,
        ws.jac.shape,
        ws.angle.shape,
        ws.rhs.shape,
        ws.rows.shape,
        ws.lmass.shape,
        ws.lbias.shape,
        ws.inv_diag.shape,
        ws.axial.shape,
        ws.chain.shape,
    )


@pytest.mark.parametrize("n", [1, 2, 4, 9])
def test_the_flat_workspace_has_the_layout_of_make_workspace(n):
    shapes = workspace_shapes(n)
    size = sum(int(np.prod(s)) for s in shapes.values())
    got = _workspace_shapes(np.zeros(size), n)
    assert [tuple(s) for s in got] == [shapes[k] for k in list(shapes)[1:]]


def test_forward_dynamics_is_the_kernel_bit_for_bit_and_the_reference(arm):
    for q, dq, tau in zip(*states(arm, 12), strict=True):
        fast = arm.forward_dynamics(q, dq, tau)
        assert np.array_equal(fast, kernel(arm, q, dq, tau))
        assert np.array_equal(fast, arm.forward_dynamics(q, dq, tau, backend="compiled"))
        assert close(fast, arm.forward_dynamics(q, dq, tau, backend="numpy"))


def test_mass_matrix_is_the_kernel_bit_for_bit_and_the_reference(arm):
    ws = make_workspace(arm.n_dof)
    for q, dq, _ in zip(*states(arm, 6), strict=True):
        dynamics.mass_and_bias(q, dq, arm.arrays, ws)
        fast = arm.mass_matrix(q)
        assert np.array_equal(fast, ws.mass)
        assert np.array_equal(fast, fast.T)
        assert close(fast, arm.mass_matrix(q, backend="numpy"))


def test_kinematics_is_the_kernel_bit_for_bit_and_the_reference(arm):
    out = np.empty(4)
    for q, dq, _ in zip(*states(arm, 6), strict=True):
        for link in range(arm.n_links):
            for distance in (0.0, 0.37 * arm.links[link].length, arm.links[link].length):
                fast = arm.point_position(q, link, distance)
                phi = arm.point_basis(link, distance)
                dynamics.point_kinematics(q, dq, arm.arrays, link, distance, phi, out)
                assert np.array_equal(fast, out[:2])
                ref = arm.point_position(q, link, distance, backend="numpy")
                assert close(fast, ref)
        last = arm.n_links - 1
        assert np.array_equal(
            arm.tip_position(q), arm.point_position(q, last, arm.link_lengths[-1])
        )
        assert close(arm.tip_position(q), arm.tip_position(q, backend="numpy"))


# -------------------------------------------------------------------- batches
def test_a_batch_is_its_rows_bit_for_bit(arm):
    q, dq, tau = states(arm, 9, seed=3)
    ddq = arm.forward_dynamics(q, dq, tau)
    M = arm.mass_matrix(q)
    tip = arm.tip_position(q)
    point = arm.point_position(q, 0, 0.5 * arm.links[0].length)
    assert ddq.shape == (9, arm.n_dof) and M.shape == (9, arm.n_dof, arm.n_dof)
    assert tip.shape == (9, 2) and point.shape == (9, 2)
    for b in range(9):
        assert np.array_equal(ddq[b], arm.forward_dynamics(q[b], dq[b], tau[b]))
        assert np.array_equal(M[b], arm.mass_matrix(q[b]))
        assert np.array_equal(tip[b], arm.tip_position(q[b]))
        assert np.array_equal(point[b], arm.point_position(q[b], 0, 0.5 * arm.links[0].length))
    ref = arm.forward_dynamics(q[:3], dq[:3], tau[:3], backend="numpy")
    assert ref.shape == (3, arm.n_dof) and close(ddq[:3], ref)


def test_an_empty_batch():
    arm = ARMS["paper-joints"]()
    q, dq, tau = (np.zeros((0, k)) for k in (arm.n_dof, arm.n_dof, arm.n_links))
    assert arm.forward_dynamics(q, dq, tau).shape == (0, arm.n_dof)


# ---------------------------------------------------- any array-like, converted
def test_lists_strided_read_only_and_integer_input_give_the_same_numbers():
    arm = ARMS["three-links-stiffening"]()
    q, dq, tau = states(arm, 1)
    q, dq, tau = q[0], dq[0], tau[0]
    want = arm.forward_dynamics(q, dq, tau)
    wide = np.zeros((arm.n_dof, 2))
    wide[:, 0] = q
    frozen = dq.copy()
    frozen.flags.writeable = False
    assert np.array_equal(arm.forward_dynamics(list(q), tuple(dq), list(tau)), want)
    assert np.array_equal(arm.forward_dynamics(wide[:, 0], frozen, tau), want)
    t32 = tau.astype(np.float32)
    assert np.array_equal(arm.forward_dynamics(q, dq, t32), arm.forward_dynamics(q, dq, t32 * 1.0))
    t_int = np.array([1, -2, 3])
    assert np.array_equal(
        arm.forward_dynamics(q, dq, t_int), arm.forward_dynamics(q, dq, [1.0, -2.0, 3.0])
    )
    assert np.array_equal(arm.mass_matrix(list(q)), arm.mass_matrix(q))
    assert np.array_equal(arm.tip_position(wide[:, 0]), arm.tip_position(q))


def test_views_the_fast_path_cannot_take_give_the_same_numbers():
    """The compiled function is called without Numba's dispatch: what the dispatch
    refused (reversed, strided, misaligned vectors; objects that only look like
    arrays) must be converted, not read as contiguous memory."""
    arm = ARMS["paper"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    want = arm.forward_dynamics(q, dq, tau)
    reversed_q = q[::-1].copy()[::-1]  # strides -8
    assert reversed_q.strides == (-8,)
    raw = np.zeros(8 * arm.n_dof + 1, dtype=np.uint8)
    misaligned = raw[1:].view(np.float64)
    misaligned[:] = dq
    assert misaligned.ctypes.data % 8 != 0

    class Alike:  # a dtype and ndim, but not an ndarray
        dtype, ndim = np.dtype(np.float64), 1

        def __array__(self, dtype=None, copy=None):
            return tau.copy()

    assert np.array_equal(arm.forward_dynamics(reversed_q, dq, tau), want)
    assert np.array_equal(arm.forward_dynamics(q, misaligned, tau), want)
    assert np.array_equal(arm.forward_dynamics(q, dq, Alike()), want)
    with pytest.raises(InvalidValueError, match=r"'q' .* shape"):  # 0-d
        arm.forward_dynamics(np.float64(0.0), dq, tau)


@pytest.mark.parametrize("name", ["paper", "rigid", "three-links-stiffening"])
def test_out_receives_the_same_numbers(name):
    arm = ARMS[name]()
    q, dq, tau = states(arm, 4)
    want = arm.forward_dynamics(q, dq, tau)
    out = np.full(arm.n_dof, np.nan)
    got = arm.forward_dynamics(q[0], dq[0], tau[0], out=out)
    assert got is out and np.array_equal(out, want[0])
    # out may be the state itself: the state is read before it is written
    q0, dq0 = q[0].copy(), dq[0].copy()
    assert arm.forward_dynamics(q0, dq0, tau[0], out=q0) is q0
    assert np.array_equal(q0, want[0])
    assert np.array_equal(arm.forward_dynamics(q[1], dq1 := dq[1].copy(), tau[1], out=dq1), want[1])
    # anything writable of the right shape: strided, batches, the NumPy backend
    wide = np.zeros((arm.n_dof, 2))
    assert arm.forward_dynamics(q[2], dq[2], tau[2], out=wide[:, 1]).base is wide
    assert np.array_equal(wide[:, 1], want[2]) and not wide[:, 0].any()
    batch = np.empty((4, arm.n_dof))
    assert arm.forward_dynamics(q, dq, tau, out=batch) is batch
    assert np.array_equal(batch, want)
    ref = arm.forward_dynamics(q[3], dq[3], tau[3], backend="numpy")
    into = np.empty(arm.n_dof, dtype=complex)
    arm.forward_dynamics(q[3], dq[3], tau[3], backend="numpy", out=into)
    assert np.array_equal(into.real, ref) and not into.imag.any()


@pytest.mark.parametrize(
    ("out", "error", "match"),
    [
        (np.empty(5), InvalidValueError, r"'out' .* shape \(4,\). Got shape \(5,\)"),
        (np.empty((1, 4)), InvalidValueError, r"'out' .* shape \(4,\)"),
        ([0.0] * 4, InvalidTypeError, "'out' .* NumPy array. Got list"),
        (np.empty(4, dtype=np.float32), InvalidTypeError, "'out' .* float64 casts to"),
        (np.empty(4, dtype=np.int64), InvalidTypeError, "'out' .* float64 casts to"),
    ],
)
def test_a_bad_out_is_refused_by_name(out, error, match):
    arm = ARMS["paper"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    with pytest.raises(error, match=match):
        arm.forward_dynamics(q, dq, tau, out=out)


def test_a_read_only_out_is_refused_and_left_alone():
    arm = ARMS["paper"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    out = np.zeros(arm.n_dof)
    out.flags.writeable = False
    with pytest.raises(InvalidValueError, match=r"'out' .* writable"):
        arm.forward_dynamics(q, dq, tau, out=out)
    assert not out.any()


def test_complex_input_takes_the_numpy_reference():
    arm = ARMS["paper-2modes"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    h = 1e-20
    qc = q.astype(complex)
    qc[0] += 1j * h
    got = arm.forward_dynamics(qc, dq, tau)
    assert np.iscomplexobj(got)
    # a complex and a real solve of M x = b agree to the forward error of a solve,
    # cond(M) eps (the complex path takes another LAPACK routine)
    bound = np.linalg.cond(arm.mass_matrix(q)) * np.finfo(float).eps
    assert close(got.real, arm.forward_dynamics(q, dq, tau, backend="numpy"), bound)
    # the complex step gives the derivative along theta1: compare with a central difference
    e = np.zeros(arm.n_dof)
    e[0] = 1e-6
    fd = (arm.forward_dynamics(q + e, dq, tau) - arm.forward_dynamics(q - e, dq, tau)) / 2e-6
    assert close(got.imag / h, fd, 1e-6)
    assert np.iscomplexobj(arm.mass_matrix(qc))
    with pytest.raises(InvalidTypeError, match="'q' parameter of FlexibleArm must be real"):
        arm.forward_dynamics(qc, dq, tau, backend="compiled")
    with pytest.raises(InvalidTypeError, match="'q' parameter of FlexibleArm must be real"):
        arm.mass_matrix(qc, backend="compiled")


# --------------------------------------------------------------------- refused
N = 6  # paper-joints: n_dof 6, two links
GOOD = {"q": np.zeros(N), "dq": np.zeros(N), "tau": np.zeros(2)}
BATCH = {"q": np.zeros((3, N)), "dq": np.zeros((3, N)), "tau": np.zeros((3, 2))}
NAN = np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    ("changes", "error", "match"),
    [
        (
            {"q": np.zeros(5)},
            InvalidValueError,
            r"'q' .* shape \(6,\) or \(m, 6\). Got shape \(5,\)",
        ),
        ({"dq": np.zeros(7)}, InvalidValueError, r"'dq' .* shape \(6,\). Got shape \(7,\)"),
        ({"tau": np.zeros(3)}, InvalidValueError, r"'tau' .* shape \(2,\). Got shape \(3,\)"),
        ({"tau": np.zeros((1, 2))}, InvalidValueError, r"'tau' .* shape \(2,\)"),
        ({"q": NAN}, InvalidValueError, "'q' .* finite"),
        ({"dq": NAN}, InvalidValueError, "'dq' .* finite"),
        ({"tau": np.array([np.inf, 0.0])}, InvalidValueError, "'tau' .* finite"),
        ({"tau": [np.inf, 0.0]}, InvalidValueError, "'tau' .* finite"),
        ({"q": np.zeros((2, 3, N))}, InvalidValueError, "'q' .* shape"),
        ({"q": 0.0}, InvalidValueError, "'q' .* shape"),
        ({"q": "q"}, InvalidTypeError, "'q'"),
        ({"dq": np.zeros(N, dtype=complex)}, InvalidTypeError, "'dq' .* real"),
    ],
)
def test_bad_states_are_refused_by_name(changes, error, match):
    arm = ARMS["paper-joints"]()
    args = GOOD | changes
    backend = "compiled" if "complex" in str(getattr(args["dq"], "dtype", "")) else "auto"
    with pytest.raises(error, match=match):
        arm.forward_dynamics(args["q"], args["dq"], args["tau"], backend=backend)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"dq": np.zeros((2, N))}, r"'dq' .* shape \(3, 6\). Got shape \(2, 6\)"),
        ({"dq": np.zeros(N)}, r"'dq' .* shape \(3, 6\). Got shape \(6,\)"),
        ({"tau": np.zeros((3, 3))}, r"'tau' .* shape \(3, 2\). Got shape \(3, 3\)"),
        ({"tau": np.zeros(2)}, r"'tau' .* shape \(3, 2\). Got shape \(2,\)"),
        ({"q": np.zeros((3, 5))}, r"'q' .* shape \(6,\) or \(m, 6\). Got shape \(3, 5\)"),
        ({"tau": np.full((3, 2), np.nan)}, "'tau' .* finite"),
    ],
)
def test_bad_batches_are_refused_by_name(changes, match):
    arm = ARMS["paper-joints"]()
    args = BATCH | changes
    with pytest.raises(InvalidValueError, match=match):
        arm.forward_dynamics(args["q"], args["dq"], args["tau"])


@pytest.mark.parametrize("method", ["mass_matrix", "tip_position"])
@pytest.mark.parametrize(
    ("q", "match"),
    [
        (np.zeros(5), r"'q' .* shape \(6,\) or \(m, 6\)"),
        (np.zeros((4, 7)), r"'q' .* shape \(6,\) or \(m, 6\)"),
        (NAN, "'q' .* finite"),
        (np.vstack([NAN, NAN]), "'q' .* finite"),
    ],
)
def test_bad_coordinates_are_refused_by_name(method, q, match):
    arm = ARMS["paper-joints"]()
    with pytest.raises(InvalidValueError, match=match):
        getattr(arm, method)(q)


@pytest.mark.parametrize("method", ["forward_dynamics", "mass_matrix", "tip_position"])
def test_unknown_backends_are_refused(method):
    arm = ARMS["paper"]()
    args = (
        (GOOD["q"][:4], GOOD["q"][:4], GOOD["tau"])
        if method == "forward_dynamics"
        else (GOOD["q"][:4],)
    )
    with pytest.raises(InvalidValueError, match="'backend' parameter of FlexibleArm"):
        getattr(arm, method)(*args, backend="jax")


def test_a_point_is_checked_before_its_basis_is_kept():
    arm = ARMS["paper"]()
    q = np.zeros(4)
    with pytest.raises(InvalidValueError, match="'distance'"):
        arm.point_position(q, 0, 4.6)
    with pytest.raises(InvalidTypeError, match="'link'"):
        arm.point_position(q, True, 1.0)
    arm.point_position(q, 1, 1.0)
    assert (1, 1.0) in arm._packed().bases
    with pytest.raises(InvalidTypeError, match="'link'"):  # a kept basis does not admit a bool
        arm.point_position(q, True, 1.0)


# ----------------------------------------------------------- state and threads
def test_the_kernels_write_every_scratch_value_before_reading_it(arm):
    """A call's workspace is uninitialised (on the stack, or just allocated)."""
    q, dq, tau = (x[0] for x in states(arm, 1))
    results = []
    for fill in (0.0, np.nan, 1e300):
        ws = make_workspace(arm.n_dof)
        for field in ws:
            field[...] = fill
        ddq = np.empty(arm.n_dof)
        dynamics.forward_dynamics(q, dq, tau, arm.arrays, ws, ddq)
        results.append(ddq)
        for field in ws:
            field[...] = fill
        dynamics.mass_and_bias(q, dq, arm.arrays, ws)
        results.append(ws.mass.copy())
    for k in (2, 4):
        assert np.array_equal(results[k], results[0])
        assert np.array_equal(results[k + 1], results[1])


def test_an_arm_too_large_for_the_stack_allocates_its_workspace():
    arm = fa.FlexibleArm([fa.Link(0.5, EI, RHO, n_modes=1)] * 16, geometric_stiffening=False)
    assert not arm._packed().on_stack
    q, dq, tau = states(arm, 3)
    for b in range(3):
        fast = arm.forward_dynamics(q[b], dq[b], tau[b])
        assert fast.shape == (arm.n_dof,)
        assert np.array_equal(fast, kernel(arm, q[b], dq[b], tau[b]))
        assert np.array_equal(
            fast, arm.forward_dynamics(q[b : b + 1], dq[b : b + 1], tau[b : b + 1])[0]
        )
        ws = make_workspace(arm.n_dof)
        dynamics.mass_and_bias(q[b], dq[b], arm.arrays, ws)
        assert np.array_equal(arm.mass_matrix(q[b]), ws.mass)
    with pytest.raises(InvalidValueError, match=r"'tau' .* shape \(16,\)"):
        arm.forward_dynamics(q[0], dq[0], tau[0, :3])


def test_two_threads_on_one_arm_give_the_serial_results():
    arm = ARMS["three-links-stiffening"]()
    q, dq, tau = states(arm, 400, seed=11)
    serial = [arm.forward_dynamics(q[b], dq[b], tau[b]) for b in range(400)]
    masses = [arm.mass_matrix(q[b]) for b in range(400)]
    results: dict[int, list] = {}
    start = threading.Barrier(2)

    def work(k: int) -> None:
        start.wait()
        got = []
        for _ in range(5):
            for b in range(400):
                got.append((arm.forward_dynamics(q[b], dq[b], tau[b]), arm.mass_matrix(q[b])))
        results[k] = got

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for got in results.values():
        assert len(got) == 2000
        for i, (ddq, M) in enumerate(got):
            assert np.array_equal(ddq, serial[i % 400])
            assert np.array_equal(M, masses[i % 400])


def test_an_arm_pickles_after_a_compiled_call():
    arm = ARMS["paper-joints"]()
    q, dq, tau = (x[0] for x in states(arm, 1))
    want = arm.forward_dynamics(q, dq, tau)
    arm.point_position(q, 0, 1.0)
    assert arm._packed().bases
    copy = pickle.loads(pickle.dumps(arm))
    assert np.array_equal(copy.forward_dynamics(q, dq, tau), want)


@settings(max_examples=60, deadline=None)
@given(
    angles=st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3),
    rates=st.lists(st.floats(-20.0, 20.0), min_size=3, max_size=3),
    modes=st.lists(st.floats(-0.2, 0.2), min_size=5, max_size=5),
    mode_rates=st.lists(st.floats(-5.0, 5.0), min_size=5, max_size=5),
    torque=st.lists(st.floats(-50.0, 50.0), min_size=3, max_size=3),
)
def test_property_any_state_gives_the_kernel_and_a_batch_of_one(
    angles, rates, modes, mode_rates, torque
):
    arm = _PROPERTY_ARM
    q = np.array(angles + modes)
    dq = np.array(rates + mode_rates)
    tau = np.array(torque)
    fast = arm.forward_dynamics(q, dq, tau)
    assert np.array_equal(fast, kernel(arm, q, dq, tau))
    assert np.array_equal(arm.forward_dynamics(q[None], dq[None], tau[None])[0], fast)


_PROPERTY_ARM = ARMS["three-links-stiffening"]()


@nb.njit
def _scratch_sizes(top):  # pragma: no cover - compiled
    return [scratch_size(n) for n in range(1, top)]


def test_the_compiled_workspace_size_is_workspace_size():
    assert _scratch_sizes(70) == [workspace_size(n) for n in range(1, 70)]
