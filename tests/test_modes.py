"""Tests of :mod:`flexarm.modes` against independent oracles.

Oracles used here (none of them calls the code under test):

* published numbers: the cantilever roots 1.8751040687, 4.6940911330, ...
  (Blevins, *Formulas for Natural Frequency and Mode Shape*), the
  clamped beam with a tip mass equal to its own mass, ``beta_1 L = 1.24792``
  (Blevins, beams with a tip mass), and the paper's ``omega_1 = 12.281 rad/s`` (Sec. III);
* the clamped-mass frequency equation, *unscaled*, solved by :func:`mpmath.findroot`
  at 50 (or more) significant digits;
* the textbook shapes ``cosh - cos - sigma (sinh - sin)`` evaluated in mpmath with
  enough digits to absorb the ``e**lam`` cancellation;
* closed forms for the cantilever integrals, derived in the tests' docstrings and
  checked against mpmath quadrature;
* a Hermite-cubic finite-element model of the beam with a tip mass and rotary
  inertia, written here, solved in flexibility form (see :func:`_fem_modes`);
* the Rayleigh estimate ``lam**4 = 3 / (mu + 33/140)`` for a heavy tip mass with
  its error term derived from the series of the frequency equation.
"""

from __future__ import annotations

import functools
import math

import mpmath as mp
import numpy as np
import pytest
import scipy.linalg as sla
import scipy.special as sps

from flexarm.modes import BeamModes, cantilever_roots, clamped_mass_roots

PUBLISHED_ROOTS = (1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349, 14.1371683910)
L_ARM, EI_ARM, RHO_ARM = 4.5, 1676.0, 0.335  # the paper's link (Sec. III)
RATIOS = (0.0, 0.1, 1.0, 10.0, 1e3, 1e6)
DOCUMENTED_ROOT_RTOL = 1e-14  # clamped_mass_roots docstring: "accurate to about 1e-14 relative"


# --------------------------------------------------------------------------- mpmath oracles
def _freq_eq(lam, mu, j):
    """Left side of the clamped-mass frequency equation, unscaled (mpmath)."""
    c, s, ch, sh = mp.cos(lam), mp.sin(lam), mp.cosh(lam), mp.sinh(lam)
    return (
        1
        + c * ch
        + mu * lam * (c * sh - s * ch)
        - j * lam**3 * (ch * s + sh * c)
        + mu * j * lam**4 * (1 - c * ch)
    )


def _freq_eq_sign_f64(lam, mu, j):
    """Same equation divided by ``cosh`` in float64: used only to bracket sign changes."""
    c, s = np.cos(lam), np.sin(lam)
    sech, th = 1.0 / np.cosh(lam), np.tanh(lam)
    return (
        sech
        + c
        + mu * lam * (c * th - s)
        - j * lam**3 * (s + th * c)
        + mu * j * lam**4 * (sech - c)
    )


def _digits_for(lam: float) -> int:
    """Working digits for the textbook shape at ``lam``: its terms are ~ e**lam / 2."""
    return max(60, int(lam / math.log(10.0)) + 40)


@functools.cache
def _mp_cantilever_root(k: int, dps: int = 50):
    """k-th root of cos(x) cosh(x) + 1 (unscaled), by findroot started at (k - 1/2) pi."""
    with mp.workdps(dps):
        x0 = (k - mp.mpf(1) / 2) * mp.pi
        x = mp.findroot(lambda t: mp.cos(t) * mp.cosh(t) + 1, x0, verify=False)
        # It is the k-th root (all roots sit within 0.31 of (k - 1/2) pi) and it is converged.
        assert abs(x - x0) < mp.mpf("0.31")
        assert abs(mp.cos(x) + 1 / mp.cosh(x)) < mp.mpf(10) ** (-(dps - 6)) * x
        return +x


@functools.cache
def _mp_clamped_mass_roots(n: int, mu: float, j: float, dps: int = 50) -> tuple:
    """First ``n`` roots of the unscaled equation, 50 digits.

    Sign changes are bracketed on a fine float64 grid (100 points per decade below 1,
    steps of pi/256 above), every bracket is confirmed at ``dps`` digits and refined by
    a bracketing solver on the unscaled equation.
    """
    grid = np.concatenate(
        [np.logspace(-6.0, 0.0, 601), 1.0 + np.arange(1, int((n + 1) * 256) + 1) * np.pi / 256]
    )
    vals = _freq_eq_sign_f64(grid, mu, j)
    idx = np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0][:n]
    assert idx.size == n
    roots = []
    with mp.workdps(dps):
        m, jj = mp.mpf(mu), mp.mpf(j)
        for i in idx:
            a, b = mp.mpf(float(grid[i])), mp.mpf(float(grid[i + 1]))
            assert _freq_eq(a, m, jj) * _freq_eq(b, m, jj) < 0
            r = mp.findroot(lambda t: _freq_eq(t, m, jj), (a, b), solver="anderson")
            assert a <= r <= b
            roots.append(+r)
    return tuple(roots)


def _uv(z, order: int):
    """``order``-th z-derivatives of u = cosh - cos and v = sinh - sin (mpmath)."""
    ch, sh, c, s = mp.cosh(z), mp.sinh(z), mp.cos(z), mp.sin(z)
    u = (ch - c, sh + s, ch + c, sh - s)[order % 4]
    v = (sh - s, ch - c, sh + s, ch + c)[order % 4]
    return u, v


