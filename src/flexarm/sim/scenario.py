"""Scenarios: one closed-loop simulation described by a TOML file.

:func:`load_scenario` reads a file, :meth:`Scenario.from_dict` builds the same
from a mapping; both return a :class:`Scenario` holding the built library
objects, and ``s.simulate()`` runs it (:func:`flexarm.simulate`).
``flexarm simulate --scenario FILE`` is the command-line front end;
``examples/paper_square.toml`` is a complete file. The schema, the reading of
files and the errors are in :mod:`flexarm.sim.scenario_schema`.

Examples
--------
>>> s = Scenario.from_dict({"trajectory": {"kind": "circle", "radius": 1.0}})
>>> type(s.controller).__name__, s.trajectory.radius, s.simulation.duration
('JacobianTransposePD', 1.0, 10.0)
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .._io import json_ready
from ..control.adaptive import FuzzyAdaptiveJTPD
from ..control.controllers import Controller, JacobianTransposePD, JointPD
from ..control.custom import call_factory, is_factory_spec, load_factory
from ..control.lqg import LQG
from ..control.reflected import ReflectedTipPD
from ..control.shapers import Shaper, design, for_modes
from ..control.trajectories import Circle, Line, PointToPoint, Square, Trajectory, Waypoints
from ..model.arm import FlexibleArm
from ..model.joints import LinearJoint, MakkarFriction, NonlinearJoint, RigidJoint
from ..model.link import Link, RigidLink
from ..sensing.delays import (
    SEED_WAVE_SPEED,
    DelayModel,
    bending_group_speed,
    travel_delay,
)
from ..sensing.sensors import JointSensor, PointSensor, Sensor, TipSensor
from .closed_loop import simulate
from .results import SimulationResult
from .scenario_schema import (
    CONTROLLERS,
    DELAY_MODELS,
    JOINT_KINDS,
    LINK_KINDS,
    SECTIONS,
    SENSOR_KINDS,
    SHAPER_MODES,
    SHAPERS,
    TRAJECTORY_KINDS,
    ScenarioReader,
    read_scenario,
)
from .settings import SimulationSettings

__all__ = [
    "SENSORS",
    "TRAJECTORIES",
    "Scenario",
    "arm_from_tables",
    "load_scenario",
    "sensor_path_length",
]

TRAJECTORIES: dict[str, type] = {
    "square": Square,
    "circle": Circle,
    "line": Line,
    "point-to-point": PointToPoint,
    "waypoints": Waypoints,
}
SENSORS: dict[str, type] = {"joint": JointSensor, "tip": TipSensor, "point": PointSensor}
assert tuple(TRAJECTORIES) == TRAJECTORY_KINDS and tuple(SENSORS) == SENSOR_KINDS

_ARM_PASSTHROUGH = (
    "boundary",
    "payload_mass",
    "payload_inertia",
    "mode_normalization",
    "mode_amplitude",
    "joint_friction",
    "rotor_coupling",
    "geometric_stiffening",
    "gravity",
)
_ARM_KEYS = ("preset", "n_modes", "links", "joints", *_ARM_PASSTHROUGH)


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


def arm_from_tables(data: Mapping[str, Any], source: str = "scenario") -> FlexibleArm:
    """The arm of a mapping's ``[arm]`` section (the scenario schema's; other sections
    are not read): how a calibration's or any other file's arm is built.

    Raises
    ------
    ScenarioError
        For an unknown or missing key or a value the library rejects, naming
        ``source`` and the dotted key.
    """
    return _arm(ScenarioReader(source), data)[0]


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and build a TOML scenario file (module docstring for the schema)."""
    return Scenario.from_dict(read_scenario(path), source=os.fspath(path))


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
    trajectory : Trajectory
        The desired end-effector path (:mod:`flexarm.control.trajectories`).
    simulation : SimulationSettings
        Everything else that defines the run: the sensor, its delay, the shaper,
        the duration, the control period and the other settings.
    source : str
        Where it came from (file name), for messages.
    description : dict
        JSON-ready account of every setting, including the derived ones (the
        delay in s and the path length it was computed over, the shaper's
        design frequencies, impulses and times, the controller's gains).
    """

    arm: FlexibleArm
    controller: Controller
    trajectory: Trajectory
    simulation: SimulationSettings = field(default_factory=SimulationSettings)
    source: str = "scenario"
    description: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def sensor(self) -> Sensor:
        """What the controller sees (``simulation.sensor``)."""
        return self.simulation.sensor

    @property
    def delay(self) -> DelayModel:
        """The sensed signal's transport delay (``simulation.delay``)."""
        return self.simulation.delay

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
        r = ScenarioReader(source)
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
        parts = {"sensor": sensor, "delay": delay, "delay_reference": reference, "shaper": shaper}
        settings, sim_d = _simulation(r, data, arm, trajectory, parts)
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
            simulation=settings,
            source=source,
            description=json_ready(description),
        )

    def simulate_kwargs(self) -> dict[str, Any]:
        """The arguments of :func:`flexarm.simulate` after the arm (the controller, the
        trajectory and the settings): ``simulate(s.arm, **s.simulate_kwargs())``, or a
        run of :func:`flexarm.simulate_many` with ``{"arm": s.arm, **s.simulate_kwargs()}``."""
        return {
            "controller": self.controller,
            "trajectory": self.trajectory,
            "settings": self.simulation,
        }

    def simulate(self, **options: Any) -> SimulationResult:
        """Run the scenario: :func:`flexarm.simulate` with its objects and settings.

        ``options`` are passed on (``progress``, ``stop``, ``rng``, or settings to
        override).
        """
        return simulate(self.arm, **self.simulate_kwargs(), **options)


