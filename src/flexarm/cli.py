"""The ``flexarm`` command line: parse, call the library, print.

Bad input ends with one line on stderr and exit status 2, never a traceback.
A simulation that diverges ends with one line on stderr and exit status 1.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import secrets
import shutil
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from . import __version__
from .arm import BOUNDARIES, FlexibleArm
from .delays import DELAY_METHODS
from .joints import LinearJoint, MakkarFriction, NonlinearJoint
from .modes import NORMALIZATIONS, BeamModes
from .results import SimulationResult
from .scenario import (
    CONTROLLERS,
    DELAY_MODELS,
    SHAPER_MODES,
    SHAPERS,
    Scenario,
    ScenarioError,
    apply_overrides,
    read_scenario,
)
from .sensors import PointSensor, Sensor, parse_sensor
from .simulate import SimulationError, simulate

JOINT_CHOICES = ("rigid", "linear", "nonlinear")

__all__ = ["main"]

EXIT_FAILURE = 1  # the simulation diverged, or the results could not be written
EXIT_USAGE = 2
OUTPUT_FILES = ("result.npz", "summary.json", "timeseries.csv", "tracking.png")


class UsageError(Exception):
    """Bad input on the command line (exit status 2)."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, not a usage dump."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: error: {message}")


# ----------------------------------------------------------------- modes
def _mode_table(modes: BeamModes) -> dict[str, Any]:
    """Modal data of one beam as JSON-ready lists."""
    return {
        "length_m": modes.length,
        "flexural_rigidity_Nm2": modes.flexural_rigidity,
        "linear_density_kg_per_m": modes.linear_density,
        "tip_mass_kg": modes.tip_mass,
        "tip_inertia_kgm2": modes.tip_inertia,
        "normalization": modes.normalization,
        "roots": modes.roots.tolist(),
        "wavenumbers_per_m": modes.wavenumbers.tolist(),
        "frequencies_rad_s": modes.frequencies.tolist(),
        "frequencies_hz": modes.frequencies_hz.tolist(),
        "modal_mass": np.diag(modes.generalized_mass).tolist(),
        "modal_stiffness": np.diag(modes.modal_stiffness).tolist(),
        "tip_deflection": modes.tip_deflection.tolist(),
        "tip_slope": modes.tip_slope.tolist(),
        "mass_integral": modes.mass_integral.tolist(),
        "moment_integral": modes.moment_integral.tolist(),
    }


def _format_modes(title: str, table: dict[str, Any]) -> str:
    t = table
    head = (
        f"{title}: L = {t['length_m']:g} m, EI = {t['flexural_rigidity_Nm2']:g} N m^2, "
        f"rho = {t['linear_density_kg_per_m']:g} kg/m, tip mass = {t['tip_mass_kg']:g} kg, "
        f"tip inertia = {t['tip_inertia_kgm2']:g} kg m^2 ({t['normalization']} normalisation)"
    )
    cols = [
        ("mode", "{:>4d}"),
        ("beta*L", "{:>14.10f}"),
        ("omega rad/s", "{:>13.5f}"),
        ("f Hz", "{:>11.5f}"),
        ("modal mass", "{:>11.5g}"),
        ("stiffness", "{:>11.5g}"),
        ("phi(L)", "{:>10.5g}"),
        ("phi'(L)", "{:>10.5g}"),
        ("int rho phi", "{:>11.5g}"),
        ("int rho x phi", "{:>13.5g}"),
    ]
    keys = [
        "roots",
        "frequencies_rad_s",
        "frequencies_hz",
        "modal_mass",
        "modal_stiffness",
        "tip_deflection",
        "tip_slope",
        "mass_integral",
        "moment_integral",
    ]
    widths = [len(fmt.format(1 if i == 0 else 1.0)) for i, (_, fmt) in enumerate(cols)]
    lines = [head, "  ".join(name.rjust(w) for (name, _), w in zip(cols, widths, strict=True))]
    for j in range(len(table["roots"])):
        row = [cols[0][1].format(j + 1)]
        row += [fmt.format(table[k][j]) for (_, fmt), k in zip(cols[1:], keys, strict=True)]
        lines.append("  ".join(row))
    if not table["roots"]:
        lines.append("  (rigid link: no modes)")
    return "\n".join(lines)


