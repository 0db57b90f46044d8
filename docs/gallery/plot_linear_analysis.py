"""
One flexible link, linearised: poles, zeros and a Bode plot
===========================================================

:func:`~flexarm.control.linearize.linearize` gives the arm at rest as a state-space model
from the joint torque to what a sensor measures. For one flexible link, the transfer from
the torque to the joint angle (collocated) has its zeros between its poles on the
imaginary axis; the transfer to the deflected tip (noncollocated) has a real pair of
zeros, one in the right half-plane: why PD on the tip is unstable at any gain.
"""

import matplotlib.pyplot as plt
import numpy as np

import flexarm as fa
from flexarm.control.linearize import linearize

link = fa.FlexibleArm([fa.Link(4.5, 1676.0, 0.335, n_modes=3)], boundary="clamped-free")
joint = linearize(link, output="joints")  # torque -> joint angle
tip = linearize(link, output="tip")  # torque -> deflected tip (x, y)


def upper(z):
    """Roots on or above the real axis, by modulus (the rest are their conjugates)."""
    z = z[z.imag >= -1e-9]
    return np.round(z[np.argsort(np.abs(z))], 2)


print("poles (rad/s):", upper(tip.poles()))
print("joint-angle zeros:", upper(joint.transmission_zeros()))
print("tip zeros:", upper(tip.transmission_zeros(outputs=[1])))

# %%
# The frequency responses, computed from the state-space matrices, and the pole-zero map
# of the tip's transfer: the zeros at about +-39 rad/s are real.


def frequency_response(sys, w, output):
    """|G(jw)| and its phase from input 0 to ``output``, from the matrices."""
    n = sys.A.shape[0]
    g = np.array(
        [
            (sys.C[output] @ np.linalg.solve(1j * wk * np.eye(n) - sys.A, sys.B[:, 0]))
            + sys.D[output, 0]
            for wk in w
        ]
    )
    return np.abs(g), np.unwrap(np.angle(g))


w = np.logspace(0, 3, 600)  # rad/s
fig, (ax_mag, ax_phase, ax_pz) = plt.subplots(3, 1, figsize=(6, 9))
for name, sys, output in [("joint angle (rad)", joint, 0), ("tip, y (m)", tip, 1)]:
    mag, phase = frequency_response(sys, w, output)
    ax_mag.loglog(w, mag, label=name)
    ax_phase.semilogx(w, np.degrees(phase), label=name)
ax_mag.set_ylabel("|G| per N m")
ax_phase.set_ylabel("phase (deg)")
ax_phase.set_xlabel("frequency (rad/s)")
ax_mag.legend()

poles = tip.poles()
zeros = tip.transmission_zeros(outputs=[1])
ax_pz.plot(poles.real, poles.imag, "x", label="poles")
ax_pz.plot(zeros.real, zeros.imag, "o", mfc="none", label="tip zeros")
ax_pz.axvline(0.0, color="0.6", lw=0.8)
ax_pz.set_xlabel("real (rad/s)")
ax_pz.set_ylabel("imaginary (rad/s)")
ax_pz.legend()
fig.tight_layout()
