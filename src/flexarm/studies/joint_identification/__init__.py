r"""Identify a flexible joint's nonlinearities from a random-torque experiment (paper §IX).

The paper closes with "experiments will be reported in the future": identify
a real manipulator's joint nonlinearity by the nonparametric methods of its
§VI–VIII. :func:`identify_joint` does that on the simulated robot and compares
every estimate with the truth the simulation knows.

Experiment
----------
One rigid link (``n_modes = 0``) on a :class:`~flexarm.NonlinearJoint` with
Makkar friction on the link side and a motor-side (back-EMF) damping
``c_m`` — :func:`joint_test_arm`. The motor drive turns a commanded torque
``u`` into the applied torque ``tau = phi(u)`` with a dead band and a
saturation (:class:`DriveNonlinearity`). The command is a seeded
piecewise-constant random sequence, ``u ~ U(-amplitude, amplitude)`` i.i.d.,
held for ``hold`` seconds, drives the plant with no controller in the loop
(:func:`flexarm.simulate_open_loop`, the torque held over each sample period
``dt``, default 0.2 ms).

Measurements (:class:`JointSensors`; Gaussian noise, seeded)
    * motor and link encoders: ``q_m``, ``q`` (rad) and their rates (rad/s);
    * the motor current, giving the applied torque ``tau`` (N m);
    * optionally a joint torque sensor (``tau_s`` directly, N m);
    * a link accelerometer with an integrate-and-dump filter over each hold:
      the mean link acceleration over the hold (rad/s**2).

(a) Static identification
-------------------------
*Stiffness torque* ``tau_s(Delta)``, ``Delta = q_m - q`` from the two encoders:

* ``torque_measurement="motor-balance"`` (default): the motor's equation
  ``J_m qdd_m + c_m qd_m + tau_s = tau`` gives
  ``tau_s = tau - c_m qd_m - J_m qdd_m`` with ``qdd_m`` the central difference
  of the measured motor rate; samples where the torque switches (the central
  difference straddles a jump of ``qdd_m``) are dropped, and so is the faster
  half of the rest (by the measured deflection rate ``|qd_m - qd|``): the
  central difference errs by about ``tau_s''(Delta) dDelta/dt**2 dt**2 / 6``,
  and at 0.2 ms the joint ringing crosses the soft-windup region (where
  ``tau_s''`` is large) in two or three samples — on all samples the windup
  stiffness comes out about 40 % too high. ``J_m`` and ``c_m`` are the
  motor's data-sheet values.
* ``torque_measurement="sensor"``: a joint torque sensor reads ``tau_s``.

*Friction* ``f(v)``: the link's equation ``I qdd = tau_s - f(qd)``, averaged
over a sliding window of ``friction_window`` samples so that the noisy
acceleration enters only as ``(qd(t + T) - qd(t)) / T``:
``f_bar = mean(tau_s) - I (qd(t+T) - qd(t)) / T`` paired with ``mean(qd)``
(``I`` from the link's model). Then both curves are estimated by the paper's
semi-recursive kernel regression (eq. 14,
:class:`~flexarm.ident.SemiRecursiveKernelRegression`, Epanechnikov kernel,
``h_1`` a fixed fraction of the regressor's standard deviation, ``decay``
0.2) on a grid spanning the central 99 % (stiffness) and 98 % (friction) of
the data.

(b) Hammerstein model
---------------------
From the commanded torque ``u_n`` (one value per hold) to the accelerometer
output ``y_n``: :class:`~flexarm.ident.HammersteinIdentifier` fitted to the
first ``1 - validation_fraction`` of the record, with the two-point
normalisation from the drive's data sheet (``phi(0) = 0`` and the rated
torque at 80 % command). Its static part is compared with the true drive
map; its free-run prediction is scored on the held-out rest (fit %), beside
the *reference fit* of a least-squares FIR model driven by the **true**
``phi(u)`` — the best any Hammerstein model with that FIR length can do on
this plant, whose joint stiffness and friction (nonlinear, inside the
feedback) are not of Hammerstein form.

(c) The dead band
-----------------
Uniform commands over ``±60`` N m do not resolve the drive's ``±2`` N m dead
band. :func:`design_dead_band_excitation` sizes an experiment that does — a
share of the commands concentrated on ``±3`` dead-band widths, a duration from
the standard error the knot values need (a pilot run measures the noise and
the gain) — and the correlated-input path (``method="correlated"``, knots at
the commands' quantiles) identifies it; ``JointIdentification.dead_band``
reports the estimate against the truth.

Modules, in the order they build on each other
----------------------------------------------
* :mod:`~flexarm.studies.joint_identification.parameters` — :class:`DriveNonlinearity`,
  :class:`JointExcitation`, :class:`JointSensors` (light: no simulator);
* :mod:`~flexarm.studies.joint_identification.experiment` — :func:`joint_test_arm`,
  the random-torque run (:class:`JointRecord`) and the noisy measurements;
* :mod:`~flexarm.studies.joint_identification.result` — :class:`CurveEstimate`,
  :class:`JointIdentification` (summary, save, plot);
* :mod:`~flexarm.studies.joint_identification.estimation` — the curves, the
  soft-windup secants and the Hammerstein fit;
* :mod:`~flexarm.studies.joint_identification.study` — :func:`identify_joint`;
* :mod:`~flexarm.studies.joint_identification.design` — an excitation sized to
  resolve the drive's dead band (:func:`design_dead_band_excitation`).

Names are imported on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .design import DeadBandDesign as DeadBandDesign
    from .design import design_dead_band_excitation as design_dead_band_excitation
    from .experiment import JointMeasurements as JointMeasurements
    from .experiment import JointRecord as JointRecord
    from .experiment import joint_test_arm as joint_test_arm
    from .parameters import DriveNonlinearity as DriveNonlinearity
    from .parameters import JointExcitation as JointExcitation
    from .parameters import JointSensors as JointSensors
    from .result import CurveEstimate as CurveEstimate
    from .result import JointIdentification as JointIdentification
    from .study import TORQUE_MEASUREMENTS as TORQUE_MEASUREMENTS
    from .study import identify_joint as identify_joint
