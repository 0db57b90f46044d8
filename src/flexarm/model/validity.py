"""What flexarm's model choices leave out, measured: notes a user meets.

The numbers come from holding flexarm against Exudyn's geometrically exact ANCF
cables (``benchmarks/exudyn_study.py``; results in BENCHMARKS.md and the
user guide's model choices and validity, ``docs/guide/validity.md``). Reports and error
messages quote :data:`PAPER_MODEL_NOTE`; :meth:`flexarm.FlexibleArm.paper` documents the
same.
"""

from __future__ import annotations

__all__ = ["PAPER_DEFLECTION_ERROR", "PAPER_MODEL_NOTE"]

PAPER_DEFLECTION_ERROR = 1.23
"""How far :meth:`flexarm.FlexibleArm.paper` (one clamped-free mode per link, no
geometric stiffening) is from the converged answer: the largest error of its
link-1 tip deflection on the default square (quintic timing, joint motion
prescribed, 20 s) over the peak of that deflection, against Exudyn's ANCF
reference (77.6 mm over 63.1 mm). Three clamped-mass modes per link with
geometric stiffening are within 0.0003 of the peak."""

PAPER_MODEL_NOTE = (
    "FlexibleArm.paper() is the paper's model, not a converged one: one clamped-free "
    "mode per link and no geometric stiffening put its link-1 tip deflection on the "
    "default square 78 mm off a 63 mm peak (1.2x) against a geometrically exact "
    "reference (Exudyn ANCF), where 3 clamped-mass modes per link with stiffening are "
    "within 0.02 mm; and without hubs every loop closed on it is stiff (collocated PD "
    "poles down to about -4,500 rad/s with one mode per link, -86,000 with three)."
)
"""One line for reports and error messages: what :meth:`flexarm.FlexibleArm.paper`
leaves out."""
