"""Feedback laws: joint-space PD, operational-space Jacobian-transpose PD, and yours.

Every controller is the same thing to the simulator: a compiled function

    control(t, y, r, params, state, tau)

of the time (s), the measurement ``y`` and reference ``r`` (layouts in
:mod:`flexarm.control.signals`), a parameter vector, a mutable state vector (for
integrators, filters, adaptation) and the output torques ``tau`` (N m, one per
joint; written in place). The simulator calls it once per control period from
its compiled loop through a C function pointer (``numba.cfunc``), so one cached
loop serves every controller; torque saturation is applied by the simulator.

Built in:

* :class:`JointPD` — ``tau = Kp (theta_r - theta) + Kd (dtheta_r - dtheta)``.
* :class:`JacobianTransposePD` — paper eq. 11,
  ``tau = J(theta)' [Kp (x_r - x) + Kd (v_r - v)]`` with ``J`` the rigid Jacobian of
  the measured (collocated) angles and ``x, v`` from the sensor in use: the end
  effector's for joint encoders and the tip, the sensed point's for a point
  short of the tip (a PD in the operational space of what is measured).
  ``JacobianTransposePD.from_arm(arm, zeta=0.707)`` gives the paper's gains
  ``Kp = omega_1**2 I``, ``Kd = 2 zeta omega_1 I`` from the exact first clamped
  frequency: 150.83 and 17.366 for the paper's arm (the paper prints 150.79 and
  17.364, from omega_1 rounded to 12.28 rad/s; the class defaults are those
  printed numbers).

Your own: write ``f(t, y, r, params, state, tau)`` with ``@numba.njit`` and wrap
it in :class:`CompiledController`.
"""

from __future__ import annotations

import math
import types as pytypes
from collections.abc import Callable
from dataclasses import dataclass, field

import numba as nb
import numpy as np
from numba import carray, types  # type: ignore[attr-defined]
from numba.core.ccallback import CFunc
from numpy.typing import ArrayLike, NDArray

from .._compile import njit_runtime_free
from .._types import F64
from .._validation import check_array, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.kinematics import lever_lengths
from ..model.plant import Plant
from ..sensing.sensors import Sensor
from ._gains import gain_matrix, gain_vector
from .signals import (
    r_angles,
    r_position,
    r_rates,
    r_velocity,
    reference_size,
    y_angles,
    y_point,
    y_point_rate,
    y_rates,
)

__all__ = [
    "CONTROL_SIGNATURE",
    "CompiledController",
    "Controller",
    "JacobianTransposePD",
    "JointPD",
    "gaussian_smoothing",
    "jacobian_transpose_law",
    "operational_lengths",
    "ringing_frequency",
    "wrap_control_function",
]


_P = types.CPointer(types.float64)  # type: ignore[no-untyped-call]
CONTROL_SIGNATURE = types.void(
    types.float64, _P, types.intp, _P, types.intp, _P, types.intp, _P, types.intp, _P, types.intp
)
"""``void(t, y*, ny, r*, nr, params*, np, state*, ns, tau*, ntau)``"""


def _call_law(t, y, ny, r, nr, p, n_p, s, ns, tau, nt):  # type: ignore[no-untyped-def]
    """The body of every compiled callback: the law ``law`` (a global of the copy that
    :func:`wrap_control_function` makes) called on array views of the C pointers."""
    law(t, carray(y, ny), carray(r, nr), carray(p, n_p), carray(s, ns), carray(tau, nt))  # type: ignore[name-defined]  # noqa: F821


