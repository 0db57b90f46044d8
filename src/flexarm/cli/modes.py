"""``flexarm modes``: natural frequencies and modal data of the paper's arm or of one link."""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from ..model.arm import BOUNDARIES, FlexibleArm
from ..model.beam import NORMALIZATIONS, BeamModes
from ..model.joints import LinearJoint, MakkarFriction, NonlinearJoint
from ._common import UsageError, number

__all__ = ["add_parser"]

JOINT_CHOICES = ("rigid", "linear", "nonlinear")


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


def add_parser(sub: Any) -> None:
    """Add ``modes`` to the subcommands ``sub``."""
    modes = sub.add_parser(
        "modes",
        help="natural frequencies and modal data of the paper's arm or of one link",
        description=(
            "Print the roots beta*L, frequencies (rad/s and Hz) and modal data of the "
            "paper's arm (default) or of one link given by --length, --flexural-rigidity "
            "and --linear-density."
        ),
        formatter_class=argparse.HelpFormatter,  # the description wrapped to the terminal
    )
    modes.add_argument(
        "--n-modes",
        type=number(integer=True, minimum=1),
        default=None,
        help="modes per link (arm: 1, link: 3)",
    )
    modes.add_argument("--boundary", choices=BOUNDARIES, default=None, help="arm mode boundary")
    positive, nonnegative = number(positive=True), number(nonnegative=True)
    modes.add_argument("--length", type=positive, help="link length, m")
    modes.add_argument("--flexural-rigidity", type=positive, help="EI, N m^2")
    modes.add_argument("--linear-density", type=positive, help="rho, kg/m")
    modes.add_argument(
        "--tip-mass", type=nonnegative, default=0.0, help="tip mass, kg (single link)"
    )
    modes.add_argument(
        "--tip-inertia", type=nonnegative, default=0.0, help="tip inertia, kg m^2 (single link)"
    )
    modes.add_argument(
        "--joints",
        choices=JOINT_CHOICES,
        default="rigid",
        help="joints of the paper's arm: rigid, or the documented default flexible joints",
    )
    modes.add_argument("--normalization", choices=NORMALIZATIONS, default="mass")
    modes.add_argument(
        "--amplitude", type=positive, default=0.1, help="the paper's A (amplitude normalisation)"
    )
    modes.add_argument("--json", action="store_true", help="print a JSON summary")
    modes.set_defaults(func=_cmd_modes)
