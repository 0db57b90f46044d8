r"""Transport delays: Padé approximants, their realisation and discretisation, wave speeds.

A torque applied at a joint reaches a distant sensor through a bending wave; the
paper (its Sec. V) models the travel time as a transport delay ``e^{-sT}`` realised by
a second-order Padé approximant,

.. math:: e^{-sT} \approx \frac{1 - sT/2 + s^2T^2/12}{1 + sT/2 + s^2T^2/12},

whose right-half-plane zeros make the loop non-minimum phase.

Padé approximants
-----------------
The ``[n/n]`` approximant is ``P(-sT) / P(sT)`` with

.. math:: P(x) = \sum_{k=0}^{n} \frac{(2n-k)!\, n!}{(2n)!\, k!\, (n-k)!} x^k .

It is all-pass (``|P(-iwT) / P(iwT)| = 1``), its poles lie in the left half-plane
and its zeros are their mirror images; its Taylor series matches that of
``e^{-sT}`` through ``s**(2n)``; its phase error grows as
``(n!)**2 / ((2n)! (2n+1)!) (wT)**(2n+1)`` at small ``wT`` and stays below 1e-3 rad
up to ``wT`` = 0.229, 0.946, 1.97, 3.19, 4.53, 5.95 for ``n = 1..6`` (about ``n``
from order 6 on). :func:`pade` returns the
coefficients, :func:`pade_state_space` a realisation.

Realisation
-----------
:func:`pade_state_space` returns a *balanced* realisation, built in closed form
rather than by balancing a companion matrix (whose entries span ``T**-n``
and whose conditioning degrades quickly with ``n``). An all-pass system is
lossless: it has a realisation with controllability and observability Gramians
both equal to the identity (all Hankel singular values are 1), namely

.. math:: A = \frac{1}{T}\left(S - \tfrac{b^2}{2} e_1 e_1^T\right), \quad
          B = \frac{b}{\sqrt T} e_1, \quad C = -\frac{(-1)^n b}{\sqrt T} e_1^T, \quad
          D = (-1)^n,

with ``S`` skew-symmetric and tridiagonal (superdiagonal ``alpha_k``). Writing
``P = E + O`` (even and odd parts), the ratio ``F`` of the lower-degree part to the
higher-degree one is a lossless reactance, ``P(-x)/P(x) = (-1)^n (1 - F)/(1 + F)``,
and its Cauer continued fraction ``F = 1/(d_1 x + 1/(d_2 x + ... + 1/(d_n x)))``
(computed exactly in rational arithmetic) gives ``b**2 = 2 / d_1`` and
``alpha_k**2 = 1 / (d_k d_{k+1})``; ``b**2 / 2 = n (n + 1)`` is the largest entry of
``A T``, so the realisation stays well scaled for any order.

Discretisation
--------------
:func:`discretize` holds the input constant over a step (zero-order hold) and is
exact: ``[[Ad, Bd], [0, I]] = expm([[A, B], [0, 0]] dt)``. Its poles are
``exp(p dt)`` for the continuous poles ``p``, inside the unit circle for any
``dt``, so a delay much shorter than the step never makes the simulation stiff
or unstable.

Wave speeds
-----------
The paper's number, ``c = sqrt(1 745 833 288.33) = 41 783 m/s``
(:data:`SEED_WAVE_SPEED`, apparently ``sqrt(EI / I)`` without the density), gives
delays of about 0.1 ms over a 4.5 m link. Bending waves of an Euler–Bernoulli
beam are dispersive: at angular frequency ``w`` the phase speed is
``c_p = sqrt(w) (EI / rho)**(1/4)`` and the group speed, at which energy and
hence a disturbance travels, ``c_g = 2 c_p``; for the paper's link at its first
mode (``w = 12.281 rad/s``) they are 29.5 and 59 m/s, i.e. 0.08–0.3 s over the
arm. :func:`travel_delay` supports both models.

Which distance: the path length *along the links* from the joint whose torque
excites the wave to the sensed point, e.g. for the paper's two 4.5 m links,
shoulder to end effector 9 m, elbow to end effector 4.5 m, shoulder to the
sensor 0.5 m beyond the elbow 5 m, elbow to that sensor 0.5 m. A simulator with
one delay per sensor uses the path from the shoulder (the longest, the worst
case) unless configured otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_int, check_option, check_real, validate_real_fields
from ..errors import InvalidTypeError, InvalidValueError

__all__ = [
    "DELAY_METHODS",
    "SEED_WAVE_SPEED",
    "TRAVEL_MODELS",
    "DelayModel",
    "bending_group_speed",
    "bending_phase_speed",
    "discretize",
    "pade",
    "pade_state_space",
    "state_space_matrices",
    "travel_delay",
    "wave_delay",
]

SEED_WAVE_SPEED: float = math.sqrt(1745833288.33)
"""The paper's bending-wave speed, m/s (about 41 783; module docstring)."""

