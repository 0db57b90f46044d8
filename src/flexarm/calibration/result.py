"""What a calibration found: :class:`Calibration`, and :func:`calibrate`.

:func:`calibrate` reads a calibration (a file or a
:class:`~flexarm.calibration.config.CalibrationConfig`), fits it
(:mod:`flexarm.calibration.fit`) and predicts every record, training and
validation, with the initial and the fitted plant. :class:`Calibration` holds the
values with their 95 % confidence intervals and correlations, the parameters the
data could not determine, each record's fit % and RMS per channel before and
after, the fitted arm's modes (frequencies and damping ratios, actuators locked),
and writes it all: ``summary.json``, a report with the measured and predicted
signals overlaid (``report.html`` and a figure per record), and the fitted arm as
a file's tables (``calibrated.toml``). :meth:`Calibration.validate` predicts
further records in the same format with the fitted arm.
"""

from __future__ import annotations

import html
import json
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._config import TomlValue, copy_value, set_key
from .._io import JSONValue, json_ready, output_directory
from .._types import F64
from ..errors import CalibrationError
from ..model.damped_modes import DampedModes, damped_modes
from .config import CalibrationConfig, load_config
from .fit import Fit, calibrate_records, fit_percent, initial_states, load_records
from .model import Plant, Predictor, build_plant
from .records import load_record

if TYPE_CHECKING:
    from ..figures import FigureFormat

__all__ = ["Calibration", "ChannelFit", "RecordFit", "calibrate", "toml_text"]


@dataclass(frozen=True)
class ChannelFit:
    """One channel of one record: fit % and RMS (SI) with the fitted and the
    initial plant."""

    fit_percent: float
    rms: float
    fit_percent_initial: float
    rms_initial: float


@dataclass(frozen=True)
class RecordFit:
    """One record replayed: its channels' fits, and the series for plots."""

    name: str
    files: tuple[str, ...]
    role: str
    channels: dict[str, ChannelFit]
    t: F64 = field(repr=False)
    measured: dict[str, F64] = field(repr=False)
    predicted: dict[str, F64] = field(repr=False)
    predicted_initial: dict[str, F64] = field(repr=False)

    def summary(self) -> dict[str, JSONValue]:
        """``{"file", "name", "channels": {name: {"fit_percent", "rms", ...}}}``."""
        return {
            "file": self.files[0] if len(self.files) == 1 else list(self.files),
            "name": self.name,
            "channels": {n: _plain(c.__dict__) for n, c in self.channels.items()},
        }


def _plain(d: Mapping[str, float]) -> dict[str, JSONValue]:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


def _rms(e: F64) -> float:
    return float(np.sqrt(np.mean(e**2))) if np.all(np.isfinite(e)) else float("nan")


def _record_fit(
    predictor: Predictor, k: int, plant: Plant, initial: Plant, fit: Fit | None
) -> RecordFit:
    rec = predictor.records[k]
    nuisance = None
    training = [i for i, r in enumerate(predictor.records) if r.role == "training"]
    if fit is not None and k in training and fit.nuisance:
        nuisance = fit.nuisance[training.index(k)]
    else:  # a record the fit did not see: its initial states estimated, parameters held
        nuisance = initial_states(predictor, plant, k)
    after = predictor.predict(plant, k, nuisance)
    before = predictor.predict(initial, k, initial_states(predictor, initial, k))
    channels = {
        name: ChannelFit(
            fit_percent(y, after[name]),
            _rms(after[name] - y),
            fit_percent(y, before[name]),
            _rms(before[name] - y),
        )
        for name, y in rec.outputs.items()
    }
    return RecordFit(
        rec.name, rec.files, rec.role, channels, rec.t, dict(rec.outputs), after, before
    )


