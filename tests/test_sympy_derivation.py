r"""Independent SymPy derivation of the flexible-arm equations of motion.

The closed-form model of :class:`flexarm.FlexibleArm` (body-frame Jacobians and
modal integrals, :mod:`flexarm.model.arm`, :mod:`flexarm.model.dynamics`) is checked here
against a derivation that shares nothing with it but the convention and the
modal integrals of :class:`flexarm.modes.BeamModes`.

Derivation
----------
For a planar arm of ``N`` links, link ``i`` (0-based) has the absolute angle

.. math:: \alpha_i = \theta_1 + \dots + \theta_{i+1} + \sum_{k<i} w_k'(L_k),
          \qquad w_k'(L_k) = \sum_j \phi_{kj}'(L_k) \delta_{kj},

and a point at distance ``x`` along it is at

.. math:: p_i(x) = o_i + R(\alpha_i) [x,\ w_i(x)]^T, \qquad
          w_i(x) = \sum_j \phi_{ij}(x) \delta_{ij},

with ``o_0 = 0`` and ``o_{i+1} = p_i(L_i)``. With geometric stiffening the
point is at ``R(alpha_i) [x - u_i(x), w_i(x)]^T`` instead, with the
foreshortening ``u_i(x) = 1/2 sum_jk S_ijk(x) delta_ij delta_ik`` and
``S_ijk(x) = int_0^x phi_ij' phi_ik' ds``. SymPy writes ``p_i`` in the
inertial frame with ``x``, the shape values ``phi_ij(x)`` and ``S_ijk(x)`` as plain symbols,
differentiates it along the coordinates, ``dp/dt = (dp/dq) qdot``, expands
``|dp/dt|^2`` (a quadratic form in ``1, x, phi_i1(x), ...``) and integrates it
term by term along the beam by mapping every monomial to a modal-integral
symbol (the algebra runs in a sparse polynomial ring, ``sympy.ring``, with
``cos(alpha_i)`` and ``sin(alpha_i)`` as generators and the chain rule through
them written out, which keeps the derivation to a few seconds)::

    1 -> int rho dx = rho L        x -> int rho x dx       x**2 -> int rho x**2 dx
    phi_j -> int rho phi_j dx      x phi_j -> int rho x phi_j dx
    phi_j phi_k -> int rho phi_j phi_k dx
    S_jk -> int rho S_jk dx      x S_jk -> int rho x S_jk dx
    phi_a S_jk -> int rho phi_a S_jk dx      S_ab S_cd -> int rho S_ab S_cd dx

Tip values ``phi_j(L)``, ``phi_j'(L)`` and ``S_jk(L)`` are symbols too. The kinetic energy
adds the hubs (``1/2 J_h alpha_i_dot**2`` and a point mass ``m_h`` at ``o_i``) and
the payload (a point mass at ``o_N`` and a rotary inertia turning with
``alpha_{N-1} + w_{N-1}'(L_{N-1})``). Then ``M`` is the Hessian of ``T`` in
``qdot`` and the velocity terms are the Lagrange expression
``h = d/dt(dT/dqdot) - dT/dq`` at ``qddot = 0``, i.e.
``h_a = sum_k d^2T/(dqdot_a dq_k) qdot_k - dT/dq_a``. The derivation uses no
``simplify``: the expressions are expanded, differentiated and lambdified with
common subexpression elimination, once per modes-per-link tuple (cached). The
numbers substituted for the modal integrals are those of ``arm.modes`` (tested
elsewhere against closed forms), so boundary conditions and normalisation match
the arm.

Two further checks keep the derivation honest: with no modes it reduces
symbolically to the textbook rigid two-link arm (uniform rods, ``l_c = L/2``,
``I = m L^2 / 12``), and its kinetic energy ``1/2 qdot' M qdot`` equals a direct
Gauss–Legendre quadrature of ``1/2 int rho |dp/dt|^2 dx`` in plain NumPy, with
``dp/dt`` obtained by a complex step along ``qdot`` through the kinematic map
evaluated with :meth:`BeamModes.shape` and the foreshortening integrated from
:meth:`BeamModes.slope` on each ``[0, x]`` (so the monomial-to-integral map and
the foreshortening integrals of :mod:`flexarm.model.foreshortening` are tested
too).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import sympy as sp

import flexarm as fa
from flexarm.model.foreshortening import foreshortening_integrals

RTOL = 1e-10

# Unequal links so that symmetric mistakes do not cancel.
LINK_DATA = (
    # length, EI, rho, hub_mass, hub_inertia, modal_damping
    (1.3, 52.0, 0.80, 0.70, 0.015, 0.02),
    (0.9, 17.0, 0.45, 0.35, 0.006, 0.03),
)
PAYLOAD = (0.25, 0.004)  # mass, rotary inertia


# --------------------------------------------------------------------------- derivation
@dataclass(frozen=True)
class Derivation:
    """Symbolic ``T``, ``M``, ``h`` for one modes-per-link tuple, plus numeric callables."""

    n_modes: tuple[int, ...]
    q: tuple[sp.Symbol, ...]
    dq: tuple[sp.Symbol, ...]
    params: tuple[sp.Symbol, ...]
    T: sp.Expr
    M: sp.Matrix
    h: sp.Matrix
    mass_and_bias: Any  # (q, dq, params) -> (M, h)


def _integrate_along_beam(f: Any, x_index: int, phi_index: list[int], integrals: dict) -> Any:
    """``int rho f dx`` for a ring element ``f`` polynomial in ``x`` and ``phi``.

    ``integrals`` maps the exponent tuple ``(deg x, deg phi_1, ..., deg phi_n)``
    of a monomial in ``x`` and the shape values to the ring generator of its modal
    integral; every monomial of ``f`` is replaced by that generator.
    """
    idx = [x_index, *phi_index]
    out: dict[tuple[int, ...], Any] = {}
    for monom, coeff in f.terms():
        key = tuple(monom[k] for k in idx)
        if key not in integrals:
            raise AssertionError(f"unexpected monomial {key} in the kinetic energy density")
        m = list(monom)
        for k in idx:
            m[k] = 0
        m[integrals[key]] += 1
        out[tuple(m)] = out.get(tuple(m), 0) + coeff
    return f.ring.from_dict(out)


def _pairs(n: int) -> list[tuple[int, int]]:
    return [(a, b) for a in range(n) for b in range(a, n)]


@functools.cache
def derive(n_modes: tuple[int, ...], stiffening: bool = False) -> Derivation:
    """Derive ``T``, ``M(q)`` and ``h(q, qdot)`` for a planar arm with ``n_modes``
    (and, with ``stiffening``, the foreshortening in the kinematic map).

    The algebra runs in a sparse polynomial ring over the rationals whose
    generators include ``C_i = cos(alpha_i)`` and ``S_i = sin(alpha_i)``; a
    derivative with respect to ``q_k`` applies the chain rule
    ``dC_i = -S_i d(alpha_i)``, ``dS_i = C_i d(alpha_i)`` explicitly. The cosines
    and sines are put back before lambdifying.
    """
    n_links = len(n_modes)
    theta = [sp.Symbol(f"theta{i + 1}") for i in range(n_links)]
    dtheta = [sp.Symbol(f"dtheta{i + 1}") for i in range(n_links)]
    delta = [sp.Symbol(f"delta{i + 1}_{j + 1}") for i, n in enumerate(n_modes) for j in range(n)]
    ddelta = [sp.Symbol(f"ddelta{i + 1}_{j + 1}") for i, n in enumerate(n_modes) for j in range(n)]
    q, dq = theta + delta, dtheta + ddelta
    n_dof = len(q)
    x = sp.Symbol("x")
    phi = [[sp.Symbol(f"phi{i + 1}_{j + 1}") for j in range(n)] for i, n in enumerate(n_modes)]
    # S_ijk(x) (j <= k), the density variables of the foreshortening
    shs = [
        {jk: sp.Symbol(f"sh{i + 1}_{jk[0] + 1}_{jk[1] + 1}") for jk in _pairs(n)}
        if stiffening
        else {}
        for i, n in enumerate(n_modes)
    ]
    cs = [sp.Symbol(f"cos_alpha{i + 1}") for i in range(n_links)]
    sn = [sp.Symbol(f"sin_alpha{i + 1}") for i in range(n_links)]

    params: list[sp.Symbol] = []
    integral_keys: list[dict[tuple[int, ...], sp.Symbol]] = []
    tip_defl: list[list[sp.Symbol]] = []
    tip_slope: list[list[sp.Symbol]] = []
    tip_short: list[dict[tuple[int, int], sp.Symbol]] = []
    for i, n in enumerate(n_modes):
        k = i + 1
        new = [sp.Symbol(f"{a}{k}") for a in ("L", "mh", "Jh", "m", "S", "I")]
        params += new
        pairs = list(shs[i])
        nv = n + len(pairs)  # density variables after x: phi_1..phi_n, then S_jk
        zero = (0,) * nv
        unit = [tuple(int(a == j) for a in range(nv)) for j in range(nv)]
        keys = {(0, *zero): new[3], (1, *zero): new[4], (2, *zero): new[5]}
        for j in range(n):
            keys[(0, *unit[j])] = sp.Symbol(f"c{k}_{j + 1}")  # int rho phi_j dx
            keys[(1, *unit[j])] = sp.Symbol(f"d{k}_{j + 1}")  # int rho x phi_j dx
            for jj in range(j, n):
                e = tuple(a + b for a, b in zip(unit[j], unit[jj], strict=True))
                keys[(0, *e)] = sp.Symbol(f"G{k}_{j + 1}_{jj + 1}")  # int rho phi_j phi_jj
        for p_, (a, b) in enumerate(pairs):
            u_ = unit[n + p_]
            keys[(0, *u_)] = sp.Symbol(f"Sm{k}_{a + 1}_{b + 1}")  # int rho S_ab dx
            keys[(1, *u_)] = sp.Symbol(f"Sx{k}_{a + 1}_{b + 1}")  # int rho x S_ab dx
            for j in range(n):
                e = tuple(c + d for c, d in zip(unit[j], u_, strict=True))
                keys[(0, *e)] = sp.Symbol(f"T3{k}_{j + 1}_{a + 1}_{b + 1}")  # int rho phi_j S_ab
            for p2 in range(p_, len(pairs)):
                c_, d_ = pairs[p2]
                e = tuple(c + d for c, d in zip(u_, unit[n + p2], strict=True))
                name = f"T4{k}_{a + 1}_{b + 1}_{c_ + 1}_{d_ + 1}"
                keys[(0, *e)] = sp.Symbol(name)  # int rho S_ab S_cd dx
        params += [s for s in keys.values() if s not in new]
        integral_keys.append(keys)
        tip_defl.append([sp.Symbol(f"e{k}_{j + 1}") for j in range(n)])  # phi_j(L)
        tip_slope.append([sp.Symbol(f"s{k}_{j + 1}") for j in range(n)])  # phi_j'(L)
        tip_short.append({jk: sp.Symbol(f"SL{k}_{jk[0] + 1}_{jk[1] + 1}") for jk in pairs})
        params += tip_defl[-1] + tip_slope[-1] + list(tip_short[-1].values())
    params += [sp.Symbol("mp"), sp.Symbol("Jp")]

    dens = [sym for i in range(n_links) for sym in shs[i].values()]
    symbols = [x, *(p for row in phi for p in row), *dens, *cs, *sn, *q, *dq, *params]
    assert len(set(symbols)) == len(symbols), "clashing symbol names"
    R, *gens = sp.ring(symbols, sp.QQ)
    g = dict(zip(symbols, gens, strict=True))
    index = {s: k for k, s in enumerate(symbols)}
    G = [g[s] for s in q]
    dG = [g[s] for s in dq]

    # alpha_i = theta_1 + ... + theta_{i+1} + sum_{k<i} sum_j s_kj delta_kj
    alpha = []
    slope_sum = R.zero
    dlt = iter(delta)
    for i in range(n_links):
        alpha.append(sum((g[t] for t in theta[: i + 1]), R.zero) + slope_sum)
        slope_sum += sum((g[s] * g[next(dlt)] for s in tip_slope[i]), R.zero)
    alpha_end = sum((g[t] for t in theta), R.zero) + slope_sum
    dalpha = [[a.diff(qk) for qk in G] for a in alpha]

    def partial(f: Any, a: int) -> Any:
        """Total ``df/dq_a`` through the explicit ``q`` and the cosines and sines."""
        out = f.diff(G[a])
        for i in range(n_links):
            if dalpha[i][a]:
                c, s = g[cs[i]], g[sn[i]]
                out += (c * f.diff(s) - s * f.diff(c)) * dalpha[i][a]
        return out

    def rate(f: Any) -> Any:
        """Time derivative along the motion, ``sum_a df/dq_a qdot_a``."""
        return sum((partial(f, a) * dG[a] for a in range(n_dof)), R.zero)

    T = R.zero
    o = [R.zero, R.zero]  # joint position o_i
    start = 0
    for i in range(n_links):
        k = i + 1
        L, mh, Jh = g[sp.Symbol(f"L{k}")], g[sp.Symbol(f"mh{k}")], g[sp.Symbol(f"Jh{k}")]
        c, s = g[cs[i]], g[sn[i]]
        dl = [g[d] for d in delta[start : start + n_modes[i]]]
        start += n_modes[i]
        w = sum((g[p] * d for p, d in zip(phi[i], dl, strict=True)), R.zero)
        # u = 1/2 sum_jk S_jk delta_j delta_k, S symmetric: S_jj / 2, S_jk (j < k) once
        u = sum(
            (
                g[sym] * dl[a] * dl[b] * (R(1) / 2 if a == b else R(1))
                for (a, b), sym in shs[i].items()
            ),
            R.zero,
        )
        p = [o[0] + c * (g[x] - u) - s * w, o[1] + s * (g[x] - u) + c * w]
        v = [rate(p[0]), rate(p[1])]
        keys = {e: index[sym] for e, sym in integral_keys[i].items()}
        dens_i = [index[p_] for p_ in phi[i]] + [index[sym] for sym in shs[i].values()]
        rho_v2 = _integrate_along_beam(v[0] ** 2 + v[1] ** 2, index[x], dens_i, keys)
        T += rho_v2 / 2
        # hub of link i: point mass at o_i, rotary inertia turning with alpha_i
        vo = [rate(o[0]), rate(o[1])]
        T += mh * (vo[0] ** 2 + vo[1] ** 2) / 2 + Jh * rate(alpha[i]) ** 2 / 2
        tip = [(g[x], L)] + [(g[a], g[b]) for a, b in zip(phi[i], tip_defl[i], strict=True)]
        tip += [(g[sym], g[tip_short[i][jk]]) for jk, sym in shs[i].items()]
        o = [p[0].compose(tip), p[1].compose(tip)]
    # payload: point mass at o_N, rotary inertia turning with alpha_{N-1} + w'_{N-1}(L)
    vo = [rate(o[0]), rate(o[1])]
    T += g[sp.Symbol("mp")] * (vo[0] ** 2 + vo[1] ** 2) / 2
    T += g[sp.Symbol("Jp")] * rate(alpha_end) ** 2 / 2

    dT = [T.diff(d) for d in dG]
    M_ring = [[dT[a].diff(dG[b]) for b in range(n_dof)] for a in range(n_dof)]
    h_ring = [rate(dT[a]) - partial(T, a) for a in range(n_dof)]  # Lagrange at qddot = 0

    trig = {}
    for i in range(n_links):
        a_expr = alpha[i].as_expr()
        trig[cs[i]], trig[sn[i]] = sp.cos(a_expr), sp.sin(a_expr)

    def to_expr(f: Any) -> sp.Expr:
        return f.as_expr().xreplace(trig)

    M = sp.Matrix(n_dof, n_dof, lambda a, b: to_expr(M_ring[a][b]))
    h = sp.Matrix([to_expr(e) for e in h_ring])
    fn = sp.lambdify((q, dq, params), [M, h], modules="numpy", cse=True)

    def mass_and_bias(qn: Any, dqn: Any, pn: Any) -> tuple[np.ndarray, np.ndarray]:
        Mn, hn = fn(list(qn), list(dqn), list(pn))
        return np.asarray(Mn, dtype=float), np.asarray(hn, dtype=float).reshape(-1)

    return Derivation(
        tuple(n_modes), tuple(q), tuple(dq), tuple(params), to_expr(T), M, h, mass_and_bias
    )


def numeric_params(arm: fa.FlexibleArm, deriv: Derivation) -> np.ndarray:
    """Values of ``deriv.params`` for ``arm``, modal integrals from ``arm.modes`` (and
    the foreshortening integrals from :mod:`flexarm.model.foreshortening`)."""
    val: dict[str, float] = {"mp": arm.payload_mass, "Jp": arm.payload_inertia}
    for i, (lk, bm) in enumerate(zip(arm.links, arm.modes, strict=True)):
        k = i + 1
        L, rho = lk.length, lk.linear_density
        val |= {
            f"L{k}": L,
            f"mh{k}": lk.hub_mass,
            f"Jh{k}": lk.hub_inertia,
            f"m{k}": rho * L,
            f"S{k}": rho * L**2 / 2,
            f"I{k}": rho * L**3 / 3,
        }
        for j in range(lk.n_modes):
            val[f"c{k}_{j + 1}"] = bm.mass_integral[j]
            val[f"d{k}_{j + 1}"] = bm.moment_integral[j]
            val[f"e{k}_{j + 1}"] = bm.tip_deflection[j]
            val[f"s{k}_{j + 1}"] = bm.tip_slope[j]
            for jj in range(j, lk.n_modes):
                val[f"G{k}_{j + 1}_{jj + 1}"] = bm.modal_mass[j, jj]
        f = foreshortening_integrals(bm)
        for a in range(lk.n_modes):
            for b in range(lk.n_modes):
                ab = f"{a + 1}_{b + 1}"
                val |= {f"Sm{k}_{ab}": f.mass[a, b], f"Sx{k}_{ab}": f.moment[a, b]}
                val[f"SL{k}_{ab}"] = f.tip[a, b]
                for j in range(lk.n_modes):
                    val[f"T3{k}_{j + 1}_{ab}"] = f.cubic[j, a, b]
                for c in range(lk.n_modes):
                    for d in range(lk.n_modes):
                        val[f"T4{k}_{ab}_{c + 1}_{d + 1}"] = f.quartic[a, b, c, d]
    return np.array([float(val[s.name]) for s in deriv.params])


# --------------------------------------------------------------------------- fixtures
def make_arm(n_modes: tuple[int, ...], boundary: str, stiffening: bool = False) -> fa.FlexibleArm:
    links = [
        fa.Link(L, EI, rho, n_modes=n, hub_mass=mh, hub_inertia=Jh, modal_damping=z)
        for (L, EI, rho, mh, Jh, z), n in zip(LINK_DATA, n_modes, strict=True)
    ]
    return fa.FlexibleArm(
        links,
        payload_mass=PAYLOAD[0],
        payload_inertia=PAYLOAD[1],
        boundary=boundary,
        geometric_stiffening=stiffening,
    )


def random_states(arm: fa.FlexibleArm, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """States with angles in [-pi, pi], tip deflections ~5-20 % of the link length
    and rates O(1) (modal rates: tip deflection rates O(L) per second)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        q = [rng.uniform(-np.pi, np.pi, arm.n_links)]
        dq = [rng.uniform(-1.5, 1.5, arm.n_links)]
        for lk, bm in zip(arm.links, arm.modes, strict=True):
            scale = lk.length / np.abs(bm.tip_deflection) / max(lk.n_modes, 1)
            sign = rng.choice([-1.0, 1.0], lk.n_modes)
            q.append(sign * rng.uniform(0.05, 0.2, lk.n_modes) * scale)
            dq.append(rng.uniform(-1.0, 1.0, lk.n_modes) * scale)
        out.append((np.concatenate(q), np.concatenate(dq)))
    return out