# ------------------------------------------------------------------ sections
def _arm(r: ScenarioReader, data: Mapping[str, Any]) -> tuple[FlexibleArm, dict[str, Any]]:
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
        built = [_link(r, lt, f"arm.links[{i}]") for i, lt in enumerate(links)]
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
    if arm.gravity is not None:
        description["gravity"] = list(arm.gravity)
    return arm, description


def _link(r: ScenarioReader, t: Mapping[str, Any], prefix: str) -> Link | RigidLink:
    """``[[arm.links]]``: a flexible :class:`Link` (``kind = "flexible"``, the default)
    or a :class:`RigidLink` (``kind = "rigid"``)."""
    kind = r.kind(t, prefix, LINK_KINDS, default="flexible")
    link: Link | RigidLink = r.build(
        Link if kind == "flexible" else RigidLink, t, prefix, kind=True
    )
    return link


def _joints(
    r: ScenarioReader, arm_table: Mapping[str, Any], n_links: int
) -> tuple[
    list[LinearJoint | NonlinearJoint | RigidJoint] | None,
    dict[str, Any] | list[dict[str, Any]],
]:
    """``[arm.joints]`` (the same joint at every link) or ``[[arm.joints]]`` (one table
    per joint, base outwards; all rigid or none)."""
    value = arm_table.get("joints", {})
    if isinstance(value, list):
        if len(value) != n_links or not all(isinstance(t, Mapping) for t in value):
            r.fail(
                "arm.joints",
                f"must be one table per joint ({n_links}) as [[arm.joints]]. Got {value!r}.",
            )
        built = [_joint(r, dict(t), f"arm.joints[{i}]") for i, t in enumerate(value)]
        rigid = [j is None for j, _ in built]
        if any(rigid) and not all(rigid):
            r.fail(
                "arm.joints", "mixes rigid and flexible joints: give every joint a spring or none"
            )
        joints = None if all(rigid) else [j for j, _ in built if j is not None]
        return joints, [d for _, d in built]
    joint, description = _joint(r, r.table(arm_table, "joints", "arm."), "arm.joints")
    return (None if joint is None else [joint] * n_links), description