DELAY_METHODS = ("exact", "pade")
TRAVEL_MODELS = ("seed", "dispersive")

_F = NDArray[np.float64]


# ---------------------------------------------------------------------- Padé
def _pade_coefficients(order: int) -> list[Fraction]:
    """``c_k = (2n-k)! n! / ((2n)! k! (n-k)!)``, ``k = 0..n``, exact."""
    n = order
    f = math.factorial
    return [Fraction(f(2 * n - k) * f(n), f(2 * n) * f(k) * f(n - k)) for k in range(n + 1)]


def pade(delay: float, order: int) -> tuple[_F, _F]:
    """The ``[n/n]`` Padé approximant of ``e^{-s T}``.

    Parameters
    ----------
    delay : float
        ``T`` in s (> 0).
    order : int
        ``n`` (>= 1); the paper uses 2.

    Returns
    -------
    num, den : ndarray, shape (n + 1,)
        Coefficients of the numerator and denominator in powers of ``s`` (s in
        1/s), highest power first (:func:`numpy.polyval`), constant terms 1:
        ``den_k = c_k T**k``, ``num_k = (-1)**k c_k T**k`` (module docstring).

    Examples
    --------
    >>> num, den = pade(1.0, 2)
    >>> num * 12, den * 12
    (array([  1.,  -6.,  12.]), array([ 1.,  6., 12.]))
    """
    t = check_real(delay, "delay", "pade", positive=True)
    n = check_int(order, "order", "pade", minimum=1)
    c = _pade_coefficients(n)
    den = np.array([float(ck) * t**k for k, ck in enumerate(c)])
    num = den * (-1.0) ** np.arange(n + 1)
    return num[::-1].copy(), den[::-1].copy()


def _cauer(order: int) -> list[Fraction]:
    """``d_1..d_n`` of ``F = 1/(d_1 x + 1/(d_2 x + ...))`` for the Padé polynomial ``P``."""
    c = _pade_coefficients(order)
    even = [ck if k % 2 == 0 else Fraction(0) for k, ck in enumerate(c)]
    odd = [ck if k % 2 == 1 else Fraction(0) for k, ck in enumerate(c)]
    hi, lo = (even, odd) if order % 2 == 0 else (odd, even)
    hi, lo = hi[: order + 1], lo[:order]  # degrees n and n - 1 (ascending coefficients)
    d: list[Fraction] = []
    for m in range(order, 0, -1):
        dk = hi[m] / lo[m - 1]
        d.append(dk)
        # remainder hi - dk x lo, of degree m - 2
        rem = [hi[j] - (dk * lo[j - 1] if j >= 1 else 0) for j in range(m - 1)]
        hi, lo = lo, rem
    return d


def pade_state_space(delay: float, order: int) -> tuple[_F, _F, _F, _F]:
    """A balanced (lossless) state-space realisation of the Padé approximant.

    Parameters
    ----------
    delay : float
        ``T`` in s (> 0).
    order : int
        ``n`` (>= 1).

    Returns
    -------
    A : ndarray, shape (n, n)
        In 1/s; tridiagonal, ``A + A.T = -B B.T``.
    B : ndarray, shape (n, 1)
        In s**-1/2 per unit input.
    C : ndarray, shape (1, n)
        In s**-1/2; ``C = -D B.T``.
    D : ndarray, shape (1, 1)
        ``(-1)**n``.

    ``C (sI - A)^-1 B + D`` equals ``polyval(num, s) / polyval(den, s)`` of
    :func:`pade`; both Gramians are the identity (module docstring).

    Examples
    --------
    >>> A, B, C, D = pade_state_space(1.0, 1)
    >>> A, B.ravel(), C.ravel(), D
    (array([[-2.]]), array([2.]), array([2.]), array([[-1.]]))
    """
    t = check_real(delay, "delay", "pade_state_space", positive=True)
    n = check_int(order, "order", "pade_state_space", minimum=1)
    d = _cauer(n)
    b = math.sqrt(float(2 / d[0]))
    a = np.zeros((n, n))
    a[0, 0] = -0.5 * b * b
    for k in range(n - 1):
        alpha = math.sqrt(float(1 / (d[k] * d[k + 1])))
        a[k, k + 1], a[k + 1, k] = alpha, -alpha
    sign = float((-1) ** n)
    bb = np.zeros((n, 1))
    bb[0, 0] = b
    cc = np.zeros((1, n))
    cc[0, 0] = -sign * b
    root_t = math.sqrt(t)
    return a / t, bb / root_t, cc / root_t, np.array([[sign]])


