"""Scenarios: one closed-loop simulation described by a TOML file.

:func:`load_scenario` reads a file, :meth:`Scenario.from_dict` builds the same
from a mapping; both return a :class:`Scenario` holding the built library
objects, and ``simulate(s.arm, **s.simulate_kwargs())`` runs it
(:func:`flexarm.sim.simulate.simulate`). ``flexarm simulate --scenario FILE`` is the
command-line front end; ``examples/paper_square.toml`` is a complete file.

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
    boundary = "clamped-free" # or "clamped-mass"
    payload_mass = 0.0        # kg
    payload_inertia = 0.0     # kg m^2
    # also: mode_normalization, mode_amplitude, joint_friction, rotor_coupling

    # [[arm.links]]           # one table per link, base outwards (Link)
    # length = 4.5            # m            (required)
    # flexural_rigidity = 1676.0   # N m^2   (required)
    # linear_density = 0.335  # kg/m         (required)
    # n_modes = 1, hub_mass = 0.0 (kg), hub_inertia = 0.0 (kg m^2), modal_damping = 0.0

    # [arm.joints]            # the same joint at every link (default: rigid joints)
    # kind = "linear"         # "rigid" | "linear" (LinearJoint.default()) |
    #                         # "nonlinear" (NonlinearJoint.default(MakkarFriction.default()))
    # stiffness, motor_inertia, motor_damping          (linear overrides)
    # a1, a2, ksw, asw, motor_inertia, motor_damping   (nonlinear overrides)
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

    [controller]
    kind = "pd"               # "pd": the paper's gains JacobianTransposePD.from_arm(arm,
                              #   zeta) (key: zeta = 0.707);
                              # "jt-pd": JacobianTransposePD(kp, kd), N/m and N s/m,
                              #   scalar, [kx, ky] or 2x2;
                              # "joint-pd": JointPD(kp, kd), N m/rad and N m s/rad,
                              #   scalar or one per link;
                              # "fuzzy": the paper's gains (zeta) adapted by the
                              #   paper's fuzzy system, FuzzyAdaptiveJTPD (keys:
                              #   zeta = 0.707, ks = 1.0, law = "scaled" | "damping")

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

Examples
--------
>>> s = Scenario.from_dict({"trajectory": {"kind": "circle", "radius": 1.0}})
>>> type(s.controller).__name__, s.trajectory.radius, s.simulation.duration
('JacobianTransposePD', 1.0, 10.0)
>>> Scenario.from_dict({"trajectory": {"sidee": 1.0}}, source="s.toml")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
flexarm.sim.scenario.ScenarioError: s.toml: unknown key 'trajectory.sidee' (Square takes ...)
"""

from __future__ import annotations

import dataclasses
import os
import re
import tomllib
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, NoReturn

import numpy as np

from .._validation import check_array, check_int, check_option, check_real
from ..control.adaptive import FuzzyAdaptiveJTPD
from ..control.controllers import Controller, JacobianTransposePD, JointPD
from ..control.shapers import Shaper, design, for_modes
from ..control.trajectories import ELBOWS, Circle, Line, PointToPoint, Square, Waypoints
from ..errors import InvalidValueError
from ..model.arm import FlexibleArm
from ..model.joints import LinearJoint, MakkarFriction, NonlinearJoint
from ..model.link import Link
from ..sensing.delays import (
    SEED_WAVE_SPEED,
    DelayModel,
    bending_group_speed,
    travel_delay,
)
from ..sensing.sensors import JointSensor, PointSensor, Sensor, TipSensor

__all__ = [
    "CONTROLLERS",
    "DELAY_MODELS",
    "JOINT_KINDS",
    "SECTIONS",
    "SENSORS",
    "SHAPERS",
    "SHAPER_MODES",
    "TRAJECTORIES",
    "Scenario",
    "ScenarioError",
    "SimulationSettings",
    "apply_overrides",
    "load_scenario",
    "read_scenario",
    "sensor_path_length",
]

