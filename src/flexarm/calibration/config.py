"""The calibration file: the arm, its drives and instruments, the parameters to fit,
the records and what they are for.

A calibration is described by a TOML file (``flexarm calibrate CONFIG.toml``) or
the same mapping (:meth:`CalibrationConfig.from_dict`)::

    [calibration]
    data = "data"              # directory of relative record files (beside the file;
                               # flexarm calibrate --data overrides it)
    substeps = "auto"          # RK4 steps per sample interval, or "auto": the fewest
                               # the initial arm's dynamics are stable at (RK4's bound)
    segment = 0.0              # s: cut records into segments this long, each
                               # started from the measured state (0: whole records)
    initial_state = "rest"     # each segment starts at the encoders' angles at rest;
                               # "measured": with their measured rates; "fit": and
                               # each flexible link's first-mode deflection and rate
                               # fitted too
    smoothing = 1e-6           # spline penalty of prescribed angles (omit: chosen
                               # by cross-validation)
    interpolation = "linear"   # torques and currents between samples ("zoh")
    max_delay = 0.5            # s: the largest delay an output's estimate may take
    restarts = 0               # further starts from seeded random initial values
    seed = 0
    max_evaluations = 100      # of the residual, per start

    [arm]                      # the scenario file's [arm] tables (flexarm.sim.scenario)
    [[arm.links]]
    length = 0.202
    ...

    [[drives]]                 # flexarm.model.drives.Drive, one per driven joint
    joint = 0
    torque_constant = 0.119    # N m/A
    gear_ratio = 100
    efficiency = 0.75

    [outputs.th12]             # an instrument (flexarm.sensing.instruments) per
    kind = "strain_gauge"      # measured channel: "encoder" | "joint_deflection" |
    link = 0                   # "strain_gauge" | "tip_angle", with its parameters
    thickness = 0.00127
    form = "tip_angle"
    delay = "estimate"         # s, or "estimate": by cross-correlation, then fitted
    offset = "fit"             # optional: the channel's zero offset, a constant per
                               # record fitted with its initial states (a gauge's
                               # bridge is not zeroed at the start of every record)

    [[parameters]]             # what to fit: any numeric key of arm, drives, outputs
    key = "arm.links[0].flexural_rigidity"
    bounds = [0.5, 10.0]       # in the key's unit (or of the factor, with scale)
    initial = 2.69             # default: the file's value there (1 with scale)
    scale = false              # true: fit a factor on the file's value
    name = "EI1"               # default: the key

    [[records]]
    file = "run.mat"           # the columns' default file
    role = "training"          # or "validation"
    start = 0.0                # s, optional window [start, stop)
    time = { variable = "time", unit = "s" }
    inputs = [{ joint = 0, kind = "angle", variable = "theta11", unit = "rad" }]
    outputs = { th12 = { variable = "theta12", unit = "rad" } }

A column is ``{variable, unit, column, file}``: a variable of a ``.mat``/``.npz``
file (``column`` picks one of a matrix's columns), or a column (index or header)
of a text file (:mod:`flexarm.calibration.records`). Every problem is one
:class:`~flexarm.errors.CalibrationError` naming the file and the dotted key.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._config import ConfigReader, TomlValue, copy_value, read_toml, split_key, table_at
from ..errors import CalibrationError, KeyPathError
from ..model.drives import Drive
from ..sensing.instruments import Encoder, JointDeflection, StrainGauge, TipAngle
from .records import INPUT_KINDS, ROLES, Column, InputColumn, RecordSpec

__all__ = [
    "OUTPUT_KINDS",
    "SECTIONS",
    "CalibrationConfig",
    "Parameter",
    "Settings",
    "load_config",
]

SECTIONS = ("calibration", "arm", "drives", "outputs", "parameters", "records")
"""The sections of a calibration file."""
OUTPUT_KINDS: dict[str, type] = {
    "encoder": Encoder,
    "joint_deflection": JointDeflection,
    "strain_gauge": StrainGauge,
    "tip_angle": TipAngle,
}
"""Instrument kinds an output may be (:mod:`flexarm.sensing.instruments`)."""
INITIAL_STATES = ("rest", "measured", "fit")
INTERPOLATIONS = ("zoh", "linear")
ESTIMATE = "estimate"
FIT = "fit"


@dataclass(frozen=True)
class Settings:
    """The ``[calibration]`` section (module docstring)."""

    data: str | None = None
    substeps: int | str = "auto"
    segment: float = 0.0
    initial_state: str = "rest"
    smoothing: float | None = None
    interpolation: str = "linear"
    max_delay: float = 0.5
    restarts: int = 0
    seed: int = 0
    max_evaluations: int = 100


@dataclass(frozen=True)
class Parameter:
    """One parameter to fit.

    Attributes
    ----------
    name : str
        As reported.
    key : str
        The dotted key it sets in the file's tables (``arm``, ``drives``, ``outputs``).
    initial, lower, upper : float
        Its start and bounds (of the factor, with ``scale``).
    scale : bool
        The fitted number is a factor on ``base``, the file's value at ``key``.
    base : float
        The file's value at ``key`` (NaN where the file sets none).
    estimate : bool
        A delay whose start is estimated from the records (``delay = "estimate"``).
    """

    name: str
    key: str
    initial: float
    lower: float
    upper: float
    scale: bool = False
    base: float = math.nan
    estimate: bool = False

    def physical(self, x: float) -> float:
        """The value set at ``key`` for the fitted number ``x``."""
        return self.base * x if self.scale else x


@dataclass(frozen=True)
class CalibrationConfig:
    """A calibration file, checked (module docstring for the schema).

    Attributes
    ----------
    source : str
        The file's name (or ``"calibration"``), first in every message.
    settings : Settings
    tables : dict
        The ``arm``, ``drives`` and ``outputs`` sections as read, into which the
        parameters' keys write.
    parameters : tuple of Parameter
    records : tuple of RecordSpec
    root : Path
        Where relative record files are found.
    """

    source: str
    settings: Settings
    tables: dict[str, TomlValue]
    parameters: tuple[Parameter, ...]
    records: tuple[RecordSpec, ...]
    root: Path = field(default_factory=Path.cwd)

    @classmethod
    def from_dict(
        cls,
        data: Mapping[str, Any],
        source: str = "calibration",
        root: str | os.PathLike[str] | None = None,
    ) -> CalibrationConfig:
        """Check a calibration mapping (the schema of the module docstring).

        Parameters
        ----------
        data : mapping
            The file's sections.
        source : str
            Named first in every message.
        root : path-like, optional
            Where ``[calibration] data`` is relative to (default: the current
            directory); record files are relative to that data directory.
        """
        r = ConfigReader(source, CalibrationError, whole="a calibration file")
        r.keys(r.sections(data), "", SECTIONS)
        settings = _settings(r, r.table(data, "calibration"))
        tables: dict[str, TomlValue] = {
            "arm": copy_value(r.table(data, "arm")),
            "drives": copy_value(list(_drives(r, data.get("drives", [])))),
            "outputs": copy_value(dict(_outputs(r, r.table(data, "outputs")))),
        }
        parameters = _parameters(r, data.get("parameters"), tables, settings)
        records = _records(r, data.get("records"), tables)
        base = Path.cwd() if root is None else Path(root)
        data_dir = base if settings.data is None else base / settings.data
        return cls(source, settings, tables, parameters, records, data_dir)

    def with_data(self, directory: str | os.PathLike[str]) -> CalibrationConfig:
        """The same calibration reading its records from ``directory``."""
        return dataclasses.replace(self, root=Path(directory))


def load_config(path: str | os.PathLike[str]) -> CalibrationConfig:
    """Read and check a calibration file; its ``data`` directory is relative to it."""
    data = read_toml(path, CalibrationError, "calibration file")
    return CalibrationConfig.from_dict(data, os.fspath(path), Path(path).resolve().parent)


# ------------------------------------------------------------------ sections
def _settings(r: ConfigReader, t: Mapping[str, Any]) -> Settings:
    s: Settings = r.build(Settings, t, "calibration")
    checks = {
        "substeps": s.substeps == "auto"
        or (isinstance(s.substeps, int) and not isinstance(s.substeps, bool) and s.substeps >= 1),
        "segment": isinstance(s.segment, int | float) and s.segment >= 0,
        "smoothing": s.smoothing is None
        or (isinstance(s.smoothing, int | float) and s.smoothing > 0),
        "max_delay": isinstance(s.max_delay, int | float) and s.max_delay >= 0,
        "restarts": isinstance(s.restarts, int) and s.restarts >= 0,
        "seed": isinstance(s.seed, int) and s.seed >= 0,
        "max_evaluations": isinstance(s.max_evaluations, int) and s.max_evaluations >= 1,
        "data": s.data is None or isinstance(s.data, str),
    }
    for name, ok in checks.items():
        if not ok or isinstance(getattr(s, name), bool):
            r.fail(
                f"calibration.{name}", f"must be a valid {name}. Got {getattr(s, name)!r} instead."
            )
    if s.initial_state not in INITIAL_STATES:
        r.fail(
            "calibration.initial_state",
            f"must be one of {INITIAL_STATES}. Got {s.initial_state!r}.",
        )
    if s.interpolation not in INTERPOLATIONS:
        r.fail(
            "calibration.interpolation",
            f"must be one of {INTERPOLATIONS}. Got {s.interpolation!r}.",
        )
    return s


def _drives(r: ConfigReader, value: object) -> list[dict[str, Any]]:
    if not isinstance(value, list) or not all(isinstance(d, Mapping) for d in value):
        r.fail_type("drives", f"must be an array of tables ([[drives]]). Got {value!r} instead.")
    allowed = ("joint", *(f.name for f in dataclasses.fields(Drive)))
    out = []
    seen: set[int] = set()
    for k, d in enumerate(value):
        key = f"drives[{k}]"
        r.keys(d, key, allowed, "a drive")
        joint = r.integer(d.get("joint"), f"{key}.joint", 0)
        if joint in seen:
            r.fail(f"{key}.joint", f"joint {joint} has a drive already")
        seen.add(joint)
        with r.library(key, d):
            Drive(**{n: v for n, v in d.items() if n != "joint"})
        out.append(dict(d))
    return out


def _outputs(r: ConfigReader, t: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    out = {}
    for name, spec in t.items():
        key = f"outputs.{name}"
        table = r.as_table(spec, key)
        kind = r.kind(table, key, tuple(OUTPUT_KINDS))
        cls = OUTPUT_KINDS[kind]
        params = {n: v for n, v in table.items() if n not in ("kind", "offset")}
        if "offset" in table and table["offset"] != FIT:
            r.fail(
                f"{key}.offset",
                f"must be {FIT!r} (a zero offset fitted per record) or absent. "
                f"Got {table['offset']!r} instead.",
            )
        if params.get("delay") == ESTIMATE:
            params["delay"] = 0.0
        r.build(cls, params, key)
        out[name] = dict(table)
    return out


def _get(tables: dict[str, TomlValue], key: str) -> TomlValue | None:
    parts = split_key(key)
    try:
        table = table_at(tables, parts, key, create=False)
    except KeyPathError:
        return None
    return table.get(str(parts[-1]))


def _parameters(
    r: ConfigReader, value: object, tables: dict[str, TomlValue], settings: Settings
) -> tuple[Parameter, ...]:
    value = [] if value is None else value
    if not isinstance(value, list) or not all(isinstance(p, Mapping) for p in value):
        r.fail_type("parameters", f"must be an array of tables ([[parameters]]). Got {value!r}.")
    found: list[Parameter] = []
    for k, p in enumerate(value):
        key = f"parameters[{k}]"
        r.keys(p, key, ("key", "bounds", "initial", "scale", "name"), "a parameter")
        target = r.string(p.get("key"), f"{key}.key")
        try:
            parts = split_key(target)
        except KeyPathError as exc:
            r.fail(f"{key}.key", exc.reason)
        if parts[0] not in ("arm", "drives", "outputs"):
            r.fail(f"{key}.key", f"must start with arm, drives or outputs. Got {target!r} instead.")
        try:
            table_at(tables, parts, target, create=False)
        except KeyPathError as exc:
            r.fail(f"{key}.key", exc.reason)
        base = _get(tables, target)
        if base is None and parts[0] == "outputs" and parts[-1] == "delay":
            base = 0.0
        if base is not None and (isinstance(base, bool) or not isinstance(base, int | float)):
            r.fail(f"{key}.key", f"{target!r} is not a number in the file (it is {base!r})")
        scale = p.get("scale", False)
        if not isinstance(scale, bool):
            r.fail_type(f"{key}.scale", f"must be true or false. Got {scale!r} instead.")
        if scale and base is None:
            r.fail(f"{key}.scale", f"a factor needs a value at {target!r} in the file")
        if scale and base == 0:
            r.fail(f"{key}.scale", f"a factor on {target!r} = 0 changes nothing")
        bounds = p.get("bounds")
        if not isinstance(bounds, list) or len(bounds) != 2:
            r.fail(f"{key}.bounds", f"must be [lower, upper]. Got {bounds!r} instead.")
        lo, hi = (r.real(b, f"{key}.bounds") for b in bounds)
        if not lo < hi:
            r.fail(f"{key}.bounds", f"must be increasing, lower < upper. Got {bounds!r} instead.")
        default = 1.0 if scale else (float(base) if base is not None else None)
        if "initial" not in p and default is None:
            default = 0.5 * (lo + hi)  # a key the file does not set: checked by the build
        initial = r.real(p["initial"], f"{key}.initial") if "initial" in p else float(default)  # type: ignore[arg-type]
        if not lo <= initial <= hi:
            r.fail(f"{key}.initial", f"must be within the bounds {bounds}. Got {initial} instead.")
        name = r.string(p.get("name", target), f"{key}.name")
        if any(q.name == name or q.key == target for q in found):
            r.fail(key, f"{name!r} ({target}) is fitted twice")
        found.append(
            Parameter(
                name, target, initial, lo, hi, scale, math.nan if base is None else float(base)
            )
        )
    # an output whose delay is to be estimated: a parameter of its own
    outputs = tables["outputs"]
    assert isinstance(outputs, dict)
    for name, spec in outputs.items():
        assert isinstance(spec, dict)
        if spec.get("delay") == ESTIMATE:
            target = f"outputs.{name}.delay"
            if any(q.key == target for q in found):
                r.fail(f"outputs.{name}.delay", "is 'estimate' and a parameter too: give one")
            spec["delay"] = 0.0
            found.append(
                Parameter(
                    f"delay {name}", target, 0.0, 0.0, settings.max_delay, base=0.0, estimate=True
                )
            )
    return tuple(found)


def _column(r: ConfigReader, value: object, key: str) -> Column:
    t = r.as_table(value, key)
    r.keys(t, key, ("variable", "unit", "column", "file"), "a column")
    if "variable" not in t or "unit" not in t:
        r.fail(key, "needs a 'variable' (or column index) and a 'unit'")
    variable = t["variable"]
    if isinstance(variable, bool) or not isinstance(variable, str | int):
        r.fail_type(f"{key}.variable", f"must be a name or a column index. Got {variable!r}.")
    column = None if t.get("column") is None else r.integer(t["column"], f"{key}.column", 0)
    file = None if t.get("file") is None else r.string(t["file"], f"{key}.file")
    return Column(variable, r.string(t["unit"], f"{key}.unit"), column, file)


def _records(
    r: ConfigReader, value: object, tables: dict[str, TomlValue]
) -> tuple[RecordSpec, ...]:
    if not isinstance(value, list) or not value or not all(isinstance(x, Mapping) for x in value):
        r.fail("records", "must be a non-empty array of tables ([[records]])")
    outputs = tables["outputs"]
    assert isinstance(outputs, dict)
    specs = []
    for k, rec in enumerate(value):
        key = f"records[{k}]"
        r.keys(
            rec,
            key,
            ("file", "name", "role", "start", "stop", "time", "inputs", "outputs"),
            "a record",
        )
        role = rec.get("role", "training")
        if role not in ROLES:
            r.fail(f"{key}.role", f"must be one of {ROLES}. Got {role!r} instead.")
        file = None if rec.get("file") is None else r.string(rec["file"], f"{key}.file")
        if "time" not in rec:
            r.fail(key, "needs a 'time' column")
        time = _column(r, rec["time"], f"{key}.time")
        raw_inputs = rec.get("inputs", [])
        if not isinstance(raw_inputs, list):
            r.fail_type(f"{key}.inputs", f"must be an array of tables. Got {raw_inputs!r}.")
        inputs = []
        for i, item in enumerate(raw_inputs):
            ikey = f"{key}.inputs[{i}]"
            t = r.as_table(item, ikey)
            joint = r.integer(t.get("joint"), f"{ikey}.joint", 0)
            kind = t.get("kind")
            if kind not in INPUT_KINDS:
                r.fail(
                    f"{ikey}.kind", f"must be one of {tuple(INPUT_KINDS)}. Got {kind!r} instead."
                )
            col = {n: v for n, v in t.items() if n not in ("joint", "kind")}
            inputs.append(InputColumn(joint, str(kind), _column(r, col, ikey)))
        joints = [ic.joint for ic in inputs]
        if len(set(joints)) != len(joints):
            r.fail(f"{key}.inputs", f"drives a joint twice: {joints}")
        kinds = {ic.kind for ic in inputs}
        if "angle" in kinds and len(kinds) > 1:
            r.fail(
                f"{key}.inputs", "prescribes angles of some joints and drives others: give one kind"
            )
        raw_outputs = r.as_table(rec.get("outputs", {}), f"{key}.outputs")
        if not raw_outputs:
            r.fail(f"{key}.outputs", "must name at least one measured output")
        cols = {}
        for name, col in raw_outputs.items():
            if name not in outputs:
                r.fail(
                    f"{key}.outputs.{name}",
                    f"unknown output {name!r} (the [outputs]: {', '.join(outputs) or 'none'})",
                )
            cols[name] = _column(r, col, f"{key}.outputs.{name}")
        window = {}
        for w in ("start", "stop"):
            window[w] = None if rec.get(w) is None else r.real(rec[w], f"{key}.{w}")
        if (
            window["start"] is not None
            and window["stop"] is not None
            and window["stop"] <= window["start"]
        ):
            r.fail(
                f"{key}.stop", f"must be after start ({window['start']} s). Got {window['stop']}."
            )
        stop = "end" if window["stop"] is None else f"{window['stop']:g} s"
        cut = window["start"] is not None or window["stop"] is not None
        span = f" [{window['start'] or 0:g} s, {stop})" if cut else ""
        name = rec.get("name") or (file or f"record {k}") + span
        specs.append(
            RecordSpec(
                str(name),
                str(role),
                time,
                tuple(inputs),
                cols,
                file,
                window["start"],
                window["stop"],
            )
        )
    return tuple(specs)