def _joint(
    r: ScenarioReader, t: dict[str, Any], prefix: str
) -> tuple[LinearJoint | NonlinearJoint | RigidJoint | None, dict[str, Any]]:
    kind = r.kind(t, "arm.joints", JOINT_KINDS)
    if kind == "rigid" and set(t) <= {"kind"}:
        return None, {"kind": "rigid"}  # an ideal rigid joint: no motor dynamics
    base: LinearJoint | NonlinearJoint | RigidJoint
    if kind == "rigid":
        base = RigidJoint()
    else:
        base = LinearJoint.default() if kind == "linear" else NonlinearJoint.default()
    allowed = tuple(f.name for f in dataclasses.fields(base))
    params = {k: v for k, v in t.items() if k != "kind"}
    r.keys(params, prefix, allowed, type(base).__name__)
    friction = params.pop("friction", kind == "nonlinear")
    if isinstance(friction, bool):
        params["friction"] = MakkarFriction.default() if friction else None
    elif isinstance(friction, Mapping):
        ft = dict(friction)
        r.keys(ft, f"{prefix}.friction", ("g1", "g2", "g3", "g4", "g5", "g6"), "MakkarFriction")
        with r.library(f"{prefix}.friction", ft):
            params["friction"] = dataclasses.replace(MakkarFriction.default(), **ft)
    else:
        r.fail(
            f"{prefix}.friction",
            f"must be true, false or a table of g1..g6. Got {friction!r} instead.",
        )
    with r.library(prefix, params):
        joint = dataclasses.replace(base, **params)
    return joint, {"kind": kind, **dataclasses.asdict(joint)}


def _trajectory(r: ScenarioReader, data: Mapping[str, Any]) -> tuple[Any, dict[str, Any]]:
    t = r.table(data, "trajectory")
    kind = r.kind(t, "trajectory", tuple(TRAJECTORIES))
    traj = r.build(TRAJECTORIES[kind], t, "trajectory", kind=True)
    params = {f.name: getattr(traj, f.name) for f in dataclasses.fields(traj) if f.init}
    return traj, {"kind": kind, **params, "duration_s": float(traj.duration)}


def _sensor(
    r: ScenarioReader, data: Mapping[str, Any], arm: FlexibleArm
) -> tuple[Sensor, dict[str, Any]]:
    t = r.table(data, "sensor")
    kind = r.kind(t, "sensor", tuple(SENSORS))
    sensor: Sensor = r.build(SENSORS[kind], t, "sensor", kind=True)
    with r.library("sensor", t):
        sensor.resolve(arm)
    params = {f.name: getattr(sensor, f.name) for f in dataclasses.fields(SENSORS[kind])}
    return sensor, {"kind": kind, "spec": sensor.describe(arm), **params}


def _controller(
    r: ScenarioReader, data: Mapping[str, Any], arm: FlexibleArm
) -> tuple[Controller, dict[str, Any]]:
    t = r.table(data, "controller")
    if is_factory_spec(t.get("kind")):  # your own: "module:factory"
        return _factory_controller(r, t, arm)
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
    elif kind == "reflected":
        params = {k: v for k, v in t.items() if k != "kind"}
        r.keys(params, "controller", ("alpha", "zeta"), "kind = 'reflected'")
        alpha, zeta = params.get("alpha", 0.5), params.get("zeta", 0.707)
        with r.library("controller", params):
            controller = ReflectedTipPD.from_arm(arm, alpha=alpha, zeta=zeta)
        description.update(alpha=controller.alpha, zeta=zeta)
    elif kind == "lqg":
        return _lqg(r, t, arm)
    else:
        cls = JacobianTransposePD if kind == "jt-pd" else JointPD
        controller = r.build(cls, t, "controller", kind=True)
        with r.library("controller", t):
            controller.parameters(arm)  # the gains are checked against the arm here
    description.update(kp=controller.kp, kd=controller.kd)
    return controller, description


