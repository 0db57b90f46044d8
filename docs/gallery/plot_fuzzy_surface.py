"""
The paper's fuzzy adaptive gain
===============================

The Mamdani system of the paper maps the two links' tip deflections to the gain factor λ.
"""

import matplotlib.pyplot as plt

from flexarm.fuzzy import paper_system, plot_surface

fls = paper_system()
print(fls(0.0, 0.0), fls(2.0, -1.0))
ax = plot_surface(fls)
plt.show()
