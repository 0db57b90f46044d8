r"""The planar multi-link arm with flexible links: :class:`FlexibleArm`.

Model
-----
Links are uniform Euler–Bernoulli beams moving in a plane: horizontal (no
gravity, the default) or, with ``gravity=(g_x, g_y)``, any plane that holds the
gravity vector (:mod:`flexarm.model.gravity`). Link ``i`` (0-based) has a
clamped frame at its joint, at absolute angle

.. math:: \alpha_i = \sum_{k \le i} \theta_k + \sum_{k < i} w_k'(L_k),

i.e. joint ``i`` turns link ``i`` relative to the *deflected* tip of link
``i-1`` (the motor's stator sits there). A point at distance ``x`` along link
``i`` is at

.. math:: p_i(x) = o_i + R(\alpha_i) \, [x - u_i(x),\ w_i(x)]^T, \qquad
          w_i(x) = \sum_j \phi_{ij}(x) \delta_{ij}, \quad
          u_i(x) = \tfrac12 \int_0^x w_i'(s)^2 ds,

with ``o_0 = 0`` and ``o_{i+1} = p_i(L_i)``. The foreshortening ``u_i``
(``geometric_stiffening=True``, the default; :mod:`flexarm.model.foreshortening`)
pulls a bent link's points, its tip and everything outboard towards its joint,
and brings the centrifugal stiffening of a spinning link. With
``geometric_stiffening=False`` (the paper's model) ``u_i = 0``: deflections
enter the kinematics linearly, as in the closed-form model of De Luca &
Siciliano (IEEE SMC 1991), and a link slewed faster than its first bending
frequency diverges. The Lagrangian is built from this one kinematic map with
no further truncation, ``T = 1/2 \int |\dot p|^2 dm`` plus the rotary inertia
of hubs and payload and ``V = 1/2 \sum EI \int w''^2``, so the equations of
motion

.. math:: M(q) \ddot q + C(q, \dot q) \dot q + K q + D \dot q = B \tau

conserve ``T + V`` exactly when ``tau = 0`` and ``D = 0``.

Coordinates ``q = (theta_1..theta_N, delta_1, ..., delta_N[, q_m1..q_mN])``:
joint (link-side) angles in rad, every link's modal coordinates in link order,
and with flexible ``joints`` the motor angles (reflected to the link side).

Flexible joints
---------------
Joint ``i`` couples its motor angle to the link angle by a spring of
deflection ``Delta_i = q_mi - theta_i`` (:mod:`flexarm.model.joints`): the spring
torque acts on ``theta_i`` and its reaction on ``q_mi``; the input torque and
motor damping act on ``q_mi``. Friction acts on the link side, on
``dtheta_i`` (paper eq. 7), or with ``joint_friction="motor"`` on ``dq_mi``
(a joint's ``friction_side`` chooses for that joint). A joint's ``damping`` is a
damper across its spring, on ``dq_mi - dtheta_i``.
The rotor of joint ``i`` is carried by link ``i-1`` (the base for ``i = 0``)
and turns ``N`` times (the joint's ``gear_ratio``) as fast as the motor angle:
with ``J_m = N**2 J_r`` its inertia seen on the link side, its kinetic energy is
``1/2 J_r (carrier angle rate + N dq_mi)**2 = 1/2 J_m (carrier angle rate / N +
dq_mi)**2``, which gives the inertial coupling ``S`` of the paper (``J_m / N`` per
carrier rate) and adds the rotor's own ``J_r`` to its carrier (with
``rotor_coupling=False`` only ``1/2 J_m dq_mi**2``, Spong's simplification).
The rotor's mass belongs in the hub mass. Joint springs add their potential to ``V``, and
gravity (``gravity``) the potential of every mass (:mod:`flexarm.model.gravity`):
:meth:`FlexibleArm.equilibrium` gives the static sag and holding torques.

Rigid joints (:class:`flexarm.model.joints.RigidJoint`) have no spring: the
motor angle is the joint angle, so ``q`` holds no motor angles; the rotor's
kinetic energy is ``1/2 J_m (carrier angle rate / N + dtheta_i)**2``, the input
torque, viscous damping and friction act on ``dtheta_i``. An arm takes flexible
joints or rigid ones, not both.

Hubs and payload: ``Link.hub_inertia`` turns with its link; ``Link.hub_mass``
is a point mass at the joint, carried by the previous link's tip. The payload
is a point mass with rotary inertia at the last tip, turning with the tip
slope.

Boundary conditions of the assumed modes (``boundary``):
``"clamped-free"`` uses cantilever modes for every link. ``"clamped-mass"``
clamps link ``i`` at its joint and loads its tip with the mass and rotary
inertia of everything outboard: all outboard beams, hubs and the payload, with
the outboard chain straight (joint angles zero) and its inertia taken about
the tip of link ``i``.

The Lagrangian is evaluated body by body (:mod:`flexarm.model.lagrangian`);
:meth:`FlexibleArm.coriolis` returns the Christoffel matrix (``Mdot - 2C``
skew-symmetric) from exact complex-step derivatives of ``M``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import (
    check_array,
    check_bool,
    check_option,
    check_real,
    check_sequence_of,
    validate_real_fields,
)
from ..errors import InvalidValueError
from .arrays import ArmArrays
from .backends import Backends
from .beam import NORMALIZATIONS, BeamModes
from .drives import Drive, check_drives, drive_torques
from .foreshortening import shortening_matrix
from .gravity import check_gravity, gravity_forces, gravity_potential
from .joints import FRICTION_SIDES, LinearJoint, NonlinearJoint, RigidJoint, check_joints
from .kinematics import RigidKinematics
from .lagrangian import body_terms, christoffel_matrix, mass_matrix_derivatives
from .link import AnyLink, Link, RigidLink
from .packing import outboard_loads, pack
from .statics import Equilibrium, equilibrium
from .validity import PAPER_DEFLECTION_ERROR, PAPER_MODEL_NOTE

__all__ = [
    "BOUNDARIES",
    "FRICTION_SIDES",
    "PAPER_DEFLECTION_ERROR",
    "PAPER_MODEL_NOTE",
    "FlexibleArm",
]

BOUNDARIES = ("clamped-free", "clamped-mass")

_OWNER = "FlexibleArm"

AnyJoint = LinearJoint | NonlinearJoint | RigidJoint


@dataclass(frozen=True)
class FlexibleArm(RigidKinematics, Backends):
    """A planar arm of ``N >= 1`` flexible links on revolute joints.

    Parameters
    ----------
    links : sequence of Link or RigidLink
        From the base outwards (a :class:`~flexarm.model.link.RigidLink` has no modes).
    payload_mass : float
        Point mass at the last tip, kg (>= 0).
    payload_inertia : float
        Rotary inertia of the payload about the tip, kg m**2 (>= 0).
    boundary : {"clamped-mass", "clamped-free"}
        Boundary conditions of the assumed modes (module docstring); default
        ``"clamped-mass"``, which converges with a few modes where the paper's
        ``"clamped-free"`` does not (user guide, "How many modes").
    joints : sequence of LinearJoint, NonlinearJoint or RigidJoint, optional
        One joint per link (None: rigid joints without rotors or friction).
        Flexible joints add the motor angles to ``q``; rigid joints
        (:class:`~flexarm.model.joints.RigidJoint`) add their rotors, viscous and
        Makkar friction to the joint angles. An arm takes flexible joints or rigid
        ones, not both.
    mode_normalization : {"mass", "amplitude", "tip"}
        Scaling of the mode shapes (:mod:`flexarm.modes`); default ``"mass"``.
    mode_amplitude : float
        The paper's ``A`` when ``mode_normalization="amplitude"``.
    joint_friction : {"link", "motor"}
        Where joint friction acts (default ``"link"``, paper eq. 7), for every
        joint whose ``friction_side`` is None.
    rotor_coupling : bool
        Whether a rotor's kinetic energy includes its carrier link's rotation
        (the paper's ``S``; default True).
    geometric_stiffening : bool
        Whether the kinematic map holds the foreshortening of bent links
        (:mod:`flexarm.model.foreshortening`) and the dynamics the centrifugal
        stiffening it brings; default True. False is the paper's linear
        kinematics, which diverge once a link turns faster than its first
        bending frequency.
    gravity : (float, float), optional
        The gravitational acceleration ``(g_x, g_y)`` in the base frame of the
        plane of motion, m/s**2, e.g. ``(0, -9.81)`` for an arm in a vertical
        plane with ``y`` up (:mod:`flexarm.model.gravity`). None (default): a
        horizontal plane, no gravity terms at all.
    drives : sequence of Drive or None, optional
        One :class:`~flexarm.model.drives.Drive` (or None) per joint: the input of a
        driven joint is its motor current (A), :meth:`joint_torques` turns the
        inputs into the joint torques. The model takes the rotor from the joint
        (give a geared rotor's ``N**2 J_r`` as its ``motor_inertia`` with
        ``gear_ratio=N``), not from the drive.

    Examples
    --------
    >>> arm = FlexibleArm.paper()
    >>> arm.n_dof
    4
    >>> round(float(arm.link_frequencies[0][0]), 3)
    12.281
    >>> user = FlexibleArm([Link(4.5, 1676.0, 0.335)] * 2)   # the defaults
    >>> user.n_modes, user.boundary, user.geometric_stiffening
    ((3, 3), 'clamped-mass', True)
    """

    links: Sequence[Link | RigidLink]
    payload_mass: float = 0.0
    payload_inertia: float = 0.0
    boundary: str = "clamped-mass"
    joints: Sequence[LinearJoint | NonlinearJoint | RigidJoint] | None = None
    mode_normalization: str = "mass"
    mode_amplitude: float = 0.1
    joint_friction: str = "link"
    rotor_coupling: bool = True
    geometric_stiffening: bool = True
    gravity: tuple[float, float] | None = None
    drives: Sequence[Drive | None] | None = None
    _derived: dict[str, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        links = check_sequence_of(
            self.links, "links", _OWNER, (Link, RigidLink), "Link or RigidLink"
        )
        if len(links) == 0:
            raise InvalidValueError(
                f"The 'links' parameter of {_OWNER} must hold >= 1 Link. Got 0 instead."
            )
        set_(self, "links", links)
        validate_real_fields(self, _OWNER, nonnegative=("payload_mass", "payload_inertia"))
        check_option(self.boundary, "boundary", _OWNER, BOUNDARIES)
        if self.joints is not None:
            set_(self, "joints", check_joints(self.joints, len(links), _OWNER))
        check_option(self.joint_friction, "joint_friction", _OWNER, FRICTION_SIDES)
        if self.drives is not None:
            set_(self, "drives", check_drives(self.drives, len(links), _OWNER))
        for flag in ("rotor_coupling", "geometric_stiffening"):
            check_bool(getattr(self, flag), flag, _OWNER)
        check_option(self.mode_normalization, "mode_normalization", _OWNER, NORMALIZATIONS)
        set_(self, "gravity", check_gravity(self.gravity, _OWNER))
        set_(
            self,
            "mode_amplitude",
            check_real(self.mode_amplitude, "mode_amplitude", _OWNER, positive=True),
        )
        modes = tuple(
            BeamModes(
                lk.length,
                lk.flexural_rigidity,
                lk.linear_density,
                lk.n_modes,
                tip_mass=tm,
                tip_inertia=tj,
                normalization=self.mode_normalization,
                amplitude=self.mode_amplitude,
            )
            if isinstance(lk, Link)
            else _no_modes(lk.length)
            for lk, (tm, tj) in zip(links, outboard_loads(self), strict=True)
        )
        self._derived["modes"] = modes
        self._derived["arrays"] = pack(self)

    # ------------------------------------------------------------ construction
    @classmethod
    def paper(cls, **overrides: Any) -> FlexibleArm:
        """The arm of Sasiadek et al. (2014) as the paper models it: two links of
        4.5 m, ``EI = 1676 N m**2``, ``rho = 0.335 kg/m``, no hubs or payload, one
        clamped-free mode per link and no geometric stiffening.

        Keyword arguments override :class:`FlexibleArm` parameters; ``n_modes``
        overrides the modes kept per link.

        Notes
        -----
        This is the paper's model, kept so the paper can be reproduced; it is not
        a converged model of that arm (:data:`PAPER_MODEL_NOTE`).

        * *Modal basis.* One clamped-free mode per link ignores that link 1
          carries link 2. Held against Exudyn's geometrically exact ANCF cables
          on the default square (quintic timing, joint motion prescribed), its
          link-1 tip deflection is off by 78 mm where the deflection peaks at
          63 mm (1.2 times the peak, :data:`PAPER_DEFLECTION_ERROR`); three
          clamped-mass modes per link with geometric stiffening — the default of
          an arm you build, e.g. ``FlexibleArm.paper(n_modes=3,
          boundary="clamped-mass", geometric_stiffening=True)`` — are within
          0.02 mm. :func:`flexarm.studies.modal_convergence.convergence_check`
          runs the comparison on your motion.
        * *No geometric stiffening.* Deflections enter the kinematics linearly:
          a link turning faster than its first bending frequency diverges
          (:mod:`flexarm.model.foreshortening`).
        * *No hubs: a stiff arm.* With massless joints every loop closed on it
          is stiff: on the default square the paper's collocated
          Jacobian-transpose PD has its fastest closed-loop pole between about
          -1,700 and -4,500 rad/s with one mode per link (-31,700 to -86,000 rad/s
          with three), so sampled-data control at 1-2 kHz is unstable and
          simulations need small steps. Hub and motor inertia slow these poles
          (1 kg m**2 at each joint: -450 to -1,200 rad/s with one mode per link).
        """
        n_modes = overrides.pop("n_modes", 1)
        overrides.setdefault("boundary", "clamped-free")
        overrides.setdefault("geometric_stiffening", False)
        link = Link(4.5, 1676.0, 0.335, n_modes=n_modes)
        return cls(links=(link, link), **overrides)

    def with_modes(self, n_modes: int | Sequence[int], **overrides: Any) -> FlexibleArm:
        """A copy of this arm keeping ``n_modes`` modes per link (one number for
        every link, or one per link); keyword arguments override other
        :class:`FlexibleArm` parameters (``boundary``, ``geometric_stiffening``, ...).
        """
        if isinstance(n_modes, int | np.integer):
            counts = [int(n_modes)] * self.n_links
        else:
            counts = [int(k) for k in n_modes]
        if len(counts) != self.n_links:
            raise InvalidValueError(
                f"The 'n_modes' parameter of {_OWNER}.with_modes must be one number or one "
                f"per link ({self.n_links}). Got {len(counts)} instead."
            )
        links: list[AnyLink] = []
        for i, (lk, k) in enumerate(zip(self.links, counts, strict=True)):
            if isinstance(lk, Link):
                links.append(dataclasses.replace(lk, n_modes=k))
            elif k == 0 or isinstance(n_modes, int | np.integer):
                links.append(lk)  # a rigid link keeps none
            else:
                raise InvalidValueError(
                    f"The 'n_modes' parameter of {_OWNER}.with_modes must be 0 for link {i}, "
                    f"a RigidLink. Got {k} instead."
                )
        return dataclasses.replace(self, links=links, **overrides)

    def joint_torques(self, inputs: ArrayLike) -> NDArray[np.float64]:
        """The joint torques (N m) of joint inputs: a motor current (A) at a joint with
        a :class:`~flexarm.model.drives.Drive` (:meth:`Drive.joint_torque`: less the
        reading's offset, clipped to the amplifier's limit, times ``eta K_t N``), a
        torque (N m) at a joint without one.

        Parameters
        ----------
        inputs : array_like, shape (..., n_links)
            One input per joint, in the joints' order.

        Returns
        -------
        ndarray, shape (..., n_links)
            N m, what :meth:`forward_dynamics` and the simulators take as ``tau``.
        """
        u = check_array(inputs, "inputs", f"{_OWNER}.joint_torques", real=True)
        if u.ndim == 0 or u.shape[-1] != self.n_links:
            raise InvalidValueError(
                f"The 'inputs' parameter of {_OWNER}.joint_torques must have {self.n_links} "
                f"entries (one per joint) along its last axis. Got shape {u.shape} instead."
            )
        return drive_torques(self.drives, u)

    # -------------------------------------------------------------- structure
    @property
    def n_links(self) -> int:
        return len(self.links)

    @property
    def n_modes(self) -> tuple[int, ...]:
        """Modes kept per link."""
        return tuple(lk.n_modes for lk in self.links)

    @property
    def has_flexible_joints(self) -> bool:
        """Whether the joints are flexible (a spring each): then ``q`` holds the
        motor angles. Rigid joints (None, or
        :class:`~flexarm.model.joints.RigidJoint`) have none."""
        return self.joints is not None and not isinstance(self.joints[0], RigidJoint)

    @property
    def _springs(self) -> Sequence[LinearJoint | NonlinearJoint]:
        """The flexible joints (empty for rigid ones)."""
        return self.joints if self.has_flexible_joints else ()  # type: ignore[return-value]

    @property
    def n_dof(self) -> int:
        """Number of generalised coordinates: joint angles, modal coordinates and,
        with flexible joints, motor angles."""
        n = self.n_links + sum(self.n_modes)
        return n + self.n_links if self.has_flexible_joints else n

    @property
    def modes(self) -> tuple[BeamModes, ...]:
        """The assumed modes of each link (with this arm's boundary conditions)."""
        return self._derived["modes"]  # type: ignore[no-any-return]

    @property
    def arrays(self) -> ArmArrays:
        """The arm packed for the compiled kernels (read-only arrays)."""
        return self._derived["arrays"]  # type: ignore[no-any-return]

    @property
    def link_frequencies(self) -> list[NDArray[np.float64]]:
        """Clamped natural frequencies of each link's modes, rad/s."""
        return [bm.frequencies for bm in self.modes]

    def modal_slice(self, link: int) -> slice:
        """Indices in ``q`` of link ``link``'s modal coordinates (0-based link)."""
        link = self._check_link(link)
        s = self.arrays.mode_start
        return slice(int(s[link]), int(s[link + 1]))

    @property
    def motor_slice(self) -> slice:
        """Indices in ``q`` of the motor angles (empty without flexible joints)."""
        start = int(self.arrays.mode_start[-1])
        return slice(start, self.n_dof)

    @property
    def actuated_slice(self) -> slice:
        """Indices in ``q`` that the joint torques drive: the joint angles for rigid
        joints, the motor angles for flexible joints."""
        return self.motor_slice if self.has_flexible_joints else slice(0, self.n_links)

    @property
    def coordinate_names(self) -> list[str]:
        """Names of the coordinates in ``q``: ``theta1``, ..., ``delta2_1`` (link,
        mode), ``qm1``, ... (motor angles)."""
        names = [f"theta{i + 1}" for i in range(self.n_links)]
        for i, nm in enumerate(self.n_modes):
            names += [f"delta{i + 1}_{j + 1}" for j in range(nm)]
        if self.has_flexible_joints:
            names += [f"qm{i + 1}" for i in range(self.n_links)]
        return names

    @property
    def stiffness_matrix(self) -> NDArray[np.float64]:
        """Stiffness ``K``, shape ``(n_dof, n_dof)``: the modal stiffness and, with
        flexible joints, each joint spring linearised at zero deflection
        (``a1 - ksw``) coupling ``theta_i`` and ``q_mi``."""
        K = np.diag(self.arrays.stiffness)
        m = self.motor_slice.start
        for i, jt in enumerate(self._springs):
            _add_across(K, i, m + i, float(jt.tangent_stiffness(0.0)))
        return K

    @property
    def damping_matrix(self) -> NDArray[np.float64]:
        """Linear damping ``D`` (modal damping, motor damping, the joints' dampers
        across their springs), shape ``(n_dof, n_dof)``, in N m s per coordinate
        rate. Joint friction is not included."""
        D = np.diag(self.arrays.damping)  # with rigid joints' viscous friction
        m = self.motor_slice.start
        for i, jt in enumerate(self._springs):
            D[m + i, m + i] += jt.motor_damping
            _add_across(D, i, m + i, jt.damping)
        return D

    @property
    def friction_sides(self) -> tuple[str, ...]:
        """Where each joint's friction acts, ``"link"`` or ``"motor"`` (a joint's
        ``friction_side``, else the arm's ``joint_friction``); empty without joints."""
        return tuple(jt.friction_side or self.joint_friction for jt in self.joints or ())

    @property
    def friction_coordinates(self) -> tuple[int, ...]:
        """The index in ``q`` on whose rate each joint's friction acts (the joint
        angle or the motor angle, :attr:`friction_sides`)."""
        m = self.motor_slice.start
        return tuple(m + i if side == "motor" else i for i, side in enumerate(self.friction_sides))

    @property
    def input_matrix(self) -> NDArray[np.float64]:
        """``B``, shape ``(n_dof, n_links)``: joint torques act on the joint angles
        (rigid joints) or on the motor angles (flexible joints)."""
        b = np.zeros((self.n_dof, self.n_links))
        b[self.actuated_slice] = np.eye(self.n_links)
        return b

    # ------------------------------------------------------------- validation
    def _check_q(self, q: ArrayLike, name: str = "q") -> NDArray[Any]:
        return check_array(q, name, _OWNER, shape=(self.n_dof,))

    # --------------------------------------------------- body Jacobians (NumPy)
    def _mass_matrix_numpy(self, q: NDArray[Any]) -> NDArray[Any]:
        """The NumPy reference of :meth:`mass_matrix` for one ``q`` (real or complex)."""
        M = np.zeros((self.n_dof, self.n_dof), dtype=np.result_type(q, float))
        for Jb, Mb, _ in body_terms(self, q, None):
            M += Jb.T @ Mb @ Jb
        return 0.5 * (M + M.T)

    def velocity_terms(self, q: ArrayLike, dq: ArrayLike) -> NDArray[np.float64]:
        """Centrifugal and Coriolis forces ``C(q, dq) dq``, shape ``(n_dof,)``."""
        q, dq = self._check_q(q), self._check_q(dq, "dq")
        h = np.zeros(self.n_dof, dtype=np.result_type(q, dq, float))
        for Jb, _, beta in body_terms(self, q, dq):
            assert beta is not None
            h += Jb.T @ beta
        return h

    def mass_matrix_derivatives(self, q: ArrayLike) -> NDArray[np.float64]:
        """``dM/dq_k`` for every ``k``, shape ``(n_dof, n_dof, n_dof)`` (k first),
        by complex-step differentiation (exact to rounding)."""
        return mass_matrix_derivatives(self._mass_matrix_numpy, self._check_q(q).real)

    def coriolis(self, q: ArrayLike, dq: ArrayLike) -> NDArray[np.float64]:
        """The Coriolis matrix ``C(q, dq)`` from Christoffel symbols of the first kind.

        ``C(q, dq) dq`` equals :meth:`velocity_terms` and ``Mdot - 2 C`` is
        skew-symmetric. Shape ``(n_dof, n_dof)``.
        """
        q, dq = self._check_q(q), self._check_q(dq, "dq")
        return christoffel_matrix(self.mass_matrix_derivatives(q), dq)

    def generalized_forces(
        self, q: NDArray[Any], dq: NDArray[Any], tau: NDArray[Any]
    ) -> NDArray[Any]:
        """Generalised forces other than inertia, shape ``(n_dof,)``: ``B tau``, the
        modal stiffness and damping, the joints' spring, friction and motor
        damping torques, and gravity (:func:`flexarm.model.gravity.gravity_forces`)."""
        out = -self.arrays.stiffness * q - self.arrays.damping * dq
        if self.gravity is not None:
            out = out + gravity_forces(self, q)
        if not self.has_flexible_joints:  # rigid joints: damping in arrays.damping
            out[: self.n_links] += tau
            for i, jt in enumerate(self.joints or ()):
                if jt.friction is not None:
                    out[i] -= jt.friction(dq[i])
            return out  # type: ignore[no-any-return]
        m0 = self.motor_slice.start
        for i, jt in enumerate(self._springs):
            m = m0 + i
            ts = jt.torque(q[m] - q[i]) + jt.damping * (dq[m] - dq[i])
            out[i] += ts
            out[m] += tau[i] - ts - jt.motor_damping * dq[m]
            if jt.friction is not None:
                k = self.friction_coordinates[i]
                out[k] -= jt.friction(dq[k])
        return out  # type: ignore[no-any-return]

    def _forward_dynamics_numpy(
        self, q: NDArray[Any], dq: NDArray[Any], tau: NDArray[Any]
    ) -> NDArray[Any]:
        """The NumPy reference of :meth:`forward_dynamics` for one state."""
        rhs = self.generalized_forces(q, dq, tau) - self.velocity_terms(q, dq)
        return np.linalg.solve(self._mass_matrix_numpy(q), rhs)

    def energy(self, q: ArrayLike, dq: ArrayLike) -> tuple[float, float]:
        """Kinetic and potential (elastic: links and joint springs; and gravity's,
        zero at the base, with ``gravity``) energy in J."""
        q, dq = self._check_q(q), self._check_q(dq, "dq")
        kinetic = 0.5 * dq @ self.mass_matrix(q) @ dq
        potential = 0.5 * q @ (self.arrays.stiffness * q)
        if self.gravity is not None:
            potential += gravity_potential(self, q)
        m0 = self.motor_slice.start
        for i, jt in enumerate(self._springs):
            potential += float(jt.potential(q[m0 + i] - q[i]))
        return float(kinetic), float(potential)

    def equilibrium(self, q_joints: ArrayLike, *, require_stable: bool = True) -> Equilibrium:
        """The arm at rest holding the joint angles ``q_joints`` (rad, shape
        ``(n_links,)``) against gravity: the links' static sag, the holding torques
        and the tangent stiffness there (:func:`flexarm.model.statics.equilibrium`).

        Raises :class:`flexarm.model.statics.UnstableEquilibriumError` where the held
        posture is unstable (a standing link beyond its buckling load) unless
        ``require_stable=False``, which returns it flagged ``stable=False``.

        Examples
        --------
        >>> arm = FlexibleArm([Link(1.0, 100.0, 1.0, n_modes=2)], gravity=(0.0, -9.81))
        >>> eq = arm.equilibrium([0.0])
        >>> round(float(eq.torques[0]), 4)   # holds rho L g L / 2
        4.905
        """
        return equilibrium(self, q_joints, require_stable=require_stable)

    def natural_frequencies(
        self, q: ArrayLike | None = None, joints: str = "locked"
    ) -> NDArray[np.float64]:
        """Natural frequencies of the arm linearised about a configuration at rest.

        Parameters
        ----------
        q : array_like, shape (n_dof,), optional
            Configuration (default: straight arm, all zeros). Modal coordinates
            should be zero for a meaningful linearisation.
        joints : {"locked", "free"}
            ``"locked"`` holds the actuated coordinates (joint angles, or motor
            angles with flexible joints) fixed, as infinitely stiff servos would;
            ``"free"`` leaves them unactuated (``tau = 0``): the ``n_links``
            rigid-body motions have zero frequency and are left out.

        Returns
        -------
        ndarray
            Increasing frequencies in rad/s: one per elastic degree of freedom
            (modal coordinates, plus joint springs).

        Notes
        -----
        The stiffness is the elastic one alone; with gravity, the frequencies
        about a posture that carries its weight (gravity's stiffening of a
        hanging link, softening of a standing one) are
        ``equilibrium(theta).frequencies``.
        """
        check_option(joints, "joints", _OWNER, ("locked", "free"))
        q = np.zeros(self.n_dof) if q is None else self._check_q(q)
        M, K = self.mass_matrix(q).real, self.stiffness_matrix
        keep = np.ones(self.n_dof, dtype=bool)
        if joints == "locked":
            keep[self.actuated_slice] = False
        M, K = M[np.ix_(keep, keep)], K[np.ix_(keep, keep)]
        if M.size == 0:
            return np.zeros(0)
        import scipy.linalg  # loaded on first use: import flexarm stays light

        lam = scipy.linalg.eigh(K, M, eigvals_only=True)
        if joints == "free":
            lam = lam[self.n_links :]  # the rigid-body modes (zero eigenvalues)
        return np.sqrt(np.clip(lam, 0.0, None))  # type: ignore[no-any-return]

    # -------------------------------------------------------------- kinematics
    def point_basis(self, link: int, distance: float) -> NDArray[np.float64]:
        """What the compiled :func:`flexarm.model.dynamics.point_kinematics` needs of a
        point: ``link``'s mode shapes at ``distance`` and, with geometric
        stiffening, the shortening matrix ``S(distance)`` row by row.

        Returns
        -------
        ndarray, shape (n_modes,) or (n_modes + n_modes**2,)
            Contiguous, float64.
        """
        link = self._check_link(link)
        distance = check_real(distance, "distance", _OWNER)
        modes = self.modes[link]
        phi = modes.shape(distance)[:, 0]
        if not self.geometric_stiffening:
            return np.ascontiguousarray(phi)
        S = shortening_matrix(modes, distance)[:, :, 0]
        return np.ascontiguousarray(np.concatenate([phi, S.ravel()]))

    @property
    def link_lengths(self) -> NDArray[np.float64]:
        """Link lengths, m, shape ``(n_links,)``."""
        return np.array([lk.length for lk in self.links], dtype=float)


def _no_modes(length: float) -> BeamModes:
    """The empty modal basis of a rigid link of ``length`` m: no modes, so the beam's
    stiffness and density never enter (placeholders of 1)."""
    return BeamModes(length, 1.0, 1.0, 0)


def _add_across(matrix: NDArray[np.float64], i: int, j: int, value: float) -> None:
    """Add, in place, a linear element of coefficient ``value`` acting across
    coordinates ``i`` and ``j`` (a joint's spring or damper between its link angle
    and its motor angle): ``+value`` on both diagonals, ``-value`` off them."""
    matrix[i, i] += value
    matrix[j, j] += value
    matrix[i, j] -= value
    matrix[j, i] -= value
