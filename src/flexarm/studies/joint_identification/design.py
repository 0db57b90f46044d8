r"""An excitation designed to resolve the drive's dead band, from its identifiability.

With commands uniform over ``±A = ±60`` N m, the ``±2`` N m dead band gets
3 % of the commands and the white path's one kernel bandwidth (Silverman's
rule on the whole command range, about 17 N m) smooths it away: in 60 s the
estimate has no dead band at all. Resolving a feature of width ``delta`` takes
(i) a **resolution** finer than ``delta`` where it lies and (ii) enough
**samples** there for the estimate's standard error to be small beside it.

:func:`design_dead_band_excitation` sizes the experiment for the
correlated-input path of :class:`~flexarm.ident.HammersteinIdentifier`, whose
static part is piecewise linear on knots at the commands' quantiles — so the
resolution follows the command density:

1. **Amplitude distribution.** A share ``p`` (default 1/2) of the commands is
   drawn from ``U(-c, c)``, ``c = 3 delta`` (the dead band and its flanks, where
   the kinks are located), the rest from ``U(-A, A)`` (the full map,
   saturation included). Inside ``[-c, c]`` a share
   ``q = p + (1 - p) c / A`` of the inputs falls, so ``K`` quantile knots are
   ``2c / (q (K - 1))`` apart there; a spacing of ``delta / 2`` needs
   ``K - 1 >= 4 c / (q delta)``.
2. **Duration.** For i.i.d. inputs the over-parameterised least squares gives
   each knot value the variance ``var(c_k) ~ sqrt(3) (K - 1) sigma**2 / (n ||b||**2)``:
   each hat carries ``n / (K - 1)`` samples, the hats' Gram matrix
   (tridiagonal, ``2/3`` and ``1/6`` per unit mass) has an inverse whose
   diagonal tends to ``sqrt(3)``, ``sigma`` is the equation-error (one-step
   prediction) standard deviation and ``b`` the MA coefficients of the linear
   part, with ``phi`` in N m. A standard error ``epsilon`` (default
   ``delta / 10``) then needs ``n >= sqrt(3) (K - 1) sigma**2 / (epsilon**2
   ||b||**2)`` estimation holds; the record is longer by the held-out share.
3. **sigma and b from a pilot.** Both are measured on a short pilot run of the
   default uniform experiment (20 s), identified the same way at the largest
   order the correlated path tries (10; the knots chosen on held-out data):
   the joint's dynamics are not of Hammerstein form, and on so few data the
   simpler order the one-standard-error rule prefers would overstate
   ``sigma`` — the designed record, many times longer, supports the richer
   structure.

References: the variance of least-squares spline coefficients, e.g. Ruppert,
Wand & Carroll, *Semiparametric Regression*, CUP (2003), ch. 3 and 5; the
design of input amplitude distributions for nonlinear identification, e.g.
Pintelon & Schoukens, *System Identification: A Frequency Domain Approach*,
2nd ed., Wiley (2012), ch. 3.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ..._io import JSONValue
from ..._validation import check_real, check_rng
from ...errors import InvalidValueError
from ...ident.hammerstein._params import CORRELATED_MAX_ORDER
from ...ident.hammerstein.identifier import HammersteinIdentifier
from ...ident.hammerstein.whiteness import IdentificationWarning
from ...model.arm import FlexibleArm
from ...model.joints import LinearJoint, NonlinearJoint
from .experiment import joint_test_arm, measure, run_excitation
from .parameters import JointExcitation, JointSensors, check_types

__all__ = ["GRAM_FACTOR", "DeadBandDesign", "design_dead_band_excitation"]

_OWNER = "design_dead_band_excitation"
#: Diagonal of the inverse Gram matrix of hats carrying equal masses, per unit mass.
GRAM_FACTOR = math.sqrt(3.0)


@dataclass(frozen=True)
class DeadBandDesign:
    """An excitation sized to resolve the dead band (module docstring).

    Attributes
    ----------
    excitation : JointExcitation
        The designed experiment.
    dead_band : float
        Nominal half-width ``delta`` the design resolves, N m.
    resolution : float
        Knot spacing wanted in ``[-c, c]``, N m (``delta / 2``).
    precision : float
        Standard error wanted for the knot values there, N m (``epsilon``).
    n_knots : int
        ``K`` the resolution needs.
    n_holds : int
        Estimation holds the precision needs.
    pilot : dict
        ``duration_s``, ``sigma`` (one-step residual std, rad/s**2), ``gain``
        (``||b||``, rad/s**2 per N m) and ``order`` of the pilot's model.
    capped : bool
        Whether the duration hit ``max_duration``.
    """

    excitation: JointExcitation
    dead_band: float
    resolution: float
    precision: float
    n_knots: int
    n_holds: int
    pilot: dict[str, float]
    capped: bool

    def summary(self) -> dict[str, JSONValue]:
        """Plain values for JSON."""
        ex = self.excitation
        return {
            "dead_band_Nm": self.dead_band,
            "resolution_Nm": self.resolution,
            "precision_Nm": self.precision,
            "n_knots": self.n_knots,
            "n_holds": self.n_holds,
            "duration_s": ex.duration,
            "dead_band_fraction": ex.dead_band_fraction,
            "dead_band_span_Nm": ex.dead_band_span,
            "amplitude_Nm": ex.amplitude,
            "pilot": {k: float(v) for k, v in self.pilot.items()},
            "capped": self.capped,
        }


def design_dead_band_excitation(
    arm: FlexibleArm | None = None,
    *,
    pilot: JointExcitation | None = None,
    sensors: JointSensors | None = None,
    dead_band: float | None = None,
    precision: float | None = None,
    fraction: float = 0.5,
    span_factor: float = 3.0,
    validation_fraction: float = 1.0 / 3.0,
    max_duration: float = 600.0,
    rng: np.random.Generator | int | None = 0,
) -> DeadBandDesign:
    """Size an experiment that resolves the drive's dead band (module docstring).

    Parameters
    ----------
    arm : FlexibleArm, optional
        The plant (default :func:`~flexarm.studies.joint_identification.joint_test_arm`).
    pilot : JointExcitation, optional
        The pilot run (default the uniform experiment of 20 s); its drive,
        amplitude, period and hold are the designed experiment's.
    sensors : JointSensors, optional
        Noise levels (default ``JointSensors()``).
    dead_band : float, optional
        Nominal half-width ``delta`` to resolve, N m (default the drive's data-sheet value).
    precision : float, optional
        Standard error ``epsilon`` wanted for ``phi`` near the dead band, N m
        (default ``delta / 10``).
    fraction : float
        Share ``p`` of the commands drawn near the dead band, in (0, 1).
    span_factor : float
        ``c = span_factor * delta`` (>= 1.5; at most the amplitude).
    validation_fraction : float
        Share of the record the study holds out (the estimation holds are the rest).
    max_duration : float
        Longest record allowed, s.
    rng : numpy.random.Generator or int, optional
        Source of the pilot's commands and noise.

    Returns
    -------
    DeadBandDesign
    """
    pilot = JointExcitation(duration=20.0) if pilot is None else pilot
    sensors = JointSensors() if sensors is None else sensors
    arm = joint_test_arm() if arm is None else arm
    check_types(
        _OWNER,
        ("pilot", pilot, JointExcitation),
        ("sensors", sensors, JointSensors),
        ("arm", arm, FlexibleArm),
    )
    drive = pilot.drive
    delta = drive.dead_band if dead_band is None else check_real(dead_band, "dead_band", _OWNER)
    if not delta > 0.0:
        raise InvalidValueError(
            f"The 'dead_band' parameter of {_OWNER} must be > 0 (the drive's data sheet "
            f"gives {drive.dead_band}). Got {delta} instead."
        )
    eps = delta / 10.0 if precision is None else check_real(precision, "precision", _OWNER)
    p = check_real(fraction, "fraction", _OWNER, positive=True)
    factor = check_real(span_factor, "span_factor", _OWNER)
    hold_out = check_real(validation_fraction, "validation_fraction", _OWNER)
    longest = check_real(max_duration, "max_duration", _OWNER, positive=True)
    for name, ok, expected, got in (
        ("precision", eps > 0.0, "> 0", eps),
        ("fraction", p < 1.0, "< 1", p),
        ("span_factor", factor >= 1.5 and factor * delta <= pilot.amplitude,
         f">= 1.5 and <= amplitude / dead_band = {pilot.amplitude / delta:.6g}", factor),
        ("validation_fraction", 0.0 <= hold_out < 1.0, "in [0, 1)", hold_out),
    ):  # fmt: skip
        if not ok:
            raise InvalidValueError(
                f"The '{name}' parameter of {_OWNER} must be {expected}. Got {got} instead."
            )
    gen = check_rng(rng, _OWNER)
    joint = arm.joints[0] if arm.joints else None
    if not isinstance(joint, LinearJoint | NonlinearJoint):
        raise InvalidValueError(
            f"The 'arm' parameter of {_OWNER} must have a flexible joint. Got none instead."
        )
    record = run_excitation(arm, pilot, gen)
    meas = measure(record, joint, sensors, gen)
    u = record.command[: record.n_holds]
    y = meas.acceleration
    known = 0.8 * pilot.amplitude
    points = ((0.0, 0.0), (known, float(drive(known))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        model = HammersteinIdentifier(
            method="correlated", order=CORRELATED_MAX_ORDER, known_points=points
        ).fit(u, y)
    first = model.max_lag_
    sigma = float(np.std((y - model.predict(u, y, steps_ahead=1))[first:]))
    gain = float(np.linalg.norm(model.arma_.b))
    c = factor * delta
    share = p + (1.0 - p) * c / pilot.amplitude
    spacing = delta / 2.0
    k_minus_1 = math.ceil(2.0 * c / (share * spacing))
    n_est = math.ceil(GRAM_FACTOR * k_minus_1 * sigma**2 / (eps**2 * gain**2))
    n_total = math.ceil(n_est / (1.0 - hold_out))
    hold = pilot.hold_steps * pilot.dt
    duration = float(math.ceil(n_total * hold))
    capped = duration > longest
    designed = replace(
        pilot,
        duration=min(duration, longest),
        dead_band_fraction=p,
        dead_band_span=c,
    )
    return DeadBandDesign(
        excitation=designed,
        dead_band=float(delta),
        resolution=spacing,
        precision=float(eps),
        n_knots=k_minus_1 + 1,
        n_holds=n_est,
        pilot={
            "duration_s": pilot.duration,
            "sigma": sigma,
            "gain": gain,
            "order": float(model.order_),
        },
        capped=bool(capped),
    )