def _ratio_c2_c1(lam, mu, j):
    """``C2 / C1`` of ``phi = C1 u + C2 v`` from the shear condition phi''' + mu lam phi = 0.

    (The denominator cosh + cos + mu lam (sinh - sin) is > 0 for lam > 0.)
    For the cantilever this is ``-(sinh - sin) / (cosh + cos) = -sigma`` at a root.
    """
    u0, v0 = _uv(lam, 0)
    u3, v3 = _uv(lam, 3)
    return -(u3 + mu * lam * u0) / (v3 + mu * lam * v0)


def _mp_shape(lam, length, c1, r, x, order: int):
    """``d^order/dx^order`` of ``c1 [u(beta x) + r v(beta x)]`` (mpmath)."""
    beta = lam / length
    u, v = _uv(beta * x, order)
    return c1 * beta**order * (u + r * v)


def _mp_sigma(lam):
    return (mp.cosh(lam) + mp.cos(lam)) / (mp.sinh(lam) + mp.sin(lam))


# --------------------------------------------------------------------------- FEM oracle
@functools.cache
def _fem_modes(n_el: int, mu: float, j: float, k: int):
    """Hermite-cubic Euler–Bernoulli FEM, L = EI = rho = 1, clamped at 0, tip mass ``mu``
    on the tip translation and rotary inertia ``j`` on the tip rotation.

    K v = w**2 M v is solved as (K**-1) M v = v / w**2. For Hermite cubics the static
    nodal solution is exact, so K**-1 on the free dofs *is* the cantilever flexibility
    matrix (closed form below, entries O(1)); this avoids the O(n_el**4) conditioning
    of the assembled stiffness and leaves only the consistent-mass discretisation error
    (O(h**4) in the eigenvalues, and the eigenvalues are Rayleigh–Ritz upper bounds).

    Returns ``(lam4, w_nodes, x_nodes)``: the first ``k`` values of w**2 = lam**4, and
    the nodal deflections of the eigenvectors, normalised to v^T M v = 1 and signed so
    the first free node moves in the positive direction.
    """
    h = 1.0 / n_el
    x = np.arange(1, n_el + 1) * h
    xi, xa = x[:, None], x[None, :]
    lo, hi = np.minimum(xi, xa), np.maximum(xi, xa)
    n = 2 * n_el
    g = np.empty((n, n))
    g[0::2, 0::2] = lo**2 * (3.0 * hi - lo) / 6.0  # deflection at xi, unit force at xa
    w_from_moment = np.where(xi <= xa, xi**2 / 2.0, xa * xi - xa**2 / 2.0)
    g[0::2, 1::2] = w_from_moment  # deflection at xi, unit moment at xa
    g[1::2, 0::2] = w_from_moment.T  # rotation at xi, unit force at xa (Maxwell)
    g[1::2, 1::2] = lo  # rotation at xi, unit moment at xa
    me = (h / 420.0) * np.array(
        [
            [156.0, 22.0 * h, 54.0, -13.0 * h],
            [22.0 * h, 4.0 * h * h, 13.0 * h, -3.0 * h * h],
            [54.0, 13.0 * h, 156.0, -22.0 * h],
            [-13.0 * h, -3.0 * h * h, -22.0 * h, 4.0 * h * h],
        ]
    )
    m = np.zeros((n + 2, n + 2))
    for e in range(n_el):
        m[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += me
    m = m[2:, 2:]
    m[-2, -2] += mu
    m[-1, -1] += j
    chol = np.linalg.cholesky(m)
    a = chol.T @ g @ chol
    nu, u = sla.eigh(a, subset_by_index=[n - k, n - 1])
    nu, u = nu[::-1], u[:, ::-1]
    v = sla.solve_triangular(chol.T, u, lower=False)  # v^T M v = u^T u = 1
    v = v * np.sign(v[0])
    return 1.0 / nu, v[0::2], x


# ============================================================================ 1. published
def test_cantilever_roots_match_published_values():
    roots = cantilever_roots(5)
    assert roots.shape == (5,)
    np.testing.assert_allclose(roots, PUBLISHED_ROOTS, rtol=0, atol=1e-10)


def test_paper_arm_first_frequency():
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=1)
    assert modes.frequencies.shape == (1,)
    # the paper's Sec. III: 12.281 rad/s, i.e. 1.955 Hz (the paper's "Hz" is a typo).
    assert abs(modes.frequencies[0] - 12.281) < 5e-4
    assert abs(modes.frequencies_hz[0] - 1.955) < 5e-4
    # and to full precision from the published root: omega = lam**2 sqrt(EI / (rho L**4)).
    expected = PUBLISHED_ROOTS[0] ** 2 * math.sqrt(EI_ARM / (RHO_ARM * L_ARM**4))
    assert modes.frequencies[0] == pytest.approx(expected, rel=1e-10)
    assert modes.frequencies_hz[0] == pytest.approx(expected / (2 * math.pi), rel=1e-10)


def test_frequencies_scale_with_the_published_roots():
    modes = BeamModes(2.0, 3.0, 5.0, n_modes=5)
    expected = np.array(PUBLISHED_ROOTS) ** 2 * math.sqrt(3.0 / (5.0 * 2.0**4))
    np.testing.assert_allclose(modes.frequencies, expected, rtol=1e-10)
    np.testing.assert_allclose(modes.wavenumbers, np.array(PUBLISHED_ROOTS) / 2.0, rtol=1e-10)


# ============================================================================ 2. cantilever roots
def test_cantilever_roots_against_mpmath_up_to_100():
    roots = cantilever_roots(100)
    assert roots.shape == (100,)
    expected = np.array([float(_mp_cantilever_root(k)) for k in range(1, 101)])
    err = np.abs(roots - expected)
    assert err.max() < 1e-10, f"worst root error {err.max():.3e} at k={err.argmax() + 1}"
    assert np.all(np.diff(roots) > 0)