@dataclass
class Calibration:
    """A calibration's result (module docstring).

    Attributes
    ----------
    config : CalibrationConfig
    fit : Fit
        The least squares' raw numbers.
    plant, initial_plant : Plant
        The fitted and the initial arm, drives and instruments.
    records : list of RecordFit
        Every record of the configuration, in its order.
    modes : DampedModes
        The fitted arm's modes, actuators locked, straight arm.
    wall_time_s : float
    """

    config: CalibrationConfig
    fit: Fit
    plant: Plant
    initial_plant: Plant
    records: list[RecordFit]
    modes: DampedModes
    wall_time_s: float
    _predictor: Predictor = field(repr=False)

    # ---------------------------------------------------------------- numbers
    def parameters(self) -> dict[str, dict[str, JSONValue]]:
        """Per parameter: ``value`` (at its key, SI), ``ci95`` (half-width, None
        where not fitted), ``ci95_correlated`` (widened for the residuals' lag-one
        correlation), ``initial``, ``bounds``, ``factor`` (scale parameters),
        ``determined`` and why not, and whether it ended at a bound."""
        out: dict[str, dict[str, JSONValue]] = {}
        fit = self.fit
        sd = np.sqrt(np.clip(np.diag(fit.covariance), 0.0, None))
        rho = max([0.0, *fit.residual_correlation.values()])
        widen = math.sqrt((1 + rho) / (1 - rho)) if rho < 1 else math.inf
        from scipy.stats import t as student

        quantile = float(student.ppf(0.975, fit.dof))
        j = 0
        for i, p in enumerate(self.config.parameters):
            x = float(fit.values[i])
            entry: dict[str, JSONValue] = {
                "key": p.key,
                "value": p.physical(x),
                "initial": p.physical(float(fit.initial[i])),
                "bounds": [p.physical(p.lower), p.physical(p.upper)],
            }
            if p.scale:
                entry["factor"] = x
            if fit.free[i]:
                half = quantile * float(sd[j]) * (abs(p.base) if p.scale else 1.0)
                entry["ci95"] = half
                entry["ci95_correlated"] = half * widen
                entry["determined"] = True
                span = p.upper - p.lower
                entry["at_bound"] = bool(min(x - p.lower, p.upper - x) <= 1e-6 * span)
                j += 1
            else:
                entry["ci95"] = None
                entry["ci95_correlated"] = None
                entry["determined"] = False
                entry["note"] = f"held at its initial value: {fit.held[p.name]}"
            out[p.name] = entry
        return out

    def correlations(self) -> tuple[list[str], F64]:
        """The fitted parameters' names and their correlation matrix."""
        names = [p.name for p, f in zip(self.config.parameters, self.fit.free, strict=True) if f]
        cov = self.fit.covariance
        sd = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
        return names, cov / np.outer(sd, sd)

    def summary(self) -> dict[str, JSONValue]:
        """JSON-ready: ``parameters``, ``correlations``, ``undetermined``,
        ``training`` and ``validation`` (per record: file, name, channels with
        ``fit_percent`` and ``rms`` after and before), ``modes``, the settings."""
        names, corr = self.correlations()
        summary: dict[str, JSONValue] = json_ready(
            {
                "source": self.config.source,
                "parameters": self.parameters(),
                "correlations": {"names": names, "matrix": corr.tolist()},
                "undetermined": dict(self.fit.held),
                "residual_lag1_correlation": self.fit.residual_correlation,
                "training": [r.summary() for r in self.records if r.role == "training"],
                "validation": [r.summary() for r in self.records if r.role == "validation"],
                "modes": {
                    "frequencies_hz": self.modes.frequencies_hz.tolist(),
                    "damping_ratios": self.modes.damping.tolist(),
                    "damped_frequencies_hz": (self.modes.damped_frequencies / (2 * np.pi)).tolist(),
                },
                "evaluations": self.fit.evaluations,
                "wall_time_s": self.wall_time_s,
                "settings": dict(self.config.settings.__dict__),
            }
        )
        return summary

    def text(self) -> str:
        """A short account for the terminal."""
        lines = [f"calibration of {self.config.source} ({self.wall_time_s:.1f} s):"]
        for name, e in self.parameters().items():
            ci = "not determined" if e["ci95"] is None else f"+- {e['ci95']:.3g}"
            lines.append(f"  {name} = {e['value']:.6g} ({ci})")
        for r in self.records:
            fits = ", ".join(
                f"{n} {c.fit_percent:.1f} % (was {c.fit_percent_initial:.1f} %)"
                for n, c in r.channels.items()
            )
            lines.append(f"  {r.role} {r.name}: {fits}")
        return "\n".join(lines)

    # ---------------------------------------------------------------- more records
    def validate(self, paths: Sequence[str | os.PathLike[str]]) -> list[RecordFit]:
        """Predict further files in the format of the configuration's first record
        (its columns and units, another file), with the fitted plant."""
        template = self.config.records[0]
        out = []
        for path in paths:
            spec = replace(template, name=os.fspath(path), role="validation", file=os.fspath(path))
            spec = replace(
                spec,
                time=replace(spec.time, file=None),
                inputs=tuple(
                    replace(ic, values=replace(ic.values, file=None)) for ic in spec.inputs
                ),
                outputs={n: replace(c, file=None) for n, c in spec.outputs.items()},
            )
            rec = load_record(spec, Path.cwd(), self.config.source, len(self.config.records))
            predictor = Predictor(self.config, [rec])
            out.append(_record_fit(predictor, 0, self.plant, self.initial_plant, None))
        return out

    def calibrated_tables(self) -> dict[str, TomlValue]:
        """The file's ``arm``, ``drives`` and ``outputs`` tables with the fitted values."""
        tables = {k: copy_value(v) for k, v in self.config.tables.items()}
        for p, x in zip(self.config.parameters, self.fit.values, strict=True):
            set_key(tables, p.key, p.physical(float(x)))
        return tables

    # ---------------------------------------------------------------- files
    def figure(self, record: RecordFit) -> Any:
        """A figure of one record: each channel measured, predicted after and before."""
        from ..figures import DOUBLE_COLUMN, new_figure

        n = len(record.measured)
        fig = new_figure(DOUBLE_COLUMN, 1.5 + 1.4 * n)
        axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
        for ax, (name, y) in zip(axes, record.measured.items(), strict=True):
            c = record.channels[name]
            ax.plot(record.t, y, color="k", lw=0.9, label="measured")
            ax.plot(
                record.t, record.predicted[name], lw=0.9, label=f"fitted ({c.fit_percent:.1f} %)"
            )
            ax.plot(
                record.t,
                record.predicted_initial[name],
                lw=0.7,
                ls="--",
                color="0.5",
                label=f"initial ({c.fit_percent_initial:.1f} %)",
            )
            unit = self.config_unit(name)
            ax.set_ylabel(f"{name} ({unit})")
            ax.legend(loc="best", fontsize=7)
        axes[-1].set_xlabel("t (s)")
        axes[0].set_title(f"{record.role}: {record.name}")
        return fig

    def config_unit(self, name: str) -> str:
        """The SI unit of an output channel."""
        inst = self.plant.outputs[name]
        kind = type(inst).__name__
        if kind == "StrainGauge" and getattr(inst, "form", "") == "strain":
            return "-"
        return "rad"

    def write(
        self, out: str | os.PathLike[str], *, figure_format: FigureFormat | str | None = None
    ) -> list[str]:
        """Write ``summary.json``, ``calibrated.toml``, a figure per record and
        ``report.html`` into the directory ``out`` (new, or empty), all at once
        (written beside it and renamed into place); return the file names."""
        from ..figures import FigureFormat, save_figure

        fmt = FigureFormat.coerce(figure_format)
        target = Path(out)
        files = ["summary.json", "calibrated.toml"]
        with output_directory(target) as tmp:
            (tmp / "summary.json").write_text(json.dumps(self.summary(), indent=2))
            (tmp / "calibrated.toml").write_text(toml_text(self.calibrated_tables()))
            figures = []
            for k, rec in enumerate(self.records):
                path = save_figure(self.figure(rec), tmp / f"record{k}", fmt)
                figures.append((path.name, rec))
                files.append(path.name)
            (tmp / "report.html").write_text(self._html(figures))
            files.append("report.html")
        return files

    def _html(self, figures: Sequence[tuple[str, RecordFit]]) -> str:
        rows = []
        for name, e in self.parameters().items():
            ci = "not determined" if e["ci95"] is None else f"&plusmn; {e['ci95']:.3g}"
            note = html.escape(str(e.get("note", "")))
            rows.append(
                f"<tr><td>{html.escape(name)}</td><td>{e['value']:.6g}</td><td>{ci}</td>"
                f"<td>{e['initial']:.6g}</td><td>{note}</td></tr>"
            )
        fits = []
        for r in self.records:
            for n, c in r.channels.items():
                fits.append(
                    f"<tr><td>{r.role}</td><td>{html.escape(r.name)}</td><td>{html.escape(n)}</td>"
                    f"<td>{c.fit_percent:.1f}</td><td>{c.rms:.3g}</td>"
                    f"<td>{c.fit_percent_initial:.1f}</td><td>{c.rms_initial:.3g}</td></tr>"
                )
        images = "".join(
            f'<figure><img src="{n}" alt="{html.escape(r.role)} record {html.escape(r.name)}: '
            'measured and predicted channels">'
            f"<figcaption>{html.escape(r.name)}</figcaption></figure>"
            for n, r in figures
        )
        modes = ", ".join(
            f"{f:.4g} Hz (damping {z:.3g})"
            for f, z in zip(self.modes.frequencies_hz, self.modes.damping, strict=True)
        )
        return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>Calibration: {html.escape(self.config.source)}</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:auto}}table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:0.2em 0.5em}}img{{max-width:100%}}</style></head><body>
