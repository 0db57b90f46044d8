"""The arm a calibration fits, and its prediction of a record.

:func:`build_plant` writes parameter values into the file's tables and builds the
arm (the scenario schema's ``[arm]``), its drives and its instruments.
:class:`Predictor` replays a record on a plant: the measured joint angles
prescribed (a smoothing spline, :func:`flexarm.sim.prescribed.motion_from_samples`),
or the measured torques or currents (through the drives) driving the arm open loop
(:func:`flexarm.simulate_open_loop`), and the instruments read from the run. A
record may be cut into segments, each started from the measured state: the
encoders' angles, at rest (``initial_state = "rest"``) or with their measured rates
(``"measured"``), the links straight and at rest, or with a fitted first-mode
deflection and rate as well (``"fit"``): a long record then does not drift. An
output with ``offset = "fit"`` adds a constant per record to its channel, fitted
with the initial states (a sensor's zero, which a logger need not reset between
records).
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._config import TomlValue, copy_value, set_key
from .._types import F64
from ..errors import CalibrationError, ConfigFileError, FlexarmError, UnstableStepError
from ..model.arm import FlexibleArm
from ..model.drives import Drive
from ..model.joints import LinearJoint, NonlinearJoint, RigidJoint
from ..sensing.instruments import Encoder, Instrument, delayed
from ..sim.open_loop import simulate_open_loop
from ..sim.prescribed import JointMotion, motion_from_samples, simulate_prescribed
from ..sim.results import SimulationError
from ..sim.scenario import arm_from_tables
from ..sim.step_check import MARGIN, stable_step
from .config import FIT, OUTPUT_KINDS, CalibrationConfig
from .records import Record

__all__ = ["Plant", "Predictor", "build_plant", "check_plant"]


@dataclass(frozen=True)
class Plant:
    """An arm with its drives (by joint) and instruments (by output name)."""

    arm: FlexibleArm
    drives: dict[int, Drive]
    outputs: dict[str, Instrument]


def build_plant(config: CalibrationConfig, values: Sequence[float] | F64 | None = None) -> Plant:
    """The plant with ``values`` (one per parameter, default their initial values)
    written into the file's tables.

    A drive's rotor (``rotor_inertia`` ``J_r`` behind ``gear_ratio`` ``N``) is
    carried by its joint as the arm counts a rotor (:class:`~flexarm.model.arm.FlexibleArm`):
    ``N**2 J_r`` added to the joint's motor inertia, the joint's gear ratio ``N``, so
    that the rotor turns at its carrier's rate plus ``N`` times the joint's and adds
    ``J_r`` (not ``N**2 J_r``) to its carrier. An arm without joints gets rigid ones
    (:class:`~flexarm.model.joints.RigidJoint`) for its drives' rotors.

    Raises
    ------
    CalibrationError
        If the values make an arm, a drive or an instrument the library refuses.
    """
    params = config.parameters
    values = [p.initial for p in params] if values is None else list(values)
    tables: dict[str, TomlValue] = {k: copy_value(v) for k, v in config.tables.items()}
    for p, x in zip(params, values, strict=True):
        set_key(tables, p.key, p.physical(float(x)))
    arm = arm_from_tables(tables, config.source)
    drives: dict[int, Drive] = {}
    raw_drives = tables["drives"]
    assert isinstance(raw_drives, list)
    for k, d in enumerate(raw_drives):
        assert isinstance(d, dict)
        joint = int(d["joint"])  # type: ignore[arg-type]
        if joint >= arm.n_links:
            raise CalibrationError(
                config.source,
                f"drives[{k}].joint",
                f"the arm has {arm.n_links} joints: no joint {joint}",
            )
        try:
            drives[joint] = Drive(**{n: v for n, v in d.items() if n != "joint"})  # type: ignore[arg-type]
        except (TypeError, ValueError) as exc:
            raise CalibrationError(config.source, f"drives[{k}]", str(exc)) from None
    arm = _with_rotors(arm, drives, config.source)
    outputs: dict[str, Instrument] = {}
    raw_outputs = tables["outputs"]
    assert isinstance(raw_outputs, dict)
    for name, spec in raw_outputs.items():
        assert isinstance(spec, dict)
        cls = OUTPUT_KINDS[str(spec.get("kind", "encoder"))]
        try:
            outputs[name] = cls(**{n: v for n, v in spec.items() if n not in ("kind", "offset")})
        except (TypeError, ValueError) as exc:
            raise CalibrationError(config.source, f"outputs.{name}", str(exc)) from None
    return Plant(arm, drives, outputs)


def check_plant(config: CalibrationConfig) -> Plant:
    """The plant at the initial values, each parameter's key set: a key that names
    nothing the arm, a drive or an instrument takes is refused by the parameter's
    own key (``parameters[k].key``); any other refusal names the table.

    Raises
    ------
    CalibrationError
        Naming the key.
    """
    try:
        return build_plant(config)
    except ConfigFileError as exc:
        last = None
        for k, p in enumerate(config.parameters):
            if exc.key is not None and exc.key.endswith(p.key.split(".")[-1]):
                last = k
        if last is None:
            raise
        key = config.parameters[last].key
        raise CalibrationError(
            config.source,
            f"parameters[{last}].key",
            f"{key!r} is not a parameter there: {exc.reason}",
        ) from None


def _with_rotors(arm: FlexibleArm, drives: Mapping[int, Drive], source: str) -> FlexibleArm:
    """``arm`` with each drive's rotor on its joint: ``N**2 J_r`` added to the joint's
    motor inertia at the drive's gear ratio ``N``. A joint that has a rotor of its own
    behind another gear ratio is refused (two rotors on one joint turn at one ratio)."""
    if not any(d.rotor_inertia > 0 for d in drives.values()):
        return arm
    joints: list[LinearJoint | NonlinearJoint | RigidJoint] = (
        list(arm.joints) if arm.joints is not None else [RigidJoint()] * arm.n_links
    )
    for j, d in sorted(drives.items()):
        if d.rotor_inertia == 0.0:
            continue
        joint = joints[j]
        if joint.motor_inertia > 0.0 and joint.gear_ratio != d.gear_ratio:
            raise CalibrationError(
                source,
                "drives",
                f"the drive of joint {j} has a rotor behind a gear ratio of {d.gear_ratio:g}, "
                f"and the joint a motor inertia behind {joint.gear_ratio:g}: give the joint "
                "the drive's gear_ratio, or its rotor in one place",
            )
        joints[j] = dataclasses.replace(
            joint,
            motor_inertia=joint.motor_inertia + d.reflected_inertia,
            gear_ratio=d.gear_ratio,
        )
    return dataclasses.replace(arm, joints=joints)


def _first_mode_gain(arm: FlexibleArm, link: int) -> float:
    """``phi_1(L) / L``: the tip angle per unit of the link's first modal coordinate."""
    length = float(arm.link_lengths[link])
    return float(arm.modes[link].shape(np.array([length]))[0, 0]) / length


