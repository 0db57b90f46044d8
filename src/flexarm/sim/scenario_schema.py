"""Scenario files: the schema, reading a TOML file, merging overrides, errors.

:func:`load_scenario` reads a file, :meth:`Scenario.from_dict` builds the same
from a mapping; both return a :class:`Scenario` holding the built library
objects, and ``s.simulate()`` runs it (:func:`flexarm.simulate`).
``flexarm simulate --scenario FILE`` is the command-line front end;
``examples/paper_square.toml`` is a complete file.

Schema
------
Every section and every key is optional; an empty file is the paper's arm
tracking the default square with the paper's Jacobian-transpose PD gains and
joint encoders. Keys are the parameters of the library class that each section
builds, with the same names and SI units::

    [arm]                     # FlexibleArm; default: the paper's arm
    preset = "paper"          # two 4.5 m links (FlexibleArm.paper); or omit it and
                              # give [[arm.links]] instead (not both)
    n_modes = 1               # modes per link of the preset only
    boundary = "clamped-free" # or "clamped-mass" (default with [[arm.links]])
    payload_mass = 0.0        # kg
    payload_inertia = 0.0     # kg m^2
    # also: mode_normalization, mode_amplitude, joint_friction, rotor_coupling,
    # geometric_stiffening (false for the preset, true with [[arm.links]]),
    # gravity = [0.0, -9.81] (m/s^2, base frame; default none: a horizontal plane)

    # [[arm.links]]           # one table per link, base outwards (Link)
    # length = 4.5            # m            (required)
    # flexural_rigidity = 1676.0   # N m^2   (required)
    # linear_density = 0.335  # kg/m         (required)
    # n_modes = 3, hub_mass = 0.0 (kg), hub_inertia = 0.0 (kg m^2), modal_damping = 0.0,
    # tip_mass = 0.0 (kg), tip_inertia = 0.0 (kg m^2): a body at the tip turning with it
    # kind = "rigid"          # a RigidLink instead: length, mass (kg), com (m from the
    #                         # joint), inertia (kg m^2 about the centre of mass), and
    #                         # hub_mass, hub_inertia, tip_mass, tip_inertia

    # [arm.joints]            # the same joint at every link (default: rigid joints)
    # kind = "linear"         # "rigid" | "linear" (LinearJoint.default()) |
    #                         # "nonlinear" (NonlinearJoint.default(MakkarFriction.default()))
    # motor_inertia, damping, gear_ratio, friction    (rigid: a RigidJoint; no keys:
    #                                                   ideal rigid joints)
    # stiffness, motor_inertia, motor_damping          (linear overrides)
    # a1, a2, ksw, asw, motor_inertia, motor_damping   (nonlinear overrides)
    # gear_ratio (default 100), damping (across the spring, N m s/rad),
    # friction_side = "link" | "motor"                  (either kind)
    # friction = true | false | { g1 = ..., ..., g6 = ... }
    #   true: MakkarFriction.default(); a table overrides some of its g's;
    #   default: false for "linear", true for "nonlinear"

    [trajectory]              # the end-effector path
    kind = "square"           # "square" | "circle" | "line" | "point-to-point" |
                              # "waypoints"; the other keys are the parameters of
                              # Square, Circle, Line, PointToPoint or Waypoints
                              # (e.g. center = [5.0, 0.0], side = 4.0, time_per_side = 5.0)

    [sensor]
    kind = "joint"            # "joint" | "tip" | "point" (needs link, 0-based, and
                              # distance, m from that link's joint)
    # noise_std, rate_noise_std, quantization, rate_quantization
    #   (rad and rad/s for "joint"; m and m/s for "tip" and "point")
    # model = "physical"      # "tip"/"point": the deflected point, or "paper": the rigid
    #                         # kinematics of the joint angles at that point (the paper's)

    [controller]
    kind = "pd"               # "pd": the paper's gains JacobianTransposePD.from_arm(arm,
                              #   zeta) (key: zeta = 0.707);
                              # "jt-pd": JacobianTransposePD(kp, kd), N/m and N s/m,
                              #   scalar, [kx, ky] or 2x2;
                              # "joint-pd": JointPD(kp, kd), N m/rad and N m s/rad,
                              #   scalar or one per link;
                              # "fuzzy": the paper's gains (zeta) adapted by the
                              #   paper's fuzzy system, FuzzyAdaptiveJTPD (keys:
                              #   zeta = 0.707, ks = 1.0, law = "scaled" | "damping");
                              # "lqg": observer-based LQG from the sensor alone (keys: the
                              #   LQG parameters, model_modes, model_boundary);
                              # "reflected": PD on the reflected output (alpha, zeta);
                              # "module:factory": your own, factory(arm, **the other
                              #   keys) returning a Controller (flexarm.control.custom;
                              #   module beside this file, in the current directory or
                              #   on sys.path; examples/my_controller.py)

    [delay]                   # transport delay of the sensed signal
    delay = 0.0               # s, or "seed" / "dispersive" (below)
    method = "exact"          # "exact" (sample buffer) | "pade"
    order = 2                 # Pade order
    reference = false         # delay the reference fed to the control law too

    [shaper]                  # input shaper on the reference path
    kind = "none"             # "none" | "zv" | "zvd" | "ei"
    modes = "first"           # "first": the first clamped frequency of the first
                              # link; "all": every link's first clamped frequency,
                              # one shaper per link convolved (shapers.for_modes)
    # damping = 0.0           # design damping ratio (default: each link's modal_damping)
    # tolerance = 0.05        # "ei" only

    [simulation]
    # duration = 20.0         # s (default: the trajectory's duration)
    dt = 2e-4                 # control period, s
    substeps = 1              # RK4 steps per control period
    # torque_limit = 100.0    # N m, scalar or one per joint (default: none)
    # seed = 0                # sensor-noise seed (default: unseeded)
    elbow = "positive"        # inverse-kinematics branch of the reference
    # max_deflection = 4.5    # m (default: each link's length)
    # smoothing = 0.1         # s: zero-phase smoothing of the reference path (preview;
    #                         # default: what the controller asks for; 0: the raw path)
    # record_signals = true   # record the measurement and the reference (false: no columns)
    # feedforward = true      # rigid inverse dynamics (default: the controller's choice)
    # gravity_compensation = true  # with [arm] gravity: add the holding torques of the
    #                         # measured posture (default: the controller's choice)
    # check_sampling = true   # refuse a period beyond the sampled loop's bound
    # record_every = 1        # record every k-th control instant (and the last)

``delay = "seed"`` or ``"dispersive"`` computes the wave-travel delay
(:func:`flexarm.sensing.delays.travel_delay`) over the path length along the links
from the base joint to the sensed point (:func:`sensor_path_length`: 0 for
joint encoders, 9 m for the paper arm's tip, 5 m for ``point`` link 1 at
0.5 m) at the seed's wave speed (:data:`flexarm.sensing.delays.SEED_WAVE_SPEED`) or at
the dispersive bending group speed of the first link at its first clamped
frequency.

Errors
------
An unknown section or key, a missing required key or a value the library
rejects raises :class:`ScenarioError` (a ``ValueError``) whose message starts
with the source (the file name) and names the dotted key, e.g.
``scenario.toml: unknown key 'trajectory.sidee'`` or ``scenario.toml:
trajectory.side: The 'side' parameter of Square must be a real number. Got
'big' instead.``

This module needs no compiled code (the command line reads its vocabulary
before any simulation is imported); :mod:`flexarm.sim.scenario` builds the
library objects a scenario describes.

Examples
--------
>>> from flexarm.sim.scenario import Scenario
>>> s = Scenario.from_dict({"trajectory": {"kind": "circle", "radius": 1.0}})
>>> type(s.controller).__name__, s.trajectory.radius, s.simulation.duration
('JacobianTransposePD', 1.0, 10.0)
>>> Scenario.from_dict({"trajectory": {"sidee": 1.0}}, source="s.toml")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
flexarm.errors.ScenarioError: s.toml: unknown key 'trajectory.sidee' (Square takes ...)
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from .._config import ConfigReader, read_toml
from ..errors import ScenarioError

__all__ = [
    "CONTROLLERS",
    "DELAY_MODELS",
    "JOINT_KINDS",
    "LINK_KINDS",
    "NOISE_KEYS",
    "SECTIONS",
    "SENSOR_KINDS",
    "SHAPERS",
    "SHAPER_MODES",
    "TRAJECTORY_KINDS",
    "ScenarioError",
    "ScenarioReader",
    "apply_overrides",
    "read_scenario",
]

SECTIONS = ("arm", "trajectory", "sensor", "controller", "delay", "shaper", "simulation")
TRAJECTORY_KINDS = ("square", "circle", "line", "point-to-point", "waypoints")
SENSOR_KINDS = ("joint", "tip", "point")
CONTROLLERS = ("pd", "jt-pd", "joint-pd", "fuzzy", "lqg", "reflected")
SHAPERS = ("none", "zv", "zvd", "ei")
SHAPER_MODES = ("first", "all")
JOINT_KINDS = ("rigid", "linear", "nonlinear")
LINK_KINDS = ("flexible", "rigid")
DELAY_MODELS = ("seed", "dispersive")
NOISE_KEYS = ("noise_std", "rate_noise_std", "quantization", "rate_quantization")

DEFAULT_KIND = {"trajectory": "square", "sensor": "joint", "controller": "pd", "shaper": "none"}


class ScenarioReader(ConfigReader):
    """Checks a scenario mapping and reports problems against its source: every
    problem, a wrong value or an entry of the wrong type, is a :class:`ScenarioError`."""

    def __init__(self, source: str):
        super().__init__(source, ScenarioError)

    def kind(
        self,
        table: Mapping[str, Any],
        prefix: str,
        options: tuple[str, ...],
        default: str | None = None,
    ) -> str:
        """The section's ``kind`` (the section's default if absent), one of ``options``."""
        fallback = DEFAULT_KIND.get(prefix, options[0]) if default is None else default
        return super().kind(table, prefix, options, fallback)


def read_scenario(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The raw mapping of a TOML scenario file (not yet checked: :meth:`Scenario.from_dict`).

    Raises
    ------
    ScenarioError
        If the file cannot be read or is not valid TOML.
    """
    return read_toml(path, ScenarioError, "scenario file")