def wrap_control_function(fn: Callable[..., None], cache: bool = False) -> CFunc:
    """Turn ``fn(t, y, r, params, state, tau)`` (a ``numba.njit`` function of
    arrays) into a ``numba.cfunc`` with :data:`CONTROL_SIGNATURE`.

    Parameters
    ----------
    fn : numba dispatcher
        The law, compiled with ``@numba.njit``.
    cache : bool
        Cache the compiled callback on disk (``numba.cfunc(cache=True)``), beside
        ``fn``'s own cache.

    Returns
    -------
    numba.core.ccallback.CFunc
        The callback, whose ``address`` the simulator's loop calls: it makes array
        views of the pointers it gets and calls ``fn`` (compiled into it), no more.

    Notes
    -----
    The callback is a copy of one function body with ``fn`` among its globals, not a
    closure: Numba keys a cached function by its code and the values it closes over,
    and a closure over a dispatcher hashes differently in every process (the cache
    would never be read). The copy takes ``fn``'s module, file, line and name with
    ``_cfunc`` appended, so its cache entry sits beside ``fn``'s and is refreshed when
    ``fn``'s source file changes, as for a callback written out by hand.
    """
    py_func = getattr(fn, "py_func", None)
    if py_func is None:
        raise InvalidTypeError(
            "The 'fn' parameter of wrap_control_function must be a numba.njit function. "
            f"Got {type(fn).__name__} instead."
        )
    name = f"{py_func.__name__}_cfunc"
    code = _call_law.__code__.replace(
        co_name=name,
        co_qualname=f"{py_func.__qualname__}_cfunc",
        co_filename=py_func.__code__.co_filename,
        co_firstlineno=py_func.__code__.co_firstlineno,
    )
    scope = {"__name__": py_func.__module__, "law": fn, "carray": carray}
    callback = pytypes.FunctionType(code, scope, name)
    return nb.cfunc(CONTROL_SIGNATURE, cache=cache)(callback)


# ------------------------------------------------------------------ built-ins
@njit_runtime_free(cache=True, nogil=True)
def _joint_pd(
    t: float, y: F64, r: F64, p: F64, s: F64, tau: F64
) -> None:  # pragma: no cover - compiled
    n = tau.shape[0]
    ra, rr, ya, yr = r_angles(n), r_rates(n), y_angles(n), y_rates(n)
    for i in range(n):
        tau[i] = p[i] * (r[ra + i] - y[ya + i]) + p[n + i] * (r[rr + i] - y[yr + i])


@nb.njit(cache=True, nogil=True, inline="always")
def jacobian_transpose_law(
    y: F64, r: F64, p: F64, stiffness: float, damping: float, tau: F64
) -> None:  # pragma: no cover - compiled
    """``tau = J' [stiffness Kp e + damping Kd de]`` with the :class:`JacobianTransposePD`
    parameter layout (``Kp``, ``Kd`` row-major in ``p[0:8]``, lever lengths in
    ``p[8:8+N]``); the scale factors let adaptive laws reuse it."""
    n = tau.shape[0]
    yp, yv, rp, rv = y_point(n), y_point_rate(n), r_position(n), r_velocity(n)
    ex, ey = r[rp] - y[yp], r[rp + 1] - y[yp + 1]
    evx, evy = r[rv] - y[yv], r[rv + 1] - y[yv + 1]
    fx = stiffness * (p[0] * ex + p[1] * ey) + damping * (p[4] * evx + p[5] * evy)
    fy = stiffness * (p[2] * ex + p[3] * ey) + damping * (p[6] * evx + p[7] * evy)
    # rigid Jacobian: column k = sum_{i >= k} L_i (-sin phi_i, cos phi_i)
    phi = 0.0
    for i in range(n):
        tau[i] = 0.0
    ya = y_angles(n)
    for i in range(n):
        phi += y[ya + i]
        jx = -p[8 + i] * math.sin(phi)
        jy = p[8 + i] * math.cos(phi)
        contrib = jx * fx + jy * fy
        for k in range(i + 1):
            tau[k] += contrib


@njit_runtime_free(cache=True, nogil=True)
def _jacobian_transpose_pd(
    t: float, y: F64, r: F64, p: F64, s: F64, tau: F64
) -> None:  # pragma: no cover - compiled
    jacobian_transpose_law(y, r, p, 1.0, 1.0, tau)


joint_pd_cfunc = wrap_control_function(_joint_pd, cache=True)
jacobian_transpose_pd_cfunc = wrap_control_function(_jacobian_transpose_pd, cache=True)