def state_space_matrices(
    A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike | None, owner: str
) -> tuple[_F, _F, _F, _F]:
    """``A`` (n, n), ``B`` (n, m), ``C`` (p, n) and ``D`` (p, m; zeros if None) of a
    state-space system, checked for ``owner``: real, and of shapes that fit together."""
    a = check_array(A, "A", owner, shape=(-1, -1))
    n = a.shape[0]
    if a.shape != (n, n):
        raise InvalidValueError(
            f"The 'A' parameter of {owner} must be square. Got shape {a.shape} instead."
        )
    b = check_array(B, "B", owner, shape=(n, -1))
    c = check_array(C, "C", owner, shape=(-1, n))
    m, p = b.shape[1], c.shape[0]
    d = np.zeros((p, m)) if D is None else check_array(D, "D", owner, shape=(p, m))
    for name, arr in (("A", a), ("B", b), ("C", c), ("D", d)):
        if arr.dtype.kind == "c":
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must be real. Got complex instead."
            )
    return a, b, c, d


def discretize(
    A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, dt: float
) -> tuple[_F, _F, _F, _F]:
    """Exact zero-order-hold discretisation of ``x' = A x + B u, y = C x + D u``.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix, 1/s.
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (p, m)
        Feedthrough.
    dt : float
        Sample period, s (> 0).

    Returns
    -------
    Ad : ndarray, shape (n, n)
        ``expm(A dt)``.
    Bd : ndarray, shape (n, m)
        ``int_0^dt expm(A s) ds B``.
    Cd : ndarray, shape (p, n)
        ``C`` (copied).
    Dd : ndarray, shape (p, m)
        ``D`` (copied).

    ``x[k+1] = Ad x[k] + Bd u[k]`` then matches the continuous system at the
    sample instants for inputs held constant between them.

    Examples
    --------
    >>> Ad, Bd, Cd, Dd = discretize([[-1.0]], [[1.0]], [[1.0]], [[0.0]], 1.0)
    >>> round(float(Ad[0, 0]), 6), round(float(Bd[0, 0]), 6)
    (0.367879, 0.632121)
    """
    owner = "discretize"
    a, b, c, dd = state_space_matrices(A, B, C, D, owner)
    n, m = b.shape
    h = check_real(dt, "dt", owner, positive=True)
    big = np.zeros((n + m, n + m))
    big[:n, :n] = a
    big[:n, n:] = b
    from scipy.linalg import expm  # loaded on first use

    e = expm(big * h)
    return e[:n, :n].copy(), e[:n, n:].copy(), c.copy(), dd.copy()


# --------------------------------------------------------------- DelayModel
@dataclass(frozen=True)
class DelayModel:
    """How the simulator realises a transport delay.

    Parameters
    ----------
    delay : float
        ``T`` in s (>= 0; 0 means no delay).
    method : {"exact", "pade"}
        ``"exact"``: a sample buffer (the signal ``T`` s ago); ``"pade"``: the
        Padé approximant of ``order``, realised by :func:`pade_state_space` and
        discretised by :func:`discretize` (the paper's choice with order 2).
    order : int
        Padé order ``n`` (>= 1, default 2); unused by ``"exact"``.

    Examples
    --------
    >>> num, den = DelayModel(0.05, "pade").transfer_function()
    >>> (den * 12 / 0.05**2).round(6).tolist()
    [1.0, 120.0, 4800.0]
    >>> DelayModel.none().delay
    0.0
    """

    delay: float = 0.0
    method: str = "pade"
    order: int = 2

    def __post_init__(self) -> None:
        owner = "DelayModel"
        validate_real_fields(self, owner, nonnegative=("delay",))
        check_option(self.method, "method", owner, DELAY_METHODS)
        object.__setattr__(self, "order", check_int(self.order, "order", owner, minimum=1))

    @classmethod
    def none(cls) -> DelayModel:
        """No delay."""
        return cls(0.0)

    def transfer_function(self) -> tuple[_F, _F]:
        """``(num, den)`` of the Padé approximant (:func:`pade`); ``([1], [1])`` for no delay."""
        if self.delay == 0.0:
            return np.array([1.0]), np.array([1.0])
        return pade(self.delay, self.order)

    def state_space(self) -> tuple[_F, _F, _F, _F]:
        """``(A, B, C, D)`` of :func:`pade_state_space`; zero states for no delay.

        Raises ``ValueError`` for ``method="exact"`` with a nonzero delay (a pure
        delay has no finite-dimensional realisation).
        """
        if self.delay == 0.0:
            return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.ones((1, 1))
        if self.method != "pade":
            raise InvalidValueError(
                "The 'method' parameter of DelayModel must be 'pade' for a state-space "
                f"realisation of a nonzero delay. Got {self.method!r} instead."
            )
        return pade_state_space(self.delay, self.order)

    def samples(self, dt: float) -> float:
        """The delay in sample periods of ``dt`` s (may be fractional)."""
        return self.delay / check_real(dt, "dt", "DelayModel.samples", positive=True)


