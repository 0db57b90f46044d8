r"""Input shapers: impulse sequences convolved with a reference to cancel vibration.

A shaper is a sequence of impulses of amplitudes ``A_i`` (summing to one, so a
shaped step still reaches the set point) at times ``t_i`` (``t_0 = 0``). The
shaped reference is ``sum_i A_i r(t - t_i)``; it reaches the set point
``t_{k-1}`` (the shaper's :attr:`~Shaper.duration`) later than ``r``. The paper
(its Sec. V) names ZV/ZVD-type shapers on the reference as a residual-vibration
remedy.

Residual vibration
------------------
A unit impulse sequence applied to a mode ``x'' + 2 zeta w x' + w**2 x = ...``
leaves, after the last impulse, an oscillation whose amplitude relative to that
left by a single unit impulse applied at the last impulse time ``t_{k-1}`` is
(Singer & Seering 1990)

.. math:: V(\omega, \zeta) = e^{-\zeta\omega t_{k-1}} \sqrt{C^2 + S^2}, \quad
          C = \sum_i A_i e^{\zeta\omega t_i}\cos\omega_d t_i, \quad
          S = \sum_i A_i e^{\zeta\omega t_i}\sin\omega_d t_i,

with ``w_d = w sqrt(1 - zeta**2)``. The same ratio holds for a shaped step and
for any shaped reference that has come to rest. Against the *unshaped* reference
observed at the same time the ratio is ``V exp(zeta w t_{k-1})`` (the unshaped
transient started ``t_{k-1}`` earlier and has decayed more); undamped, both are
``V``. :func:`residual_vibration` evaluates ``V`` for arrays of frequencies
(sensitivity curves) as ``|sum_i A_i exp(w c (t_i - t_{k-1}))|`` with
``c = zeta + 1j sqrt(1 - zeta**2)``, which never overflows.

Designers
---------
With ``K = exp(-zeta pi / sqrt(1 - zeta**2))`` and the damped period
``T_d = 2 pi / (w sqrt(1 - zeta**2))``:

* :func:`zv` (zero vibration): ``A = [1, K] / (1 + K)``, ``t = [0, T_d/2]``.
  Undamped, ``V(w) = |cos(pi w / (2 w0))|``.
* :func:`zvd` (zero vibration and derivative): ``A = [1, 2K, K**2] / (1 + K)**2``,
  ``t = [0, T_d/2, T_d]``; ``V`` and ``dV/dw`` vanish at the design point.
* :func:`ei` (extra insensitive, Singhose, Seering & Singer): ``V = V_tol`` at
  the design frequency, where ``V`` has a hump (``dV/dw = 0``), and ``V = 0`` at
  one frequency below and one above it, which widens the band where
  ``V <= V_tol`` (about +-20 % of ``w0`` at ``V_tol = 5 %``, against +-14 % for
  ZVD). Undamped, the closed form ``A = [(1+V)/4, (1-V)/2, (1+V)/4]``,
  ``t = [0, T_d/2, T_d]`` is used. **Damped, these five constraints are solved
  numerically** (unknowns ``A_0..A_2``, ``t_1``, ``t_2`` and the two
  zero-vibration frequencies; Powell's hybrid method, continued in damping
  from the undamped closed form in steps of 0.02), so ``V(w0) = V_tol`` holds
  to rounding. The solution agrees with the published polynomial fit of
  damped EI shapers (amplitudes to about 1e-3, times to about 1 % for
  ``zeta <= 0.2``, ``V_tol = 5 %``), which is approximate by construction.
  As damping grows, the upper zero-vibration frequency runs off to infinity and
  the constraints lose their solution (near ``zeta = 0.7`` for ``V_tol = 5 %``,
  earlier for larger tolerances); :func:`ei` then raises ``ValueError``.

:func:`for_modes` convolves one shaper per mode (times add, amplitudes
multiply), which cancels every mode at once: the residual vibration of a
convolution is the product of the factors' residual vibrations.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ._ei import ei_unit

__all__ = [
    "KINDS",
    "Shaper",
    "design",
    "ei",
    "for_modes",
    "residual_vibration",
    "zv",
    "zvd",
]

KINDS = ("zv", "zvd", "ei")

_SUM_TOL = 1e-9  # allowed |sum(A) - 1|
_MERGE_RTOL = 1e-12  # impulse times closer than this fraction of the duration are merged


def _frozen(a: NDArray[np.float64]) -> NDArray[np.float64]:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Shaper:
    """An impulse sequence: amplitudes summing to one at increasing times from 0.

    Parameters
    ----------
    amplitudes : array_like, shape (k,)
        Impulse amplitudes ``A_i``, dimensionless, summing to 1 (within 1e-9).
        Negative amplitudes are allowed (negative shapers); the designers of this
        module return positive ones.
    times : array_like, shape (k,)
        Impulse times ``t_i`` in s, strictly increasing, ``times[0] == 0``.

    Both are stored as read-only float arrays. Two shapers compare equal when
    their arrays are equal element by element.

    Examples
    --------
    >>> s = zv(2 * np.pi)  # 1 Hz mode, undamped
    >>> s.amplitudes, s.times
    (array([0.5, 0.5]), array([0. , 0.5]))
    >>> s.apply([0.0, 0.25, 0.5, 0.75], [0.0, 1.0, 1.0, 1.0])
    array([0. , 0.5, 0.5, 1. ])
    """

    amplitudes: NDArray[np.float64]
    times: NDArray[np.float64]

    def __post_init__(self) -> None:
        owner = "Shaper"
        a = check_array(self.amplitudes, "amplitudes", owner, shape=(-1,))
        t = check_array(self.times, "times", owner, shape=(-1,))
        if a.dtype.kind == "c" or t.dtype.kind == "c":
            name = "amplitudes" if a.dtype.kind == "c" else "times"
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must be real. Got complex instead."
            )
        if a.size == 0:
            raise InvalidValueError(
                f"The 'amplitudes' parameter of {owner} must be non-empty. Got []."
            )
        if t.shape != a.shape:
            raise InvalidValueError(
                f"The 'times' parameter of {owner} must be of shape {a.shape} (one time per "
                f"amplitude). Got shape {t.shape} instead."
            )
        total = float(np.sum(a))
        if abs(total - 1.0) > _SUM_TOL:
            raise InvalidValueError(
                f"The 'amplitudes' parameter of {owner} must sum to 1. Got sum {total!r} instead."
            )
        if t[0] != 0.0:
            raise InvalidValueError(
                f"The 'times' parameter of {owner} must start at 0. Got {float(t[0])!r} instead."
            )
        if np.any(np.diff(t) <= 0.0):
            raise InvalidValueError(
                f"The 'times' parameter of {owner} must be strictly increasing. Got {t!r} instead."
            )
        object.__setattr__(self, "amplitudes", _frozen(a))
        object.__setattr__(self, "times", _frozen(t))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Shaper):
            return NotImplemented
        return bool(
            np.array_equal(self.amplitudes, other.amplitudes)
            and np.array_equal(self.times, other.times)
        )

    def __hash__(self) -> int:
        return hash((self.amplitudes.tobytes(), self.times.tobytes()))

    @classmethod
    def none(cls) -> Shaper:
        """The identity shaper: one unit impulse at ``t = 0`` (no shaping, no delay)."""
        return cls(np.array([1.0]), np.array([0.0]))

    @property
    def n_impulses(self) -> int:
        """Number of impulses ``k``."""
        return int(self.amplitudes.size)

    @property
    def duration(self) -> float:
        """``times[-1]``: the delay the shaper adds to a move, s."""
        return float(self.times[-1])

    # ------------------------------------------------------------ application
    def apply(self, t: ArrayLike, values: ArrayLike) -> NDArray[np.float64]:
        """Shape a sampled signal: ``sum_i A_i values(t - t_i)`` on the same grid.

        Parameters
        ----------
        t : array_like, shape (m,)
            Sample times in s, strictly increasing (normally a uniform grid).
        values : array_like, shape (m, ...)
            The signal at ``t``, any unit, any trailing shape.

        Returns
        -------
        ndarray, shape (m, ...)
            The shaped signal at ``t``, in the unit of ``values``. Between samples
            the signal is interpolated linearly (exact when every ``t_i`` is a
            multiple of a uniform step); before ``t[0]`` it is held at
            ``values[0]``, so a signal at rest when sampling starts stays at rest.
        """
        owner = "Shaper.apply"
        tt = check_array(t, "t", owner, shape=(-1,))
        v = check_array(values, "values", owner)
        if tt.size == 0:
            raise InvalidValueError(f"The 't' parameter of {owner} must be non-empty. Got [].")
        if np.any(np.diff(tt) <= 0.0):
            raise InvalidValueError(
                f"The 't' parameter of {owner} must be strictly increasing. Got {tt!r} instead."
            )
        if v.ndim == 0 or v.shape[0] != tt.size:
            raise InvalidValueError(
                f"The 'values' parameter of {owner} must be of shape ({tt.size}, ...) "
                f"(one row per sample time). Got shape {v.shape} instead."
            )
        out = np.zeros(v.shape, dtype=np.result_type(v.dtype, float))
        for a, ti in zip(self.amplitudes, self.times, strict=True):
            out += a * _shifted(tt, v, float(ti))
        return out

    def apply_function(self, fn: Callable[[Any], Any]) -> Callable[[ArrayLike], Any]:
        """Shape a function of time exactly: ``g(t) = sum_i A_i fn(t - t_i)``.

        Parameters
        ----------
        fn : callable
            ``fn(t)`` with ``t`` in s (a float or an array); it returns an array
            (any shape) or a tuple of arrays, e.g. a trajectory's
            ``evaluate(t) -> (position, velocity, acceleration)``. ``fn`` is
            called at times before its first sample too (``t - t_i`` may be
            negative); it must define the signal there.

        Returns
        -------
        callable
            ``g(t)``: an array, or a tuple (of the same type as ``fn``'s, for
            named tuples) whose members are summed separately. A float ``t`` is
            passed to ``fn`` as a float.

        Examples
        --------
        >>> g = zv(np.pi).apply_function(lambda t: (np.asarray(t), np.ones_like(t)))
        >>> g(np.array([2.0, 3.0]))
        (array([1.5, 2.5]), array([1., 1.]))
        """
        if not callable(fn):
            raise InvalidTypeError(
                f"The 'fn' parameter of Shaper.apply_function must be callable. "
                f"Got {type(fn).__name__} instead."
            )
        pairs = tuple(
            (float(a), float(ti)) for a, ti in zip(self.amplitudes, self.times, strict=True)
        )

        def shaped(t: ArrayLike) -> Any:
            ta = np.asarray(t, dtype=float)
            arg: Any = float(ta) if ta.ndim == 0 else ta
            parts = [(a, fn(arg - ti)) for a, ti in pairs]
            first = parts[0][1]
            if isinstance(first, tuple):
                members = [_weighted_sum([(a, p[k]) for a, p in parts]) for k in range(len(first))]
                make = getattr(type(first), "_make", None)
                return make(members) if make is not None else tuple(members)
            return _weighted_sum(parts)

        return shaped

    def convolve(self, other: Shaper) -> Shaper:
        """The shaper of the two in series: times add, amplitudes multiply.

        Impulses that land at the same time (within 1e-12 of the duration) are merged.
        """
        if not isinstance(other, Shaper):
            raise InvalidTypeError(
                f"The 'other' parameter of Shaper.convolve must be a Shaper. "
                f"Got {type(other).__name__} instead."
            )
        a = np.multiply.outer(self.amplitudes, other.amplitudes).ravel()
        t = np.add.outer(self.times, other.times).ravel()
        order = np.argsort(t, kind="stable")
        a, t = a[order], t[order]
        tol = _MERGE_RTOL * float(t[-1])
        times: list[float] = [0.0]
        amps: list[float] = [float(a[0])]
        for ai, ti in zip(a[1:], t[1:], strict=True):
            if ti - times[-1] <= tol:
                amps[-1] += float(ai)
            else:
                times.append(float(ti))
                amps.append(float(ai))
        return Shaper(np.array(amps), np.array(times))


def _weighted_sum(parts: list[tuple[float, Any]]) -> Any:
    total: Any = parts[0][0] * np.asarray(parts[0][1])
    for a, p in parts[1:]:
        total = total + a * np.asarray(p)
    return total


def _shifted(t: NDArray[np.float64], v: NDArray[Any], delay: float) -> NDArray[Any]:
    """``v`` delayed by ``delay`` s on the grid ``t``: linear, held before ``t[0]``."""
    if delay == 0.0 or t.size == 1:
        return v
    q = t - delay
    lo = np.clip(np.searchsorted(t, q, side="right") - 1, 0, t.size - 2)
    w = np.clip((q - t[lo]) / (t[lo + 1] - t[lo]), 0.0, 1.0)
    w = w.reshape((-1,) + (1,) * (v.ndim - 1))
    out: NDArray[Any] = (1.0 - w) * v[lo] + w * v[lo + 1]
    return out


# ---------------------------------------------------------------- sensitivity
def residual_vibration(
    shaper: Shaper, frequency: ArrayLike, damping: float = 0.0
) -> NDArray[np.float64]:
    """Residual vibration ``V(w, zeta)`` of a shaper on a second-order mode.

    Parameters
    ----------
    shaper : Shaper
        The impulse sequence.
    frequency : array_like, any shape
        Undamped natural frequencies ``w`` of the mode, rad/s (>= 0).
    damping : float
        Damping ratio ``zeta`` of the mode, in [0, 1).

    Returns
    -------
    ndarray, shape of ``frequency``
        The residual amplitude relative to that of a unit impulse at the last
        impulse time (1 = no reduction; multiply by 100 for percent). Module
        docstring.

    Examples
    --------
    >>> s = zv(10.0)
    >>> residual_vibration(s, [10.0, 5.0]).round(6)
    array([0.      , 0.707107])
    """
    owner = "residual_vibration"
    if not isinstance(shaper, Shaper):
        raise InvalidTypeError(
            f"The 'shaper' parameter of {owner} must be a Shaper. "
            f"Got {type(shaper).__name__} instead."
        )
    w = check_array(frequency, "frequency", owner)
    if w.dtype.kind == "c":
        raise InvalidTypeError(
            f"The 'frequency' parameter of {owner} must be real. Got complex instead."
        )
    if np.any(w < 0.0):
        raise InvalidValueError(
            f"The 'frequency' parameter of {owner} must be >= 0. Got {float(w.min())!r} instead."
        )
    z = _check_damping(damping, owner)
    c = complex(z, math.sqrt(1.0 - z * z))
    tau = shaper.times - shaper.times[-1]  # <= 0: the exponentials stay bounded
    terms = np.exp(np.multiply.outer(w, c * tau))
    v: NDArray[np.float64] = np.abs(terms @ shaper.amplitudes)
    return v


# ------------------------------------------------------------------ designers
def _check_damping(value: Any, owner: str) -> float:
    z = check_real(value, "damping", owner, nonnegative=True)
    if not z < 1.0:
        raise InvalidValueError(
            f"The 'damping' parameter of {owner} must be < 1. Got {z!r} instead."
        )
    return z


def _design_point(frequency: Any, damping: Any, owner: str) -> tuple[float, float, float, float]:
    """Validated ``(w, zeta, K, T_d)``."""
    w = check_real(frequency, "frequency", owner, positive=True)
    z = _check_damping(damping, owner)
    root_1mz2 = math.sqrt(1.0 - z * z)
    k = math.exp(-z * math.pi / root_1mz2)
    period = 2.0 * math.pi / (w * root_1mz2)
    return w, z, k, period


def zv(frequency: float, damping: float = 0.0) -> Shaper:
    """Zero-vibration shaper (two impulses) for one mode.

    Parameters
    ----------
    frequency : float
        Undamped natural frequency ``w`` of the mode, rad/s (> 0).
    damping : float
        Damping ratio ``zeta``, in [0, 1).

    Returns
    -------
    Shaper
        ``A = [1, K] / (1 + K)``, ``t = [0, T_d / 2]`` (module docstring).
    """
    _, _, k, period = _design_point(frequency, damping, "zv")
    return Shaper(np.array([1.0, k]) / (1.0 + k), np.array([0.0, 0.5 * period]))


def zvd(frequency: float, damping: float = 0.0) -> Shaper:
    """Zero-vibration-and-derivative shaper (three impulses) for one mode.

    Parameters
    ----------
    frequency, damping : float
        The mode, as for :func:`zv`: its undamped natural frequency ``w`` in rad/s
        (> 0) and its damping ratio ``zeta`` in [0, 1).

    Returns
    -------
    Shaper
        ``A = [1, 2K, K**2] / (1 + K)**2``, ``t = [0, T_d / 2, T_d]``.
    """
    _, _, k, period = _design_point(frequency, damping, "zvd")
    amps = np.array([1.0, 2.0 * k, k * k]) / (1.0 + k) ** 2
    return Shaper(amps, np.array([0.0, 0.5 * period, period]))


def ei(frequency: float, damping: float = 0.0, tolerance: float = 0.05) -> Shaper:
    """Extra-insensitive shaper (three impulses) for one mode.

    Parameters
    ----------
    frequency : float
        Undamped natural frequency ``w`` of the mode, rad/s (> 0).
    damping : float
        Damping ratio ``zeta``, in [0, 1). Undamped: closed form; damped: the EI
        constraints solved numerically (module docstring).
    tolerance : float
        ``V_tol``, the residual vibration accepted at the design frequency, in
        (0, 1) (0.05 = 5 %).

    Returns
    -------
    Shaper
        ``V(w) = V_tol`` with ``dV/dw = 0`` at the design point.

    Raises
    ------
    ValueError
        If the damped EI constraints have no solution (heavy damping with a
        large tolerance).
    """
    owner = "ei"
    w, z, _, period = _design_point(frequency, damping, owner)
    v = check_real(tolerance, "tolerance", owner, positive=True)
    if not v < 1.0:
        raise InvalidValueError(
            f"The 'tolerance' parameter of {owner} must be < 1. Got {v!r} instead."
        )
    if z == 0.0:
        amps = np.array([(1.0 + v) / 4.0, (1.0 - v) / 2.0, (1.0 + v) / 4.0])
        return Shaper(amps, np.array([0.0, 0.5 * period, period]))
    amps, unit_times = ei_unit(z, v)
    return Shaper(amps / amps.sum(), unit_times / w)


_DESIGNERS: dict[str, Callable[..., Shaper]] = {"zv": zv, "zvd": zvd, "ei": ei}
_EXTRA_KEYWORDS: dict[str, tuple[str, ...]] = {"zv": (), "zvd": (), "ei": ("tolerance",)}


def design(kind: str, frequency: float, damping: float = 0.0, **kw: Any) -> Shaper:
    """Design a shaper of the given kind for one mode.

    Parameters
    ----------
    kind : {"zv", "zvd", "ei"}
        The designer (:func:`zv`, :func:`zvd`, :func:`ei`).
    frequency : float
        Undamped natural frequency, rad/s (> 0).
    damping : float
        Damping ratio, in [0, 1).
    **kw
        Extra parameters of the designer (``tolerance`` for ``"ei"``); any
        other keyword raises ``TypeError``.

    Examples
    --------
    >>> design("zvd", 2 * np.pi).times
    array([0. , 0.5, 1. ])
    """
    check_option(kind, "kind", "design", KINDS)
    allowed = _EXTRA_KEYWORDS[kind]
    for name in kw:
        if name not in allowed:
            raise InvalidTypeError(
                f"design got an unexpected keyword argument {name!r} for kind={kind!r} "
                f"(allowed: {allowed})."
            )
    return _DESIGNERS[kind](frequency, damping, **kw)


def for_modes(
    frequencies: ArrayLike, damping: ArrayLike = 0.0, kind: str = "zv", **kw: Any
) -> Shaper:
    """A multi-mode shaper: the convolution of one shaper per mode.

    Parameters
    ----------
    frequencies : array_like, shape (p,)
        Undamped natural frequencies of the modes to cancel, rad/s (> 0).
    damping : float or array_like, shape (p,)
        Damping ratios, in [0, 1), one for all or one per mode.
    kind : {"zv", "zvd", "ei"}
        Designer used for every mode.
    **kw
        Passed to :func:`design` (``tolerance`` for ``"ei"``).

    Returns
    -------
    Shaper
        ``prod(k_j)`` impulses at most (coincident ones merged); its duration is
        the sum of the factors' durations.

    Examples
    --------
    >>> for_modes([np.pi, 2 * np.pi]).times
    array([0. , 0.5, 1. , 1.5])
    """
    owner = "for_modes"
    check_option(kind, "kind", owner, KINDS)
    w = check_array(frequencies, "frequencies", owner, shape=(-1,))
    if w.size == 0:
        raise InvalidValueError(
            f"The 'frequencies' parameter of {owner} must be non-empty. Got []."
        )
    if w.dtype.kind == "c" or np.any(w <= 0.0):
        raise InvalidValueError(
            f"The 'frequencies' parameter of {owner} must be real and > 0. "
            f"Got {frequencies!r} instead."
        )
    z = check_array(damping, "damping", owner)
    if z.dtype.kind == "c" or np.any(z < 0.0) or np.any(z >= 1.0):
        raise InvalidValueError(
            f"The 'damping' parameter of {owner} must be real, in [0, 1). Got {damping!r} instead."
        )
    if z.ndim == 0:
        z = np.full(w.shape, float(z))
    elif z.shape != w.shape:
        raise InvalidValueError(
            f"The 'damping' parameter of {owner} must be a float or of shape {w.shape}. "
            f"Got shape {z.shape} instead."
        )
    shapers = [design(kind, wi, zi, **kw) for wi, zi in zip(w.tolist(), z.tolist(), strict=True)]
    return functools.reduce(Shaper.convolve, shapers)