def test_cantilever_roots_300_asymptotic():
    roots = cantilever_roots(300)
    assert roots.shape == (300,)
    assert np.all(np.diff(roots) > 0)
    # For k >= 20 the root differs from (k - 1/2) pi by ~2 e**(-lam) < 1e-26: the
    # documented root accuracy (about 1e-14 relative) is all that separates them.
    k = np.arange(20, 301)
    np.testing.assert_allclose(roots[19:], (k - 0.5) * np.pi, rtol=DOCUMENTED_ROOT_RTOL, atol=0)
    for kk in (150, 300):
        assert abs(roots[kk - 1] - float(_mp_cantilever_root(kk))) < 1e-10


def test_zero_roots():
    assert cantilever_roots(0).shape == (0,)
    assert clamped_mass_roots(0, 1.0, 1.0).shape == (0,)


# ============================================================================ 3. clamped-mass roots
def test_clamped_mass_root_blevins_mass_ratio_one():
    # Blevins (cantilever with a tip mass): M / (rho L) = 1 gives lam_1 = 1.24792.
    assert abs(clamped_mass_roots(1, 1.0, 0.0)[0] - 1.24792) < 5e-6


@pytest.mark.parametrize("j", RATIOS)
@pytest.mark.parametrize("mu", RATIOS)
def test_clamped_mass_roots_against_mpmath(mu, j):
    n = 6
    got = clamped_mass_roots(n, mu, j)
    expected = np.array([float(r) for r in _mp_clamped_mass_roots(n, mu, j)])
    assert got.shape == (n,)
    np.testing.assert_allclose(got, expected, rtol=1e-10, atol=0)
    assert np.all(np.diff(got) > 0)


@pytest.mark.parametrize(
    ("mu", "j"), [(1e6, 0.0), (1e6, 1e6), (1e8, 0.0), (1e12, 0.0), (0.0, 1e6), (1e3, 1e3)]
)
def test_clamped_mass_roots_meet_documented_accuracy_for_heavy_tips(mu, j):
    """The docstring promises ~1e-14 relative accuracy; allow ten times that."""
    got = clamped_mass_roots(3, mu, j)
    expected = np.array([float(r) for r in _mp_clamped_mass_roots(3, mu, j)])
    rel = np.abs(got - expected) / expected
    assert rel.max() <= 10 * DOCUMENTED_ROOT_RTOL, f"relative root errors {rel}"


# Clamped-mass FEM cases: (mu, j) pairs; FEM on L = EI = rho = 1 (so M = mu, J = j).
FEM_CASES = [(0.0, 0.0), (1.0, 0.0), (0.0, 0.1), (0.5, 0.02), (2.0, 0.3), (10.0, 1.0), (0.1, 5.0)]
FEM_COARSE, FEM_FINE, FEM_K = 48, 96, 4


@pytest.mark.parametrize(("mu", "j"), FEM_CASES)
def test_clamped_mass_frequencies_against_fem(mu, j):
    """FEM eigenvalues are upper bounds converging as h**4: the exact lam**4 must lie in
    [fine - 2 * (coarse - fine) / 15, fine] (the bracket is twice the Richardson estimate
    of the fine-mesh error; 15 = 2**4 - 1). A floor of 1e-12 covers rounding."""
    coarse = _fem_modes(FEM_COARSE, mu, j, FEM_K)[0]
    fine = _fem_modes(FEM_FINE, mu, j, FEM_K)[0]
    assert np.all(coarse >= fine * (1 - 1e-12))  # sanity of the oracle: monotone convergence
    lam4 = BeamModes(1.0, 1.0, 1.0, n_modes=FEM_K, tip_mass=mu, tip_inertia=j).frequencies ** 2
    est = (coarse - fine) / 15.0
    assert np.all(lam4 <= fine * (1 + 1e-12)), (lam4 - fine) / fine
    assert np.all(fine - lam4 <= 2 * est + 1e-12 * fine), ((fine - lam4) / fine, est / fine)


@pytest.mark.parametrize(("mu", "j"), FEM_CASES)
def test_clamped_mass_shapes_against_fem(mu, j):
    """Mass-normalised shapes (tip mass and inertia included, sign: C1 > 0 means the beam
    starts upward) equal the FEM eigenvectors, normalised v^T M v = 1, at the nodes.
    Tolerance: as for the frequencies, twice the Richardson estimate of the fine-mesh
    error, (coarse - fine) / 15 for an O(h**4) error (observed: the actual error is half
    of the allowance), plus 1e-12 for rounding."""
    _, v_c, x_c = _fem_modes(FEM_COARSE, mu, j, FEM_K)
    _, v_f, x_f = _fem_modes(FEM_FINE, mu, j, FEM_K)
    v_f_on_c = v_f[1::2]  # fine nodes that coincide with the coarse ones
    np.testing.assert_allclose(x_f[1::2], x_c, rtol=0, atol=1e-15)
    est = np.abs(v_c - v_f_on_c).max(axis=0)
    modes = BeamModes(1.0, 1.0, 1.0, n_modes=FEM_K, tip_mass=mu, tip_inertia=j)
    phi = modes.shape(x_f)
    err = np.abs(phi.T - v_f).max(axis=0)
    assert np.all(err <= 2 * est / 15.0 + 1e-12), (err, est / 15.0)


