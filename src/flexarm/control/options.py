"""Names of the control laws' options, importable without compiling a law.

The command line, scenario files and the reproduction read these to check what a
user asked for before any controller (whose compiled callbacks are built on
import) is loaded.
"""

from __future__ import annotations

__all__ = ["ADAPTATION_LAWS"]

ADAPTATION_LAWS = ("scaled", "damping")
"""How the fuzzy adaptive law applies its gain ``g``
(:class:`flexarm.control.adaptive.FuzzyAdaptiveJTPD`): ``"scaled"`` scales the whole
Jacobian-transpose PD law, ``"damping"`` its damping term only."""
