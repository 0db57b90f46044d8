"""The joint study in one call: :func:`identify_joint` (experiment, estimates, result)."""

from __future__ import annotations

import numpy as np

from ..._io import JSONValue
from ..._validation import check_int, check_option, check_real, check_rng
from ...errors import InvalidTypeError, InvalidValueError
from ...ident.options import METHODS
from ...model.arm import FlexibleArm
from ...model.joints import LinearJoint, NonlinearJoint
from .estimation import estimate_friction, estimate_stiffness, fit_hammerstein, windup_secants
from .experiment import joint_test_arm, measure, run_excitation
from .parameters import JointExcitation, JointSensors, check_types
from .result import JointIdentification

__all__ = ["TORQUE_MEASUREMENTS", "identify_joint"]

TORQUE_MEASUREMENTS = ("motor-balance", "sensor")
"""How the stiffness torque is measured (:func:`identify_joint`)."""
_OWNER = "identify_joint"


def identify_joint(
    arm: FlexibleArm | None = None,
    excitation: JointExcitation | None = None,
    sensors: JointSensors | None = None,
    *,
    torque_measurement: str = "motor-balance",
    friction_window: int = 25,
    quasi_static_fraction: float = 0.5,
    stiffness_bandwidth: float = 0.022,
    friction_bandwidth: float = 0.056,
    n_lags: int = 40,
    validation_fraction: float = 1.0 / 3.0,
    method: str = "auto",
    n_knots: int | str = "auto",
    rng: np.random.Generator | int | None = 0,
) -> JointIdentification:
    """Excite the joint with a random torque and identify its nonlinearities.

    The experiment and the methods are described in
    :mod:`flexarm.studies.joint_identification`.

    Parameters
    ----------
    arm : FlexibleArm, optional
        One rigid link (``n_modes = 0``) on a flexible joint; default
        :func:`joint_test_arm` ().
    excitation : JointExcitation, optional
        The experiment (default ``JointExcitation()``: 60 s at 0.2 ms).
    sensors : JointSensors, optional
        Noise levels (default ``JointSensors()``).
    torque_measurement : {"motor-balance", "sensor"}
        How ``tau_s`` is measured (the package docstring).
    friction_window : int
        Samples ``m`` of the sliding window of the link's torque balance (>= 1).
    quasi_static_fraction : float
        With ``"motor-balance"``, the fraction of samples kept for the stiffness
        curve: those with the smallest measured deflection rate
        ``|qd_m - qd|`` (0 < fraction <= 1).
    stiffness_bandwidth, friction_bandwidth : float
        Bandwidths of the kernel regressions as multiples ``c`` of Silverman's
        rule (``Silverman(c)``, :mod:`flexarm.ident.regression.bandwidth`: the one rule of
        flexarm's defaults), > 0. Narrow (about 1/45 and 1/18 of the rule), because
        the stiffness and friction curves have features (the soft windup, the
        Stribeck dip) much narrower than the regressors' spread.
    n_lags : int
        Impulse-response length of the Hammerstein model, in holds (>= 10).
    validation_fraction : float
        Trailing part of the record held out to score the Hammerstein model
        (0 < fraction < 1).
    method : {"auto", "white", "correlated"}
        Path of the Hammerstein identifier (:class:`~flexarm.ident.HammersteinIdentifier`);
        the commands are i.i.d., so "auto" takes the white path. "correlated"
        puts the knots of the static part at the commands' quantiles, which
        follows a concentrated command distribution
        (:mod:`~flexarm.studies.joint_identification.design`).
    n_knots : int or "auto"
        Knots of the static part on the correlated path (``>= 2``), or chosen on
        held-out data; a :class:`DeadBandDesign` gives the number its resolution needs.
    rng : numpy.random.Generator or int, optional
        Source of the commands and the sensor noise (default seed 0).

    Returns
    -------
    JointIdentification
    """
    arm = joint_test_arm() if arm is None else arm
    if not isinstance(arm, FlexibleArm):
        raise InvalidTypeError(
            f"The 'arm' parameter of {_OWNER} must be a FlexibleArm. "
            f"Got {type(arm).__name__} instead."
        )
    if arm.n_links != 1 or not arm.has_flexible_joints or arm.n_modes != (0,):
        joints = "flexible" if arm.has_flexible_joints else "rigid"
        raise InvalidValueError(
            f"The 'arm' parameter of {_OWNER} must be one rigid link (n_modes=0) on a "
            f"flexible joint. Got {arm.n_links} link(s), modes {arm.n_modes}, "
            f"joints {joints} instead."
        )
    excitation = JointExcitation() if excitation is None else excitation
    sensors = JointSensors() if sensors is None else sensors
    check_types(
        _OWNER, ("excitation", excitation, JointExcitation), ("sensors", sensors, JointSensors)
    )
    check_option(torque_measurement, "torque_measurement", _OWNER, TORQUE_MEASUREMENTS)
    check_option(method, "method", _OWNER, METHODS)
    quasi_static_fraction = check_real(
        quasi_static_fraction, "quasi_static_fraction", _OWNER, positive=True
    )
    if quasi_static_fraction > 1.0:
        raise InvalidValueError(
            f"The 'quasi_static_fraction' parameter of {_OWNER} must be <= 1. "
            f"Got {quasi_static_fraction} instead."
        )
    friction_window = check_int(friction_window, "friction_window", _OWNER, minimum=1)
    stiffness_bandwidth = check_real(
        stiffness_bandwidth, "stiffness_bandwidth", _OWNER, positive=True
    )
    friction_bandwidth = check_real(friction_bandwidth, "friction_bandwidth", _OWNER, positive=True)
    n_lags = check_int(n_lags, "n_lags", _OWNER, minimum=10)
    validation_fraction = check_real(validation_fraction, "validation_fraction", _OWNER)
    if not 0.0 < validation_fraction < 1.0:
        raise InvalidValueError(
            f"The 'validation_fraction' parameter of {_OWNER} must be in (0, 1). "
            f"Got {validation_fraction} instead."
        )
    gen = check_rng(rng, _OWNER)
    n_holds = excitation.n_holds
    if n_holds < 4 * n_lags or n_holds < 300:
        raise InvalidValueError(
            f"The 'excitation' parameter of {_OWNER} must give at least "
            f"{max(4 * n_lags, 300)} holds (duration / hold). Got {n_holds} instead."
        )

    joint = arm.joints[0] if arm.joints else None
    assert isinstance(joint, LinearJoint | NonlinearJoint)  # a flexible joint (checked above)
    record = run_excitation(arm, excitation, gen)
    meas = measure(record, joint, sensors, gen)
    stiffness, n_static = estimate_stiffness(
        record,
        meas,
        joint,
        torque_measurement=torque_measurement,
        quasi_static_fraction=quasi_static_fraction,
        bandwidth=stiffness_bandwidth,
    )
    inertia = float(arm.mass_matrix(np.zeros(arm.n_dof))[0, 0])
    friction = estimate_friction(
        record,
        meas,
        joint,
        inertia,
        torque_measurement=torque_measurement,
        window=friction_window,
        bandwidth=friction_bandwidth,
    )
    windup, width = windup_secants(stiffness, joint)
    drive = excitation.drive
    ham = fit_hammerstein(
        record,
        meas,
        drive,
        excitation.amplitude,
        n_lags=n_lags,
        validation_fraction=validation_fraction,
        method=method,
        n_knots=n_knots,
        span=excitation.dead_band_span,
    )
    dt = excitation.dt
    info: dict[str, JSONValue] = {
        "duration_s": excitation.n_steps * dt,
        "dt_s": dt,
        "hold_s": excitation.hold_steps * dt,
        "amplitude_Nm": excitation.amplitude,
        "dead_band_fraction": excitation.dead_band_fraction,
        "dead_band_span_Nm": excitation.dead_band_span,
        "hammerstein_method": ham.model.method_,
        "drive": {"dead_band_Nm": drive.dead_band, "limit_Nm": drive.limit},
        "torque_measurement": torque_measurement,
        "friction_window": friction_window,
        "quasi_static_fraction": quasi_static_fraction,
        "link_inertia_kgm2": inertia,
        "motor_inertia_kgm2": joint.motor_inertia,
        "motor_damping_Nms": joint.motor_damping,
        "n_static_samples": n_static,
        "n_holds": int(n_holds),
        "n_fit": int(ham.n_fit),
        "windup_width_rad": width,
        "sensors": {
            "angle_noise_rad": sensors.angle_noise,
            "rate_noise_rad_s": sensors.rate_noise,
            "torque_noise_Nm": sensors.torque_noise,
            "torque_sensor_noise_Nm": sensors.torque_sensor_noise,
            "acceleration_noise_rad_s2": sensors.acceleration_noise,
        },
        "simulation_status": record.status,
    }
    return JointIdentification(
        stiffness,
        friction,
        ham.drive,
        windup,
        ham.model,
        ham.validation,
        ham.fit_percent,
        ham.reference_fit_percent,
        info,
        ham.dead_band,
    )