def test_fem_oracle_converges_to_the_cantilever():
    """Self-check of the FEM oracle against the 50-digit roots: O(h**4) convergence (error
    ratio 16 where the error is well above rounding) and the bracket used above holds."""
    exact = np.array([float(_mp_cantilever_root(k)) ** 4 for k in range(1, FEM_K + 1)])
    coarse = _fem_modes(FEM_COARSE, 0.0, 0.0, FEM_K)[0]
    fine = _fem_modes(FEM_FINE, 0.0, 0.0, FEM_K)[0]
    ratio = (coarse[1:] - exact[1:]) / (fine[1:] - exact[1:])
    np.testing.assert_allclose(ratio, 16.0, rtol=0.02)
    assert np.all(exact <= fine * (1 + 1e-12))
    assert np.all(fine - exact <= 2 * (coarse - fine) / 15.0 + 1e-12 * fine)


# Rayleigh: a massless-spring estimate with the cubic static shape gives
# lam**4 = 3 / (mu + 33/140). Series of the frequency equation solved for mu
# (sympy, j = 0): mu = 3/lam**4 - 33/140 - (1037/1940400) lam**4 - O(lam**8), hence
# lam**4 (mu + 33/140) / 3 - 1 = -(1037/5821200) lam**8 + O(lam**12),
# and lam**8 ~ 9 / mu**2: the Rayleigh error is 1.603e-3 / mu**2 (relative, in lam**4).
RAYLEIGH_C = 1037.0 / 5821200.0


def test_rayleigh_error_term_against_mpmath():
    """Self-check of the error term above at mu = 1e3 (next term ~ 4e-3 lam**4 ~ 1e-5)."""
    mu = 1e3
    with mp.workdps(50):
        lam = _mp_clamped_mass_roots(1, mu, 0.0)[0]
        rel = lam**4 * (mu + mp.mpf(33) / 140) / 3 - 1
        assert float(rel / (-RAYLEIGH_C * lam**8)) == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("mu", [1e6, 1e8, 1e10, 1e12])
def test_heavy_tip_mass_rayleigh_asymptote(mu):
    lam = clamped_mass_roots(1, mu, 0.0)[0]
    rel = lam**4 * (mu + 33.0 / 140.0) / 3.0 - 1.0
    model = RAYLEIGH_C * (3.0 / mu) ** 2  # |Rayleigh error|, <= 1.6e-15 here
    # lam**4 carries four times the relative error of the root (documented ~1e-14), x2 slack.
    tol = 2 * model + 8 * DOCUMENTED_ROOT_RTOL
    assert abs(rel) <= tol, f"relative error in lam**4: {rel:.3e} (tolerance {tol:.1e})"


def test_zero_ratios_give_the_cantilever():
    np.testing.assert_allclose(clamped_mass_roots(8, 0.0, 0.0), cantilever_roots(8), rtol=0)
    np.testing.assert_allclose(clamped_mass_roots(5, 0.0, 0.0), PUBLISHED_ROOTS, atol=1e-10)
    # and continuity: tiny ratios are indistinguishable from the cantilever
    np.testing.assert_allclose(clamped_mass_roots(5, 1e-14, 1e-14), PUBLISHED_ROOTS, atol=1e-10)
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=5, tip_mass=0.0, tip_inertia=0.0)
    np.testing.assert_allclose(modes.roots, PUBLISHED_ROOTS, atol=1e-10)


GRID = (0.0, 0.01, 0.1, 1.0, 10.0, 100.0, 1e3)


@pytest.mark.parametrize("j", [0.0, 0.05, 2.0])
def test_roots_decrease_with_mass_ratio(j):
    table = np.array([clamped_mass_roots(5, mu, j) for mu in GRID])
    assert np.all(np.diff(table, axis=0) < 0), table


@pytest.mark.parametrize("mu", [0.0, 0.3, 5.0])
def test_roots_decrease_with_inertia_ratio(mu):
    table = np.array([clamped_mass_roots(5, mu, j) for j in GRID])
    assert np.all(np.diff(table, axis=0) < 0), table


# ============================================================================ 4. shapes, integrals
def test_output_shapes():
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=3)
    x = np.linspace(0.0, L_ARM, 7)
    for arr in (modes.shape(x), modes.slope(x), modes.curvature(x), modes.derivative(x, 3)):
        assert arr.shape == (3, 7)
    assert modes.shape(1.0).shape == (3, 1)
    assert modes.shape([0.0, L_ARM]).shape == (3, 2)
    for vec in (modes.roots, modes.frequencies, modes.tip_deflection, modes.mass_integral):
        assert vec.shape == (3,)
    assert modes.modal_mass.shape == (3, 3)
    assert modes.generalized_mass.shape == (3, 3)
    assert modes.modal_stiffness.shape == (3, 3)
    empty = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=0)
    assert empty.frequencies.shape == (0,)
    assert empty.shape(x).shape == (0, 7)


def test_shape_slope_curvature_are_derivative_orders():
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=4, tip_mass=0.3, tip_inertia=0.05)
    x = np.linspace(0.0, L_ARM, 9)
    np.testing.assert_array_equal(modes.shape(x), modes.derivative(x, 0))
    np.testing.assert_array_equal(modes.slope(x), modes.derivative(x, 1))
    np.testing.assert_array_equal(modes.curvature(x), modes.derivative(x, 2))


N_CLOSED = 30


