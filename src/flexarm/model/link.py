"""The parameters of one link: :class:`Link` (a flexible beam) and :class:`RigidLink`."""

from __future__ import annotations

from dataclasses import dataclass

from .._validation import check_real, validate_real_fields
from .beam import UniformBeam

__all__ = ["AnyLink", "Link", "RigidLink"]


@dataclass(frozen=True)
class Link(UniformBeam):
    """A uniform Euler–Bernoulli link driven at its base joint.

    Parameters
    ----------
    length : float
        ``L`` in m (> 0).
    flexural_rigidity : float
        ``EI`` in N m**2 (> 0).
    linear_density : float
        ``rho`` in kg/m (> 0).
    n_modes : int
        Assumed modes kept (>= 0); 0 makes the link a rigid uniform rod. The
        default, 3, is where a two-link arm with clamped-mass modes and geometric
        stiffening converges: against a geometrically exact reference (Exudyn's
        ANCF cables) its link tip deflections are within 0.2 % of their peak
        under torque pulses and on a prescribed square, where one mode is up to 45 %
        off and two modes up to 1 % (user guide, "How many modes").
    hub_mass : float
        Mass of the hub at this link's joint, in kg (>= 0). The hub sits at the
        previous link's tip, which carries it; the first link's hub sits on the
        fixed base and its mass has no dynamic effect.
    hub_inertia : float
        Rotary inertia of the hub about the joint axis, kg m**2 (>= 0). It turns
        with this link and adds to its inertia about the joint.
    modal_damping : float
        Damping ratio ``zeta`` of every mode of this link (>= 0): the modal
        damping force is ``2 zeta omega_j G_jj ddelta_j`` with ``G`` the
        generalised modal mass.
    tip_mass : float
        Mass of a rigid body at this link's tip, kg (>= 0): a point mass there.
    tip_inertia : float
        Rotary inertia of that body about the tip, kg m**2 (>= 0); it turns with
        the tip's slope. With ``boundary="clamped-mass"`` the tip body loads the
        link's own modes.

    Examples
    --------
    >>> Link(4.5, 1676.0, 0.335).mass
    1.5075
    """

    n_modes: int = 3
    hub_mass: float = 0.0
    hub_inertia: float = 0.0
    modal_damping: float = 0.0
    tip_mass: float = 0.0
    tip_inertia: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        validate_real_fields(
            self,
            "Link",
            nonnegative=("hub_mass", "hub_inertia", "modal_damping", "tip_mass", "tip_inertia"),
        )

    @property
    def rod_inertia(self) -> float:
        """Rigid-rod inertia about the joint, ``rho L**3 / 3``, kg m**2 (hub excluded)."""
        return self.linear_density * self.length**3 / 3.0

    @property
    def first_moment(self) -> float:
        """``int rho x dx = rho L**2 / 2``, kg m: the beam's mass times the distance of
        its centre of mass from the joint (hub and tip body excluded)."""
        return self.linear_density * self.length**2 / 2.0

    @property
    def joint_inertia(self) -> float:
        """The undeformed beam's inertia about the joint, kg m**2 (:attr:`rod_inertia`)."""
        return self.rod_inertia

    def inertia_behind(self, distance: float) -> float:
        """The undeformed beam's inertia about a point ``distance`` m behind its
        joint on its line, ``rho ((d + L)**3 - d**3) / 3`` (kg m**2)."""
        return self.linear_density * ((distance + self.length) ** 3 - distance**3) / 3.0


@dataclass(frozen=True)
class RigidLink:
    """A rigid link as a data sheet gives it: no bending, no modes.

    Parameters
    ----------
    length : float
        Joint to tip (the next joint), m (> 0).
    mass : float
        kg (>= 0).
    com : float
        Distance of the centre of mass from the joint along the link, m (the
        centre of mass lies on the line from the joint to the tip).
    inertia : float
        Rotary inertia about the centre of mass, kg m**2 (>= 0).
    hub_mass, hub_inertia : float
        The hub at the joint, as for :class:`Link` (kg, kg m**2; >= 0).
    tip_mass, tip_inertia : float
        A rigid body at the tip, as for :class:`Link` (kg, kg m**2; >= 0).

    Examples
    --------
    >>> rod = RigidLink(1.0, 3.0, 0.5, 3.0 / 12)   # a uniform rod of 3 kg
    >>> round(rod.joint_inertia, 12)
    1.0
    """

    length: float
    mass: float
    com: float
    inertia: float
    hub_mass: float = 0.0
    hub_inertia: float = 0.0
    tip_mass: float = 0.0
    tip_inertia: float = 0.0

    def __post_init__(self) -> None:
        owner = "RigidLink"
        validate_real_fields(
            self,
            owner,
            positive=("length",),
            nonnegative=("mass", "inertia", "hub_mass", "hub_inertia", "tip_mass", "tip_inertia"),
        )
        object.__setattr__(self, "com", check_real(self.com, "com", owner))

    @property
    def n_modes(self) -> int:
        """0: a rigid link has no modes."""
        return 0

    @property
    def modal_damping(self) -> float:
        """0.0: nothing to damp."""
        return 0.0

    @property
    def first_moment(self) -> float:
        """``mass * com``, kg m."""
        return self.mass * self.com

    @property
    def joint_inertia(self) -> float:
        """Inertia about the joint, ``inertia + mass com**2`` (kg m**2; hub and tip
        body excluded)."""
        return self.inertia + self.mass * self.com**2

    def inertia_behind(self, distance: float) -> float:
        """Inertia about a point ``distance`` m behind the joint on the link's line
        (kg m**2; hub and tip body excluded)."""
        return self.inertia + self.mass * (distance + self.com) ** 2


AnyLink = Link | RigidLink
"""A link of either kind."""