<h1>Calibration of {html.escape(self.config.source)}</h1>
<h2>Parameters</h2><table><tr><th>parameter</th><th>value (SI)</th><th>95 % interval</th>
<th>initial</th><th>note</th></tr>{"".join(rows)}</table>
<h2>Fit per record and channel</h2><table><tr><th>role</th><th>record</th><th>channel</th>
<th>fit (%)</th><th>RMS (SI)</th><th>initial fit (%)</th><th>initial RMS (SI)</th></tr>
{"".join(fits)}</table>
<h2>Modes of the fitted arm (actuators locked)</h2><p>{modes or "none"}</p>
<h2>Records</h2>{images}</body></html>
"""


def calibrate(
    config: CalibrationConfig | str | os.PathLike[str],
    *,
    data: str | os.PathLike[str] | None = None,
    workers: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> Calibration:
    """Calibrate an arm on measured records.

    Parameters
    ----------
    config : CalibrationConfig or path
        The calibration (a TOML file: :mod:`flexarm.calibration.config`).
    data : path, optional
        Read the records from this directory instead of the file's ``data``.
    workers : int, optional
        Threads for the Jacobian (default: every core this process may use).
    progress : callable, optional
        Called with a line of text at each stage.

    Returns
    -------
    Calibration

    Raises
    ------
    CalibrationError
        For a configuration or a record that cannot be used, naming the key.
    """
    if not isinstance(config, CalibrationConfig):
        config = load_config(config)
    if data is not None:
        config = config.with_data(data)
    start = time.perf_counter()
    records = load_records(config)
    fit = calibrate_records(config, records, workers=workers, progress=progress)
    plant = build_plant(config, fit.values)
    initial = build_plant(config, fit.initial)
    predictor = Predictor(config, records)
    n_workers = workers or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1)
    with ThreadPoolExecutor(max(1, n_workers)) as pool:  # the replays release the GIL
        fits = list(
            pool.map(lambda k: _record_fit(predictor, k, plant, initial, fit), range(len(records)))
        )
    return Calibration(
        config=config,
        fit=fit,
        plant=plant,
        initial_plant=initial,
        records=fits,
        modes=damped_modes(plant.arm),
        wall_time_s=time.perf_counter() - start,
        _predictor=predictor,
    )


def toml_text(tables: Mapping[str, TomlValue]) -> str:
    """``tables`` as TOML text: scalars and arrays of scalars as key-value pairs,
    tables as ``[a.b]`` sections and arrays of tables as ``[[a.b]]``."""

    def value(v: TomlValue) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int | float):
            if isinstance(v, float) and not math.isfinite(v):
                return "inf" if v > 0 else ("-inf" if v < 0 else "nan")
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        raise CalibrationError("calibrated.toml", None, f"cannot write {v!r} as TOML")

    lines: list[str] = []

    def section(prefix: str, table: Mapping[str, TomlValue], header: str) -> None:
        scalars = {k: v for k, v in table.items() if not _is_table(v) and not _is_table_array(v)}
        if header:
            lines.append("")
            lines.append(header)
        for k, v in scalars.items():
            lines.append(f"{k} = {value(v)}")
        for k, v in table.items():
            name = f"{prefix}.{k}" if prefix else k
            if _is_table(v):
                assert isinstance(v, dict)
                section(name, v, f"[{name}]")
            elif _is_table_array(v):
                assert isinstance(v, list)
                for item in v:
                    assert isinstance(item, dict)
                    section(name, item, f"[[{name}]]")

    section("", tables, "")
    return "\n".join(lines).lstrip("\n") + "\n"


def _is_table(v: TomlValue) -> bool:
    return isinstance(v, dict)


def _is_table_array(v: TomlValue) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)