@functools.cache
def _cantilever_closed_forms(n: int, length: float, amp: float):
    """phi(L), int phi, int x phi for A [u - sigma v] (mpmath, 50 digits), as float arrays.

    int phi dx   = (A/beta) [sinh - sin - sigma (cosh + cos)]_0^lam = 2 A sigma / beta,
                   because sinh - sin - sigma (cosh + cos) = -2 (1 + cos cosh)/(sinh + sin) = 0.
    int x phi dx = beta**-4 int x phi'''' dx = beta**-4 ([x phi''']_0^L - [phi'']_0^L)
                 = beta**-4 phi''(0) (free end: phi''(L) = phi'''(L) = 0) = 2 A / beta**2.
    """
    tip, ints, xints = [], [], []
    with mp.workdps(50):
        for k in range(1, n + 1):
            lam = _mp_cantilever_root(k)
            beta = lam / mp.mpf(length)
            tip.append(2 * amp * (-1) ** (k + 1))
            ints.append(float(2 * amp * _mp_sigma(lam) / beta))
            xints.append(float(2 * amp / beta**2))
    return np.array(tip), np.array(ints), np.array(xints)


def test_closed_form_integrals_against_mpmath_quadrature():
    """Self-check of the closed forms above (modes 1-3, L = 1.7, A = 0.3)."""
    length, amp = 1.7, 0.3
    _, ints, xints = _cantilever_closed_forms(3, length, amp)
    with mp.workdps(30):
        for k in range(1, 4):
            lam = _mp_cantilever_root(k)
            sig = _mp_sigma(lam)

            def phi(x, lam=lam, sig=sig):
                return _mp_shape(lam, length, amp, -sig, x, 0)

            q0 = mp.quad(phi, [0, length])
            q1 = mp.quad(lambda x, phi=phi: x * phi(x), [0, length])
            q2 = mp.quad(lambda x, phi=phi: phi(x) ** 2, [0, length])
            assert float(q0) == pytest.approx(ints[k - 1], rel=1e-14)
            assert float(q1) == pytest.approx(xints[k - 1], rel=1e-14)
            assert float(q2) == pytest.approx(amp**2 * length, rel=1e-14)
            assert float(phi(length)) == pytest.approx(2 * amp * (-1) ** (k + 1), rel=1e-14)


def _check_integrals(modes, amp, ints, xints):
    """int rho phi and int rho x phi against the closed forms.

    These integrals shrink like 1/beta and 1/beta**2 while the integrands stay of size
    A and A L: for high modes they are the small remainder of a cancelling sum, and no
    quadrature can hold them to a fixed *relative* precision. Rounding is bounded by
    ~eps * int |integrand| <= eps * 2 A L (resp. 2 A L**2): the check is relative 1e-12
    or absolute 1e-13 rho A L**p (about 200 eps of that bound), whichever is larger.
    """
    mi, wi = modes.mass_integral, modes.moment_integral
    for got, want, p in ((mi, RHO_ARM * ints, 1), (wi, RHO_ARM * xints, 2)):
        tol = np.maximum(1e-12 * np.abs(want), 1e-13 * RHO_ARM * amp * L_ARM**p)
        err = np.abs(got - want)
        assert np.all(err <= tol), (p, (err / (RHO_ARM * amp * L_ARM**p)).max())


@pytest.mark.parametrize("amp", [0.1, 2.5])
def test_amplitude_normalisation_closed_forms(amp):
    modes = BeamModes(
        L_ARM, EI_ARM, RHO_ARM, n_modes=N_CLOSED, normalization="amplitude", amplitude=amp
    )
    tip, ints, xints = _cantilever_closed_forms(N_CLOSED, L_ARM, amp)
    np.testing.assert_allclose(modes.tip_deflection, tip, rtol=1e-12)
    np.testing.assert_allclose(modes.shape(L_ARM)[:, 0], tip, rtol=1e-12)
    _check_integrals(modes, amp, ints, xints)
    # int rho phi_j phi_k = rho A**2 L delta_jk (beam only; here the beam is everything)
    scale = RHO_ARM * amp**2 * L_ARM
    np.testing.assert_allclose(modes.modal_mass / scale, np.eye(N_CLOSED), rtol=0, atol=1e-12)
    np.testing.assert_allclose(modes.generalized_mass / scale, np.eye(N_CLOSED), rtol=0, atol=1e-12)
    # the coefficient of (cosh - cos) is A: phi''(0) = 2 A beta**2
    beta = np.array([float(_mp_cantilever_root(k)) for k in range(1, N_CLOSED + 1)]) / L_ARM
    np.testing.assert_allclose(modes.curvature(0.0)[:, 0], 2 * amp * beta**2, rtol=1e-12)


def test_mass_normalisation_cantilever_closed_forms():
    """Mass-normalised cantilever modes are the amplitude ones with A = 1/sqrt(rho L)."""
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=N_CLOSED)
    amp = 1.0 / math.sqrt(RHO_ARM * L_ARM)
    tip, ints, xints = _cantilever_closed_forms(N_CLOSED, L_ARM, amp)
    np.testing.assert_allclose(modes.tip_deflection, tip, rtol=1e-12)
    _check_integrals(modes, amp, ints, xints)
    np.testing.assert_allclose(modes.modal_mass, np.eye(N_CLOSED), rtol=0, atol=1e-12)


