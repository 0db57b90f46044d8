"""The arm packed as plain arrays for compiled code: :class:`ArmArrays`, :class:`Workspace`.

:attr:`flexarm.FlexibleArm.arrays` builds an :class:`ArmArrays` once (with
:func:`pack_arm_arrays`, by keyword); the compiled kernels of
:mod:`flexarm.model.dynamics` read it. This module needs NumPy only, so an arm
can be built without loading Numba.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidValueError

__all__ = [
    "AX_BETA",
    "AX_BETA_MODES",
    "AX_IALPHA",
    "AX_Q",
    "AX_ROWS",
    "AX_SL",
    "AX_TIP",
    "AX_WALPHA",
    "AX_Y",
    "CH_AD",
    "CH_COS",
    "CH_CX",
    "CH_CY",
    "CH_D",
    "CH_E",
    "CH_EX",
    "CH_IAH",
    "CH_LT",
    "CH_SIN",
    "CH_U",
    "CH_Z",
    "CH_ZB",
    "HUB_MASS",
    "INERTIA",
    "J_A1",
    "J_A2",
    "J_ASW",
    "J_COUPLED",
    "J_DAMPING",
    "J_FRICTION_ON_MOTOR",
    "J_G1",
    "J_HAS_FRICTION",
    "J_INERTIA",
    "J_KSW",
    "J_SPRING_DAMPING",
    "LEN",
    "MASS",
    "N_CHAIN_COLUMNS",
    "N_JOINT_COLUMNS",
    "N_LINK_COLUMNS",
    "ROTOR_COUPLING",
    "ROTOR_FRICTION",
    "ROTOR_G1",
    "ROTOR_INERTIA",
    "STATIC",
    "TIP_INERTIA",
    "ArmArrays",
    "Workspace",
    "field_shapes",
    "make_workspace",
    "pack_arm_arrays",
    "workspace_shapes",
    "workspace_size",
]

F64 = NDArray[np.float64]

# Columns of ArmArrays.link
LEN, MASS, STATIC, INERTIA, HUB_MASS = 0, 1, 2, 3, 4
TIP_INERTIA = 5  # rotary inertia at the tip, turning with the tip slope (not the last link's)
ROTOR_INERTIA, ROTOR_COUPLING = 6, 7  # a rigid joint's rotor: J_m, 1 / N (0: uncoupled)
ROTOR_FRICTION, ROTOR_G1 = 8, 9  # a rigid joint's friction: flag, Makkar g1..g6
N_LINK_COLUMNS = 15
# Columns of ArmArrays.joint
J_A1, J_A2, J_KSW, J_ASW, J_INERTIA, J_DAMPING, J_COUPLED = 0, 1, 2, 3, 4, 5, 6
J_HAS_FRICTION, J_FRICTION_ON_MOTOR, J_G1 = 7, 8, 9
J_SPRING_DAMPING = 15  # viscous damping across the spring, on dq_m - dq
N_JOINT_COLUMNS = 16
# Rows of Workspace.axial (one link's foreshortening terms, by local mode index)
AX_TIP = 0  # u(L), delta_dot' S(L) delta_dot, (S(L) delta) . delta_dot
AX_SL = 1  # S(L) delta
AX_Y = 2  # int rho S delta
AX_WALPHA = 3  # added to Mb[alpha, delta]
AX_IALPHA = 4  # [0]: added to Mb[alpha, alpha]
AX_BETA = 5  # added to beta_ux, beta_uy, beta_alpha
AX_BETA_MODES = 6  # added to beta_delta
AX_ROWS = 7
AX_Q = AX_ROWS  # then K rows of Q, K rows of R, K rows of Q~ (K = n_dof)
# Columns of Workspace.chain, the recursive algorithm's records (flexarm.model.dynamics).
# Row i < n_links (joint i) holds link i's; row g of a modal coordinate holds that mode's.
CH_AD = 0  # absolute angular rate of link i, rad/s
CH_COS, CH_SIN = 1, 2  # cos, sin of the angle from link i-1's frame to link i's
CH_IAH = 3  # 3 columns: the articulated inertia of link i's subtree times the joint axis
CH_D, CH_U = 6, 7  # its pivot (inertia about joint i) and the joint's force less the bias
CH_LT, CH_E = 8, 9  # the tip of link i in its frame, m
CH_CX, CH_CY = 10, 11  # velocity-dependent acceleration of the tip relative to its joint
N_CHAIN_COLUMNS = 12
CH_Z = 0  # modal rows, 3 columns: K_dd^-1 K_da (the mode's answer to its frame's acceleration)
CH_ZB = 3  # K_dd^-1 (Q_delta - k_delta): the mode's acceleration at zero frame acceleration
CH_EX = 4  # the tip's axial velocity per unit mode rate (foreshortening), m


class ArmArrays(NamedTuple):
    """The arm packed as plain arrays for the compiled kernels.

    Attributes
    ----------
    mode_start : int64 array, shape (n_links + 1,)
        Index in ``q`` of link ``i``'s first modal coordinate; link ``i`` owns
        ``q[mode_start[i]:mode_start[i + 1]]``.
    link : float array, shape (n_links, 15)
        Per link: length (m), mass ``rho L`` (kg), static moment ``rho L**2 / 2``
        (kg m), inertia about the joint ``rho L**3 / 3 + hub_inertia`` (kg m**2)
        (a rigid link: its mass, first moment and inertia about the joint), the
        point mass at the joint (kg: its hub and the previous link's tip body),
        the rotary inertia of its tip body (kg m**2; the last link's is in
        ``payload``), and a rigid joint's rotor
        (:class:`~flexarm.model.joints.RigidJoint`) driving it:
        ``J_m`` (kg m**2), coupling ``1 / N`` (0: uncoupled or no rotor), friction
        flag and Makkar ``g1..g6``.
    mass_integral, moment_integral, tip_deflection, tip_slope : float arrays, shape (n_dof,)
        ``int rho phi``, ``int rho x phi``, ``phi(L)``, ``phi'(L)`` at each modal
        coordinate's index in ``q`` (zero at joint indices).
    modal_mass : float array, shape (n_dof, n_dof)
        ``int rho phi_j phi_k`` within each link's block, zero elsewhere.
    stiffness, damping : float arrays, shape (n_dof,)
        Diagonal of the stiffness (N m) and damping (N m s) matrices.
    payload : float array, shape (2,)
        Payload mass (kg) and rotary inertia (kg m**2) at the last link's tip.
    shortening_tip, shortening_mass, shortening_moment : float arrays, shape (n_dof, n_dof)
        The foreshortening integrals ``S(L)``, ``int rho S dx`` and
        ``int rho x S dx`` of :mod:`flexarm.model.foreshortening` within each
        link's block, zero elsewhere (all zero without geometric stiffening).
    shortening_cubic : float array, shape (n_dof, K, K)
        Row ``g`` (a modal coordinate of link ``i``, whose first is ``a0``):
        ``int rho phi_g S_bc dx`` for link ``i``'s modes ``a0 + b``, ``a0 + c``.
        ``K`` is the most modes of any link with geometric stiffening, 0
        without: ``K == 0`` switches every foreshortening term off.
    shortening_quartic : float array, shape (n_dof, K, K, K)
        Row ``g``: ``int rho S_ga S_cd dx`` over link ``i``'s modes
        (``a0 + a``, ``a0 + c``, ``a0 + d``), indexed ``[g, a, c, d]``.
    gravity : float array, shape (2,)
        The gravitational acceleration ``(g_x, g_y)`` in the base frame, m/s**2
        (:mod:`flexarm.model.gravity`). ``(0, 0)`` (an arm built with
        ``gravity=None``) switches every gravity term off: the kernels skip them.
    joint : float array, shape (n_joints, 16)
        Flexible joints (``n_joints`` is 0 for rigid joints or ``n_links``), one
        row each: ``a1, a2, ksw, asw`` of the spring law (a linear joint is
        ``k, 0, 0, 0``), reflected motor inertia ``J_m``, motor viscous damping,
        rotor coupling ``1 / N`` (``N`` the gear ratio; 0: Spong's uncoupled
        rotor: the rotor's kinetic energy is ``1/2 J_m (carrier rate / N +
        dq_m)**2`` in link-side units), friction
        flag, friction side (0: link, 1: motor), Makkar ``g1..g6``, the spring's
        viscous damping (N m s/rad, on ``dq_m - dq``). The motor
        angle of joint ``i`` is ``q[mode_start[-1] + i]``.
    """

    mode_start: NDArray[np.int64]
    link: F64
    mass_integral: F64
    moment_integral: F64
    tip_deflection: F64
    tip_slope: F64
    modal_mass: F64
    stiffness: F64
    damping: F64
    payload: F64
    joint: F64
    shortening_tip: F64
    shortening_mass: F64
    shortening_moment: F64
    shortening_cubic: F64
    shortening_quartic: F64
    gravity: F64


class Workspace(NamedTuple):
    """Scratch arrays for one thread of kernel calls (``n = n_dof``).

    ``mass`` and ``bias`` hold :func:`mass_and_bias`'s results in the order of
    ``q``; the other arrays are scratch of the solvers: the dense one works in
    the link-major order of :func:`local_order`, the recursive one
    (:func:`flexarm.model.dynamics.forward_dynamics_recursive`) keeps its records in ``chain``
    and each link's modal block in ``lmass``.
    """

    mass: F64  # (n, n) M(q), order of q
    bias: F64  # (n,) C(q, dq) dq, order of q
    jac: F64  # (2, n) base velocity Jacobian of the current link, link frame, local order
    angle: F64  # (n,) gradient of the current link's absolute angle, local order
    rhs: F64  # (n,) generalised forces, order of q
    rows: F64  # (3, n) rows of the body inertia times the body Jacobian, local order
    lmass: F64  # (n, n) lower triangle of M, then its LDL' factor, local order
    lbias: F64  # (n,) C(q, dq) dq, then the right-hand side and solution, local order
    inv_diag: F64  # (n,) reciprocal pivots of the LDL' factor
    axial: F64  # (AX_ROWS + 3 n, max(n, 3)) one link's foreshortening terms (AX_* rows)
    chain: F64  # (n, N_CHAIN_COLUMNS) the recursive algorithm's records (CH_* columns)


def workspace_shapes(n_dof: int) -> dict[str, tuple[int, ...]]:
    """The shape of each :class:`Workspace` array for ``n_dof`` coordinates, in field
    order (the one layout :func:`make_workspace`, the checks and the flat workspace
    of :mod:`flexarm.model.packed` share)."""
    n = int(n_dof)
    return {
        "mass": (n, n),
        "bias": (n,),
        "jac": (2, n),
        "angle": (n,),
        "rhs": (n,),
        "rows": (3, n),
        "lmass": (n, n),
        "lbias": (n,),
        "inv_diag": (n,),
        "axial": (AX_ROWS + 3 * n, max(n, 3)),
        "chain": (n, N_CHAIN_COLUMNS),
    }


def workspace_size(n_dof: int) -> int:
    """Number of float64 values in a :class:`Workspace` for ``n_dof`` coordinates."""
    return sum(int(np.prod(shape)) for shape in workspace_shapes(n_dof).values())


def make_workspace(n_dof: int) -> Workspace:
    """Allocate the scratch arrays for an arm with ``n_dof`` coordinates."""
    return Workspace(**{name: np.zeros(shape) for name, shape in workspace_shapes(n_dof).items()})


def field_shapes(
    n_links: int, n_dof: int, k: int, n_joints: int | None = None
) -> dict[str, tuple[int, ...]]:
    """The shape of each field of :class:`ArmArrays` of ``n_links`` links, ``n_dof``
    degrees of freedom, ``k`` foreshortened modes a link at the most and ``n_joints``
    flexible joints (``n_links`` or none; default ``n_links``)."""
    n = n_dof
    return {
        "link": (n_links, N_LINK_COLUMNS),
        "mass_integral": (n,),
        "moment_integral": (n,),
        "tip_deflection": (n,),
        "tip_slope": (n,),
        "modal_mass": (n, n),
        "stiffness": (n,),
        "damping": (n,),
        "payload": (2,),
        "joint": (n_links if n_joints is None else n_joints, N_JOINT_COLUMNS),
        "shortening_tip": (n, n),
        "shortening_mass": (n, n),
        "shortening_moment": (n, n),
        "shortening_cubic": (n, k, k),
        "shortening_quartic": (n, k, k, k),
        "gravity": (2,),
    }


def pack_arm_arrays(
    *,
    mode_start: NDArray[np.int64],
    link: F64,
    mass_integral: F64,
    moment_integral: F64,
    tip_deflection: F64,
    tip_slope: F64,
    modal_mass: F64,
    stiffness: F64,
    damping: F64,
    payload: F64,
    joint: F64,
    shortening_tip: F64 | None = None,
    shortening_mass: F64 | None = None,
    shortening_moment: F64 | None = None,
    shortening_cubic: F64 | None = None,
    shortening_quartic: F64 | None = None,
    gravity: F64 | None = None,
) -> ArmArrays:
    """The one way to build :class:`ArmArrays`: by keyword, shapes and dtypes checked,
    every array contiguous and read-only.

    The foreshortening arrays default to none (zero, ``K = 0``): the arm without
    geometric stiffening; ``gravity`` defaults to ``(0, 0)``: no gravity.

    Raises
    ------
    ValueError
        If an array's shape does not fit the others (``n_links`` from
        ``mode_start``, ``n_dof`` from ``mass_integral``).
    """
    ms = np.ascontiguousarray(mode_start, dtype=np.int64)
    n_links = ms.shape[0] - 1
    n = int(np.asarray(mass_integral).shape[0])
    k = 0 if shortening_cubic is None else int(np.asarray(shortening_cubic).shape[-1])
    shapes = field_shapes(n_links, n, k)
    del shapes["joint"]  # its rows are checked below: none, or one per link
    none2, none3, none4 = np.zeros((n, n)), np.zeros((n, 0, 0)), np.zeros((n, 0, 0, 0))
    given = {
        "link": link,
        "mass_integral": mass_integral,
        "moment_integral": moment_integral,
        "tip_deflection": tip_deflection,
        "tip_slope": tip_slope,
        "modal_mass": modal_mass,
        "stiffness": stiffness,
        "damping": damping,
        "payload": payload,
        "joint": joint,
        "shortening_tip": none2 if shortening_tip is None else shortening_tip,
        "shortening_mass": none2 if shortening_mass is None else shortening_mass,
        "shortening_moment": none2 if shortening_moment is None else shortening_moment,
        "shortening_cubic": none3 if shortening_cubic is None else shortening_cubic,
        "shortening_quartic": none4 if shortening_quartic is None else shortening_quartic,
        "gravity": np.zeros(2) if gravity is None else gravity,
    }
    out: dict[str, F64] = {}
    for name, value in given.items():
        arr = np.ascontiguousarray(value, dtype=np.float64)
        want = shapes.get(name, (arr.shape[0], N_JOINT_COLUMNS))
        if arr.shape != want or (name == "joint" and arr.shape[0] not in (0, n_links)):
            raise InvalidValueError(
                f"The '{name}' parameter of pack_arm_arrays must be of shape {want}. "
                f"Got shape {arr.shape} instead."
            )
        arr.flags.writeable = False
        out[name] = arr
    if ms.ndim != 1 or n_links < 1 or ms[0] != n_links or np.any(np.diff(ms) < 0):
        raise InvalidValueError(
            "The 'mode_start' parameter of pack_arm_arrays must start at n_links and "
            f"not decrease. Got {ms.tolist()} instead."
        )
    ms.flags.writeable = False
    return ArmArrays(mode_start=ms, **out)
