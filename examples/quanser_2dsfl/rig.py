"""The Quanser 2 DOF Serial Flexible Link built from its data sheet, both ways.

The vendor's numbers are read from its own ``config_2dslf.m`` (each ``NAME = expr;``
line evaluated in order, so nothing is retyped), and every one of them is put where
it belongs in the two model forms flexarm offers:

* the **joint model** (the vendor's own form): each stage a rigid link on a
  flexible joint whose spring is the strip's equivalent root stiffness
  ``Ks = E b t**3 / (4 L)``, the drive's inertia and viscous damping on the
  motor side;
* the **beam model**: each strip an Euler-Bernoulli link (``EI = E b t**3 / 12``,
  ``rho = 7850 kg/m**3 b t``) clamped to its hub, the stage-2 mechanism a body at
  the first strip's tip.

Run it to print the table and both forms' first link frequency beside the
measured one (the strip's free ringing in the LQ step runs, 1.82-1.90 Hz)::

    python examples/quanser_2dsfl/rig.py [DATA_DIR]

``DATA_DIR`` defaults to ``../shared/data/quanser_2dsfl`` beside the repository.
"""

from __future__ import annotations

import ast
import math
import operator
import re
import sys
from pathlib import Path

import numpy as np

import flexarm as fa
from flexarm.model.joints import LinearJoint
from flexarm.model.link import Link, RigidLink

STEEL_DENSITY = 7850.0  # kg/m**3: the data sheet gives none
MEASURED_HZ = (1.82, 1.90)  # the first strip's ringing in the LQ step runs

# Every vendor number: (name, meaning, where it goes in the joint model, in the beam model).
TABLE: tuple[tuple[str, str, str, str], ...] = (
    ("Me", "Young's modulus of the steel strips, Pa", "(through Ks1, Ks2)", "EI = Me X T**3 / 12"),
    ("X1, T1", "strip 1 width and thickness, m", "(through Ks1)", "links[0] EI and density"),
    ("L1", "strip 1 length, hub to tip load, m", "links[0].length", "links[0].length"),
    ("Ks1", "strip 1 root stiffness 3 EI / L, N m/rad", "joints[0].stiffness", "(EI instead)"),
    (
        "B11",
        "viscous damping at drive 1's shaft, N m s/rad",
        "joints[0].motor_damping",
        "fsf_current.toml: joints[0].damping (a RigidJoint)",
    ),
    ("B12", "strip 1 damping at its axis (neglected: 0)", "-", "links[0].modal_damping (fitted)"),
    ("Kg1, Kt1", "gear ratio 100, torque constant 0.119 N m/A", "drives[0]", "drives[0]"),
    (
        "0.75",
        "gear efficiency in Ktg1 = 0.75 Kt1 Kg1",
        "drives[0].efficiency",
        "drives[0].efficiency",
    ),
    (
        "Jm1",
        "rotor inertia at the motor shaft, kg m**2",
        "in J11",
        "joints[0].motor_inertia = Kg1**2 Jm1",
    ),
    ("J1fix", "motor fixture inertia, kg m**2", "in J11", "links[0].hub_inertia"),
    (
        "J11",
        "Kg1**2 Jm1 + J1fix: drive 1 at its output, kg m**2",
        "joints[0].motor_inertia",
        "(its parts instead)",
    ),
    ("M12", "stage 2 at strip 1's tip, kg", "links[0].tip_mass", "links[0].tip_mass"),
    (
        "J12",
        "stage 2 about axis 1, kg m**2",
        "links[0].tip_inertia (as in the beam model)",
        "links[0].tip_inertia = J12 - M12 L1**2 - rho1 L1**3/3 - stage 2 turning - J2fix",
    ),
    ("X2, T2", "strip 2 width and thickness, m", "(through Ks2)", "links[1] EI and density"),
    ("L2", "strip 2 length, m", "links[1].length", "links[1].length"),
    ("Ks2", "strip 2 root stiffness, N m/rad", "joints[1].stiffness", "(EI instead)"),
    (
        "B21",
        "viscous damping at drive 2's shaft, N m s/rad",
        "joints[1].motor_damping",
        "fsf_current.toml: joints[1].damping (a RigidJoint)",
    ),
    (
        "B22",
        "strip 2 damping at its axis, N m s/rad",
        "(joint spring damping)",
        "links[1].modal_damping (fitted)",
    ),
    ("Kg2, Kt2", "gear ratio 50, torque constant 0.0232 N m/A", "drives[1]", "drives[1]"),
    (
        "Jm2, J2fix, J21",
        "drive 2's rotor, fixture, at its output",
        "joints[1].motor_inertia",
        "joints[1].motor_inertia = Kg2**2 Jm2, links[1].hub_inertia = J2fix",
    ),
    ("M22", "tip load of strip 2, kg", "payload_mass", "payload_mass"),
    (
        "J22",
        "tip load about axis 2 (the formula, not the CAD's)",
        "payload_inertia = J22 - M22 L2**2 (strip 2 a uniform rod)",
        "payload_inertia = J22 - M22 L2**2",
    ),
    (
        "K_strain",
        "strain gauge 1.35e-4 strain/V",
        "-",
        "the logs are in the tip-angle form already",
    ),
    ("V_MAX, W*_MAX, T*_MAX", "amplifier and safety limits", "-", "- (not dynamics)"),
)

