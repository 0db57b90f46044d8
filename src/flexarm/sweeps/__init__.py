"""Parameter sweeps: a grid or Monte Carlo over any scenario parameter, one tidy table.

* :func:`sweep` (also ``flexarm.sweep``) — run a sweep on every core or on a
  Dask cluster, resumable (:mod:`~flexarm.sweeps.driver`);
* :class:`SweepSpec`, :func:`load_sweep` — the sweep file and its runs
  (:mod:`~flexarm.sweeps.spec`; dotted keys in :mod:`~flexarm.sweeps.keys`,
  distributions in :mod:`~flexarm.sweeps.distributions`);
* :class:`SweepTable` — one row per run, CSV and Parquet (:mod:`~flexarm.sweeps.table`);
* the journal that makes a sweep resumable (:mod:`~flexarm.sweeps.journal`);
* local and Dask execution (:mod:`~flexarm.sweeps.execute`,
  :mod:`~flexarm.sweeps.cluster`, with how to run on a cluster).

``flexarm sweep SWEEP.toml`` is the command-line front end;
``examples/sweep_noise.toml`` is a complete file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__)

if TYPE_CHECKING:  # the public names (attach reads them); nothing is imported at run time
    from .cluster import ClusterError as ClusterError
    from .distributions import Choice as Choice
    from .distributions import Integers as Integers
    from .distributions import LogUniform as LogUniform
    from .distributions import Normal as Normal
    from .distributions import Uniform as Uniform
    from .driver import SweepInterrupted as SweepInterrupted
    from .driver import sweep as sweep
    from .reader import SweepError as SweepError
    from .reader import SweepTypeError as SweepTypeError
    from .spec import METRICS as METRICS
    from .spec import Grid as Grid
    from .spec import MonteCarlo as MonteCarlo
    from .spec import SweepRun as SweepRun
    from .spec import SweepSpec as SweepSpec
    from .spec import load_sweep as load_sweep
    from .spec import read_sweep as read_sweep
    from .table import SweepTable as SweepTable
