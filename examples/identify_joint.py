"""Identify a robot joint's nonlinearities from a random-torque experiment (paper §IX).

A rigid 4.5 m link on the default nonlinear joint (cubic stiffness with soft
windup, Makkar friction) is driven open loop through a drive with a dead band
and a saturation by a seeded piecewise-constant random command. From noisy
encoder, rate, current and accelerometer signals the script identifies

* the stiffness torque ``tau_s(Delta)`` (motor-side torque balance, or a joint
  torque sensor with ``--torque-sensor``),
* the friction curve ``f(v)`` (link-side torque balance over a sliding window),
* a Hammerstein model from the command to the link acceleration,

and compares each with the truth. With ``--design`` the experiment is sized to
resolve the drive's ±2 N m dead band — half the commands within ±6 N m, the
duration from a 20 s pilot run — and the Hammerstein model is identified on
the correlated-input path, whose knots follow the command density
(:mod:`flexarm.studies.joint_identification.design`). See
:mod:`flexarm.studies.joint_identification`. Run from the repository root::

    python examples/identify_joint.py                      # 60 s experiment
    python examples/identify_joint.py --duration 30 --out results/joint
    python examples/identify_joint.py --design             # resolve the dead band
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.studies.joint_identification import (
    JointExcitation,
    design_dead_band_excitation,
    identify_joint,
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0, help="record length, s")
    parser.add_argument("--seed", type=int, default=0, help="seed of commands and noise")
    parser.add_argument(
        "--torque-sensor",
        action="store_true",
        help="measure tau_s with a joint torque sensor instead of the motor balance",
    )
    parser.add_argument(
        "--design", action="store_true", help="size the experiment to resolve the dead band"
    )
    parser.add_argument("--out", metavar="DIR", help="write summary.json, curves.npz and a plot")
    args = parser.parse_args(argv)
    measurement = "sensor" if args.torque_sensor else "motor-balance"
    try:
        if args.design:
            pilot_rng, main_rng = np.random.default_rng(args.seed).spawn(2)
            design = design_dead_band_excitation(rng=pilot_rng)
            d = design.summary()
            print(
                f"design: {100 * d['dead_band_fraction']:g} % of the commands within "
                f"+-{d['dead_band_span_Nm']:g} N m for {d['n_knots']} knots {d['resolution_Nm']:g} "
                f"N m apart and a standard error of {d['precision_Nm']:g} N m: "
                f"{d['n_holds']} estimation holds, {d['duration_s']:g} s "
                f"(pilot: sigma {d['pilot']['sigma']:.3g} rad/s^2, gain {d['pilot']['gain']:.3g})"
            )
            res = identify_joint(
                excitation=design.excitation,
                torque_measurement=measurement,
                method="correlated",
                rng=main_rng,
            )
        else:
            res = identify_joint(
                excitation=JointExcitation(duration=args.duration),
                torque_measurement=measurement,
                rng=args.seed,
            )
    except (InvalidTypeError, InvalidValueError) as exc:  # bad settings; a bug keeps its traceback
        print(f"identify_joint: {exc}", file=sys.stderr)
        return 2
    info = res.info
    print(
        f"{info['duration_s']:.0f} s at {1e3 * info['dt_s']:.1f} ms, commands held "
        f"{1e3 * info['hold_s']:.0f} ms, tau_s by {info['torque_measurement']}"
    )
    for curve in (res.stiffness, res.friction, res.drive):
        print(
            f"{curve.name:10s} grid [{curve.x[0]:+.4g}, {curve.x[-1]:+.4g}] {curve.x_unit:6s} "
            f"rms error {curve.rms_error:.3g} {curve.y_unit} "
            f"({100 * curve.relative_rms_error:.2f} % of range), max {curve.max_error:.3g}"
        )
    w = res.windup
    if w:
        print(
            f"soft windup, |Delta| <= {1e6 * w['inner_halfwidth_rad']:.0f} urad: stiffness "
            f"{w['stiffness_inside_estimate']:.0f} N m/rad (true "
            f"{w['stiffness_inside_true']:.0f}); outside: {w['stiffness_outside_estimate']:.0f} "
            f"(true {w['stiffness_outside_true']:.0f})"
        )
    model = res.hammerstein
    print(
        f"Hammerstein model ({model.method_} path): ARMA order {model.order_}, free-run fit on "
        f"held-out data {res.fit_percent:.1f} % (FIR on the true drive map: "
        f"{res.reference_fit_percent:.1f} %)"
    )
    db = res.dead_band
    print(
        f"dead band: half-width {db['half_width_negative_Nm']:.2f} / "
        f"{db['half_width_positive_Nm']:.2f} N m (true {db['true_half_width_Nm']:g}), RMS error "
        f"{db['rms_error_Nm']:.3g} N m and largest {db['max_error_Nm']:.3g} N m within "
        f"+-{db['span_Nm']:g} N m"
    )
    if args.out:
        for path in res.save(args.out):
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
