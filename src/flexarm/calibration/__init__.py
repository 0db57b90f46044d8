"""Calibration of an arm's physical parameters on measured runs.

* :func:`calibrate` — fit named parameters of an arm, its drives and its
  instruments to measured records, judge the fit on records kept for validation
  (:mod:`~flexarm.calibration.result`, :class:`Calibration`);
* :mod:`~flexarm.calibration.config` — the calibration file (TOML): the arm, drives,
  instruments, parameters, records;
* :mod:`~flexarm.calibration.records` — which columns of which files a record's
  inputs and outputs are, in which units (:mod:`~flexarm.calibration.units`);
* :mod:`~flexarm.calibration.model` — the plant a calibration fits and its replay
  of a record; :mod:`~flexarm.calibration.fit` — the least squares.

``flexarm calibrate CONFIG.toml`` is the command-line front end.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .config import CalibrationConfig as CalibrationConfig
    from .config import Parameter as Parameter
    from .config import load_config as load_config
    from .result import Calibration as Calibration
    from .result import calibrate as calibrate
