"""Euler–Bernoulli beam modes: clamped-free and clamped-mass roots, shapes, integrals.

A uniform beam of length ``L``, flexural rigidity ``EI`` and linear density
``rho`` is clamped at ``x = 0`` and carries at ``x = L`` a point mass ``M`` and a
rotary inertia ``J`` about the tip (``M = J = 0`` is the cantilever). With
``mu = M / (rho L)``, ``j = J / (rho L**3)`` and ``lam = beta L`` the natural
frequencies are ``omega = lam**2 sqrt(EI / (rho L**4))`` where ``lam`` solves::

    1 + cos(lam) cosh(lam) + mu lam (cos(lam) sinh(lam) - sin(lam) cosh(lam))
      - j lam**3 (cosh(lam) sin(lam) + sinh(lam) cos(lam))
      + mu j lam**4 (1 - cos(lam) cosh(lam)) = 0

(boundary conditions ``EI w''(L) = J omega**2 w'(L)`` and
``EI w'''(L) = -M omega**2 w(L)``).

Numerics
--------
*Roots.* The equation is divided by ``cosh(lam) (1 + mu lam + j lam**3 +
mu j lam**4)`` so it stays O(1) for every ``lam``, ``mu`` and ``j``; roots are
bracketed on a grid that is logarithmic below ``lam = 1`` (a heavy tip pushes
the first roots towards zero as ``(3/mu)**0.25`` and ``j**-0.25``) and linear
with step ``pi/64`` above it, then refined by Brent's method to full double
precision.

*Shapes.* The textbook form ``cosh z - cos z - sigma (sinh z - sin z)``
subtracts two numbers of size ``e**z / 2`` and loses every digit above the
tenth mode. Here a shape is written in the basis
``{e**(z - lam), e**(-z), cos z, sin z}`` (``z = beta x``), whose members are
all bounded by one on ``[0, L]``, so shapes, slopes and curvatures keep full
precision for any mode number.

Normalisation
-------------
``"mass"`` (the default): the generalised modal mass is one,
``int rho phi_j**2 dx + M phi_j(L)**2 + J phi_j'(L)**2 = 1`` (kg m**2 per
unit ``delta``**2; the modal coordinates then carry units of sqrt(kg) m).
The modes are orthonormal in that inner product and the modal stiffness is
``diag(omega**2)``.
``"amplitude"``: the paper's form ``phi = A [cosh - cos - sigma (sinh - sin)]``
with ``A = amplitude`` (0.1 in the paper), i.e. the coefficient of
``(cosh - cos)`` is ``A``; for a cantilever ``phi_j(L) = 2 A (-1)**(j+1)``.
``"tip"``: ``phi_j(L) = 1``, so each modal coordinate is that mode's tip
deflection in metres (this fixes the sign too).
For ``"mass"`` and ``"amplitude"`` the sign is fixed so the coefficient of
``(cosh - cos)`` is positive (``phi_j''(0) > 0``).

Accuracy: roots to about 1e-14 relative for any tip ratios (the scaled
equation switches to exact series below ``lam = 1``, where heavy tips put the
first roots). Shapes are built from bounded basis functions; for a very heavy
tip (``lam`` far below one) the shape near the clamp, which is
``O(lam**2)``, carries a relative error of about ``1e-16 / lam**2``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._budget import check_memory, check_time
from .._validation import (
    check_array,
    check_int,
    check_option,
    check_real,
    validate_real_fields,
)
from ..errors import InvalidValueError
from . import _roots
from ._roots import CACHED_UP_TO, frequency_function, frozen

__all__ = [
    "MAX_TIP_RATIO",
    "NORMALIZATIONS",
    "BeamModes",
    "UniformBeam",
    "cantilever_roots",
    "clamped_mass_roots",
    "frequency_function",
]

MAX_TIP_RATIO = 1e12
"""The largest tip mass over ``rho L`` (and tip inertia over ``rho L**3``) the modes
take (dimensionless): far beyond any physical arm, and the scaled frequency equation's
``mu j lam**4`` stays a float64 number."""

NORMALIZATIONS = ("mass", "amplitude", "tip")


def clamped_mass_roots(
    n: int, mass_ratio: float = 0.0, inertia_ratio: float = 0.0
) -> NDArray[np.float64]:
    """First ``n`` roots ``beta_j L`` of the clamped-mass frequency equation.

    Parameters
    ----------
    n : int
        Number of roots (>= 0).
    mass_ratio : float
        Tip mass over beam mass, ``mu = M / (rho L)`` (>= 0).
    inertia_ratio : float
        Tip rotary inertia about the tip over ``rho L**3``, ``j = J / (rho L**3)``
        (>= 0).

    Returns
    -------
    ndarray, shape (n,)
        Increasing roots, dimensionless, accurate to about 1e-14 relative.
    """
    owner = "clamped_mass_roots"
    n = check_int(n, "n", owner, minimum=0)
    mu = check_real(mass_ratio, "mass_ratio", owner, nonnegative=True)
    jr = check_real(inertia_ratio, "inertia_ratio", owner, nonnegative=True)
    for name, ratio in (("mass_ratio", mu), ("inertia_ratio", jr)):
        if ratio > MAX_TIP_RATIO:
            raise InvalidValueError(
                f"The '{name}' parameter of {owner} must be at most {MAX_TIP_RATIO:g} (beyond "
                f"it the frequency equation overflows float64). Got {ratio!r} instead."
            )
    if n <= CACHED_UP_TO:  # arms built again and again, as in a sweep, share them
        return _roots.cached_roots(n, mu, jr).copy()
    return _roots.roots(n, mu, jr)


def cantilever_roots(n: int) -> NDArray[np.float64]:
    """First ``n`` roots of ``cos(x) cosh(x) + 1 = 0`` (clamped-free beam).

    Returns
    -------
    ndarray, shape (n,)
        1.8751040687, 4.6940911330, 7.8547574382, ... (dimensionless).
    """
    return clamped_mass_roots(n, 0.0, 0.0)


def _shape_coefficients(lam: NDArray[np.float64], mu: float, jr: float) -> NDArray[np.float64]:
    """Coefficients (a, b, c, d), shape (4, n), of the unnormalised shapes.

    ``phi(z) = a e**(z - lam) + b e**(-z) + c cos z + d sin z`` with the clamp
    conditions solved (``c = -b - a e**-lam``, ``d = b - a e**-lam``) and (a, b)
    the null vector of the better-conditioned tip condition. The sign makes
    ``C1 = -c`` (the coefficient of ``cosh - cos``) positive.
    """
    eps = np.exp(-lam)
    co, si = np.cos(lam), np.sin(lam)
    # phi^(k)(lam) = a * pa[k] + b * pb[k]
    pa = [
        1 - eps * co - eps * si,
        1 + eps * si - eps * co,
        1 + eps * co + eps * si,
        1 - eps * si + eps * co,
    ]
    pb = [eps - co + si, -eps + si + co, eps + co - si, -eps - si - co]
    # Tip conditions: phi'' - j lam^3 phi' = 0 and phi''' + mu lam phi = 0, each scaled.
    s1 = 1.0 + jr * lam**3
    s2 = 1.0 + mu * lam
    r1a, r1b = (pa[2] - jr * lam**3 * pa[1]) / s1, (pb[2] - jr * lam**3 * pb[1]) / s1
    r2a, r2b = (pa[3] + mu * lam * pa[0]) / s2, (pb[3] + mu * lam * pb[0]) / s2
    use1 = np.hypot(r1a, r1b) >= np.hypot(r2a, r2b)
    a = np.where(use1, r1b, r2b)
    b = np.where(use1, -r1a, -r2a)
    nrm = np.hypot(a, b)
    a, b = a / nrm, b / nrm
    c = -b - a * eps
    d = b - a * eps
    sign = np.where(-c < 0.0, -1.0, 1.0)
    return np.stack([a, b, c, d]) * sign


def _quadrature_points(roots: NDArray[np.float64]) -> int:
    """Gauss–Legendre points exact enough for modes up to the largest root."""
    lam_max = float(roots[-1]) if roots.shape[0] else 0.0
    return 64 + 2 * math.ceil(lam_max)


def _check_scales(length: float, rigidity: float, density: float, owner: str) -> None:
    """The beam's scales ``rho L**3`` and ``EI / (rho L**4)`` must be float64 numbers."""
    try:
        scales = (density * length**3, rigidity / (density * length**4))
    except (OverflowError, ZeroDivisionError):
        scales = (math.inf, math.inf)
    if not all(math.isfinite(v) and v > 0.0 for v in scales):
        raise InvalidValueError(
            f"The 'length', 'flexural_rigidity' and 'linear_density' parameters of {owner} "
            "must give a beam whose scales rho L**3 and EI / (rho L**4) are finite, "
            f"positive float64 numbers (at most 1.8e308). Got L = {length!r} m, "
            f"EI = {rigidity!r} N m**2, rho = {density!r} kg/m instead."
        )