def _cmd_modes(args: argparse.Namespace) -> int:
    single = [args.length, args.flexural_rigidity, args.linear_density]
    if any(v is not None for v in single):
        if any(v is None for v in single):
            raise UsageError(
                "flexarm modes: error: a link needs --length, --flexural-rigidity and "
                "--linear-density"
            )
        if args.boundary is not None or args.joints != "rigid":
            raise UsageError(
                "flexarm modes: error: --boundary and --joints apply to the arm, not a single link"
            )
        modes = BeamModes(
            args.length,
            args.flexural_rigidity,
            args.linear_density,
            n_modes=args.n_modes if args.n_modes is not None else 3,
            tip_mass=args.tip_mass,
            tip_inertia=args.tip_inertia,
            normalization=args.normalization,
            amplitude=args.amplitude,
        )
        summary: dict[str, Any] = {"links": [_mode_table(modes)]}
        text = _format_modes("Link", summary["links"][0])
    else:
        if args.tip_mass or args.tip_inertia:
            raise UsageError(
                "flexarm modes: error: --tip-mass and --tip-inertia need a single link"
            )
        joints: list[LinearJoint | NonlinearJoint] | None = None
        if args.joints == "linear":
            joints = [LinearJoint.default()] * 2
        elif args.joints == "nonlinear":
            joints = [NonlinearJoint.default(MakkarFriction.default())] * 2
        arm = FlexibleArm.paper(
            n_modes=args.n_modes if args.n_modes is not None else 1,
            boundary=args.boundary or "clamped-free",
            mode_normalization=args.normalization,
            mode_amplitude=args.amplitude,
            joints=joints,
        )
        tables = [_mode_table(m) for m in arm.modes]
        locked = arm.natural_frequencies(joints="locked")
        free = arm.natural_frequencies(joints="free")
        summary = {
            "arm": "paper",
            "boundary": arm.boundary,
            "joints": args.joints,
            "links": tables,
            "arm_frequencies_locked_rad_s": locked.tolist(),
            "arm_frequencies_free_rad_s": free.tolist(),
        }
        text = "\n\n".join(
            _format_modes(f"Link {i + 1} of the paper's arm ({arm.boundary})", t)
            for i, t in enumerate(tables)
        )
        kind = {
            "rigid": "rigid joints",
            "linear": "linear joints (default)",
            "nonlinear": "nonlinear joints (default, stiffness a1 - ksw at rest)",
        }
        text += f"\n\nWhole arm, straight, {kind[args.joints]}, linearised (rad/s | Hz):"
        for label, w in (("actuators locked", locked), ("actuators free  ", free)):
            text += f"\n  {label}: " + ", ".join(f"{x:.5f} | {x / (2 * np.pi):.5f}" for x in w)
    print(json.dumps(summary, indent=2) if args.json else text)
    return 0


# ----------------------------------------------------------------- simulate
# which command-line option set which scenario key (for error messages)
_OPTION_OF_KEY = {
    "controller.kind": "--controller",
    "sensor.kind": "--sensor",
    "sensor.link": "--sensor",
    "sensor.distance": "--sensor",
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
}


def _sensor_option(text: str) -> Sensor:
    try:
        return parse_sensor(text)
    except (TypeError, ValueError) as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _delay_option(text: str) -> str | float:
    if text in DELAY_MODELS:
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be a number of seconds (>= 0), 'seed' or 'dispersive'. Got {text!r} instead."
        ) from None


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
    return out


def _build_scenario(args: argparse.Namespace) -> Scenario:
    """The scenario file (if any) with the command-line options over it."""
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


def _check_out(out: Path) -> None:
    """Refuse an --out that cannot take the results, before simulating."""
    if out.exists() and not (out.is_dir() and not any(out.iterdir())):
        raise UsageError(
            f"flexarm simulate: error: argument --out: {str(out)!r} exists and is not an empty "
            "directory (results are never overwritten)"
        )
    parent = out.parent
    if not parent.is_dir():
        raise UsageError(
            f"flexarm simulate: error: argument --out: the parent directory {str(parent)!r} "
            "does not exist"
        )


