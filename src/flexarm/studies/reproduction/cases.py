"""The study's vocabulary: one run (:class:`Case`), its outcome (:class:`CaseResult`), defaults.

Light on purpose (NumPy only): the command line takes its choices and
defaults from here without loading the simulator.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, cast

import numpy as np

from ..._io import JSONValue
from ...control.options import ADAPTATION_LAWS

if TYPE_CHECKING:
    from ...sim.results import SimulationResult

__all__ = [
    "ADAPTATION_LAWS",
    "CONTROLLER_DESCRIPTIONS",
    "CONTROLLER_KINDS",
    "CONVERGED_ARM_TABLE",
    "DEFAULT_DT",
    "DEFAULT_KS",
    "DEFAULT_KS_RANGE",
    "DEFAULT_LAW",
    "DEFAULT_TOLERANCE",
    "DELAY_CASES",
    "MODEL_LABELS",
    "PAPER_DELAY",
    "SENSOR_CASES",
    "SENSOR_LABELS",
    "SENSOR_MODELS",
    "Case",
    "CaseResult",
    "Metrics",
    "Row",
]

CONTROLLER_KINDS = ("pd", "fuzzy")
"""Nonadaptive (the paper's JT-PD gains) and fuzzy adaptive: each law's one name, the
same in the JSON summary, on the console, in the figures and in the report (and on
the command line: ``flexarm simulate --controller pd``)."""
SENSOR_CASES = ("joint", "tip", "point:1:0.5")
"""Joint encoders, the end effector, and 0.5 m from the elbow along link 2."""
DELAY_CASES = ("none", "seed", "dispersive")
"""No delay, the seed's wave speed, the dispersive bending-wave speed."""
SENSOR_MODELS = ("paper", "physical")
"""How a noncollocated sensor is modelled (:mod:`flexarm.sensing.sensors`): the paper's
rigid kinematics of the joint angles at the sensor's distance through a transport
delay (the paper's experiment), or the deflected point itself (a real arm)."""
PAPER_DELAY = "seed"
"""The transport delay of the paper's experiment (the seed's wave speed over the
path to the sensor, a 2nd-order Padé, the reference delayed the same): paper.md §3."""
DEFAULT_KS_RANGE = (0.0, 1.0, 10.0, 100.0, 1000.0)
"""The ``ks`` values of the sensitivity study (dimensionless)."""
DEFAULT_DT = 2e-4
"""Control period, s: the hubless paper arm under the paper's gains is
sampled-data unstable at 1 ms."""
DEFAULT_KS = 1.0
"""Membership-width gain of the fuzzy law in the paper's matrix (the paper's
+-5 m universe)."""
DEFAULT_LAW = "scaled"
"""Adaptation law of the paper's matrix (the paper's printed form)."""
DEFAULT_TOLERANCE = 0.05
"""A run tracks well when its RMS error is at most this fraction of the square's side."""

Metrics = Mapping[str, float | Sequence[float] | None]
"""Metrics of a run by name, units in the names (:meth:`SimulationResult.metrics`)."""
Row = dict[str, str | float | None]
"""One row of the study's table, units in the column names."""

CONVERGED_ARM_TABLE: dict[str, JSONValue] = {
    "preset": "paper",
    "n_modes": 3,
    "boundary": "clamped-mass",
    "geometric_stiffening": True,
}
"""The converged arm in the scenario schema: the paper's links with three
clamped-mass modes each and geometric stiffening (within 0.02 mm of a
geometrically exact reference's 63 mm peak on the square;
:mod:`flexarm.model.validity`)."""

CONTROLLER_DESCRIPTIONS = {
    "pd": "the paper's nonadaptive Jacobian-transpose PD law",
    "fuzzy": "the paper's fuzzy adaptive law (the same PD, its gains scaled by the fuzzy system)",
}
"""What each name of :data:`CONTROLLER_KINDS` stands for, once per report."""
MODEL_LABELS = {"paper": "the paper's sensor model", "physical": "the physical sensor model"}
SENSOR_LABELS = {"joint": "joint", "tip": "end effector", "point:1:0.5": "0.5 m from elbow"}


@dataclass(frozen=True)
class Case:
    """One run of the study.

    Parameters
    ----------
    controller : {"pd", "fuzzy"}
    sensor : {"joint", "tip", "point:1:0.5"}
    delay : {"none", "seed", "dispersive"}
    ks : float
        Membership-width gain of the fuzzy law, dimensionless (ignored by "pd").
    law : {"scaled", "damping"}
        Adaptation law of the fuzzy controller (ignored by "pd").
    sensor_model : {"paper", "physical"}
        The paper's sensor model (its delays realised as 2nd-order Padé with the
        reference delayed, as the paper did), or the deflected point (delays
        exact, the reference not delayed). The encoders are the same in both.
    arm : {"paper", "converged"}
        The paper's model of the arm, or the converged one (three clamped-mass
        modes per link, geometric stiffening:
        :data:`flexarm.studies.reproduction.converged.CONVERGED_ARM`).
    """

    controller: str
    sensor: str
    delay: str = "none"
    ks: float = DEFAULT_KS
    law: str = DEFAULT_LAW
    sensor_model: str = "paper"
    arm: str = "paper"

    def key(self) -> tuple[str | float, ...]:
        """Identity of the run (the fuzzy settings do not matter for "pd", the sensor
        model not for the encoders, whose delay path is empty)."""
        model = "encoders" if self.sensor == "joint" else self.sensor_model
        delay = "none" if self.sensor == "joint" else self.delay
        if self.controller == "pd":
            return ("pd", self.sensor, model, delay, self.arm)
        return (self.controller, self.sensor, model, delay, self.ks, self.law, self.arm)

    def scenario_dict(self, duration: float | None, dt: float) -> dict[str, JSONValue]:
        """The case in the scenario-file schema (:mod:`flexarm.sim.scenario`).

        Parameters
        ----------
        duration : float or None
            Simulated time, s (None: the whole square).
        dt : float
            Control period, s.
        """
        if self.sensor.startswith("point:"):
            _, link, distance = self.sensor.split(":")
            sensor: dict[str, JSONValue] = {
                "kind": "point",
                "link": int(link),
                "distance": float(distance),
            }
        else:
            sensor = {"kind": self.sensor}
        sensor["model"] = self.sensor_model
        controller: dict[str, JSONValue] = {"kind": self.controller}
        if self.controller == "fuzzy":
            controller.update(ks=self.ks, law=self.law)
        simulation: dict[str, JSONValue] = {"dt": dt}
        if duration is not None:
            simulation["duration"] = duration
        data: dict[str, JSONValue] = {
            "sensor": sensor,
            "controller": controller,
            "simulation": simulation,
        }
        if self.arm == "converged":
            data["arm"] = dict(CONVERGED_ARM_TABLE)
        if self.delay != "none":
            delay: dict[str, JSONValue] = {"delay": self.delay}
            if self.sensor_model == "paper":
                delay.update(method="pade", order=2, reference=True)
            data["delay"] = delay
        return data

    @property
    def label(self) -> str:
        """A readable name: controller, sensor, and the settings that differ from the matrix."""
        text = f"{self.controller}, {SENSOR_LABELS[self.sensor]} sensor"
        if self.sensor != "joint":
            text += f" ({self.sensor_model} model)"
        if self.controller == "fuzzy":
            text += f" (ks = {self.ks:g}, {self.law})"
        if self.delay != "none":
            text += f", {self.delay} delay"
        if self.arm == "converged":
            text += ", converged arm"
        return text


@dataclass
class CaseResult:
    """The outcome of one :class:`Case`.

    Attributes
    ----------
    case : Case
    status : {"ok", "diverged"}
    diverged_at_s : float or None
        When the state diverged, s.
    metrics : Metrics
        :meth:`SimulationResult.metrics` of the completed run; for a diverged
        run only ``sim_time_s`` and ``wall_time_s`` (errors of a run that blew
        up are not tracking errors).
    delay_s : float
        The sensor delay the case ran with, s.
    max_real_pole : float
        Largest real part of the closed-loop poles linearised at the start of
        the path, in continuous time without delay
        (:func:`flexarm.control.linearize.closed_loop_poles`), rad/s: > 0 means the
        loop cannot hold the path's start whatever the control period.
    result : SimulationResult
        The (partial, if diverged) time series, for the figures.
    """

    case: Case
    status: str
    diverged_at_s: float | None
    metrics: Metrics
    delay_s: float
    max_real_pole: float
    result: SimulationResult = field(repr=False)

    @property
    def rms(self) -> float:
        """RMS tracking error, m (inf if diverged)."""
        return float(cast(float, self.metrics["rms_error_m"])) if self.status == "ok" else np.inf

    def row(self) -> Row:
        """One flat, JSON-ready table row (units in the keys)."""
        m = self.metrics

        def scalar(name: str) -> float | None:
            value = m.get(name)
            return float(value) if isinstance(value, int | float) else None

        listed = m.get("corner_errors_m")
        corners = [
            float(x)
            for x in (listed if isinstance(listed, Sequence) else [])
            if x is not None and np.isfinite(x)
        ]
        return {
            "controller": self.case.controller,
            "law": self.case.law if self.case.controller == "fuzzy" else None,
            "ks": self.case.ks if self.case.controller == "fuzzy" else None,
            "sensor": self.case.sensor,
            "sensor_model": self.case.sensor_model,
            "delay": self.case.delay,
            "delay_s": self.delay_s,
            "status": self.status,
            "diverged_at_s": self.diverged_at_s,
            "max_real_pole_rad_s": self.max_real_pole,
            "rms_error_m": scalar("rms_error_m"),
            "max_error_m": scalar("max_error_m"),
            "corner_error_max_m": max(corners) if corners else None,
            "residual_vibration_m": scalar("residual_vibration_m"),
            "control_effort_N2m2s": scalar("control_effort_N2m2s"),
            "max_torque_Nm": scalar("max_torque_Nm"),
            "sim_time_s": scalar("sim_time_s"),
            "wall_time_s": scalar("wall_time_s"),
        }