@pytest.mark.parametrize(("mu", "j"), [(0.7, 0.0), (0.0, 0.4), (3.0, 0.2), (50.0, 10.0)])
def test_clamped_mass_shapes_and_integrals_against_mpmath(mu, j):
    """Mass-normalised shapes with a tip body against the mpmath solution of the boundary
    value problem; integrals against the identities (ODE phi'''' = beta**4 phi)
    int phi dx = beta**-4 [phi''']_0^L, int x phi dx = beta**-4 ([x phi''' - phi'']_0^L)."""
    n = 4
    tip_mass, tip_inertia = mu * RHO_ARM * L_ARM, j * RHO_ARM * L_ARM**3
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=n, tip_mass=tip_mass, tip_inertia=tip_inertia)
    x = np.linspace(0.0, L_ARM, 11)
    with mp.workdps(30):
        length = mp.mpf(L_ARM)
        for k, lam in enumerate(_mp_clamped_mass_roots(n, mu, j)):
            lam = +lam
            beta = lam / length
            r = _ratio_c2_c1(lam, mu, j)

            def p(z, order=0, r=r):
                u, v = _uv(z, order)
                return u + r * v

            gm = (
                RHO_ARM * length / lam * mp.quad(lambda z, p=p: p(z) ** 2, [0, lam])
                + tip_mass * p(lam) ** 2
                + tip_inertia * (beta * p(lam, 1)) ** 2
            )
            c1 = 1 / mp.sqrt(gm)
            scale = [float(c1 * beta**o * 2) for o in range(4)]  # ~ the mode's amplitude
            for order in range(4):
                want = np.array(
                    [float(_mp_shape(lam, length, c1, r, mp.mpf(xi), order)) for xi in x]
                )
                got = modes.derivative(x, order)[k]
                assert np.abs(got - want).max() <= 1e-11 * scale[order], (k, order)

            def d(o, xx, lam=lam, c1=c1, r=r):
                return _mp_shape(lam, length, c1, r, xx, o)

            int0 = (d(3, length) - d(3, 0)) / beta**4
            int1 = (length * d(3, length) - d(2, length) + d(2, 0)) / beta**4
            assert modes.mass_integral[k] == pytest.approx(
                RHO_ARM * float(int0), rel=1e-11, abs=1e-13 * scale[0] * L_ARM
            )
            assert modes.moment_integral[k] == pytest.approx(
                RHO_ARM * float(int1), rel=1e-11, abs=1e-13 * scale[0] * L_ARM**2
            )


def test_clamped_mass_tip_boundary_conditions():
    """EI phi''(L) = J w**2 phi'(L) and EI phi'''(L) = -M w**2 phi(L), w from mpmath roots."""
    mu, j = 2.0, 0.3
    tip_mass, tip_inertia = mu * RHO_ARM * L_ARM, j * RHO_ARM * L_ARM**3
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=5, tip_mass=tip_mass, tip_inertia=tip_inertia)
    lam = np.array([float(r) for r in _mp_clamped_mass_roots(5, mu, j)])
    w2 = lam**4 * EI_ARM / (RHO_ARM * L_ARM**4)
    beta = lam / L_ARM
    d = [modes.derivative(L_ARM, o)[:, 0] for o in range(4)]
    d0 = [modes.derivative(0.0, o)[:, 0] for o in range(2)]
    amp = 1.0 / math.sqrt(RHO_ARM * L_ARM)  # |C1| scale of mass-normalised modes (~0.81)
    # Rounding: each side is a sum of terms of size |C1| beta**k times its factor.
    moment_scale = EI_ARM * amp * beta**2 + tip_inertia * w2 * amp * beta
    shear_scale = EI_ARM * amp * beta**3 + tip_mass * w2 * amp
    moment_res = np.abs(EI_ARM * d[2] - tip_inertia * w2 * d[1]) / moment_scale
    shear_res = np.abs(EI_ARM * d[3] + tip_mass * w2 * d[0]) / shear_scale
    assert moment_res.max() < 1e-12, moment_res
    assert shear_res.max() < 1e-12, shear_res
    assert np.all(np.abs(d0[0]) < 1e-14 * amp)
    assert np.all(np.abs(d0[1]) < 1e-14 * amp * beta)


def test_cantilever_free_end_and_clamp():
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=40, normalization="amplitude", amplitude=1.0)
    beta = np.array([float(_mp_cantilever_root(k)) for k in range(1, 41)]) / L_ARM
    for order, x in ((0, 0.0), (1, 0.0), (2, L_ARM), (3, L_ARM)):
        val = modes.derivative(x, order)[:, 0] / beta**order
        assert np.abs(val).max() < 1e-11, (order, np.abs(val).max())


def test_fourth_derivative_satisfies_the_beam_equation():
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=12, tip_mass=0.4, tip_inertia=0.1)
    mu, j = 0.4 / (RHO_ARM * L_ARM), 0.1 / (RHO_ARM * L_ARM**3)
    assert modes.mass_ratio == pytest.approx(mu, rel=1e-15)
    assert modes.inertia_ratio == pytest.approx(j, rel=1e-15)
    lam = np.array([float(r) for r in _mp_clamped_mass_roots(12, mu, j)])
    beta = lam / L_ARM
    x = np.linspace(0.0, L_ARM, 17)
    d4 = modes.derivative(x, 4)
    d0 = modes.shape(x)
    amp = 1.0 / math.sqrt(RHO_ARM * L_ARM)
    assert np.all(np.abs(d4 - beta[:, None] ** 4 * d0) <= 1e-11 * amp * beta[:, None] ** 4)


# ============================================================================ 5. high modes
HIGH_MODES = (20, 40, 60, 100)


@functools.cache
def _mp_textbook_high(k: int, length: float, amp: float, xs: tuple, order: int):
    lam0 = float(_mp_cantilever_root(k))
    dps = _digits_for(lam0)
    with mp.workdps(dps):
        lam = _mp_cantilever_root(k, dps)
        sig = _mp_sigma(lam)
        return np.array(
            [float(_mp_shape(lam, mp.mpf(length), amp, -sig, mp.mpf(x), order)) for x in xs]
        )


