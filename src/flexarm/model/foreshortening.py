r"""Foreshortening of a bent link: the axial shortening and its modal integrals.

A link bent to ``w(x) = sum_j phi_j(x) delta_j`` keeps its length (it is
inextensible), so a point at arc length ``x`` sits, along the link's clamped
axis, short of ``x`` by

.. math:: u(x) = \frac12 \int_0^x w'(s)^2 \, ds
               = \frac12 \, \delta^T S(x) \, \delta, \qquad
          S_{jk}(x) = \int_0^x \phi_j'(s) \phi_k'(s) \, ds,

to second order in the slope (the exact shortening is
``int (1 - sqrt(1 - w'^2))``; the difference is of fourth order). The tip
shortens by ``u(L)``, and everything outboard of the link moves with its tip.
Held in the kinematic map of :class:`flexarm.FlexibleArm` (``geometric_stiffening=True``),
``u`` brings the centrifugal (geometric) stiffening of a spinning link: a
link turning at ``Omega`` pulls its own points outward, and ``u`` turns that
pull into a restoring force ``Omega**2 int rho x S(x) dx delta`` on the modes.

The Lagrangian built from that map needs five integrals of each link's modes
(:class:`Foreshortening`); with ``rho`` the linear density:

* ``tip = S(L)``: the tip's shortening, ``u(L) = 1/2 delta' S(L) delta``;
* ``mass = int rho S(x) dx``: ``int rho u dx = 1/2 delta' mass delta``;
* ``moment = int rho x S(x) dx``: ``int rho x u dx = 1/2 delta' moment delta``
  (the centrifugal stiffening);
* ``cubic[a, b, c] = int rho phi_a(x) S_bc(x) dx``: the products of the
  transverse and the axial motion;
* ``quartic[a, b, c, d] = int rho S_ab(x) S_cd(x) dx``: the kinetic energy of
  the axial motion itself.

All five are computed by Gauss–Legendre quadrature exact to rounding for these
smooth shapes: ``S`` at each outer node by an inner rule on ``[0, x]``.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array
from ..errors import InvalidValueError
from .beam import BeamModes

__all__ = ["Foreshortening", "foreshortening_integrals", "shortening_matrix"]

F64 = NDArray[np.float64]


class Foreshortening(NamedTuple):
    """The foreshortening integrals of one link's modes (module docstring).

    Attributes
    ----------
    tip : ndarray, shape (n, n)
        ``S(L)``, 1/m per unit coordinate**2 times m: ``u(L)`` in m is
        ``1/2 delta' tip delta``.
    mass : ndarray, shape (n, n)
        ``int rho S(x) dx``, kg per unit coordinate**2.
    moment : ndarray, shape (n, n)
        ``int rho x S(x) dx``, kg m per unit coordinate**2.
    cubic : ndarray, shape (n, n, n)
        ``int rho phi_a S_bc dx``, symmetric in ``(b, c)``.
    quartic : ndarray, shape (n, n, n, n)
        ``int rho S_ab S_cd dx``, symmetric in ``(a, b)``, ``(c, d)`` and the
        exchange of the two pairs.
    """

    tip: F64
    mass: F64
    moment: F64
    cubic: F64
    quartic: F64


@functools.lru_cache(maxsize=16)
def _legendre_rule(n_nodes: int) -> tuple[F64, F64]:
    """Gauss–Legendre nodes and weights on ``[-1, 1]`` (read-only: shared by every call
    with ``n_nodes``; an eigenvalue problem each time was most of a linearisation)."""
    t, w = np.polynomial.legendre.leggauss(n_nodes)
    t.flags.writeable = False
    w.flags.writeable = False
    return t, w


def _gauss(n_modes: int, roots: F64, a: float, b: float) -> tuple[F64, F64]:
    """Gauss–Legendre nodes and weights on ``[a, b]``, exact to rounding for these
    modes' slopes and their products (the rule of :class:`BeamModes`' integrals)."""
    lam_max = float(roots[-1]) if n_modes else 0.0
    t, w = _legendre_rule(64 + 2 * math.ceil(lam_max))
    half = 0.5 * (b - a)
    return a + half * (t + 1.0), half * w


def shortening_matrix(modes: BeamModes, x: ArrayLike) -> F64:
    """``S(x) = int_0^x phi'(s) phi'(s)' ds`` at each ``x``.

    Parameters
    ----------
    modes : BeamModes
        The link's modes.
    x : array_like, shape (m,) or scalar
        Positions along the link, m, in ``[0, L]``.

    Returns
    -------
    ndarray, shape (n_modes, n_modes, m)
        ``u(x) = 1/2 delta' S(x) delta`` is the axial shortening in m.
    """
    xa = np.atleast_1d(check_array(x, "x", "shortening_matrix"))
    L = modes.length
    if xa.ndim != 1 or np.any(xa < -1e-12 * L) or np.any(xa > L * (1 + 1e-12)):
        raise InvalidValueError(
            f"The 'x' parameter of shortening_matrix must be a scalar or 1-D with values in "
            f"[0, {L}]. Got shape {xa.shape} and range [{xa.min()}, {xa.max()}] instead."
        )
    n = modes.n_modes
    t, w = _gauss(n, modes.roots, 0.0, 1.0)
    # nodes s = x t on [0, x] for every x at once: slopes at (m * n_nodes) points
    s = np.clip(xa[:, None] * t[None, :], 0.0, L)
    g = modes.slope(s.ravel()).reshape(n, xa.shape[0], t.shape[0])  # (n, m, k)
    out: F64 = np.einsum("amk,bmk,k->abm", g, g, w) * xa[None, None, :]
    return 0.5 * (out + out.transpose(1, 0, 2))


def foreshortening_integrals(modes: BeamModes) -> Foreshortening:
    """The five foreshortening integrals of ``modes`` (:class:`Foreshortening`)."""
    n, L, rho = modes.n_modes, modes.length, modes.linear_density
    x, wx = _gauss(n, modes.roots, 0.0, L)
    S = shortening_matrix(modes, x)  # (n, n, k)
    phi = modes.shape(x)  # (n, k)
    rw = rho * wx
    tip = shortening_matrix(modes, [L])[:, :, 0]
    mass = S @ rw
    moment = S @ (rw * x)
    cubic = np.einsum("ak,bck,k->abc", phi, S, rw)
    quartic = np.einsum("abk,cdk,k->abcd", S, S, rw)
    # symmetrise what is symmetric by construction (rounding only)
    cubic = 0.5 * (cubic + cubic.transpose(0, 2, 1))
    quartic = 0.5 * (quartic + quartic.transpose(2, 3, 0, 1))
    return Foreshortening(tip=tip, mass=mass, moment=moment, cubic=cubic, quartic=quartic)