def apply_overrides(data: Mapping[str, Any], changes: Mapping[str, Any]) -> dict[str, Any]:
    """``data`` with ``changes`` (same schema) merged over it, table by table; a new dict.

    Where ``changes`` sets a section's ``kind`` to another kind than ``data``'s
    (defaults included), that section's other keys in ``data`` are dropped:
    they were parameters of the other kind. The sensor keeps its noise keys,
    which every kind takes.

    Examples
    --------
    >>> apply_overrides({"controller": {"kind": "pd", "zeta": 0.5}, "shaper": {"kind": "zv"}},
    ...                 {"controller": {"kind": "joint-pd"}, "shaper": {"tolerance": 0.1}})
    {'controller': {'kind': 'joint-pd'}, 'shaper': {'kind': 'zv', 'tolerance': 0.1}}
    """
    out = dict(data)
    for section, value in changes.items():
        old = out.get(section)
        if not isinstance(value, Mapping) or not isinstance(old, Mapping):
            out[section] = value
            continue
        merged = dict(old)
        if "kind" in value and value["kind"] != old.get("kind", DEFAULT_KIND.get(section)):
            keep = NOISE_KEYS if section == "sensor" else ()
            merged = {k: v for k, v in old.items() if k in keep}
        merged.update(value)
        out[section] = merged
    return out
