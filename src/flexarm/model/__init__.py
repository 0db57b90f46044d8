"""The plant: beam modes, links, joints, the arm and its compiled dynamics.

* :mod:`~flexarm.model.beam` — Euler–Bernoulli assumed modes (clamped-free, clamped-mass),
  public as :mod:`flexarm.modes` too;
* :mod:`~flexarm.model.link`, :mod:`~flexarm.model.joints` — link and joint parameters;
* :mod:`~flexarm.model.arm` — :class:`FlexibleArm`, the NumPy reference of the dynamics;
* :mod:`~flexarm.model.kinematics`, :mod:`~flexarm.model.lagrangian` — its kinematics and
  Lagrangian as functions of arrays; :mod:`~flexarm.model.foreshortening` — the axial
  shortening of bent links (geometric stiffening) and its modal integrals;
* :mod:`~flexarm.model.gravity`, :mod:`~flexarm.model.statics` — gravity in the plane of
  motion (its potential and forces) and the arm at rest under it (sag, holding torques,
  buckling);
* :mod:`~flexarm.model.prescribed` — the arm with its joint motion prescribed;
* :mod:`~flexarm.model.validity` — what the model choices leave out, measured;
* :mod:`~flexarm.model.arrays`, :mod:`~flexarm.model.dynamics` — the arm packed as plain
  arrays and the compiled kernels that read them (for your own Numba loops): the
  dense, the recursive (articulated-body) and the paper's scalar forward dynamics,
  the mass matrix, the kinematics of a point;
* :mod:`~flexarm.model.packed`, :mod:`~flexarm.model.backends` — the kernels behind
  cheap calls from Python (one packed buffer per arm), and which backend a public call
  of the arm takes;
* :mod:`~flexarm.model.plant` — :class:`Plant`, what the simulator reads of an arm.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

_SUBMODULES = (
    "arm",
    "arrays",
    "beam",
    "drives",
    "dynamics",
    "foreshortening",
    "gravity",
    "joints",
    "kinematics",
    "lagrangian",
    "link",
    "plant",
    "prescribed",
    "statics",
    "validity",
)
_NAMES = {
    "BeamModes": "beam",
    "Drive": "drives",
    "FlexibleArm": "arm",
    "LinearJoint": "joints",
    "Link": "link",
    "MakkarFriction": "joints",
    "NonlinearJoint": "joints",
    "Plant": "plant",
    "RigidJoint": "joints",
    "RigidLink": "link",
    "cantilever_roots": "beam",
    "clamped_mass_roots": "beam",
}

__getattr__, __dir__, __all__ = attach(__name__, _SUBMODULES, _NAMES)

if TYPE_CHECKING:  # what type checkers see; nothing is imported at run time
    from .arm import FlexibleArm as FlexibleArm
    from .beam import BeamModes as BeamModes
    from .beam import cantilever_roots as cantilever_roots
    from .beam import clamped_mass_roots as clamped_mass_roots
    from .drives import Drive as Drive
    from .joints import LinearJoint as LinearJoint
    from .joints import MakkarFriction as MakkarFriction
    from .joints import NonlinearJoint as NonlinearJoint
    from .joints import RigidJoint as RigidJoint
    from .link import Link as Link
    from .link import RigidLink as RigidLink
    from .plant import Plant as Plant
