r"""Joints: the flexible linear (Spong) and nonlinear (Ulrich) models, the rigid
joint, Makkar friction.

A flexible joint couples a motor angle ``q_m`` (reflected to the link side of
the gear) to the link angle ``q`` through a torsional spring of deflection
``Delta = q_m - q``:

* :class:`LinearJoint` (Spong 1987): ``tau_s = k Delta``.
* :class:`NonlinearJoint` (Ulrich et al.): cubic stiffness with soft windup,

  .. math:: \tau_s(\Delta) = a_1 \Delta + a_2 \Delta^3
            - k_{sw} e^{-a_{sw} \Delta^2} \Delta,

  whose stiffness ``d tau_s / d Delta`` is ``a1 - ksw`` at zero deflection and
  tends to ``a1 + 3 a2 Delta**2`` outside the windup region
  ``|Delta| ~ 1/sqrt(asw)`` (at its edge it overshoots ``a1`` by up to
  ``ksw / e**1.5``, a property of this law) (Kircanski & Goldenberg observed this softening of
  harmonic drives below about 1 N m). ``a1 > ksw`` keeps it positive.
  Its potential is closed-form:
  ``V = a1 Delta**2 / 2 + a2 Delta**4 / 4 - ksw (1 - exp(-asw Delta**2)) / (2 asw)``.
* :class:`RigidJoint`: no spring, the motor drives the link through its gear
  (rotor inertia, viscous and Makkar friction on the joint rate).
* :class:`MakkarFriction`:
  ``f(v) = g1 (tanh(g2 v) - tanh(g3 v)) + g4 tanh(g5 v) + g6 v`` — a Stribeck
  hump (``g2 > g3``), smoothed Coulomb friction and viscous friction; the
  static (breakaway) level is about ``g1 + g4``.

Where friction acts is the arm's choice (:class:`flexarm.FlexibleArm`): on the
link side of the spring (paper eq. 7) by default; a joint's ``friction_side``
overrides it for that joint. A joint's ``damping`` is a viscous damper across
the spring, on the deflection rate ``dq_m - dq``.

Default parameters
------------------
The paper gives no numbers. ``LinearJoint.default()``,
``NonlinearJoint.default()`` and ``MakkarFriction.default()`` describe a
space-manipulator-class joint sized for the paper's arm (two 4.5 m links,
about 81 kg m**2 about the shoulder when straight, joint torques of tens to a
few hundred N m under the paper's gains):

=========  ================  =====================================================
parameter  value             reasoning
=========  ================  =====================================================
a1         1.0e4 N m/rad     harmonic-drive class (CSF-25 catalogue stiffness
                             1.3e4–2.5e4 N m/rad); the rigid-link estimate of the
                             shoulder's joint mode, sqrt(a1 / 81) = 11 rad/s, sits
                             next to the links' 12.3 rad/s, so joint and link
                             flexibility interact (``flexarm modes --joints
                             linear`` prints the coupled frequencies)
ksw        6.0e3 N m/rad     stiffness at zero deflection a1 - ksw = 0.4 a1, the
                             low/high stiffness ratio of harmonic drives (~0.5)
asw        1.6e7 1/rad**2    windup region ``|Delta| < 1/sqrt(asw)`` = 2.5e-4 rad, i.e.
                             torques below (a1 - ksw) 2.5e-4 = 1 N m (Kircanski &
                             Goldenberg)
a2         4.0e7 N m/rad**3  hardening adds 10 % to the stiffness at 5e-3 rad
                             (50 N m), a typical cubic fit of harmonic-drive curves
J_m        0.3 kg m**2       rotor 3e-5 kg m**2 reflected through a 100:1 gear
                             (``gear_ratio=100``: the rotor adds its own 3e-5
                             kg m**2 to the link that carries it)
g1, g4     0.5, 1.0 N m      Stribeck excess and Coulomb level: breakaway about
                             1.5 N m, 3 % of a 50 N m rated torque
g2, g3     100, 10 s/rad     Stribeck velocity between 0.01 and 0.1 rad/s (as in
                             Makkar et al.'s example, gamma = [0.25, 100, 10, 0.1,
                             100, 0.01])
g5         100 s/rad         Coulomb smoothing below 0.01 rad/s
g6         0.5 N m s/rad     viscous friction of a greased gear
=========  ================  =====================================================

``LinearJoint.default()``   uses ``k = a1`` and the same rotor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_option, check_real, check_sequence_of, validate_real_fields
from ..errors import InvalidTypeError, InvalidValueError

__all__ = [
    "DEFAULT_GEAR_RATIO",
    "FRICTION_SIDES",
    "Joint",
    "LinearJoint",
    "MakkarFriction",
    "NonlinearJoint",
    "RigidJoint",
    "check_joints",
]

FRICTION_SIDES = ("link", "motor")
"""Where a flexible joint's friction acts: on the link angle or the motor angle."""

