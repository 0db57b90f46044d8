"""``flexarm simulate``: one closed-loop run from a scenario file and options."""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..control.custom import FACTORY_SPEC
from ..errors import InvalidTypeError, InvalidValueError
from ..sensing.delays import DELAY_METHODS
from ..sensing.sensors import SENSOR_MODELS, PointSensor, Sensor, parse_sensor
from ..sim.animation import ANIMATION_FORMATS
from ..sim.results import SimulationError, SimulationResult, result_files
from ..sim.scenario_schema import (
    CONTROLLERS,
    DELAY_MODELS,
    SHAPER_MODES,
    SHAPERS,
    ScenarioError,
    apply_overrides,
    read_scenario,
)
from ._common import (
    EXIT_FAILURE,
    UsageError,
    add_figure_options,
    check_out,
    figure_format,
    json_ready,
    number,
    word_or_number,
    write_failed,
)

if TYPE_CHECKING:
    from ..sim.scenario import Scenario

__all__ = ["add_parser"]

# which command-line option set which scenario key (for error messages)
_OPTION_OF_KEY = {
    "controller.kind": "--controller",
    "sensor.kind": "--sensor",
    "sensor.link": "--sensor",
    "sensor.distance": "--sensor",
    "sensor.model": "--sensor-model",
    "simulation.smoothing": "--smoothing",
    "simulation.feedforward": "--feedforward",
    "simulation.check_sampling": "--check-sampling",
    "simulation.gravity_compensation": "--gravity-compensation",
    "arm.gravity": "--gravity",
    "delay.delay": "--delay",
    "delay.method": "--delay-method",
    "delay.order": "--pade-order",
    "delay.reference": "--delay-reference",
    "shaper.kind": "--shaper",
    "shaper.modes": "--shaper-modes",
    "simulation.duration": "--duration",
    "simulation.dt": "--dt",
    "simulation.substeps": "--substeps",
    "simulation.seed": "--seed",
    "simulation.record_every": "--record-every",
}


def _sensor_option(text: str) -> Sensor:
    try:
        return parse_sensor(text)
    except (TypeError, ValueError) as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _controller_option(text: str) -> str:
    if text in CONTROLLERS or FACTORY_SPEC.match(text):
        return text
    raise argparse.ArgumentTypeError(
        f"must be one of {', '.join(CONTROLLERS)} or MODULE:FACTORY (your own). "
        f"Got {text!r} instead."
    )