# ----------------------------------------------------------------- wave speeds
def _beam(omega: Any, flexural_rigidity: Any, linear_density: Any, owner: str) -> float:
    w = check_real(omega, "omega", owner, positive=True)
    ei = check_real(flexural_rigidity, "flexural_rigidity", owner, positive=True)
    rho = check_real(linear_density, "linear_density", owner, positive=True)
    return math.sqrt(w) * math.sqrt(math.sqrt(ei / rho))


def bending_phase_speed(omega: float, flexural_rigidity: float, linear_density: float) -> float:
    """Phase speed of Euler–Bernoulli bending waves, ``sqrt(w) (EI / rho)**(1/4)``, m/s.

    Parameters
    ----------
    omega : float
        Angular frequency ``w``, rad/s (> 0).
    flexural_rigidity : float
        ``EI``, N m**2 (> 0).
    linear_density : float
        ``rho``, kg/m (> 0).

    Examples
    --------
    >>> round(bending_phase_speed(12.281, 1676.0, 0.335), 2)
    29.47
    """
    return _beam(omega, flexural_rigidity, linear_density, "bending_phase_speed")


def bending_group_speed(omega: float, flexural_rigidity: float, linear_density: float) -> float:
    """Group speed of Euler–Bernoulli bending waves, twice the phase speed, m/s.

    Parameters as :func:`bending_phase_speed`.
    """
    return 2.0 * _beam(omega, flexural_rigidity, linear_density, "bending_group_speed")


def wave_delay(distance: float, speed: float) -> float:
    """Travel time ``distance / speed`` in s (distance in m, >= 0; speed in m/s, > 0)."""
    x = check_real(distance, "distance", "wave_delay", nonnegative=True)
    c = check_real(speed, "speed", "wave_delay", positive=True)
    return x / c


def travel_delay(
    distance: float,
    model: str,
    *,
    omega: float | None = None,
    flexural_rigidity: float | None = None,
    linear_density: float | None = None,
    speed: str = "group",
) -> float:
    """The time a bending wave takes to travel ``distance`` along the links, s.

    Parameters
    ----------
    distance : float
        Path length along the links from the actuating joint to the sensed
        point, m (>= 0; module docstring).
    model : {"seed", "dispersive"}
        ``"seed"``: the paper's :data:`SEED_WAVE_SPEED`. ``"dispersive"``: the
        Euler–Bernoulli speed at ``omega``, which needs the three beam
        parameters.
    omega : float, optional
        Angular frequency of the wave, rad/s (> 0), e.g. the first modal
        frequency. Only for ``"dispersive"``.
    flexural_rigidity : float, optional
        ``EI``, N m**2 (> 0). Only for ``"dispersive"``.
    linear_density : float, optional
        ``rho``, kg/m (> 0). Only for ``"dispersive"``.
    speed : {"group", "phase"}
        Which speed the dispersive model uses (default ``"group"``, the speed of
        energy).

    Examples
    --------
    >>> round(travel_delay(4.5, "seed") * 1e3, 3)  # ms
    0.108
    >>> round(travel_delay(9.0, "dispersive", omega=12.281, flexural_rigidity=1676.0,
    ...                    linear_density=0.335), 3)
    0.153
    """
    owner = "travel_delay"
    check_option(model, "model", owner, TRAVEL_MODELS)
    check_option(speed, "speed", owner, ("group", "phase"))
    beam = {
        "omega": omega,
        "flexural_rigidity": flexural_rigidity,
        "linear_density": linear_density,
    }
    if model == "seed":
        for name, value in beam.items():
            if value is not None:
                raise InvalidValueError(
                    f"The '{name}' parameter of {owner} must be None when model='seed' "
                    f"(the seed speed is fixed). Got {value!r} instead."
                )
        return wave_delay(distance, SEED_WAVE_SPEED)
    for name, value in beam.items():
        if value is None:
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must be a real number > 0 when "
                f"model='dispersive'. Got None instead."
            )
    c = _beam(omega, flexural_rigidity, linear_density, owner)
    c_used = 2.0 * c if speed == "group" else c
    return wave_delay(distance, c_used)