DEFAULT_GEAR_RATIO = 100.0
"""The gear of the documented default joints (module docstring), motor turns per
joint turn."""


def _as_float_array(x: ArrayLike, name: str, owner: str) -> NDArray[np.float64]:
    arr = np.asarray(x, dtype=float)
    if arr.dtype.kind != "f":  # pragma: no cover - asarray(float) guarantees it
        raise InvalidTypeError(f"The '{name}' parameter of {owner} must be numeric.")
    return arr


@dataclass(frozen=True)
class MakkarFriction:
    """Makkar et al.'s smooth friction model (all parameters >= 0).

    ``f(v) = g1 (tanh(g2 v) - tanh(g3 v)) + g4 tanh(g5 v) + g6 v``.

    Parameters
    ----------
    g1 : float
        Stribeck excess level, N m.
    g2, g3 : float
        Rates (s/rad) whose difference shapes the Stribeck hump; ``g2 > g3``
        for a hump that decays with speed.
    g4 : float
        Coulomb level, N m.
    g5 : float
        Coulomb smoothing rate, s/rad.
    g6 : float
        Viscous coefficient, N m s/rad.

    Examples
    --------
    >>> f = MakkarFriction.default()
    >>> float(f(0.0)), round(float(f(10.0)), 3)
    (0.0, 6.0)
    """

    g1: float
    g2: float
    g3: float
    g4: float
    g5: float
    g6: float

    def __post_init__(self) -> None:
        validate_real_fields(
            self, "MakkarFriction", nonnegative=("g1", "g2", "g3", "g4", "g5", "g6")
        )

    @classmethod
    def default(cls) -> MakkarFriction:
        """The documented default (module docstring)."""
        return cls(0.5, 100.0, 10.0, 1.0, 100.0, 0.5)

    @property
    def static_level(self) -> float:
        """``g1 + g4``: the breakaway level the hump approaches at low speed, N m."""
        return self.g1 + self.g4

    def friction(self, velocity: ArrayLike) -> NDArray[np.float64]:
        """Friction torque in N m at ``velocity`` (rad/s), any shape; odd in ``v``."""
        v = _as_float_array(velocity, "velocity", "MakkarFriction")
        out: NDArray[np.float64] = (
            self.g1 * (np.tanh(self.g2 * v) - np.tanh(self.g3 * v))
            + self.g4 * np.tanh(self.g5 * v)
            + self.g6 * v
        )
        return out

    __call__ = friction

    def slope(self, velocity: ArrayLike) -> NDArray[np.float64]:
        """``df/dv`` in N m s/rad at ``velocity`` (rad/s): at 0 it is
        ``g1 (g2 - g3) + g4 g5 + g6``, the viscous coefficient a linearisation sees."""
        v = _as_float_array(velocity, "velocity", "MakkarFriction")

        def sech2(x: NDArray[np.float64]) -> NDArray[np.float64]:
            return 1.0 - np.tanh(x) ** 2

        out: NDArray[np.float64] = (
            self.g1 * (self.g2 * sech2(self.g2 * v) - self.g3 * sech2(self.g3 * v))
            + self.g4 * self.g5 * sech2(self.g5 * v)
            + self.g6
        )
        return out

    @property
    def params(self) -> NDArray[np.float64]:
        """``(g1, ..., g6)`` as an array of shape (6,)."""
        return np.array([self.g1, self.g2, self.g3, self.g4, self.g5, self.g6])