_BINARY = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}


def _evaluate(node: ast.AST, names: dict[str, float]) -> float:
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
        return float(node.value)
    if isinstance(node, ast.Name):
        return names["pi"] if node.id == "pi" else names[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return -_evaluate(node.operand, names)
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        return _BINARY[type(node.op)](_evaluate(node.left, names), _evaluate(node.right, names))
    raise ValueError(f"not a number expression: {ast.dump(node)}")


def vendor_numbers(directory: Path) -> dict[str, float]:
    """The numbers of ``config_2dslf.m``: each ``NAME = expr;`` evaluated in order."""
    names: dict[str, float] = {"pi": math.pi}
    assignment = re.compile(r"^\s*([A-Za-z]\w*)\s*=\s*([^;%]+);")
    for line in (directory / "config_2dslf.m").read_text().splitlines():
        match = assignment.match(line)
        if match:
            expr = ast.parse(match.group(2).replace("^", "**"), mode="eval").body
            names[match.group(1)] = _evaluate(expr, names)
    return names


def _bodies(v: dict[str, float]) -> dict[str, float]:
    """The mass bookkeeping both forms share: the strips' density, the tip load about
    its own centre, and stage 2's housing (what of ``J12`` turns with strip 1's tip and
    not with stage 2: ``J12 - M12 L1**2 - rho1 L1**3 / 3`` less stage 2's turning part
    about its axis and drive 2's output fixture ``J2fix``)."""
    rho1 = STEEL_DENSITY * v["X1"] * v["T1"]
    rho2 = STEEL_DENSITY * v["X2"] * v["T2"]
    tip_load = v["J22"] - v["M22"] * v["L2"] ** 2
    turning = rho2 * v["L2"] ** 3 / 3.0 + v["M22"] * v["L2"] ** 2 + tip_load
    housing = v["J12"] - v["M12"] * v["L1"] ** 2 - rho1 * v["L1"] ** 3 / 3.0 - turning
    return {"rho1": rho1, "rho2": rho2, "tip_load": tip_load, "housing": housing - v["J2fix"]}


def joint_model(v: dict[str, float]) -> fa.FlexibleArm:
    """The vendor's form: rigid strips (no modes) on flexible joints of stiffness Ks,
    with the drives' inertia and damping at the motor side of each spring."""
    b = _bodies(v)

    def strip(length: float, rho: float, **bodies: float) -> RigidLink:
        mass = rho * length
        return RigidLink(length, mass, length / 2.0, mass * length**2 / 12.0, **bodies)

    return fa.FlexibleArm(
        [
            strip(v["L1"], b["rho1"], tip_mass=v["M12"], tip_inertia=b["housing"]),
            strip(v["L2"], b["rho2"]),
        ],
        joints=[
            # the spring is the strip's root: the hub and fixture turn on its motor side
            LinearJoint(v["Ks1"], v["J11"], motor_damping=v["B11"], gear_ratio=v["Kg1"]),
            LinearJoint(v["Ks2"], v["J21"], motor_damping=v["B21"], gear_ratio=v["Kg2"]),
        ],
        payload_mass=v["M22"],
        payload_inertia=b["tip_load"],
        geometric_stiffening=False,
    )


def beam_model(v: dict[str, float], n_modes: int = 2) -> fa.FlexibleArm:
    """Both strips as Euler-Bernoulli links, stage 2's housing a body at strip 1's tip."""
    b = _bodies(v)
    ei1 = v["Me"] * v["X1"] * v["T1"] ** 3 / 12.0
    ei2 = v["Me"] * v["X2"] * v["T2"] ** 3 / 12.0
    return fa.FlexibleArm(
        [
            Link(
                v["L1"],
                ei1,
                b["rho1"],
                n_modes=n_modes,
                hub_inertia=v["J1fix"],
                tip_mass=v["M12"],
                tip_inertia=b["housing"],
            ),
            Link(v["L2"], ei2, b["rho2"], n_modes=n_modes, hub_inertia=v["J2fix"]),
        ],
        payload_mass=v["M22"],
        payload_inertia=b["tip_load"],
        geometric_stiffening=False,
    )


def first_link_hz(arm: fa.FlexibleArm) -> float:
    """The lowest linearised frequency with the hubs held (stage 1's strip ringing), Hz."""
    return float(np.min(arm.natural_frequencies())) / (2.0 * math.pi)


def main(argv: list[str]) -> int:
    default = Path(__file__).resolve().parents[3] / "shared" / "data" / "quanser_2dsfl"
    directory = Path(argv[0]) if argv else default
    if not (directory / "config_2dslf.m").is_file():
        print(f"rig.py: no config_2dslf.m in {directory} (pass the data directory)")
        return 2
    v = vendor_numbers(directory)
    width = max(len(r[0]) for r in TABLE)
    print(f"{'vendor':<{width}}  meaning | joint model | beam model")
    for name, meaning, joint, beam in TABLE:
        print(f"{name:<{width}}  {meaning} | {joint} | {beam}")
    print()
    lo, hi = MEASURED_HZ
    for label, arm in (("joint model", joint_model(v)), ("beam model", beam_model(v))):
        print(f"{label}: first link frequency {first_link_hz(arm):.3f} Hz (measured {lo}-{hi} Hz)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
