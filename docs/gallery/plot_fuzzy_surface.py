"""
The paper's fuzzy adaptive gain
===============================

The Mamdani system of the paper (:func:`flexarm.fuzzy.paper_system`) maps the two links'
tip deflections ``delta1``, ``delta2`` (m, on [-5, 5]) to the gain factor ``lambda`` on
[0, 1]: min for AND, min implication, max aggregation and an exact centroid. The surface
is flat where both links are straight and rises as either link bends.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexarm.fuzzy import paper_system, plot_surface

fls = paper_system()
for d1, d2 in [(0.0, 0.0), (2.5, 0.0), (5.0, 5.0)]:
    print(f"lambda({d1}, {d2}) = {float(fls(d1, d2)):.4f}")

# the system is vectorised: a whole grid in one call
d = np.linspace(-5.0, 5.0, 5)
print(np.round(fls(d[:, None], d[None, :]), 3))

# a pyplot axes, so that the figure is shown (by default the plot makes its own figure)
ax = plt.figure(figsize=(5.0, 4.0)).add_subplot(projection="3d")
ax, surface = plot_surface(fls, ax=ax, n=61)
