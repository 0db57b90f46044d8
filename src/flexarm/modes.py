"""Beam modes under the name the public API contract gives them (``flexarm.modes``).

The implementation lives in :mod:`flexarm.model.modes`, beside the rest of the
plant model; this module is the stable public entry point that
``../shared/spec/api.md`` promises (``cantilever_roots``, ``clamped_mass_roots``,
``BeamModes``), so that ``from flexarm.modes import BeamModes`` keeps working.
"""

from __future__ import annotations

from .model.modes import (
    NORMALIZATIONS,
    BeamModes,
    cantilever_roots,
    clamped_mass_roots,
    frequency_function,
)

__all__ = [
    "NORMALIZATIONS",
    "BeamModes",
    "cantilever_roots",
    "clamped_mass_roots",
    "frequency_function",
]