class _PairAction(argparse.Action):
    """Two numbers (``--gravity GX GY``): one or three are an error naming the option,
    not an unrecognised argument."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        if len(values) != 2:
            parser.error(
                f"argument {option_string}: expected 2 numbers ({' '.join(self.metavar or ())}). "
                f"Got {len(values)} instead."
            )
        setattr(namespace, self.dest, tuple(values))


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """The help of ``simulate``: a pair option shows its two metavariables."""

    def _format_args(self, action: argparse.Action, default_metavar: str) -> str:
        if isinstance(action, _PairAction):
            return " ".join(action.metavar)  # type: ignore[arg-type]
        return super()._format_args(action, default_metavar)


_delay_option = word_or_number(DELAY_MODELS, "a number of seconds (>= 0), 'seed' or 'dispersive'")


def _overrides(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """The options given on the command line, in the scenario schema."""
    out: dict[str, dict[str, Any]] = {}

    def put(key: str, value: Any) -> None:
        if value is not None:
            section, name = key.split(".")
            out.setdefault(section, {})[name] = value

    put("controller.kind", args.controller)
    sensor: Sensor | None = args.sensor
    if sensor is not None:
        put("sensor.kind", sensor.name)
        if isinstance(sensor, PointSensor):
            put("sensor.link", sensor.link)
            put("sensor.distance", sensor.distance)
    put("sensor.model", args.sensor_model)
    put("simulation.smoothing", args.smoothing)
    put("simulation.feedforward", args.feedforward)
    put("simulation.check_sampling", args.check_sampling)
    put("simulation.gravity_compensation", args.gravity_compensation)
    if args.gravity is not None:
        put("arm.gravity", list(args.gravity))
    put("delay.delay", args.delay)
    put("delay.method", args.delay_method)
    put("delay.order", args.pade_order)
    put("delay.reference", args.delay_reference)
    put("shaper.kind", args.shaper)
    put("shaper.modes", args.shaper_modes)
    put("simulation.duration", args.duration)
    put("simulation.dt", args.dt)
    put("simulation.substeps", args.substeps)
    put("simulation.seed", args.seed)
    put("simulation.record_every", args.record_every)
    return out


def _build_scenario(args: argparse.Namespace) -> Scenario:
    """The scenario file (if any) with the command-line options over it."""
    from ..sim.scenario import Scenario

    overrides = _overrides(args)
    given = {f"{s}.{k}" for s, table in overrides.items() for k in table}
    try:
        data = read_scenario(args.scenario) if args.scenario is not None else {}
        source = args.scenario if args.scenario is not None else "command line"
        return Scenario.from_dict(apply_overrides(data, overrides), source=source)
    except ScenarioError as exc:
        if exc.key in given:
            option = _OPTION_OF_KEY[exc.key]
            raise UsageError(f"flexarm simulate: error: argument {option}: {exc.reason}") from None
        raise UsageError(f"flexarm simulate: error: {exc}") from None


def _format_summary(summary: dict[str, Any]) -> str:
    s = summary["settings"]
    sim = s["simulation"]
    delay = s["delay"]
    delay_text = (
        "none" if delay["delay_s"] == 0 else f"{delay['delay_s']:.6g} s ({delay['method']})"
    )
    lines = [
        f"flexarm simulate: {len(s['arm']['links'])}-link arm, "
        f"controller {s['controller']['kind']}, "
        f"sensor {s['sensor']['spec']}, delay {delay_text}, shaper {s['shaper']['kind']}, "
        f"{s['trajectory']['kind']} trajectory",
        f"  simulated {summary['sim_time_s']:g} s at dt = {sim['dt']:g} s "
        f"({sim['substeps']} substep(s)) in {summary['wall_time_s']:.3g} s",
        f"  reference: {_reference_text(summary['run'])}",
    ]

    def num(x: Any, unit: str) -> str:
        return "n/a" if x is None else f"{x:.6g} {unit}"

    known = [x for x in summary["corner_errors_m"] if x is not None]
    corners = (
        ", ".join("n/a" if x is None else f"{x:.4g}" for x in summary["corner_errors_m"]) + " m"
        if known
        else "n/a"
    )
    rows = [
        ("rms error", num(summary["rms_error_m"], "m")),
        ("max error", num(summary["max_error_m"], "m")),
        ("corner errors", corners),
        ("residual vibration", num(summary["residual_vibration_m"], "m")),
        ("settling time", num(summary["settling_time_s"], "s")),
        ("control effort", num(summary["control_effort_N2m2s"], "N^2 m^2 s")),
        ("max torque", num(summary["max_torque_Nm"], "N m")),
    ]
    lines += [f"  {name:<20}{value}" for name, value in rows]
    return "\n".join(lines)


def _json_text(summary: dict[str, Any], result: SimulationResult | None) -> str:
    """What ``--json`` prints: the summary, and with ``result`` its time series (the
    columns of ``timeseries.csv``, one list per column, non-finite values null) under
    ``"series"``, each column on one line."""
    text = json.dumps(summary, indent=2)
    if result is None:
        return text
    header, table = result.table()
    columns = [
        f'    "{name}": ' + json.dumps([v if math.isfinite(v) else None for v in col.tolist()])
        for name, col in zip(header, table.T, strict=True)
    ]
    series = ',\n  "series": {\n' + ",\n".join(columns) + "\n  }\n}"
    return text[: text.rindex("}")].rstrip() + series


def _reference_text(run: dict[str, Any]) -> str:
    """The reference the run used, and who chose it."""
    sigma = run.get("smoothing_s")
    who = "the controller's choice" if run.get("reference_chosen_by") == "controller" else "set"
    shape = "the raw path" if not sigma else f"the path smoothed by a {sigma:.3g} s Gaussian"
    return f"{shape} ({who})"


def _check_animate(path: str | None) -> Path | None:
    """The ``--animate`` file, checked before anything runs: a .gif or .mp4 (ffmpeg on
    PATH) in an existing directory."""
    if path is None:
        return None
    target = Path(os.path.abspath(path))
    option = "flexarm simulate: error: argument --animate"
    if target.suffix.lower() not in ANIMATION_FORMATS:
        raise UsageError(f"{option}: must end in .gif or .mp4. Got {path!r} instead.")
    if target.suffix.lower() == ".mp4" and shutil.which("ffmpeg") is None:
        raise UsageError(f"{option}: writing an MP4 needs ffmpeg on PATH (not found); use a .gif")
    if not target.parent.is_dir():
        raise UsageError(f"{option}: no such directory: {str(target.parent)!r}")
    return target


def _cmd_simulate(args: argparse.Namespace) -> int:
    if args.series and not args.json:
        raise UsageError("flexarm simulate: error: argument --series: needs --json")
    scenario = _build_scenario(args)
    out = Path(os.path.abspath(args.out)) if args.out is not None else None
    if out is not None:
        check_out(out, "flexarm simulate")
    movie = _check_animate(args.animate)
    fmt = figure_format(args, "flexarm simulate", out)
    files = list(result_files(fmt))

    # the measurement and the reference are recorded only where something reads them
    # (the files, the animation, the printed series): the summary's metrics do not
    keep = out is not None or movie is not None or args.series
    record = scenario.simulation.record_signals and keep
    try:
        result = scenario.simulate(progress=None, record_signals=record)
        diverged = None
    except (InvalidValueError, InvalidTypeError) as exc:  # e.g. a path outside the workspace
        raise UsageError(f"flexarm simulate: error: {scenario.source}: {exc}") from None
    except SimulationError as exc:  # the partial run is a result too: kept, marked
        result, diverged = exc.result, exc
    metrics: dict[str, object] = dict(result.metrics())
    if diverged is not None:  # the metrics of a run that did not finish mean nothing
        metrics = dict.fromkeys(metrics)
    summary = json_ready(
        {
            "status": "ok" if diverged is None else "diverged",
            **metrics,
            **(
                {}
                if diverged is None
                else {"diverged_at_s": diverged.time, "last_state": diverged.state}
            ),
            "settings": scenario.description,
            "run": result.info,
            "out": args.out,
            "files": [] if out is None else files,
            "animation": None if movie is None else str(movie),
        }
    )
    if out is not None:
        try:
            result.write(out, summary, figure_format=fmt)
        except OSError as exc:
            print(write_failed("flexarm simulate", out, exc), file=sys.stderr)
            return EXIT_FAILURE
    if movie is not None:  # a diverged run's partial result too: watch it go
        from ..sim.animation import write_animation

        try:
            write_animation(result, movie)
        except OSError as exc:
            print(f"flexarm simulate: error: cannot write {str(movie)!r}: {exc}", file=sys.stderr)
            return EXIT_FAILURE
    if diverged is not None:
        kept = f"; the run up to then is in {out}" if out is not None else "; nothing written"
        if out is None and movie is not None:
            kept = f"; the run up to then is drawn in {movie}"
        print(
            f"flexarm simulate: the simulation diverged at t = {diverged.time:.6g} s (state "
            f"non-finite, overflowing or a tip deflection beyond max_deflection){kept}",
            file=sys.stderr,
        )
        if args.json:
            print(_json_text(summary, result if args.series else None))
        return EXIT_FAILURE
    if args.json:
        print(_json_text(summary, result if args.series else None))
    else:
        print(_format_summary(summary))
        if out is not None:
            print(f"  results in {out}: {', '.join(files)}")
    return 0


_SIMULATE_DESCRIPTION = """\
Simulate the closed loop: by default the paper's arm (two 4.5 m links, one mode each)
tracking the default square (20 s) under the paper's Jacobian-transpose PD gains with
joint encoders. --scenario FILE.toml sets anything (arm, trajectory, sensor, controller,
delay, shaper, simulation; schema in flexarm.sim.scenario_schema, example in
examples/paper_square.toml); options given on the command line override the file.
"""

_SIMULATE_EPILOG = """\
shaper: designed for the first clamped frequency of the first link (--shaper-modes
first, the default), or for every link's first clamped frequency, one shaper per link
convolved (--shaper-modes all).