@dataclass(frozen=True)
class UniformBeam:
    """A uniform Euler–Bernoulli beam and the modes kept of it: what a
    :class:`~flexarm.model.link.Link` and its :class:`BeamModes` share.

    Parameters
    ----------
    length, flexural_rigidity, linear_density : float
        ``L`` in m, ``EI`` in N m**2, ``rho`` in kg/m, all > 0.
    n_modes : int
        Assumed modes kept (>= 0).
    """

    length: float
    flexural_rigidity: float
    linear_density: float
    n_modes: int = 1

    def __post_init__(self) -> None:
        owner = type(self).__name__
        positive = ("length", "flexural_rigidity", "linear_density")
        validate_real_fields(self, owner, positive=positive)
        object.__setattr__(self, "n_modes", check_int(self.n_modes, "n_modes", owner, minimum=0))

    @property
    def mass(self) -> float:
        """Beam mass ``rho L`` in kg (hubs and tip loads excluded)."""
        return self.linear_density * self.length


@dataclass(frozen=True, eq=True)
class BeamModes(UniformBeam):
    """Assumed modes of a uniform Euler–Bernoulli beam, clamped at ``x = 0``.

    Parameters
    ----------
    length : float
        Beam length ``L`` in m (> 0).
    flexural_rigidity : float
        ``EI`` in N m**2 (> 0).
    linear_density : float
        Mass per unit length ``rho`` in kg/m (> 0).
    n_modes : int
        Number of modes kept (>= 0).
    tip_mass : float
        Point mass ``M`` at the tip in kg (>= 0); 0 with ``tip_inertia = 0``
        gives the clamped-free (cantilever) modes.
    tip_inertia : float
        Rotary inertia ``J`` at the tip, about the tip, in kg m**2 (>= 0).
    normalization : {"mass", "amplitude", "tip"}
        Mode scaling, see the module docstring. Default ``"mass"``.
    amplitude : float
        The paper's ``A`` for ``normalization="amplitude"`` (default 0.1, in m
        per unit modal coordinate).

    Attributes
    ----------
    roots : ndarray, shape (n_modes,)
        ``beta_j L``, dimensionless.
    wavenumbers : ndarray, shape (n_modes,)
        ``beta_j`` in 1/m.
    frequencies : ndarray, shape (n_modes,)
        ``omega_j`` in rad/s.
    frequencies_hz : ndarray, shape (n_modes,)
        ``omega_j / (2 pi)`` in Hz.
    mass_ratio, inertia_ratio : float
        ``mu = M / (rho L)``, ``j = J / (rho L**3)``.

    Examples
    --------
    >>> modes = BeamModes(4.5, 1676.0, 0.335, n_modes=2)
    >>> modes.frequencies.round(3)
    array([12.281, 76.966])
    """

    tip_mass: float = 0.0
    tip_inertia: float = 0.0
    normalization: str = "mass"
    amplitude: float = 0.1
    _cache: dict[str, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        owner = "BeamModes"
        set_ = object.__setattr__
        super().__post_init__()
        validate_real_fields(self, owner, nonnegative=("tip_mass", "tip_inertia"))
        check_option(self.normalization, "normalization", owner, NORMALIZATIONS)
        set_(self, "amplitude", check_real(self.amplitude, "amplitude", owner, positive=True))
        _check_scales(self.length, self.flexural_rigidity, self.linear_density, owner)
        for name, ratio, of in (
            ("tip_mass", self.mass_ratio, "the link's mass rho L"),
            ("tip_inertia", self.inertia_ratio, "rho L**3"),
        ):
            if not ratio <= MAX_TIP_RATIO:
                raise InvalidValueError(
                    f"The '{name}' parameter of {owner} must be at most {MAX_TIP_RATIO:g} times "
                    f"{of} (beyond it the frequency equation overflows float64). "
                    f"Got {getattr(self, name)!r} instead."
                )
        # the quadrature evaluates every mode at ~2 pi n points: refuse what cannot fit
        n = self.n_modes
        npts = 64 + 2 * math.ceil(math.pi * (n + 1))
        what = f"{n} modes of one beam ({npts} quadrature points)"
        remedy = "Use fewer modes (a handful converge for the arm's motion)"
        check_memory(8.0 * 4 * npts * max(n, 1), what, owner, remedy)
        check_time(1e-6 * npts * n, what, owner, remedy)  # ~1 us a mode and point here
        lam = clamped_mass_roots(self.n_modes, self.mass_ratio, self.inertia_ratio)
        coef = _shape_coefficients(lam, self.mass_ratio, self.inertia_ratio)
        self._cache["roots"] = frozen(lam)
        # Scale the unit-norm coefficients by the chosen normalisation.
        self._cache["coef"] = coef
        scale = self._normalization_scale(coef)
        self._cache["coef"] = frozen(coef * scale)

    # ------------------------------------------------------------------ basics
    @property
    def mass_ratio(self) -> float:
        """``mu = M / (rho L)``."""
        return self.tip_mass / (self.linear_density * self.length)

    @property
    def inertia_ratio(self) -> float:
        """``j = J / (rho L**3)``."""
        return self.tip_inertia / (self.linear_density * self.length**3)

    @property
    def roots(self) -> NDArray[np.float64]:
        return self._cache["roots"]  # type: ignore[no-any-return]

    @property
    def wavenumbers(self) -> NDArray[np.float64]:
        return self.roots / self.length

    @property
    def frequencies(self) -> NDArray[np.float64]:
        """Natural frequencies in rad/s, shape ``(n_modes,)``."""
        ei, rho, L = self.flexural_rigidity, self.linear_density, self.length
        return self.roots**2 * math.sqrt(ei / (rho * L**4))

    @property
    def frequencies_hz(self) -> NDArray[np.float64]:
        return self.frequencies / (2.0 * math.pi)

    @property
    def coefficients(self) -> NDArray[np.float64]:
        """Normalised coefficients (a, b, c, d), shape ``(4, n_modes)``, of
        ``phi(x) = a e**(beta x - lam) + b e**(-beta x) + c cos(beta x) + d sin(beta x)``."""
        return self._cache["coef"]  # type: ignore[no-any-return]

    # ------------------------------------------------------------------ shapes
    def derivative(self, x: ArrayLike, order: int = 0) -> NDArray[np.float64]:
        """``order``-th derivative of every mode shape at ``x``.

        Parameters
        ----------
        x : array_like, shape (m,) or scalar
            Positions along the beam in m, ``0 <= x <= L``.
        order : int
            0 shape (m per unit modal coordinate), 1 slope (rad), 2 curvature
            (1/m), 3 (1/m**2). Higher orders repeat the pattern.

        Returns
        -------
        ndarray, shape (n_modes, m)
        """
        order = check_int(order, "order", "BeamModes.derivative", minimum=0)
        xa = np.atleast_1d(check_array(x, "x", "BeamModes.derivative"))
        if xa.ndim != 1:
            raise InvalidValueError(
                "The 'x' parameter of BeamModes.derivative must be a scalar or 1-D. "
                f"Got shape {xa.shape} instead."
            )
        L = self.length
        if np.any(xa < -1e-12 * L) or np.any(xa > L * (1 + 1e-12)):
            raise InvalidValueError(
                f"The 'x' parameter of BeamModes.derivative must lie in [0, {L}]. "
                f"Got values in [{xa.min()}, {xa.max()}] instead."
            )
        return self._derivative_unchecked(xa, order)

    def _derivative_unchecked(self, x: NDArray[np.float64], order: int) -> NDArray[np.float64]:
        lam = self.roots[:, None]
        beta = lam / self.length
        z = beta * x[None, :]
        a, b, c, d = (row[:, None] for row in self.coefficients)
        k = order % 4
        e1 = np.exp(z - lam)
        e2 = np.exp(-z) * (-1.0) ** order
        cz, sz = np.cos(z), np.sin(z)
        # derivatives of cos: cos, -sin, -cos, sin; of sin: sin, cos, -sin, -cos
        trig_c = (cz, -sz, -cz, sz)[k]
        trig_s = (sz, cz, -sz, -cz)[k]
        return beta**order * (a * e1 + b * e2 + c * trig_c + d * trig_s)  # type: ignore[no-any-return]

    def shape(self, x: ArrayLike) -> NDArray[np.float64]:
        """Mode shapes ``phi_j(x)``, shape ``(n_modes, len(x))``, m per unit coordinate."""
        return self.derivative(x, 0)

    def slope(self, x: ArrayLike) -> NDArray[np.float64]:
        """Slopes ``phi_j'(x)``, shape ``(n_modes, len(x))``."""
        return self.derivative(x, 1)

    def curvature(self, x: ArrayLike) -> NDArray[np.float64]:
        """Curvatures ``phi_j''(x)``, shape ``(n_modes, len(x))``, 1/m."""
        return self.derivative(x, 2)

    # --------------------------------------------------------------- integrals
    @property
    def tip_deflection(self) -> NDArray[np.float64]:
        """``phi_j(L)``, shape ``(n_modes,)``."""
        return self._derivative_unchecked(np.array([self.length]), 0)[:, 0]

    @property
    def tip_slope(self) -> NDArray[np.float64]:
        """``phi_j'(L)``, shape ``(n_modes,)``, rad per unit coordinate."""
        return self._derivative_unchecked(np.array([self.length]), 1)[:, 0]

    def _quadrature(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Gauss–Legendre nodes and weights on ``[0, L]`` exact for these modes."""
        if "quad" not in self._cache:
            npts = _quadrature_points(self.roots)
            small = self.n_modes <= CACHED_UP_TO
            t, w = _legendre_rule(npts) if small else _legendre_nodes(npts)
            L = self.length
            self._cache["quad"] = (frozen(0.5 * L * (t + 1.0)), frozen(0.5 * L * w))
        return self._cache["quad"]  # type: ignore[no-any-return]

    def _integral(self, key: str, fn: Any) -> NDArray[np.float64]:
        if key not in self._cache:
            x, w = self._quadrature()
            self._cache[key] = frozen(fn(x, w))
        return self._cache[key]  # type: ignore[no-any-return]

    @property
    def mass_integral(self) -> NDArray[np.float64]:
        """``int_0^L rho phi_j dx``, shape ``(n_modes,)``, kg m per unit coordinate."""
        rho = self.linear_density
        return self._integral("v", lambda x, w: rho * self._derivative_unchecked(x, 0) @ w)

    @property
    def moment_integral(self) -> NDArray[np.float64]:
        """``int_0^L rho x phi_j dx``, shape ``(n_modes,)``, kg m**2 per unit coordinate."""
        rho = self.linear_density
        return self._integral("w", lambda x, w: rho * self._derivative_unchecked(x, 0) @ (w * x))

    @property
    def modal_mass(self) -> NDArray[np.float64]:
        """``int_0^L rho phi_j phi_k dx`` (beam only), shape ``(n_modes, n_modes)``."""
        rho = self.linear_density

        def f(x: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.float64]:
            p = self._derivative_unchecked(x, 0)
            m = rho * (p * w) @ p.T
            return 0.5 * (m + m.T)

        return self._integral("M", f)

    @property
    def generalized_mass(self) -> NDArray[np.float64]:
        """Modal mass including the tip body,
        ``int rho phi_j phi_k + M phi_j(L) phi_k(L) + J phi_j'(L) phi_k'(L)``.

        Diagonal by orthogonality (the identity for ``normalization="mass"``).
        Shape ``(n_modes, n_modes)``.
        """
        h, g = self.tip_deflection, self.tip_slope
        return self.modal_mass + self.tip_mass * np.outer(h, h) + self.tip_inertia * np.outer(g, g)

    @property
    def modal_stiffness(self) -> NDArray[np.float64]:
        """``int_0^L EI phi_j'' phi_k'' dx``, shape ``(n_modes, n_modes)``, N m per coordinate**2.

        Computed from the exact identity ``K = diag(omega_j**2 G_jj)`` with ``G``
        the generalised mass (orthogonality makes ``K`` diagonal).
        """
        g = np.diag(self.generalized_mass)
        return np.diag(self.frequencies**2 * g)

    def stiffness_by_quadrature(self) -> NDArray[np.float64]:
        """``int EI phi_j'' phi_k'' dx`` by quadrature of the curvatures (a check on
        :attr:`modal_stiffness`). Shape ``(n_modes, n_modes)``."""
        x, w = self._quadrature()
        c = self._derivative_unchecked(x, 2)
        k = self.flexural_rigidity * (c * w) @ c.T
        return 0.5 * (k + k.T)

    # --------------------------------------------------------------- internals
    def _normalization_scale(self, coef: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.n_modes == 0:
            return np.ones(0)
        if self.normalization == "amplitude":
            c1 = -coef[2]
            return self.amplitude / c1  # type: ignore[no-any-return]
        if self.normalization == "tip":
            return 1.0 / self.tip_deflection
        # "mass": unit generalised modal mass; built from the unit-norm coefficients.
        self._cache.pop("M", None)
        gm = np.diag(self.generalized_mass)
        self._cache.pop("M", None)
        return 1.0 / np.sqrt(gm)


def _legendre_nodes(n_nodes: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gauss–Legendre nodes and weights on ``[-1, 1]`` (SciPy's, O(n) for any number of
    modes)."""
    from scipy.special import roots_legendre

    t, w = roots_legendre(n_nodes)
    return np.asarray(t, dtype=np.float64), np.asarray(w, dtype=np.float64)


@functools.lru_cache(maxsize=16)
def _legendre_rule(n_nodes: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`_legendre_nodes`, once per process for each ``n_nodes`` (read-only)."""
    t, w = _legendre_nodes(n_nodes)
    return frozen(t), frozen(w)