def assert_close(actual: np.ndarray, expected: np.ndarray, what: str) -> None:
    err = np.linalg.norm(actual - expected)
    ref = np.linalg.norm(expected)
    assert err <= RTOL * ref, (
        f"{what}: |arm - sympy| = {err:.3e}, |sympy| = {ref:.3e}, "
        f"relative {err / ref:.3e}\narm - sympy =\n{np.array2string(actual - expected)}"
    )


MODES = [(1, 1), (2, 2), (1, 2), (0, 0)]
BOUNDARIES = ["clamped-free", "clamped-mass"]


# --------------------------------------------------------------------------- sanity
def test_rigid_limit_is_textbook_two_link_arm() -> None:
    """With no modes the derivation is the rigid two-link arm of uniform rods."""
    d = derive((0, 0))
    rho1, rho2, L1, L2 = sp.symbols("rho1 rho2 L1 L2", positive=True)
    th2 = d.q[1]
    dth1, dth2 = d.dq
    sub = {s: 0 for s in d.params if s.name in ("mh1", "mh2", "Jh1", "Jh2", "mp", "Jp")}
    for k, rho, L in ((1, rho1, L1), (2, rho2, L2)):
        sub |= {
            sp.Symbol(f"L{k}"): L,
            sp.Symbol(f"m{k}"): rho * L,
            sp.Symbol(f"S{k}"): rho * L**2 / 2,
            sp.Symbol(f"I{k}"): rho * L**3 / 3,
        }
    m1, m2, lc1, lc2 = rho1 * L1, rho2 * L2, L1 / 2, L2 / 2
    I1, I2 = m1 * L1**2 / 12, m2 * L2**2 / 12
    c2, s2 = sp.cos(th2), sp.sin(th2)
    M_book = sp.Matrix(
        [
            [
                m1 * lc1**2 + I1 + m2 * (L1**2 + lc2**2 + 2 * L1 * lc2 * c2) + I2,
                m2 * (lc2**2 + L1 * lc2 * c2) + I2,
            ],
            [m2 * (lc2**2 + L1 * lc2 * c2) + I2, m2 * lc2**2 + I2],
        ]
    )
    hc = m2 * L1 * lc2 * s2
    h_book = sp.Matrix([-hc * (2 * dth1 * dth2 + dth2**2), hc * dth1**2])
    dM = (d.M.subs(sub) - M_book).applyfunc(lambda e: sp.simplify(sp.expand_trig(e)))
    dh = (d.h.subs(sub) - h_book).applyfunc(lambda e: sp.simplify(sp.expand_trig(e)))
    assert dM == sp.zeros(2, 2)
    assert dh == sp.zeros(2, 1)