SECTIONS = ("arm", "trajectory", "sensor", "controller", "delay", "shaper", "simulation")
TRAJECTORIES: dict[str, type] = {
    "square": Square,
    "circle": Circle,
    "line": Line,
    "point-to-point": PointToPoint,
    "waypoints": Waypoints,
}
SENSORS: dict[str, type] = {"joint": JointSensor, "tip": TipSensor, "point": PointSensor}
CONTROLLERS = ("pd", "jt-pd", "joint-pd", "fuzzy")
SHAPERS = ("none", "zv", "zvd", "ei")
SHAPER_MODES = ("first", "all")
JOINT_KINDS = ("rigid", "linear", "nonlinear")
DELAY_MODELS = ("seed", "dispersive")

_DEFAULT_KIND = {"trajectory": "square", "sensor": "joint", "controller": "pd", "shaper": "none"}
_ARM_PASSTHROUGH = (
    "boundary",
    "payload_mass",
    "payload_inertia",
    "mode_normalization",
    "mode_amplitude",
    "joint_friction",
    "rotor_coupling",
)
_ARM_KEYS = ("preset", "n_modes", "links", "joints", *_ARM_PASSTHROUGH)
_NOISE_KEYS = ("noise_std", "rate_noise_std", "quantization", "rate_quantization")
_PARAMETER = re.compile(r"The '(\w+)' parameter")


class ScenarioError(InvalidValueError):
    """A scenario that cannot be built.

    Attributes
    ----------
    source : str
        Where the scenario came from (the file name).
    key : str or None
        Dotted key of the offending entry (``"trajectory.side"``,
        ``"arm.links[1].length"``), the section, or None for the whole file.
    reason : str
        The problem, without the source and key.
    """

    def __init__(self, source: str, key: str | None, reason: str, *, show_key: bool = True):
        self.source = source
        self.key = key
        self.reason = reason
        where = f"{key}: " if key and show_key else ""
        super().__init__(f"{source}: {where}{reason}")


# ------------------------------------------------------------------ reading
class _Reader:
    """Checks a scenario mapping and reports problems against its source."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str | None, reason: str, *, show_key: bool = True) -> NoReturn:
        raise ScenarioError(self.source, key, reason, show_key=show_key)

    def table(self, data: Mapping[str, Any], key: str, prefix: str = "") -> dict[str, Any]:
        value = data.get(key, {})
        name = f"{prefix}{key}"
        if not isinstance(value, Mapping):
            self.fail(name, f"must be a table ([{name}]). Got {value!r} instead.")
        return dict(value)

    def keys(
        self, table: Mapping[str, Any], prefix: str, allowed: tuple[str, ...], what: str
    ) -> None:
        for key in table:
            if key not in allowed:
                self.fail(
                    f"{prefix}.{key}",
                    f"unknown key '{prefix}.{key}' ({what} takes {', '.join(allowed)})",
                    show_key=False,
                )

    @contextmanager
    def library(self, prefix: str, table: Mapping[str, Any] | None = None) -> Iterator[None]:
        """Report the library's TypeError/ValueError against the key it names."""
        try:
            yield
        except ScenarioError:
            raise
        except (TypeError, ValueError) as exc:
            m = _PARAMETER.search(str(exc))
            key = prefix
            if m is not None and table is not None and m[1] in table:
                key = f"{prefix}.{m[1]}"
            self.fail(key, str(exc))

    def build(self, cls: type, table: Mapping[str, Any], prefix: str, *, kind: bool = False) -> Any:
        """``cls(**table)`` for a dataclass, with unknown and missing keys named
        (``kind``: the table also holds the ``kind`` key that chose ``cls``)."""
        fields = [f for f in dataclasses.fields(cls) if f.init]
        allowed = tuple(f.name for f in fields)
        params = {k: v for k, v in table.items() if not (kind and k == "kind")}
        self.keys(params, prefix, allowed, cls.__name__)
        required = [
            f.name
            for f in fields
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        ]
        for name in required:
            if name not in params:
                needs = ", ".join(required)
                self.fail(prefix, f"missing key '{prefix}.{name}' ({cls.__name__} needs {needs})")
        with self.library(prefix, params):
            return cls(**params)

    def kind(self, table: Mapping[str, Any], prefix: str, options: tuple[str, ...]) -> str:
        value = table.get("kind", _DEFAULT_KIND.get(prefix, options[0]))
        if not isinstance(value, str) or value not in options:
            self.fail(f"{prefix}.kind", f"must be one of {options}. Got {value!r} instead.")
        return value