@dataclass(frozen=True)
class LinearJoint:
    """A linear torsional spring between motor and link (Spong 1987).

    Parameters
    ----------
    stiffness : float
        ``k`` in N m/rad (> 0).
    motor_inertia : float
        Rotor inertia reflected to the link side, ``J_m`` in kg m**2 (> 0).
    motor_damping : float
        Viscous damping on the motor side, N m s/rad (>= 0).
    friction : MakkarFriction or None
        Joint friction (None: frictionless).
    gear_ratio : float
        ``N``, motor turns per joint turn (>= 1; default 1, a direct drive). The
        rotor's own inertia is ``J_m / N**2``: what it adds to its carrier link
        when the arm couples rotors (``FlexibleArm(rotor_coupling=True)``).
    damping : float
        Viscous damping of the spring, N m s/rad (>= 0): the torque
        ``damping (dq_m - dq)`` on the link and its reaction on the motor.
    friction_side : {"link", "motor"} or None
        Where this joint's friction acts; None (default): the arm's
        ``joint_friction``.

    Examples
    --------
    >>> LinearJoint(100.0, 0.5).torque([0.0, 0.01])
    array([0., 1.])
    """

    stiffness: float
    motor_inertia: float
    motor_damping: float = 0.0
    friction: MakkarFriction | None = None
    gear_ratio: float = 1.0
    damping: float = 0.0
    friction_side: str | None = None

    def __post_init__(self) -> None:
        owner = "LinearJoint"
        validate_real_fields(
            self,
            owner,
            positive=("stiffness", "motor_inertia"),
            nonnegative=("motor_damping", "damping"),
        )
        _check_friction(self.friction, owner)
        _check_gear_ratio(self, owner)
        _check_friction_side(self.friction_side, owner)

    @classmethod
    def default(cls) -> LinearJoint:
        """``k = 1e4 N m/rad``, ``J_m = 0.3 kg m**2`` through a 100:1 gear (module
        docstring)."""
        return cls(1.0e4, 0.3, gear_ratio=DEFAULT_GEAR_RATIO)

    @property
    def rotor_inertia(self) -> float:
        """The rotor's own inertia about its axis, ``J_m / N**2`` (kg m**2)."""
        return self.motor_inertia / self.gear_ratio**2

    def torque(self, deflection: ArrayLike) -> NDArray[np.float64]:
        """Spring torque ``k Delta`` in N m for ``Delta = q_m - q`` (rad), any shape."""
        return self.stiffness * _as_float_array(deflection, "deflection", "LinearJoint")

    def tangent_stiffness(self, deflection: ArrayLike) -> NDArray[np.float64]:
        """``d tau_s / d Delta`` in N m/rad (constant ``k``), same shape as ``deflection``."""
        d = _as_float_array(deflection, "deflection", "LinearJoint")
        return np.full_like(d, self.stiffness)

    def potential(self, deflection: ArrayLike) -> NDArray[np.float64]:
        """Spring energy ``k Delta**2 / 2`` in J."""
        d = _as_float_array(deflection, "deflection", "LinearJoint")
        return 0.5 * self.stiffness * d**2

    @property
    def spring_params(self) -> NDArray[np.float64]:
        """``(a1, a2, ksw, asw)`` of the equivalent nonlinear law: ``(k, 0, 0, 0)``."""
        return np.array([self.stiffness, 0.0, 0.0, 0.0])