# ------------------------------------------------------------------ classes
class Controller:
    """Interface: what the simulator needs from a controller.

    Subclasses provide :attr:`cfunc` (a ``numba.cfunc`` with
    :data:`CONTROL_SIGNATURE`, made from the law by :func:`wrap_control_function`),
    :meth:`parameters` (the ``params`` vector for a
    given arm) and :meth:`initial_state` (the initial ``state`` vector).
    """

    name = "controller"
    """The law's name in results, figures and reports: the name that selects it on the
    command line (``pd``, ``joint-pd``, ``fuzzy``, ``lqg``, ``reflected``)."""
    feedforward = False
    """Whether :func:`flexarm.simulate` adds the reference's rigid feedforward torques to
    this law's output by default (its ``feedforward=None``)."""
    gravity_compensation = True
    """Whether :func:`flexarm.simulate` adds the holding torques of the measured posture
    (:mod:`flexarm.control.gravity_compensation`) to this law's output by default when
    the arm has gravity (its ``gravity_compensation=None``): the built-in laws are
    designed for the arm without its weight."""

    def reference_smoothing(
        self,
        arm: Plant,
        sensor: Sensor | None,
        dt: float,
        path: NDArray[np.float64],
        elbow: str = "positive",
    ) -> float:
        """The reference this law asks for: the standard deviation (s) of the zero-phase
        Gaussian smoothing of the path that :func:`flexarm.simulate` applies when its
        ``smoothing`` is None (the default); 0 is the raw path.

        Parameters
        ----------
        arm : Plant
            The simulated arm.
        sensor : Sensor, optional
            What the law reads.
        dt : float
            The control period, s.
        path : ndarray, shape (P, 2)
            End-effector points along the path, m, where the law may evaluate its loop.
        elbow : {"positive", "negative"}
            The path's inverse-kinematics branch.

        Returns
        -------
        float
            Seconds, >= 0. The default: 0.0, the raw path (the paper's laws were run on
            it); :class:`flexarm.control.lqg.LQG` and
            :class:`flexarm.control.reflected.ReflectedTipPD` choose it from their
            closed loops.
        """
        return 0.0

    @property
    def cfunc(self) -> CFunc:  # pragma: no cover - interface
        """The compiled law, a ``numba.cfunc`` with :data:`CONTROL_SIGNATURE`."""
        raise NotImplementedError

    def parameters(self, arm: Plant) -> NDArray[np.float64]:  # pragma: no cover - interface
        """The ``params`` vector of the law for ``arm``."""
        raise NotImplementedError

    def initial_state(self, arm: Plant) -> NDArray[np.float64]:
        """The initial ``state`` vector of the law for ``arm`` (default: empty)."""
        return np.zeros(0)

    def parameters_for(self, arm: Plant, sensor: Sensor | None) -> NDArray[np.float64]:
        """The ``params`` vector for ``arm`` read through ``sensor`` (what the
        simulator passes). Default: :meth:`parameters`; operational-space laws
        use the sensed point's Jacobian."""
        return self.parameters(arm)

    def design(
        self, arm: Plant, sensor: Sensor | None, dt: float, reference: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The ``params`` vector the simulator passes, knowing the control period
        ``dt`` (s) and the run's reference vectors (shape (K, 6 + 4 N)). Default:
        :meth:`parameters_for`; laws designed for a period (:class:`flexarm.control.lqg.LQG`)
        override it.

        A law that overrides it is given every reference vector of the run, which the
        simulator then computes before the run; a law that does not may be given the
        first one only (a path of straight segments is then computed inside the
        compiled loop, instant by instant)."""
        return self.parameters_for(arm, sensor)

    def __call__(
        self,
        t: float,
        y: NDArray[np.float64],
        r: NDArray[np.float64],
        params: NDArray[np.float64],
        state: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """Evaluate the compiled law once from Python (``state`` is updated in place).

        ``r`` has the layout of :mod:`flexarm.control.signals` (its length gives the
        number of links); returns the torques, shape (n_links,), N m.
        """
        n_links = (np.shape(r)[0] - reference_size(0)) // (reference_size(1) - reference_size(0))
        if n_links < 1 or reference_size(n_links) != np.shape(r)[0]:
            raise InvalidValueError(
                f"The 'r' parameter of {type(self).__name__} must have the length of a "
                f"reference vector (6 + 4 n_links). Got {np.shape(r)[0]} instead."
            )
        tau = np.zeros(n_links)
        y = np.ascontiguousarray(y, dtype=float)
        r = np.ascontiguousarray(r, dtype=float)
        params = np.ascontiguousarray(params, dtype=float)
        fn = self.cfunc.ctypes
        fn(
            float(t),
            _ptr(y),
            y.size,
            _ptr(r),
            r.size,
            _ptr(params),
            params.size,
            _ptr(state),
            state.size,
            _ptr(tau),
            tau.size,
        )
        return tau


def ringing_frequency(poles: ArrayLike, damping: float = 0.5) -> float:
    """The natural frequency (rad/s) of the slowest pole that rings: the smallest
    ``|s|`` among continuous-time ``poles`` (rad/s) off the real axis with a damping
    ratio ``-Re(s) / |s|`` below ``damping`` (0.5: more than 16 % overshoot). NaN if
    none does. (The example's pair at 5 rad/s has a damping ratio of 0.6, the one
    at 20 rad/s 0.05.)

    Examples
    --------
    >>> round(ringing_frequency([-1.0, -3.0 + 4.0j, -3.0 - 4.0j, -1.0 + 20.0j]), 4)
    20.025
    """
    s = np.asarray(poles, dtype=complex).ravel()
    s = s[(s.imag != 0.0) & (np.abs(s) > 0.0)]
    s = s[-s.real / np.abs(s) < damping]
    return float(np.min(np.abs(s))) if s.size else float("nan")


def gaussian_smoothing(frequency: float, attenuation: float) -> float:
    """The standard deviation (s) of the zero-phase Gaussian smoothing whose frequency
    response ``exp(-(omega sigma)**2 / 2)`` is ``1 / attenuation`` at ``frequency``
    (rad/s): ``sigma = sqrt(2 ln attenuation) / frequency``; 0 for a NaN or infinite
    frequency (nothing to attenuate).

    Examples
    --------
    >>> round(gaussian_smoothing(10.0, 100.0), 6)  # 40 dB at 10 rad/s
    0.303485
    """
    if not np.isfinite(frequency) or frequency <= 0.0:
        return 0.0
    return float(np.sqrt(2.0 * np.log(attenuation)) / frequency)


def _ptr(a: NDArray[np.float64]) -> object:
    import ctypes

    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def operational_lengths(arm: Plant, sensor: Sensor | None = None) -> NDArray[np.float64]:
    """Lever lengths of the rigid Jacobian of the point an operational-space law controls.

    The end effector (the link lengths) for joint encoders and the tip; for a
    point ``distance`` along link ``l``: ``L_0, ..., L_{l-1}, distance, 0, ...``
    (:func:`flexarm.model.kinematics.lever_lengths`), so that ``J' F`` is the
    rigid Jacobian of the sensed point and the law is a PD in that point's
    operational space.
    """
    lengths = np.array(arm.link_lengths, dtype=float)
    if sensor is None:
        return lengths
    link, distance, _ = sensor.resolve(arm)
    return lengths if link < 0 else lever_lengths(lengths, link, distance)


@dataclass(frozen=True)
class JointPD(Controller):
    """Joint-space PD: ``tau = Kp (theta_r - theta) + Kd (dtheta_r - dtheta)``.

    Parameters
    ----------
    kp : float or array_like, shape (n_links,)
        Proportional gains, N m/rad (>= 0).
    kd : float or array_like, shape (n_links,)
        Derivative gains, N m s/rad (>= 0).
    """

    kp: ArrayLike = 100.0
    kd: ArrayLike = 10.0
    name = "joint-pd"

    @property
    def cfunc(self) -> CFunc:
        return joint_pd_cfunc

    def parameters(self, arm: Plant) -> NDArray[np.float64]:
        n = arm.n_links
        kp = gain_vector(self.kp, "kp", "JointPD", n)
        kd = gain_vector(self.kd, "kd", "JointPD", n)
        return np.concatenate([kp, kd])


@dataclass(frozen=True)
class JacobianTransposePD(Controller):
    """Operational-space PD through the transposed rigid Jacobian (paper eq. 11).

    ``tau = J(theta)' [Kp (x_r - x) + Kd (v_r - v)]``.

    Parameters
    ----------
    kp : float or array_like, shape (2,) or (2, 2)
        Stiffness, N/m (a scalar is ``kp I``).
    kd : float or array_like, shape (2,) or (2, 2)
        Damping, N s/m.
    """

    kp: ArrayLike = 150.79
    kd: ArrayLike = 17.364
    name = "pd"  # the paper's law (``--controller jt-pd`` is the same law with your gains)

    def __post_init__(self) -> None:
        for gain in ("kp", "kd"):  # checked now, not at the first run
            gain_matrix(getattr(self, gain), gain, type(self).__name__)

    @classmethod
    def from_arm(cls, arm: Plant, zeta: float = 0.707) -> JacobianTransposePD:
        """The paper's gains from the first link's first clamped frequency ``omega_1``:
        ``Kp = omega_1**2 I``, ``Kd = 2 zeta omega_1 I``."""
        zeta = check_real(zeta, "zeta", "JacobianTransposePD.from_arm", nonnegative=True)
        freqs = arm.link_frequencies[0]
        if len(freqs) == 0:
            raise InvalidValueError(
                "JacobianTransposePD.from_arm needs a first link with at least one mode."
            )
        w1 = float(freqs[0])
        return cls(kp=w1**2, kd=2.0 * zeta * w1)

    @property
    def cfunc(self) -> CFunc:
        return jacobian_transpose_pd_cfunc

    def parameters(self, arm: Plant) -> NDArray[np.float64]:
        return self.parameters_for(arm, None)

    def parameters_for(self, arm: Plant, sensor: Sensor | None) -> NDArray[np.float64]:
        kp = gain_matrix(self.kp, "kp", "JacobianTransposePD")
        kd = gain_matrix(self.kd, "kd", "JacobianTransposePD")
        return np.concatenate([kp.ravel(), kd.ravel(), operational_lengths(arm, sensor)])


@dataclass(frozen=True)
class CompiledController(Controller):
    """A user-written law ``function(t, y, r, params, state, tau)``.

    Parameters
    ----------
    function : numba dispatcher
        An ``@numba.njit`` function of (float, 1-D arrays...) writing ``tau``.
    params : array_like, shape (p,)
        Passed to every call.
    state : array_like, shape (s,)
        Initial state; the function may update it in place.
    name : str
        Label for results.

    Examples
    --------
    >>> import numba
    >>> @numba.njit
    ... def hold(t, y, r, params, state, tau):
    ...     for i in range(tau.shape[0]):
    ...         tau[i] = -params[0] * y[tau.shape[0] + i]   # damp the joints
    >>> ctrl = CompiledController(hold, params=[5.0])
    """

    function: Callable[..., None]
    params: ArrayLike = ()
    state: ArrayLike = ()
    name: str = "compiled"
    gravity_compensation = False  # your law's torque is all it commands, unless asked
    _cfunc: list[CFunc] = field(default_factory=list, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not hasattr(self.function, "py_func"):
            raise InvalidTypeError(
                "The 'function' parameter of CompiledController must be a numba.njit "
                f"function. Got {type(self.function).__name__} instead."
            )
        object.__setattr__(
            self, "params", check_array(self.params, "params", "CompiledController").ravel()
        )
        object.__setattr__(
            self, "state", check_array(self.state, "state", "CompiledController").ravel()
        )

    @property
    def cfunc(self) -> CFunc:
        if not self._cfunc:
            self._cfunc.append(wrap_control_function(self.function))
        return self._cfunc[0]

    def parameters(self, arm: Plant) -> NDArray[np.float64]:
        return np.asarray(self.params, dtype=float)

    def initial_state(self, arm: Plant) -> NDArray[np.float64]:
        return np.array(self.state, dtype=float)
