"""
The paper's square, two seconds of it
=====================================

The paper's two-link arm (4.5 m links, one clamped-free mode each) follows the default
square under the paper's Jacobian-transpose PD law, read from the joint encoders. The
figure is :meth:`~flexarm.sim.results.SimulationResult.plot`: the end effector's path
against the reference, the tracking error, and the links' tip deflections.
"""

import matplotlib.pyplot as plt

import flexarm as fa
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.trajectories import Square
from flexarm.sensing.sensors import JointSensor

arm = fa.FlexibleArm.paper()
controller = JacobianTransposePD.from_arm(arm, zeta=0.707)  # Kp = w1^2 I, Kd = 2 zeta w1 I
result = fa.simulate(arm, controller, Square(), sensor=JointSensor(), duration=2.0)

metrics = result.metrics()
print(f"RMS error {metrics['rms_error_m']:.4f} m, max {metrics['max_error_m']:.4f} m")
print(f"peak torque {metrics['max_torque_Nm']:.1f} N m")
# flexarm's plots draw on a figure apart from pyplot (they never show or block); hand
# them a pyplot figure to see it in a notebook or a gallery
fig = result.plot(plt.figure(figsize=(7.0, 3.6)))