def _json_ready(value: Any) -> Any:
    """Strict JSON: NaN and infinities become null; tuples and arrays, lists."""
    if isinstance(value, Mapping):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_ready(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _write_outputs(out: Path, result: SimulationResult, summary: dict[str, Any]) -> None:
    """Write every file into a fresh directory beside ``out``, then rename it into place."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    while True:
        tmp = out.parent / f".{out.name}.{secrets.token_hex(4)}.tmp"
        try:
            tmp.mkdir()
            break
        except FileExistsError:  # pragma: no cover - 32 random bits
            continue
    try:
        result.save(tmp / "result.npz")
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        header, table = result.table()
        np.savetxt(
            tmp / "timeseries.csv",
            table,
            fmt="%.10g",
            delimiter=",",
            header=",".join(header),
            comments="",
        )
        fig = Figure(figsize=(10, 6.5), layout="constrained")
        FigureCanvasAgg(fig)
        result.plot(fig=fig)
        fig.savefig(tmp / "tracking.png", dpi=100)
        os.replace(tmp, out)  # atomic; replaces an empty directory
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


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


def _cmd_simulate(args: argparse.Namespace) -> int:
    scenario = _build_scenario(args)
    out = Path(os.path.abspath(args.out)) if args.out is not None else None
    if out is not None:
        _check_out(out)
    try:
        result = simulate(scenario.arm, **scenario.simulate_kwargs(), progress=None)
    except (TypeError, ValueError) as exc:  # e.g. a path outside the workspace
        raise UsageError(f"flexarm simulate: error: {scenario.source}: {exc}") from None
    except SimulationError as exc:
        print(
            f"flexarm simulate: the simulation diverged at t = {exc.time:.6g} s (state "
            "non-finite, overflowing or a tip deflection beyond max_deflection); nothing written",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    summary = _json_ready(
        {
            "status": "ok",
            **result.metrics(),
            "settings": scenario.description,
            "run": result.info,
            "out": args.out,
            "files": [] if out is None else list(OUTPUT_FILES),
        }
    )
    if out is not None:
        try:
            _write_outputs(out, result, summary)
        except OSError as exc:
            print(f"flexarm simulate: error: cannot write {str(out)!r}: {exc}", file=sys.stderr)
            return EXIT_FAILURE
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(_format_summary(summary))
        if out is not None:
            print(f"  results in {out}: {', '.join(OUTPUT_FILES)}")
    return 0


_SIMULATE_DESCRIPTION = """\
Simulate the closed loop: by default the paper's arm (two 4.5 m links, one mode each)
tracking the default square (20 s) under the paper's Jacobian-transpose PD gains with
joint encoders. --scenario FILE.toml sets anything (arm, trajectory, sensor, controller,
delay, shaper, simulation; schema in flexarm.scenario, example in
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

output: with --out DIR, nothing is written unless the run succeeds; then DIR (new, or
an empty directory) receives result.npz (SimulationResult.load), summary.json (what
--json prints), timeseries.csv and tracking.png, all at once (written beside it and
renamed into place). Metrics that are undefined (corners after a short run's end) are
null in JSON.

exit status: 0 success; 1 the simulation diverged (one line on stderr with the time;
nothing is written: run it from Python to get SimulationError.result, the partial
result) or the results could not be written; 2 bad input (one line on stderr).
"""


# ----------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    """The ``flexarm`` argument parser (one subcommand per job)."""
    parser = _Parser(
        prog="flexarm",
        description=(
            "Model, simulate, control and identify flexible robot manipulators. "
            "Run 'flexarm COMMAND --help' for a command's options."
        ),
    )
    parser.add_argument("--version", action="version", version=f"flexarm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    modes = sub.add_parser(
        "modes",
        help="natural frequencies and modal data of the paper's arm or of one link",
        description=(
            "Print the roots beta*L, frequencies (rad/s and Hz) and modal data of the "
            "paper's arm (default) or of one link given by --length, --flexural-rigidity "
            "and --linear-density."
        ),
    )
    modes.add_argument("--n-modes", type=int, default=None, help="modes per link (arm: 1, link: 3)")
    modes.add_argument("--boundary", choices=BOUNDARIES, default=None, help="arm mode boundary")
    modes.add_argument("--length", type=float, help="link length, m")
    modes.add_argument("--flexural-rigidity", type=float, help="EI, N m^2")
    modes.add_argument("--linear-density", type=float, help="rho, kg/m")
    modes.add_argument("--tip-mass", type=float, default=0.0, help="tip mass, kg (single link)")
    modes.add_argument(
        "--tip-inertia", type=float, default=0.0, help="tip inertia, kg m^2 (single link)"
    )
    modes.add_argument(
        "--joints",
        choices=JOINT_CHOICES,
        default="rigid",
        help="joints of the paper's arm: rigid, or the documented default flexible joints",
    )
    modes.add_argument("--normalization", choices=NORMALIZATIONS, default="mass")
    modes.add_argument(
        "--amplitude", type=float, default=0.1, help="the paper's A (amplitude normalisation)"
    )
    modes.add_argument("--json", action="store_true", help="print a JSON summary")
    modes.set_defaults(func=_cmd_modes)

    sim = sub.add_parser(
        "simulate",
        help="simulate the closed loop (the paper's arm on the square by default)",
        description=_SIMULATE_DESCRIPTION,
        epilog=_SIMULATE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sim.add_argument("--scenario", metavar="FILE.toml", help="scenario file (TOML)")
    sim.add_argument(
        "--controller",
        choices=CONTROLLERS,
        help="pd: the paper's Jacobian-transpose PD gains from the first link's first "
        "frequency (default); jt-pd: JacobianTransposePD with the scenario's kp, kd; "
        "joint-pd: JointPD",
    )
    sim.add_argument(
        "--sensor",
        type=_sensor_option,
        metavar="joint|tip|point:LINK:DISTANCE",
        help="joint encoders (default), the end effector, or a point DISTANCE m along link "
        "LINK (0-based: point:1:0.5 is 0.5 m from the elbow)",
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
    sim.add_argument("--seed", type=int, metavar="N", help="seed of the sensor noise")
    sim.add_argument("--out", metavar="DIR", help="write the results into DIR (see below)")
    sim.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    sim.set_defaults(func=_cmd_simulate)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return 0
        status: int = args.func(args)
        return status
    except UsageError as exc:
        print(exc, file=sys.stderr)
        return EXIT_USAGE
    except (ValueError, TypeError) as exc:
        print(f"flexarm: error: {exc}", file=sys.stderr)
        return EXIT_USAGE


def _entry() -> NoReturn:  # pragma: no cover - console script shim
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    _entry()