X_HIGH = (*(float(v) for v in np.linspace(0.0, L_ARM, 13)), 0.123, 4.321)


def test_high_modes_accurate():
    amp = 0.1
    modes = BeamModes(
        L_ARM, EI_ARM, RHO_ARM, n_modes=max(HIGH_MODES), normalization="amplitude", amplitude=amp
    )
    x = np.array(X_HIGH)
    for k in HIGH_MODES:
        beta = float(_mp_cantilever_root(k)) / L_ARM
        for order in range(4):
            want = _mp_textbook_high(k, L_ARM, amp, X_HIGH, order)
            got = modes.derivative(x, order)[k - 1]
            err = np.abs(got - want).max() / (2 * amp * beta**order)
            assert err < 1e-12, (k, order, err)


@pytest.mark.parametrize("k", [15, 20, 40])
def test_naive_textbook_formula_fails_for_high_modes(k):
    """Why the stable basis exists: float64 cosh - cos - sigma (sinh - sin) is garbage."""
    amp = 0.1
    lam = float(_mp_cantilever_root(k))
    beta = lam / L_ARM
    sigma = (math.cosh(lam) + math.cos(lam)) / (math.sinh(lam) + math.sin(lam))
    z = beta * np.array(X_HIGH)
    naive = amp * (np.cosh(z) - np.cos(z) - sigma * (np.sinh(z) - np.sin(z)))
    want = _mp_textbook_high(k, L_ARM, amp, X_HIGH, 0)
    assert np.abs(naive - want).max() / (2 * amp) > 1e-3


# ============================================================================ 6. orthogonality
@pytest.mark.parametrize(
    ("mu", "j"), [(0.0, 0.0), (0.5, 0.0), (0.0, 0.2), (2.0, 0.3), (10.0, 1.0), (100.0, 50.0)]
)
def test_mass_normalisation_generalised_mass_is_identity(mu, j):
    n = 12
    modes = BeamModes(
        L_ARM,
        EI_ARM,
        RHO_ARM,
        n_modes=n,
        tip_mass=mu * RHO_ARM * L_ARM,
        tip_inertia=j * RHO_ARM * L_ARM**3,
    )
    np.testing.assert_allclose(modes.generalized_mass, np.eye(n), rtol=0, atol=1e-12)
    # independent quadrature of the shapes: scipy's Gauss–Legendre rule, 160 points (the
    # products oscillate at most like exp(2 i lam_12 x / L), lam_12 < 38: 160 is ample)
    t, w = sps.roots_legendre(160)
    x, w = 0.5 * L_ARM * (t + 1.0), 0.5 * L_ARM * w
    p = modes.shape(x)
    h = modes.shape(L_ARM)[:, 0]
    g = modes.slope(L_ARM)[:, 0]
    gm = (
        RHO_ARM * (p * w) @ p.T
        + modes.tip_mass * np.outer(h, h)
        + modes.tip_inertia * np.outer(g, g)
    )
    np.testing.assert_allclose(gm, np.eye(n), rtol=0, atol=1e-12)


def assert_stiffness_is_omega_squared(modes, lam):
    """The modal stiffness, exact and by quadrature, is ``diag(omega**2)`` with
    ``omega = lam**2 sqrt(EI / (rho L**4))`` from the independent roots ``lam``."""
    n = lam.shape[0]
    w2 = lam**4 * EI_ARM / (RHO_ARM * L_ARM**4)
    scale = np.sqrt(np.outer(w2, w2))
    np.testing.assert_allclose(modes.modal_stiffness / scale, np.eye(n), rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        modes.stiffness_by_quadrature() / scale, np.eye(n), rtol=0, atol=1e-11
    )


@pytest.mark.parametrize("n", [1, 5, 20, 50])
def test_modal_stiffness_cantilever(n):
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=n)
    lam = np.array([float(_mp_cantilever_root(k)) for k in range(1, n + 1)])
    assert_stiffness_is_omega_squared(modes, lam)


@pytest.mark.parametrize(("mu", "j"), [(0.5, 0.0), (2.0, 0.3), (10.0, 1.0)])
def test_modal_stiffness_clamped_mass(mu, j):
    n = 10
    tips = {"tip_mass": mu * RHO_ARM * L_ARM, "tip_inertia": j * RHO_ARM * L_ARM**3}
    modes = BeamModes(L_ARM, EI_ARM, RHO_ARM, n_modes=n, **tips)
    lam = np.array([float(r) for r in _mp_clamped_mass_roots(n, mu, j)])
    assert_stiffness_is_omega_squared(modes, lam)


@pytest.mark.parametrize(("mu", "j"), [(0.0, 0.0), (0.5, 0.0), (2.0, 0.3)])
def test_tip_normalisation(mu, j):
    kw = dict(tip_mass=mu * RHO_ARM * L_ARM, tip_inertia=j * RHO_ARM * L_ARM**3, n_modes=8)
    tip = BeamModes(L_ARM, EI_ARM, RHO_ARM, normalization="tip", **kw)
    mass = BeamModes(L_ARM, EI_ARM, RHO_ARM, normalization="mass", **kw)
    np.testing.assert_allclose(tip.tip_deflection, 1.0, rtol=1e-14)
    np.testing.assert_allclose(tip.shape(L_ARM)[:, 0], 1.0, rtol=1e-14)
    x = np.linspace(0.0, L_ARM, 9)
    np.testing.assert_allclose(
        tip.shape(x), mass.shape(x) / mass.shape(L_ARM), rtol=1e-12, atol=1e-14
    )


