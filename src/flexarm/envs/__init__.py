"""Gymnasium environments of the flexible arm (``pip install "flexarm[rl]"``).

``import flexarm.envs`` registers ``"flexarm/FlexibleArm-v0"`` with Gymnasium:
``gymnasium.make("flexarm/FlexibleArm-v0", **options)`` builds a
:class:`FlexibleArmEnv` and ``gymnasium.make_vec("flexarm/FlexibleArm-v0",
num_envs=n, vectorization_mode="vector_entry_point")`` a
:class:`FlexibleArmVectorEnv` (many arms in one compiled call); the options are
the fields of :class:`EnvConfig`.

* :mod:`flexarm.envs.config` — :class:`EnvConfig`, the episode's definition;
* :mod:`flexarm.envs.step` — the compiled step of a batch of arms;
* :mod:`flexarm.envs.core` — :class:`ArmBatch`, the batch behind both environments;
* :mod:`flexarm.envs.env` — :class:`FlexibleArmEnv`;
* :mod:`flexarm.envs.vector` — :class:`FlexibleArmVectorEnv`.
"""

from __future__ import annotations

import gymnasium

from .config import EnvConfig
from .env import FlexibleArmEnv
from .vector import FlexibleArmVectorEnv

__all__ = ["ENV_ID", "EnvConfig", "FlexibleArmEnv", "FlexibleArmVectorEnv"]

ENV_ID = "flexarm/FlexibleArm-v0"
"""The id under which :class:`FlexibleArmEnv` is registered."""

if ENV_ID not in gymnasium.registry:  # registered once per process
    gymnasium.register(
        id=ENV_ID,
        entry_point="flexarm.envs.env:FlexibleArmEnv",
        vector_entry_point="flexarm.envs.vector:FlexibleArmVectorEnv",
    )
