"""
An input-shaped move
====================

A rest-to-rest move of the paper's arm's end effector, 2 m in one second, under a stiff
joint PD law: the joints follow the planned motion closely and the links ring at the
arm's locked-joint frequencies. A zero-vibration (ZV) shaper tuned to the first of them
at the end of the move splits the reference in two, half a period apart, so that the
vibration the first half excites is cancelled by the second. Compare the links' tip
deflections once the move is over.
"""

import matplotlib.pyplot as plt
import numpy as np

import flexarm as fa
from flexarm.control.controllers import JointPD
from flexarm.control.shapers import zv
from flexarm.control.trajectories import PointToPoint
from flexarm.sensing.sensors import JointSensor

arm = fa.FlexibleArm.paper()
controller = JointPD(kp=8000.0, kd=1200.0)  # N m/rad, N m s/rad
move = PointToPoint((6.0, -1.0), (6.0, 1.0), 1.0)  # m, m, s

q_end = np.zeros(arm.n_dof)
q_end[:2] = arm.inverse_kinematics([6.0, 1.0])
w = arm.natural_frequencies(q_end, joints="locked")  # rad/s
shaper = zv(w[0])
print(f"locked-joint frequencies at the end: {np.round(w, 2)} rad/s")
print(f"ZV shaper: amplitudes {shaper.amplitudes}, times {np.round(shaper.times, 3)} s")

# %%
# The same move, as planned and shaped; the tip deflections of both links.

runs = {
    "as planned": fa.simulate(arm, controller, move, sensor=JointSensor(), duration=3.0),
    "ZV-shaped": fa.simulate(
        arm, controller, move, sensor=JointSensor(), shaper=shaper, duration=3.0
    ),
}

fig, axes = plt.subplots(2, 1, sharex=True, figsize=(6, 5))
for name, res in runs.items():
    for link, ax in enumerate(axes):
        ax.plot(res.t, 1e3 * res.link_deflections[:, link], label=name)
    after = res.t > 1.8  # s: the move and the shaper's delay are over
    peak = 1e3 * np.abs(res.link_deflections[after]).max(axis=0)
    print(f"{name}: largest tip deflections after 1.8 s {np.round(peak, 1)} mm")
for link, ax in enumerate(axes):
    ax.set_ylabel(f"link {link + 1} tip (mm)")
axes[0].legend()
axes[-1].set_xlabel("time (s)")