@pytest.mark.parametrize("normalization", ["mass", "amplitude"])
@pytest.mark.parametrize(("mu", "j"), [(0.0, 0.0), (0.5, 0.0), (2.0, 0.3), (1e3, 1e2)])
def test_sign_convention_cosh_minus_cos_positive(normalization, mu, j):
    """phi = C1 (cosh - cos) + C2 (sinh - sin) has phi''(0) = 2 C1 beta**2: C1 > 0 means
    every mode starts curving upward at the clamp."""
    modes = BeamModes(
        L_ARM,
        EI_ARM,
        RHO_ARM,
        n_modes=10,
        normalization=normalization,
        tip_mass=mu * RHO_ARM * L_ARM,
        tip_inertia=j * RHO_ARM * L_ARM**3,
    )
    assert np.all(modes.curvature(0.0)[:, 0] > 0)
    assert np.all(modes.shape(1e-3)[:, 0] > 0)


# ============================================================================ 7. bad input
BASE = dict(length=4.5, flexural_rigidity=1676.0, linear_density=0.335, n_modes=2)
NAN, INF = float("nan"), float("inf")
BAD_BEAM = (
    [
        (p, v, ValueError)
        for p in ("length", "flexural_rigidity", "linear_density")
        for v in (0.0, -1.0, NAN, INF, -INF)
    ]
    + [
        (p, True, TypeError)
        for p in (
            "length",
            "flexural_rigidity",
            "linear_density",
            "tip_mass",
            "tip_inertia",
            "amplitude",
            "n_modes",
        )
    ]
    + [(p, "1.0", TypeError) for p in ("length", "flexural_rigidity", "linear_density")]
    + [
        ("n_modes", -1, ValueError),
        ("n_modes", 1.5, TypeError),
        ("n_modes", 2.0, TypeError),
        ("tip_mass", -0.1, ValueError),
        ("tip_mass", NAN, ValueError),
        ("tip_mass", INF, ValueError),
        ("tip_inertia", -0.1, ValueError),
        ("tip_inertia", NAN, ValueError),
        ("normalization", "unit", ValueError),
        ("normalization", "Mass", ValueError),
        ("normalization", None, TypeError),
        ("amplitude", 0.0, ValueError),
        ("amplitude", -0.1, ValueError),
    ]
)


@pytest.mark.parametrize(("param", "value", "exc"), BAD_BEAM)
def test_beam_modes_rejects_bad_input(param, value, exc):
    with pytest.raises(exc, match=f"'{param}'"):
        BeamModes(**{**BASE, param: value})


@pytest.mark.parametrize("x", [-0.01, 4.5 * 1.001, [0.0, 5.0], [-1.0, 1.0], NAN, [[0.0, 1.0]]])
def test_shape_rejects_bad_x(x):
    modes = BeamModes(**BASE)
    with pytest.raises(ValueError, match="'x'"):
        modes.shape(x)
    with pytest.raises(ValueError, match="'x'"):
        modes.derivative(x, 2)


def test_shape_accepts_the_end_points():
    modes = BeamModes(**BASE)
    assert modes.shape([0.0, 4.5]).shape == (2, 2)


@pytest.mark.parametrize(("order", "exc"), [(-1, ValueError), (1.0, TypeError), (True, TypeError)])
def test_derivative_rejects_bad_order(order, exc):
    with pytest.raises(exc, match="'order'"):
        BeamModes(**BASE).derivative(1.0, order)


@pytest.mark.parametrize(
    ("kwargs", "param", "exc"),
    [
        (dict(n=-1), "n", ValueError),
        (dict(n=2.5), "n", TypeError),
        (dict(n=True), "n", TypeError),
        (dict(n=2, mass_ratio=-1.0), "mass_ratio", ValueError),
        (dict(n=2, mass_ratio=NAN), "mass_ratio", ValueError),
        (dict(n=2, mass_ratio=INF), "mass_ratio", ValueError),
        (dict(n=2, inertia_ratio=-1e-3), "inertia_ratio", ValueError),
        (dict(n=2, inertia_ratio=NAN), "inertia_ratio", ValueError),
        (dict(n=2, mass_ratio=True), "mass_ratio", TypeError),
    ],
)
def test_clamped_mass_roots_rejects_bad_input(kwargs, param, exc):
    with pytest.raises(exc, match=f"'{param}'"):
        clamped_mass_roots(**kwargs)


@pytest.mark.parametrize(("n", "exc"), [(-1, ValueError), (1.5, TypeError)])
def test_cantilever_roots_rejects_bad_n(n, exc):
    with pytest.raises(exc, match="'n'"):
        cantilever_roots(n)


def test_the_roots_kept_per_process_are_the_computed_ones_and_yours_to_change():
    """Small root sets are kept once per process (a sweep builds the same links again
    and again): each call still returns its own writable array, equal to a fresh
    computation; large sets are computed each time."""
    from flexarm.model import _roots

    first = clamped_mass_roots(5, 0.3, 0.01)
    first[:] = -1.0  # the caller's own copy
    again = clamped_mass_roots(5, 0.3, 0.01)
    assert np.array_equal(again, _roots.roots(5, 0.3, 0.01)) and np.all(again > 0)
    big = _roots.CACHED_UP_TO + 1
    np.testing.assert_array_equal(clamped_mass_roots(big, 0.3), _roots.roots(big, 0.3, 0.0))
    small, large = (BeamModes(2.0, 1676.0, 0.335, n_modes=m) for m in (5, big))
    # the kept rule (5 modes) and one computed afresh (65 modes; more nodes): both exact
    np.testing.assert_allclose(small.mass_integral, large.mass_integral[:5], rtol=1e-12)