def _quadratic_slope(t: F64, y: F64, i: int, half: int) -> float:
    """The slope at sample ``i`` of the quadratic fitted by least squares to the samples
    within ``half`` of it (a window of ``2 half + 1`` samples, shifted inwards at the
    ends): a rate from noisy readings."""
    n = t.shape[0]
    width = min(2 * half + 1, n)
    a = min(max(0, i - half), n - width)
    _, slope, _ = np.polyfit(t[a : a + width] - t[i], y[a : a + width], 2)
    return float(slope)


class _CachedMotion:
    """A joint motion evaluated once per set of times (a record's motion does not
    depend on the parameters)."""

    def __init__(self, motion: JointMotion) -> None:
        self.motion = motion
        self.cache: dict[bytes, tuple[Any, Any, Any]] = {}

    def __call__(self, times: F64) -> tuple[Any, Any, Any]:
        key = np.asarray(times).tobytes()
        if key not in self.cache:
            self.cache[key] = self.motion(times)
        return self.cache[key]


class Predictor:
    """Replays records on plants (module docstring).

    Parameters
    ----------
    config : CalibrationConfig
    records : sequence of Record
    """

    def __init__(self, config: CalibrationConfig, records: Sequence[Record]) -> None:
        self.config = config
        self.records = tuple(records)
        s = config.settings
        self.segments: list[list[tuple[int, int]]] = []
        self.motions: list[_CachedMotion | None] = []
        self.encoders: list[dict[int, F64]] = []
        plant = check_plant(config)
        self.substeps = self._substeps(plant)
        raw_outputs = config.tables["outputs"]
        assert isinstance(raw_outputs, dict)
        self.offsets = tuple(
            name
            for name, spec in raw_outputs.items()
            if isinstance(spec, dict) and spec.get("offset") == FIT
        )
        for k, rec in enumerate(self.records):
            n = rec.t.shape[0]
            per = n if s.segment <= 0 else max(2, round(s.segment / rec.dt))
            starts = list(range(0, n - 1, per))
            self.segments.append([(a, min(a + per, n - 1)) for a in starts])
            if rec.drive == "angle":
                missing = sorted(set(range(plant.arm.n_links)) - set(rec.inputs))
                if missing:
                    raise CalibrationError(
                        config.source,
                        f"records[{k}].inputs",
                        f"prescribes some joints' angles but not joint(s) {missing}: prescribe "
                        "every joint's angle, or drive them by torques or currents",
                    )
                angles = np.column_stack([rec.inputs[j][1] for j in range(plant.arm.n_links)])
                self.motions.append(_CachedMotion(motion_from_samples(rec.t, angles, s.smoothing)))
            else:
                self.motions.append(None)
            self.encoders.append(self._measured_joints(rec, plant))

    def _substeps(self, plant: Plant) -> int:
        """The substeps every replay takes at least: the file's, or with ``"auto"`` the
        fewest the initial arm is stable at over the shortest sample interval, with a
        margin of half again for the parameters' moves (an arm they move beyond it is
        replayed with the substeps it needs, :meth:`for_plant`)."""
        s = self.config.settings.substeps
        if s != "auto":
            return int(s)
        return self._stable_substeps(plant, 1.5)

    def _stable_substeps(self, plant: Plant, margin: float) -> int:
        dt = min(rec.dt for rec in self.records)
        free = None
        if any(rec.drive == "angle" for rec in self.records):
            free = np.ones(plant.arm.n_dof, dtype=bool)
            free[plant.arm.actuated_slice] = False
        h = stable_step(plant.arm, None, free)
        return 1 if h == np.inf else max(1, math.ceil(margin * dt / (MARGIN * h)))

    def for_plant(self, plant: Plant) -> Predictor:
        """This predictor with substeps the arm of ``plant`` is stable at (with
        ``substeps = "auto"``, where the parameters moved the arm beyond the step the
        initial arm took): a replay is never failed by the step alone."""
        if self.config.settings.substeps != "auto":
            return self
        needed = self._stable_substeps(plant, 1.0)
        if needed <= self.substeps:
            return self
        other = copy.copy(self)
        other.substeps = needed
        return other

    def _measured_joints(self, rec: Record, plant: Plant) -> dict[int, F64]:
        """Joint -> its encoder's readings in the record (undelayed encoders only)."""
        return {
            inst.joint: rec.outputs[name]
            for name, inst in plant.outputs.items()
            if isinstance(inst, Encoder) and name in rec.outputs and inst.delay == 0.0
        }

    def n_nuisance(self, plant: Plant, k: int) -> int:
        """Nuisance parameters of record ``k``: its initial states
        (:meth:`n_initial`), then the zero offset of each of its channels with
        ``offset = "fit"``, in ``offsets`` order."""
        return self.n_initial(plant, k) + len(self._offset_channels(k))

    def n_initial(self, plant: Plant, k: int) -> int:
        """Initial-state parameters of record ``k``: the first mode's deflection and
        rate of each flexible link, per segment (with ``initial_state = "fit"``)."""
        if self.config.settings.initial_state != "fit":
            return 0
        flexible = sum(1 for m in plant.arm.n_modes if m > 0)
        return 2 * flexible * len(self.segments[k])

    def _offset_channels(self, k: int) -> list[str]:
        return [name for name in self.offsets if name in self.records[k].outputs]

    def _initial_state(self, plant: Plant, k: int, i0: int, nuisance: F64) -> F64:
        arm, rec = plant.arm, self.records[k]
        n = arm.n_dof
        x = np.zeros(2 * n)
        actuated = arm.actuated_slice
        motion = self.motions[k]
        for j in range(arm.n_links):
            angle = rate = 0.0
            if motion is not None:
                th, dth, _ = motion.motion(rec.t[i0 : i0 + 1])
                angle, rate = float(np.asarray(th)[0, j]), float(np.asarray(dth)[0, j])
            elif j in self.encoders[k]:
                readings = self.encoders[k][j]
                angle = float(readings[i0])
                if self.config.settings.initial_state != "rest":
                    rate = _quadratic_slope(rec.t, readings, i0, 10)
            x[j] = angle  # the link angle (equal to the motor's behind a flexible joint)
            x[n + j] = rate
            if arm.has_flexible_joints:
                x[actuated.start + j] = angle
                x[n + actuated.start + j] = rate
        if nuisance.size:
            c = 0
            for link in range(arm.n_links):
                if arm.n_modes[link] == 0:
                    continue
                g = _first_mode_gain(arm, link)
                first = arm.modal_slice(link).start
                x[first] = nuisance[c] / g
                x[n + first] = nuisance[c + 1] / g
                c += 2
        return x

    def states(self, plant: Plant, k: int, nuisance: F64 | None = None) -> F64:
        """The states ``q`` (shape (K, n_dof)) of record ``k`` replayed on ``plant``
        (NaN from where a segment diverged)."""
        arm, rec, s = plant.arm, self.records[k], self.config.settings
        substeps = self.for_plant(plant).substeps
        n_initial = self.n_initial(plant, k)
        nu = np.zeros(n_initial) if nuisance is None else np.asarray(nuisance)[:n_initial]
        per_segment = nu.size // max(1, len(self.segments[k]))
        q = np.full((rec.t.shape[0], arm.n_dof), np.nan)
        torque = None if self.motions[k] is not None else self._torques(plant, rec)
        for g, (i0, i1) in enumerate(self.segments[k]):
            x0 = self._initial_state(plant, k, i0, nu[g * per_segment : (g + 1) * per_segment])
            t = rec.t[i0 : i1 + 1]
            try:
                motion = self.motions[k]
                if motion is not None:
                    res = simulate_prescribed(arm, t, motion, initial_state=x0, substeps=substeps)
                else:
                    assert torque is not None
                    res = simulate_open_loop(
                        arm,
                        t,
                        torque[i0 : i1 + 1],
                        initial_state=x0,
                        substeps=substeps,
                        interpolation=s.interpolation,
                        progress=False,
                    )
                rows = res.q
            except SimulationError as exc:
                rows = exc.result.q
            except UnstableStepError:  # parameters moved where the step is too long
                rows = np.full((i1 + 1 - i0, arm.n_dof), np.nan)
            except FlexarmError as exc:
                raise CalibrationError(self.config.source, f"records[{k}]", str(exc)) from None
            last = i1 + 1 if g == len(self.segments[k]) - 1 else i1
            q[i0:last] = rows[: last - i0]
        return q

    def _torques(self, plant: Plant, rec: Record) -> F64:
        """The joint torques of a torque- or current-driven record, shape (K, n_links)."""
        torque = np.zeros((rec.t.shape[0], plant.arm.n_links))
        for j, (kind, values) in rec.inputs.items():
            if j >= plant.arm.n_links:
                raise CalibrationError(
                    self.config.source,
                    "records",
                    f"drives joint {j} of a {plant.arm.n_links}-joint arm",
                )
            if kind == "torque":
                torque[:, j] = values
            else:
                drive = plant.drives.get(j)
                if drive is None:
                    raise CalibrationError(
                        self.config.source,
                        "drives",
                        f"joint {j} is driven by a current and has no drive",
                    )
                torque[:, j] = drive.joint_torque(current=values)
        return torque

    def predict(self, plant: Plant, k: int, nuisance: F64 | None = None) -> dict[str, F64]:
        """The predicted channels of record ``k`` (SI, shape (K,) each), each
        instrument's delay applied, and the fitted zero offsets added."""
        rec = self.records[k]
        q = self.states(plant, k, nuisance)
        offsets = dict.fromkeys(rec.outputs, 0.0)
        if nuisance is not None:
            tail = np.asarray(nuisance)[self.n_initial(plant, k) :]
            offsets.update(zip(self._offset_channels(k), (float(v) for v in tail), strict=True))
        out = {}
        for name in rec.outputs:
            inst = plant.outputs[name]
            out[name] = delayed(rec.t, inst.raw(plant.arm, q), inst.delay) + offsets[name]
        return out