def read_scenario(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The raw mapping of a TOML scenario file (not yet checked: :meth:`Scenario.from_dict`).

    Raises
    ------
    ScenarioError
        If the file cannot be read or is not valid TOML.
    """
    source = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ScenarioError(source, None, "no such file") from None
    except OSError as exc:
        raise ScenarioError(source, None, f"cannot read the file: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(source, None, f"not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise ScenarioError(source, None, "not valid TOML: not UTF-8 text") from None


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and build a TOML scenario file (module docstring for the schema)."""
    return Scenario.from_dict(read_scenario(path), source=os.fspath(path))


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
        if "kind" in value and value["kind"] != old.get("kind", _DEFAULT_KIND.get(section)):
            keep = _NOISE_KEYS if section == "sensor" else ()
            merged = {k: v for k, v in old.items() if k in keep}
        merged.update(value)
        out[section] = merged
    return out


# ------------------------------------------------------------------ geometry
def sensor_path_length(arm: FlexibleArm, sensor: Sensor) -> float:
    """Path length along the links from the base joint to the sensed point, m.

    0 for joint encoders (collocated); the sum of the inboard links' lengths
    plus the distance along the sensed link otherwise.

    Examples
    --------
    >>> arm = FlexibleArm.paper()
    >>> sensor_path_length(arm, PointSensor(1, 0.5)), sensor_path_length(arm, TipSensor())
    (5.0, 9.0)
    """
    link, distance, _ = sensor.resolve(arm)
    if link < 0:
        return 0.0
    return float(sum(lk.length for lk in arm.links[:link]) + distance)


# ------------------------------------------------------------------ settings
@dataclass(frozen=True)
class SimulationSettings:
    """The ``[simulation]`` section: keyword arguments of :func:`flexarm.sim.simulate.simulate`.

    Parameters
    ----------
    duration : float, optional
        Simulated time, s (> 0; None: the trajectory's duration).
    dt : float
        Control period, s (> 0).
    substeps : int
        RK4 steps per control period (>= 1).
    torque_limit : float or tuple of float, optional
        Symmetric saturation of the joint torques, N m (> 0; None: none).
    seed : int, optional
        Seed of the sensor noise (>= 0; None: unseeded).
    elbow : {"positive", "negative"}
        Inverse-kinematics branch of the reference.
    max_deflection : float, optional
        Link tip deflection counted as divergence, m (> 0; None: the link's length).
    """

    duration: float | None = None
    dt: float = 2e-4
    substeps: int = 1
    torque_limit: float | tuple[float, ...] | None = None
    seed: int | None = None
    elbow: str = "positive"
    max_deflection: float | None = None

    def __post_init__(self) -> None:
        owner = "SimulationSettings"
        set_ = object.__setattr__
        if self.duration is not None:
            set_(self, "duration", check_real(self.duration, "duration", owner, positive=True))
        set_(self, "dt", check_real(self.dt, "dt", owner, positive=True))
        set_(self, "substeps", check_int(self.substeps, "substeps", owner, minimum=1))
        if self.torque_limit is not None:
            limit = check_array(self.torque_limit, "torque_limit", owner, finite=False)
            if limit.ndim > 1 or limit.dtype.kind == "c" or not np.all(limit > 0):
                raise InvalidValueError(
                    f"The 'torque_limit' parameter of {owner} must be > 0, a scalar or one per "
                    f"joint. Got {self.torque_limit!r} instead."
                )
            value = float(limit) if limit.ndim == 0 else tuple(float(x) for x in limit)
            set_(self, "torque_limit", value)
        if self.seed is not None:
            set_(self, "seed", check_int(self.seed, "seed", owner, minimum=0))
        check_option(self.elbow, "elbow", owner, ELBOWS)
        if self.max_deflection is not None:
            set_(
                self,
                "max_deflection",
                check_real(self.max_deflection, "max_deflection", owner, positive=True),
            )


# ------------------------------------------------------------------ scenario
@dataclass(frozen=True)
class Scenario:
    """A complete simulation set-up: the built library objects.

    Parameters
    ----------
    arm : FlexibleArm
        The plant.
    controller : Controller
        The feedback law.
    trajectory : trajectory object
        The desired end-effector path (:mod:`flexarm.control.trajectories`).
    sensor : JointSensor, PointSensor or TipSensor
        What the controller sees.
    delay : DelayModel
        Transport delay of the sensed signal.
    delay_reference : bool
        Whether the reference fed to the control law is delayed as well.
    shaper : Shaper or None
        Input shaper on the reference path.
    simulation : SimulationSettings
        Duration, control period and the other simulator settings.
    source : str
        Where it came from (file name), for messages.
    description : dict
        JSON-ready account of every setting, including the derived ones (the
        delay in s and the path length it was computed over, the shaper's
        design frequencies, impulses and times, the controller's gains).
    """

    arm: FlexibleArm
    controller: Controller
    trajectory: Any
    sensor: Sensor
    delay: DelayModel = field(default_factory=DelayModel.none)
    delay_reference: bool = False
    shaper: Shaper | None = None
    simulation: SimulationSettings = field(default_factory=SimulationSettings)
    source: str = "scenario"
    description: dict[str, Any] = field(default_factory=dict, compare=False)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "scenario") -> Scenario:
        """Build a scenario from a mapping with the schema of the module docstring.

        Parameters
        ----------
        data : mapping
            Sections to tables (as :func:`tomllib.load` returns them).
        source : str
            Named at the start of every error message (the file name).

        Raises
        ------
        ScenarioError
            For an unknown section or key, a missing key or a rejected value.
        """
        r = _Reader(source)
        if not isinstance(data, Mapping):
            r.fail(None, f"must be a table of sections. Got {type(data).__name__} instead.")
        for key, value in data.items():
            if key not in SECTIONS:
                what = "section" if isinstance(value, Mapping) else "key"
                r.fail(
                    key, f"unknown {what} '{key}' (sections: {', '.join(SECTIONS)})", show_key=False
                )
        arm, arm_d = _arm(r, data)
        trajectory, traj_d = _trajectory(r, data)
        sensor, sensor_d = _sensor(r, data, arm)
        controller, ctrl_d = _controller(r, data, arm)
        delay, reference, delay_d = _delay(r, data, arm, sensor)
        shaper, shaper_d = _shaper(r, data, arm)
        settings, sim_d = _simulation(r, data, arm, trajectory)
        description = {
            "source": source,
            "arm": arm_d,
            "trajectory": traj_d,
            "sensor": sensor_d,
            "controller": ctrl_d,
            "delay": delay_d,
            "shaper": shaper_d,
            "simulation": sim_d,
        }
        return cls(
            arm=arm,
            controller=controller,
            trajectory=trajectory,
            sensor=sensor,
            delay=delay,
            delay_reference=reference,
            shaper=shaper,
            simulation=settings,
            source=source,
            description=_plain(description),
        )

    def simulate_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`flexarm.sim.simulate.simulate` after the arm:
        ``simulate(s.arm, **s.simulate_kwargs())``."""
        s = self.simulation
        return {
            "controller": self.controller,
            "trajectory": self.trajectory,
            "sensor": self.sensor,
            "delay": self.delay,
            "delay_reference": self.delay_reference,
            "shaper": self.shaper,
            "duration": s.duration,
            "dt": s.dt,
            "substeps": s.substeps,
            "torque_limit": s.torque_limit,
            "elbow": s.elbow,
            "max_deflection": s.max_deflection,
            "rng": s.seed,
        }


# ------------------------------------------------------------------ sections
def _arm(r: _Reader, data: Mapping[str, Any]) -> tuple[FlexibleArm, dict[str, Any]]:
    t = r.table(data, "arm")
    r.keys(t, "arm", _ARM_KEYS, "[arm]")
    preset, links = t.get("preset"), t.get("links")
    if preset is not None and links is not None:
        r.fail("arm.preset", "give either preset or [[arm.links]], not both")
    kwargs = {k: t[k] for k in _ARM_PASSTHROUGH if k in t}
    if links is None:
        if preset is None:
            preset = "paper"
        if preset != "paper":
            r.fail(
                "arm.preset", f"must be 'paper' (or give [[arm.links]]). Got {preset!r} instead."
            )
        n_links = 2
    else:
        if "n_modes" in t:
            r.fail(
                "arm.n_modes",
                "applies to preset = 'paper' only; give n_modes in each [[arm.links]]",
            )
        if (
            not isinstance(links, list)
            or not links
            or not all(isinstance(x, Mapping) for x in links)
        ):
            r.fail(
                "arm.links",
                f"must be a non-empty array of tables ([[arm.links]]). Got {links!r} instead.",
            )
        n_links = len(links)
    joints, joints_d = _joints(r, t, n_links)
    if links is None:
        with r.library("arm", t):
            arm = FlexibleArm.paper(n_modes=t.get("n_modes", 1), joints=joints, **kwargs)
    else:
        built = [r.build(Link, lt, f"arm.links[{i}]") for i, lt in enumerate(links)]
        with r.library("arm", t):
            arm = FlexibleArm(built, joints=joints, **kwargs)
    description = {
        "preset": preset,
        "links": [dataclasses.asdict(lk) for lk in arm.links],
        "boundary": arm.boundary,
        "payload_mass": arm.payload_mass,
        "payload_inertia": arm.payload_inertia,
        "mode_normalization": arm.mode_normalization,
        "joints": joints_d,
        "link_frequencies_rad_s": [f.tolist() for f in arm.link_frequencies],
    }
    return arm, description


def _joints(
    r: _Reader, arm_table: Mapping[str, Any], n_links: int
) -> tuple[list[LinearJoint | NonlinearJoint] | None, dict[str, Any]]:
    t = r.table(arm_table, "joints", "arm.")
    kind = r.kind(t, "arm.joints", JOINT_KINDS)
    if kind == "rigid":
        for key in t:
            if key != "kind":
                r.fail(
                    f"arm.joints.{key}",
                    f"unknown key 'arm.joints.{key}' (rigid joints take no parameters)",
                    show_key=False,
                )
        return None, {"kind": "rigid"}
    base: LinearJoint | NonlinearJoint
    base = LinearJoint.default() if kind == "linear" else NonlinearJoint.default()
    allowed = tuple(f.name for f in dataclasses.fields(base))
    params = {k: v for k, v in t.items() if k != "kind"}
    r.keys(params, "arm.joints", allowed, type(base).__name__)
    friction = params.pop("friction", kind == "nonlinear")
    if isinstance(friction, bool):
        params["friction"] = MakkarFriction.default() if friction else None
    elif isinstance(friction, Mapping):
        ft = dict(friction)
        r.keys(ft, "arm.joints.friction", ("g1", "g2", "g3", "g4", "g5", "g6"), "MakkarFriction")
        with r.library("arm.joints.friction", ft):
            params["friction"] = dataclasses.replace(MakkarFriction.default(), **ft)
    else:
        r.fail(
            "arm.joints.friction",
            f"must be true, false or a table of g1..g6. Got {friction!r} instead.",
        )
    with r.library("arm.joints", params):
        joint = dataclasses.replace(base, **params)
    description = {"kind": kind, **dataclasses.asdict(joint)}
    return [joint] * n_links, description


def _trajectory(r: _Reader, data: Mapping[str, Any]) -> tuple[Any, dict[str, Any]]:
    t = r.table(data, "trajectory")
    kind = r.kind(t, "trajectory", tuple(TRAJECTORIES))
    traj = r.build(TRAJECTORIES[kind], t, "trajectory", kind=True)
    params = {f.name: getattr(traj, f.name) for f in dataclasses.fields(traj) if f.init}
    return traj, {"kind": kind, **params, "duration_s": float(traj.duration)}


def _sensor(r: _Reader, data: Mapping[str, Any], arm: FlexibleArm) -> tuple[Sensor, dict[str, Any]]:
    t = r.table(data, "sensor")
    kind = r.kind(t, "sensor", tuple(SENSORS))
    sensor: Sensor = r.build(SENSORS[kind], t, "sensor", kind=True)
    with r.library("sensor", t):
        sensor.resolve(arm)
    params = {f.name: getattr(sensor, f.name) for f in dataclasses.fields(sensor)}
    return sensor, {"kind": kind, "spec": sensor.describe(arm), **params}


def _controller(
    r: _Reader, data: Mapping[str, Any], arm: FlexibleArm
) -> tuple[Controller, dict[str, Any]]:
    t = r.table(data, "controller")
    kind = r.kind(t, "controller", CONTROLLERS)
    controller: Any
    description: dict[str, Any] = {"kind": kind}
    if kind == "pd":
        params = {k: v for k, v in t.items() if k != "kind"}
        r.keys(params, "controller", ("zeta",), "kind = 'pd' (the paper's gains)")
        zeta = params.get("zeta", 0.707)
        with r.library("controller", params):
            controller = JacobianTransposePD.from_arm(arm, zeta)
        description["zeta"] = zeta
    elif kind == "fuzzy":
        params = {k: v for k, v in t.items() if k != "kind"}
        r.keys(params, "controller", ("zeta", "ks", "law"), "kind = 'fuzzy'")
        zeta = params.get("zeta", 0.707)
        ks = params.get("ks", 1.0)
        law = params.get("law", "scaled")
        with r.library("controller", params):
            controller = FuzzyAdaptiveJTPD.from_arm(arm, zeta, ks=ks, law=law)
        description.update(zeta=zeta, ks=controller.ks, law=controller.law)
    else:
        cls = JacobianTransposePD if kind == "jt-pd" else JointPD
        controller = r.build(cls, t, "controller", kind=True)
    with r.library("controller", t):
        controller.parameters(arm)  # the gains are checked against the arm here
    description.update(kp=controller.kp, kd=controller.kd)
    return controller, description


def _delay(
    r: _Reader, data: Mapping[str, Any], arm: FlexibleArm, sensor: Sensor
) -> tuple[DelayModel, bool, dict[str, Any]]:
    t = r.table(data, "delay")
    r.keys(t, "delay", ("delay", "method", "order", "reference"), "[delay]")
    spec = t.get("delay", 0.0)
    reference = t.get("reference", False)
    if not isinstance(reference, bool):
        r.fail("delay.reference", f"must be true or false. Got {reference!r} instead.")
    description: dict[str, Any] = {"delay": spec}
    if isinstance(spec, str):
        if spec not in DELAY_MODELS:
            r.fail(
                "delay.delay",
                "must be a number of seconds (>= 0), 'seed' or 'dispersive'. "
                f"Got {spec!r} instead.",
            )
        path = sensor_path_length(arm, sensor)
        if spec == "seed":
            speed = SEED_WAVE_SPEED
            seconds = travel_delay(path, "seed")
        else:
            first = arm.links[0]
            freqs = arm.link_frequencies[0]
            if len(freqs) == 0:
                r.fail("delay.delay", "'dispersive' needs a first link with at least one mode")
            w1, ei, rho = float(freqs[0]), first.flexural_rigidity, first.linear_density
            speed = bending_group_speed(w1, ei, rho)
            seconds = travel_delay(
                path, "dispersive", omega=w1, flexural_rigidity=ei, linear_density=rho
            )
        description.update(path_length_m=path, wave_speed_m_s=speed)
    else:
        seconds = spec
    kwargs = {"delay": seconds, "method": t.get("method", "exact"), "order": t.get("order", 2)}
    with r.library("delay", t):
        model = DelayModel(**kwargs)
    description.update(
        delay_s=model.delay, method=model.method, order=model.order, reference=reference
    )
    return model, reference, description


def _shaper(
    r: _Reader, data: Mapping[str, Any], arm: FlexibleArm
) -> tuple[Shaper | None, dict[str, Any]]:
    t = r.table(data, "shaper")
    kind = r.kind(t, "shaper", SHAPERS)
    params = {k: v for k, v in t.items() if k != "kind"}
    r.keys(params, "shaper", ("modes", "damping", "tolerance"), "[shaper]")
    if kind == "none":
        return None, {"kind": "none"}
    modes = params.get("modes", "first")
    if not isinstance(modes, str) or modes not in SHAPER_MODES:
        r.fail("shaper.modes", f"must be one of {SHAPER_MODES}. Got {modes!r} instead.")
    if "tolerance" in params and kind != "ei":
        r.fail("shaper.tolerance", "applies to kind = 'ei' only")
    links = [0] if modes == "first" else range(arm.n_links)
    chosen = [i for i in links if len(arm.link_frequencies[i]) > 0]
    if not chosen:
        r.fail("shaper.kind", "a shaper needs a link with at least one mode to design it for")
    freqs = [float(arm.link_frequencies[i][0]) for i in chosen]
    own = [arm.links[i].modal_damping for i in chosen]
    damping = params.get("damping", own[0] if modes == "first" else own)
    extra = {"tolerance": params["tolerance"]} if "tolerance" in params else {}
    with r.library("shaper", params):
        if modes == "first":
            shaper = design(kind, freqs[0], damping, **extra)
        else:
            shaper = for_modes(freqs, damping, kind, **extra)
    description = {
        "kind": kind,
        "modes": modes,
        "frequencies_rad_s": freqs,
        "damping": damping,
        **extra,
        "amplitudes": shaper.amplitudes.tolist(),
        "times_s": shaper.times.tolist(),
    }
    return shaper, description


def _simulation(
    r: _Reader, data: Mapping[str, Any], arm: FlexibleArm, trajectory: Any
) -> tuple[SimulationSettings, dict[str, Any]]:
    t = r.table(data, "simulation")
    settings: SimulationSettings = r.build(SimulationSettings, t, "simulation")
    duration = float(trajectory.duration) if settings.duration is None else settings.duration
    settings = dataclasses.replace(settings, duration=duration)
    if round(duration / settings.dt) < 1:
        r.fail(
            "simulation.duration" if "duration" in t else "simulation.dt",
            f"the duration ({duration} s) must cover at least one control period ({settings.dt} s)",
        )
    limit = settings.torque_limit
    if isinstance(limit, tuple) and len(limit) != arm.n_links:
        r.fail(
            "simulation.torque_limit",
            f"must be a scalar or one value per joint ({arm.n_links}). "
            f"Got {len(limit)} values instead.",
        )
    return settings, dataclasses.asdict(settings)


def _plain(value: Any) -> Any:
    """JSON-ready copy: tuples and arrays to lists, NumPy scalars to Python."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value