delay: 'seed' and 'dispersive' compute the bending-wave travel time over the path
along the links from the base joint to the sensed point (0 for joint encoders, 9 m
for the paper arm's tip), at the seed's speed (41 783 m/s) or at the dispersive group
speed of the first link at its first clamped frequency.

output: with --out DIR, once the run has ended DIR (new, or an empty directory)
receives result.npz (SimulationResult.load), summary.json (what --json prints),
timeseries.csv and tracking.png (tracking.pdf, tracking.svg with --format), all at
once (written beside it and renamed into place): the whole run, or a diverged run up
to its divergence (its summary's status "diverged", its metrics null). Bad input
writes nothing. Metrics that are undefined (corners after a short run's end) are
null in JSON.

exit status: 0 success; 1 the simulation diverged (one line on stderr with the time
and where the partial run is kept) or the results could not be written; 2 bad input
(one line on stderr, nothing written).
"""


def add_parser(sub: Any) -> None:
    """Add ``simulate`` to the subcommands ``sub``."""
    summary = "simulate the closed loop (the paper's arm on the square by default)"
    sim = sub.add_parser(
        "simulate",
        help=summary,
        description=_SIMULATE_DESCRIPTION,
        epilog=_SIMULATE_EPILOG,
        formatter_class=_Formatter,
    )
    sim.add_argument("--scenario", metavar="FILE.toml", help="scenario file (TOML)")
    sim.add_argument(
        "--controller",
        type=_controller_option,
        metavar="|".join((*CONTROLLERS, "MODULE:FACTORY")),
        help="pd: the paper's Jacobian-transpose PD gains from the first link's first "
        "frequency (default); jt-pd: the same law with the scenario's kp, kd (named pd in "
        "the results); "
        "joint-pd: JointPD; fuzzy: the paper's gains with the fuzzy adaptive law "
        "(FuzzyAdaptiveJTPD; set ks and law in the scenario file); lqg: observer-based "
        "LQG from the sensor alone with rigid feedforward; reflected: PD on the reflected "
        "output (alpha in the scenario file); MODULE:FACTORY: your own, FACTORY(arm, the "
        "scenario's other controller keys as keywords) returning a Controller (module from "
        "the current directory or sys.path; examples/my_controller.py)",
    )
    sim.add_argument(
        "--sensor",
        type=_sensor_option,
        metavar="joint|tip|point:LINK:DISTANCE",
        help="joint encoders (default), the end effector, or a point DISTANCE m along link "
        "LINK (0-based: point:1:0.5 is 0.5 m from the elbow)",
    )
    sim.add_argument(
        "--sensor-model",
        choices=SENSOR_MODELS,
        help="physical: the deflected point (default); paper: the rigid kinematics of the "
        "joint angles at that point, as the paper simulated it",
    )
    sim.add_argument(
        "--delay",
        type=_delay_option,
        metavar="SECONDS|seed|dispersive",
        help="transport delay of the sensed signal (default 0; see below)",
    )
    sim.add_argument("--delay-method", choices=DELAY_METHODS, help="default exact")
    sim.add_argument("--pade-order", type=int, metavar="N", help="Pade order (default 2)")
    sim.add_argument(
        "--delay-reference",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="delay the command fed to the control law by the same amount",
    )
    sim.add_argument("--shaper", choices=SHAPERS, help="input shaper (default none)")
    sim.add_argument("--shaper-modes", choices=SHAPER_MODES, help="default first (see below)")
    sim.add_argument(
        "--duration", type=float, metavar="SECONDS", help="default: the trajectory's duration"
    )
    sim.add_argument(
        "--dt",
        type=float,
        metavar="SECONDS",
        help="control period (default 2e-4 s; the hubless paper arm under the paper's gains "
        "is sampled-data unstable at 1 ms)",
    )
    sim.add_argument("--substeps", type=int, metavar="N", help="RK4 steps per period (default 1)")
    sim.add_argument(
        "--record-every",
        type=int,
        metavar="K",
        help="record every K-th control instant and the last (default 1: all); a long run "
        "then fits in bounded memory",
    )
    sim.add_argument(
        "--smoothing",
        type=float,
        metavar="SECONDS",
        help="standard deviation of a zero-phase Gaussian smoothing of the reference path "
        "(default: what the controller asks for: none for pd, jt-pd, joint-pd and fuzzy, the "
        "paper's laws; lqg and reflected choose it from their closed loop, 0.056 s and 0.23 s "
        "on the paper's arm with the tip; 0: the raw path, its corners taken at constant "
        "speed; the summary's run.smoothing_s and run.reference_chosen_by say which was used)",
    )
    sim.add_argument(
        "--feedforward",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="add the rigid inverse dynamics of the reference (default: the controller's "
        "choice; on for lqg)",
    )
    sim.add_argument(
        "--check-sampling",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="refuse a control period beyond the sampled loop's stability bound (default on)",
    )
    sim.add_argument(
        "--gravity",
        nargs="+",
        action=_PairAction,
        type=number(),
        metavar=("GX", "GY"),
        help="gravity in the plane of motion, m/s^2 in the base frame (0 -9.81: a vertical "
        "plane with y up); overrides the scenario's [arm] gravity (default: the scenario's, "
        "none without: a horizontal plane)",
    )
    sim.add_argument(
        "--gravity-compensation",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="with gravity: add to the law's torque the holding torques of the measured "
        "posture, its links' sag included (default: the controller's choice; on for the "
        "built-in laws, off for your own)",
    )
    sim.add_argument("--seed", type=int, metavar="N", help="seed of the sensor noise")
    sim.add_argument("--out", metavar="DIR", help="write the results into DIR (see below)")
    sim.add_argument(
        "--animate",
        metavar="FILE.gif|FILE.mp4",
        help="write an animation of the deflected arm (25 frames per simulated second; GIF "
        "through Pillow, MP4 through ffmpeg, which must be on PATH)",
    )
    add_figure_options(sim)
    sim.add_argument(
        "--json",
        action="store_true",
        help="print the JSON summary on stdout (the metrics, the settings and the run's "
        "account, not the time series; what --out writes as summary.json)",
    )
    sim.add_argument(
        "--series",
        action="store_true",
        help="with --json: also print the time series (the columns of timeseries.csv: t, "
        'q, dq, tau, desired, reference and tip positions, error) under "series"',
    )
    sim.set_defaults(func=_cmd_simulate)
