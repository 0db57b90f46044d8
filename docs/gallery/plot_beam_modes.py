"""
Assumed modes of a link: clamped-free and clamped-mass
======================================================

The paper's link (4.5 m, EI = 1676 N m², ρ = 0.335 kg/m) bends in Euler–Bernoulli modes.
Clamped-free modes are the cantilever's; clamped-mass modes carry at the tip the mass of
everything outboard (here a tip mass equal to the link's own), which lowers the
frequencies and changes the shapes — the basis that converges fast for a link carrying
another.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexarm.modes import BeamModes, cantilever_roots, clamped_mass_roots

L, EI, rho = 4.5, 1676.0, 0.335
print("cantilever beta*L:", np.round(cantilever_roots(3), 6))
print("tip mass = beam mass:", np.round(clamped_mass_roots(3, 1.0, 0.0), 6))

free = BeamModes(L, EI, rho, n_modes=3)
loaded = BeamModes(L, EI, rho, n_modes=3, tip_mass=rho * L)
print("clamped-free (rad/s):", np.round(free.frequencies, 3))
print("clamped-mass (rad/s):", np.round(loaded.frequencies, 3))

x = np.linspace(0.0, L, 200)
fig, axes = plt.subplots(1, 2, sharey=True, figsize=(8, 3.5))
for ax, modes, title in [(axes[0], free, "clamped-free"), (axes[1], loaded, "clamped-mass")]:
    shapes = modes.shape(x)
    for j, (w, phi) in enumerate(zip(modes.frequencies, shapes, strict=True)):
        ax.plot(x, phi / np.abs(phi).max(), label=f"mode {j + 1}: {w:.1f} rad/s")
    ax.set_title(title)
    ax.set_xlabel("x (m)")
    ax.legend(fontsize=8)
axes[0].set_ylabel("shape (scaled to 1)")
