"""Beam modes under their public name, ``flexarm.modes``.

The implementation lives in :mod:`flexarm.model.beam`, beside the rest of the
plant model; this module is the stable public entry point promised to users
(``cantilever_roots``, ``clamped_mass_roots``, ``BeamModes``), so that
``from flexarm.modes import BeamModes`` keeps working.
"""

from __future__ import annotations

from .model.beam import (
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