def _factory_controller(
    r: ScenarioReader, t: Mapping[str, Any], arm: FlexibleArm
) -> tuple[Controller, dict[str, Any]]:
    """kind = "module:factory": ``factory(arm, **other keys)``, the module found on
    ``sys.path``, beside the scenario file or in the current directory."""
    spec = str(t["kind"])
    params = {k: v for k, v in t.items() if k != "kind"}
    here = [os.path.dirname(os.path.abspath(r.source))] if os.path.isfile(r.source) else []
    with r.library("controller.kind"):
        factory = load_factory(spec, search=[*here, os.getcwd()])
    with r.library("controller", params):
        controller = call_factory(factory, spec, arm, params)
    return controller, {"kind": spec, "name": controller.name, **params}


_LQG_KEYS = (
    "position_weight",
    "velocity_weight",
    "torque_weight",
    "torque_noise",
    "position_noise",
    "velocity_noise",
    "schedule_points",
    "gain",
    "ks",
)


def _lqg(r: ScenarioReader, t: Mapping[str, Any], arm: FlexibleArm) -> tuple[LQG, dict[str, Any]]:
    """kind = "lqg": the LQG's parameters, and ``model_modes`` / ``model_boundary`` for a
    design model with other modes than the arm (default: the arm itself)."""
    params = {k: v for k, v in t.items() if k != "kind"}
    r.keys(params, "controller", (*_LQG_KEYS, "model_modes", "model_boundary"), "kind = 'lqg'")
    model = None
    if "model_modes" in params or "model_boundary" in params:
        modes = params.get("model_modes", arm.n_modes[0])
        boundary = params.get("model_boundary", arm.boundary)
        with r.library("controller", {"n_modes": modes, "boundary": boundary}):
            links = [dataclasses.replace(lk, n_modes=modes) for lk in arm.links]
            model = dataclasses.replace(arm, links=links, boundary=boundary)
    with r.library("controller", params):
        controller = LQG(model=model, **{k: v for k, v in params.items() if k in _LQG_KEYS})
    description = {"kind": "lqg", **{k: getattr(controller, k) for k in _LQG_KEYS}}
    description["model"] = (
        "the arm" if model is None else f"{model.n_modes} modes, {model.boundary}"
    )
    return controller, description


def _delay(
    r: ScenarioReader, data: Mapping[str, Any], arm: FlexibleArm, sensor: Sensor
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
            if len(freqs) == 0 or not isinstance(first, Link):
                r.fail("delay.delay", "'dispersive' needs a first link with at least one mode")
            assert isinstance(first, Link)
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
    r: ScenarioReader, data: Mapping[str, Any], arm: FlexibleArm
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
    r: ScenarioReader,
    data: Mapping[str, Any],
    arm: FlexibleArm,
    trajectory: Trajectory,
    parts: Mapping[str, Any],
) -> tuple[SimulationSettings, dict[str, Any]]:
    """The ``[simulation]`` section with the sections built before it (``parts``: the
    sensor, the delay and the shaper) as :class:`SimulationSettings`."""
    t = r.table(data, "simulation")
    r.keys(t, "simulation", SimulationSettings.FILE_KEYS, "[simulation]")
    with r.library("simulation", t):
        settings = SimulationSettings(**parts, **t)
    duration = float(trajectory.duration) if settings.duration is None else settings.duration
    settings = settings.replace(duration=duration)
    if round(duration / settings.dt) < 1:
        # the key that set the duration: the simulation's, or the trajectory's own length
        if "duration" in t:
            key = "simulation.duration"
        elif isinstance(data.get("trajectory"), Mapping) and data["trajectory"]:
            key = "trajectory"  # the duration is the trajectory's length
        else:
            key = "simulation.dt"
        r.fail(
            key,
            f"the duration ({duration} s) must cover at least one control period ({settings.dt} s)",
        )
    limit = settings.torque_limit
    if isinstance(limit, tuple) and len(limit) != arm.n_links:
        r.fail(
            "simulation.torque_limit",
            f"must be a scalar or one value per joint ({arm.n_links}). "
            f"Got {len(limit)} values instead.",
        )
    return settings, {k: getattr(settings, k) for k in SimulationSettings.FILE_KEYS}