def _shortening_by_quadrature(bm: Any, delta: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``u(x) = 1/2 int_0^x w'(s)**2 ds`` by Gauss–Legendre on each ``[0, x]``, from
    :meth:`BeamModes.slope` alone (``delta`` may be complex: complex step)."""
    if delta.shape[0] == 0:
        return np.zeros_like(x)
    t, wts = np.polynomial.legendre.leggauss(80)
    nodes = 0.5 * x[:, None] * (t[None, :] + 1.0)  # (m, 80)
    slope = delta @ bm.slope(nodes.ravel())  # w'(s) at every node
    return 0.5 * (slope.reshape(nodes.shape) ** 2 @ wts) * 0.5 * x


def _kinetic_energy_by_quadrature(arm: fa.FlexibleArm, q: np.ndarray, dq: np.ndarray) -> float:
    """``T`` straight from the kinematic map: Gauss–Legendre in ``x``, complex step in time."""
    step = 1e-30
    qc = q + 1j * step * dq
    nl = arm.n_links
    theta, deltas, start = qc[:nl], [], nl
    for lk in arm.links:
        deltas.append(qc[start : start + lk.n_modes])
        start += lk.n_modes
    t, wts = np.polynomial.legendre.leggauss(80)
    T = 0.0
    o = np.zeros(2, dtype=complex)
    slope = 0.0 + 0.0j
    for i, (lk, bm) in enumerate(zip(arm.links, arm.modes, strict=True)):
        alpha = theta[: i + 1].sum() + slope
        T += 0.5 * lk.hub_mass * np.sum((o.imag / step) ** 2)
        T += 0.5 * lk.hub_inertia * (alpha.imag / step) ** 2
        L = lk.length
        x = np.concatenate([0.5 * L * (t + 1.0), [L]])
        w = deltas[i] @ bm.shape(x) if lk.n_modes else np.zeros_like(x)
        xs = x - _shortening_by_quadrature(bm, deltas[i], x) if arm.geometric_stiffening else x
        c, s = np.cos(alpha), np.sin(alpha)
        px = o[0] + c * xs - s * w
        py = o[1] + s * xs + c * w
        v2 = (px.imag / step) ** 2 + (py.imag / step) ** 2
        T += 0.5 * lk.linear_density * (0.5 * L * wts) @ v2[:-1]
        o = np.array([px[-1], py[-1]])
        if lk.n_modes:
            slope = slope + deltas[i] @ bm.slope([L])[:, 0]
    T += 0.5 * arm.payload_mass * np.sum((o.imag / step) ** 2)
    T += 0.5 * arm.payload_inertia * ((theta.sum() + slope).imag / step) ** 2
    return float(T)


@pytest.mark.parametrize("stiffening", [False, True], ids=["linear", "stiffening"])
@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("n_modes", MODES, ids=lambda m: "modes" + "".join(map(str, m)))
def test_derivation_kinetic_energy_matches_quadrature(
    n_modes: tuple[int, ...], boundary: str, stiffening: bool
) -> None:
    """``1/2 qdot' M_sympy qdot`` is the integral of ``1/2 rho |dp/dt|^2`` itself."""
    arm = make_arm(n_modes, boundary, stiffening)
    d = derive(n_modes, stiffening)
    pn = numeric_params(arm, d)
    for q, dq in random_states(arm, 3, seed=7):
        M, _ = d.mass_and_bias(q, dq, pn)
        T_quad = _kinetic_energy_by_quadrature(arm, q, dq)
        assert abs(0.5 * dq @ M @ dq - T_quad) <= RTOL * T_quad


# --------------------------------------------------------------------------- the model
@pytest.mark.parametrize("stiffening", [False, True], ids=["linear", "stiffening"])
@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("n_modes", MODES, ids=lambda m: "modes" + "".join(map(str, m)))
def test_mass_matrix_matches_sympy(
    n_modes: tuple[int, ...], boundary: str, stiffening: bool
) -> None:
    arm = make_arm(n_modes, boundary, stiffening)
    d = derive(n_modes, stiffening)
    pn = numeric_params(arm, d)
    for q, dq in random_states(arm, 5, seed=11):
        M_sym, _ = d.mass_and_bias(q, dq, pn)
        assert_close(np.asarray(arm.mass_matrix(q)), M_sym, f"M at q={q}")


@pytest.mark.parametrize("stiffening", [False, True], ids=["linear", "stiffening"])
@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("n_modes", MODES, ids=lambda m: "modes" + "".join(map(str, m)))
def test_velocity_terms_match_sympy(
    n_modes: tuple[int, ...], boundary: str, stiffening: bool
) -> None:
    arm = make_arm(n_modes, boundary, stiffening)
    d = derive(n_modes, stiffening)
    pn = numeric_params(arm, d)
    for q, dq in random_states(arm, 5, seed=13):
        _, h_sym = d.mass_and_bias(q, dq, pn)
        assert_close(arm.velocity_terms(q, dq), h_sym, f"C dq at q={q}, dq={dq}")


@pytest.mark.parametrize("stiffening", [False, True], ids=["linear", "stiffening"])
@pytest.mark.parametrize("boundary", BOUNDARIES)
@pytest.mark.parametrize("n_modes", MODES, ids=lambda m: "modes" + "".join(map(str, m)))
def test_coriolis_matrix_times_rates_matches_sympy(
    n_modes: tuple[int, ...], boundary: str, stiffening: bool
) -> None:
    arm = make_arm(n_modes, boundary, stiffening)
    d = derive(n_modes, stiffening)
    pn = numeric_params(arm, d)
    for q, dq in random_states(arm, 5, seed=17):
        _, h_sym = d.mass_and_bias(q, dq, pn)
        assert_close(arm.coriolis(q, dq) @ dq, h_sym, f"C(q, dq) dq at q={q}, dq={dq}")


@pytest.mark.parametrize("stiffening", [False, True], ids=["linear", "stiffening"])
@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_forward_dynamics_matches_sympy(backend: str, stiffening: bool) -> None:
    n_modes, boundary = (2, 2), "clamped-mass"
    arm = make_arm(n_modes, boundary, stiffening)
    d = derive(n_modes, stiffening)
    pn = numeric_params(arm, d)
    K, D, B = arm.stiffness_matrix, arm.damping_matrix, arm.input_matrix
    assert np.any(np.diag(D) > 0)  # damping is exercised
    rng = np.random.default_rng(19)
    for q, dq in random_states(arm, 5, seed=23):
        tau = rng.uniform(-2.0, 2.0, arm.n_links)
        M_sym, h_sym = d.mass_and_bias(q, dq, pn)
        ddq_sym = np.linalg.solve(M_sym, B @ tau - K @ q - D @ dq - h_sym)
        ddq = arm.forward_dynamics(q, dq, tau, backend=backend)
        assert_close(ddq, ddq_sym, f"qddot ({backend}) at q={q}, dq={dq}, tau={tau}")