@dataclass(frozen=True)
class NonlinearJoint:
    """Cubic stiffness with soft windup (Ulrich et al.), module docstring.

    Parameters
    ----------
    a1 : float
        Linear stiffness, N m/rad (> ksw).
    a2 : float
        Cubic hardening, N m/rad**3 (>= 0).
    ksw : float
        Soft-windup stiffness reduction, N m/rad (>= 0, < a1).
    asw : float
        Soft-windup width parameter, 1/rad**2 (> 0).
    motor_inertia : float
        Reflected rotor inertia, kg m**2 (> 0).
    friction : MakkarFriction or None
        Joint friction (None: frictionless).
    motor_damping : float
        Viscous damping on the motor side, N m s/rad (>= 0).
    gear_ratio : float
        ``N``, motor turns per joint turn (>= 1; default 1): as for
        :class:`LinearJoint`.
    damping : float
        Viscous damping of the spring, N m s/rad (>= 0), as for :class:`LinearJoint`.
    friction_side : {"link", "motor"} or None
        Where this joint's friction acts (None: the arm's ``joint_friction``).

    Examples
    --------
    >>> j = NonlinearJoint.default()
    >>> float(j.tangent_stiffness(0.0))
    4000.0
    """

    a1: float
    a2: float
    ksw: float
    asw: float
    motor_inertia: float
    friction: MakkarFriction | None = None
    motor_damping: float = 0.0
    gear_ratio: float = 1.0
    damping: float = 0.0
    friction_side: str | None = None

    def __post_init__(self) -> None:
        owner = "NonlinearJoint"
        validate_real_fields(
            self,
            owner,
            positive=("a1", "asw", "motor_inertia"),
            nonnegative=("a2", "ksw", "motor_damping", "damping"),
        )
        _check_friction_side(self.friction_side, owner)
        if not self.a1 > self.ksw:
            raise InvalidValueError(
                f"The 'ksw' parameter of {owner} must be < a1 = {self.a1} (stiffness "
                f"a1 - ksw must be positive at zero deflection). Got {self.ksw} instead."
            )
        _check_friction(self.friction, owner)
        _check_gear_ratio(self, owner)

    @classmethod
    def default(cls, friction: MakkarFriction | None = None) -> NonlinearJoint:
        """The documented space-manipulator-class joint (module docstring)."""
        return cls(
            1.0e4, 4.0e7, 6.0e3, 1.6e7, 0.3, friction=friction, gear_ratio=DEFAULT_GEAR_RATIO
        )

    @property
    def rotor_inertia(self) -> float:
        """The rotor's own inertia about its axis, ``J_m / N**2`` (kg m**2)."""
        return self.motor_inertia / self.gear_ratio**2

    def torque(self, deflection: ArrayLike) -> NDArray[np.float64]:
        """Spring torque ``tau_s(Delta)`` in N m for ``Delta = q_m - q`` (rad), any shape."""
        d = _as_float_array(deflection, "deflection", "NonlinearJoint")
        out: NDArray[np.float64] = (
            self.a1 * d + self.a2 * d**3 - self.ksw * np.exp(-self.asw * d * d) * d
        )
        return out

    def tangent_stiffness(self, deflection: ArrayLike) -> NDArray[np.float64]:
        """``d tau_s / d Delta`` in N m/rad, same shape as ``deflection``."""
        d = _as_float_array(deflection, "deflection", "NonlinearJoint")
        e = np.exp(-self.asw * d * d)
        out: NDArray[np.float64] = (
            self.a1 + 3 * self.a2 * d**2 - self.ksw * e * (1 - 2 * self.asw * d * d)
        )
        return out

    def potential(self, deflection: ArrayLike) -> NDArray[np.float64]:
        """Spring energy ``int_0^Delta tau_s`` in J (closed form)."""
        d = _as_float_array(deflection, "deflection", "NonlinearJoint")
        out: NDArray[np.float64] = (
            0.5 * self.a1 * d**2
            + 0.25 * self.a2 * d**4
            + self.ksw * np.expm1(-self.asw * d * d) / (2 * self.asw)
        )
        return out

    @property
    def spring_params(self) -> NDArray[np.float64]:
        """``(a1, a2, ksw, asw)``, shape (4,)."""
        return np.array([self.a1, self.a2, self.ksw, self.asw])


@dataclass(frozen=True)
class RigidJoint:
    """A joint without a spring: the motor drives its link through the gear directly.

    The joint angle is the motor angle (link side): an arm of rigid joints has no
    motor coordinates. The rotor turns ``N`` times as fast as the joint relative
    to its carrier (the previous link's tip), so its kinetic energy is
    ``1/2 J_m (carrier rate / N + dtheta)**2`` with coupled rotors
    (``FlexibleArm(rotor_coupling=True)``), ``1/2 J_m dtheta**2`` without.

    Parameters
    ----------
    motor_inertia : float
        Rotor inertia reflected to the link side, ``J_m = N**2 J_r`` in kg m**2 (>= 0).
    damping : float
        Viscous friction on the joint rate, N m s/rad (>= 0).
    friction : MakkarFriction or None
        Joint friction on the joint rate (None: frictionless).
    gear_ratio : float
        ``N``, motor turns per joint turn (>= 1; default 1, a direct drive).

    Examples
    --------
    >>> RigidJoint(0.3, damping=0.5, gear_ratio=100).rotor_inertia
    3e-05
    """

    motor_inertia: float = 0.0
    damping: float = 0.0
    friction: MakkarFriction | None = None
    gear_ratio: float = 1.0

    def __post_init__(self) -> None:
        owner = "RigidJoint"
        validate_real_fields(self, owner, nonnegative=("motor_inertia", "damping"))
        _check_friction(self.friction, owner)
        _check_gear_ratio(self, owner)

    @property
    def rotor_inertia(self) -> float:
        """The rotor's own inertia about its axis, ``J_m / N**2`` (kg m**2)."""
        return self.motor_inertia / self.gear_ratio**2

    @property
    def friction_side(self) -> str:
        """``"link"``: a rigid joint's friction acts on its one angle."""
        return "link"


Joint = LinearJoint | NonlinearJoint
"""A flexible joint (a spring between motor and link)."""


def check_gear_ratio(value: object, owner: str) -> float:
    """``value`` as a gear ratio ``N >= 1`` (motor turns per joint turn), or raise
    naming ``owner``: a joint's, or a drive's."""
    ratio = check_real(value, "gear_ratio", owner, positive=True)
    if ratio < 1.0:
        raise InvalidValueError(
            f"The 'gear_ratio' parameter of {owner} must be >= 1 (motor turns per joint "
            f"turn). Got {ratio} instead."
        )
    return ratio


def _check_gear_ratio(joint: LinearJoint | NonlinearJoint | RigidJoint, owner: str) -> None:
    object.__setattr__(joint, "gear_ratio", check_gear_ratio(joint.gear_ratio, owner))


def _check_friction_side(side: object, owner: str) -> None:
    if side is not None:
        check_option(side, "friction_side", owner, FRICTION_SIDES)


def _check_friction(friction: object, owner: str) -> None:
    if friction is not None and not isinstance(friction, MakkarFriction):
        raise InvalidTypeError(
            f"The 'friction' parameter of {owner} must be a MakkarFriction or None. "
            f"Got {type(friction).__name__} instead."
        )


def check_joints(
    joints: object, n_links: int, owner: str
) -> tuple[LinearJoint | NonlinearJoint | RigidJoint, ...]:
    """``joints`` checked: one joint per link, all flexible or all rigid."""
    what = "LinearJoint, NonlinearJoint or RigidJoint"
    kinds = (LinearJoint, NonlinearJoint, RigidJoint)
    joints = check_sequence_of(joints, "joints", owner, kinds, what)
    if len(joints) != n_links:
        raise InvalidValueError(
            f"The 'joints' parameter of {owner} must hold one joint per link "
            f"({n_links}). Got {len(joints)} instead."
        )
    rigid = [isinstance(jt, RigidJoint) for jt in joints]
    if any(rigid) and not all(rigid):
        raise InvalidValueError(
            f"The 'joints' parameter of {owner} must be all flexible joints "
            "(LinearJoint, NonlinearJoint) or all RigidJoint: an arm mixing them is "
            f"not modelled. Got rigid joints at {[i for i, r in enumerate(rigid) if r]} "
            "instead (give those a stiff LinearJoint, or make every joint rigid)."
        )
    checked: tuple[LinearJoint | NonlinearJoint | RigidJoint, ...] = joints
    return checked
