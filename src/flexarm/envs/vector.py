"""Many arms in one compiled call: :class:`FlexibleArmVectorEnv`.

A ``gymnasium.vector.VectorEnv`` whose ``num_envs`` sub-environments are the
arms of one :class:`flexarm.envs.core.ArmBatch`: a step is one call of the
compiled step over every arm (split over ``workers`` threads, as the step
releases the GIL), not a Python loop over environments. Sub-environment ``i``
behaves exactly as :class:`flexarm.envs.FlexibleArmEnv` reset with seed
``seed + i`` (a list of seeds gives each its own), step for step, bit for bit.

Autoreset follows Gymnasium 1.x (``metadata["autoreset_mode"]``):

``AutoresetMode.NEXT_STEP`` (default)
    A sub-environment that terminates or truncates is reset by the *next*
    ``step``, which ignores its action and returns its first observation with
    reward 0, ``terminated`` and ``truncated`` False.
``AutoresetMode.SAME_STEP``
    It is reset in the step that ends its episode: the step returns its first
    observation of the new episode, and the last one of the old in
    ``info["final_obs"]`` (with ``info["final_info"]``), masked by
    ``info["_final_obs"]``.
"""

from __future__ import annotations

from collections.abc import Sequence

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import ArrayLike, NDArray

from .._types import F64
from .._validation import check_int
from ..errors import InvalidTypeError, InvalidValueError
from .config import EnvConfig
from .core import ArmBatch
from .env import config_from
from .step import DIVERGED, TRUNCATED

__all__ = ["FlexibleArmVectorEnv"]

VectorInfo = dict[str, object]


class FlexibleArmVectorEnv(gym.vector.VectorEnv[F64, F64, NDArray[np.generic]]):
    """``num_envs`` flexible arms stepped together (module docstring).

    Parameters
    ----------
    num_envs : int
        Number of arms (>= 1).
    config : EnvConfig, optional
        Shared by every arm (default :class:`EnvConfig` ()).
    workers : int
        Threads stepping disjoint ranges of arms (default 1: the calling thread).
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default) or ``SAME_STEP``.
    **options
        Fields of :class:`EnvConfig` replacing those of ``config``.

    Attributes
    ----------
    single_action_space, single_observation_space : gymnasium.spaces.Box
        Those of :class:`FlexibleArmEnv`; ``action_space`` and ``observation_space``
        batch them (shape ``(num_envs, ...)``).
    """

    def __init__(
        self,
        num_envs: int,
        config: EnvConfig | None = None,
        *,
        workers: int = 1,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        render_mode: None = None,
        **options: object,
    ) -> None:
        owner = "FlexibleArmVectorEnv"
        if render_mode is not None:
            raise InvalidValueError(
                f"The 'render_mode' parameter of {owner} must be None. Got {render_mode!r} instead."
            )
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            mode = AutoresetMode.DISABLED
        if mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
            raise InvalidValueError(
                f"The 'autoreset_mode' parameter of {owner} must be NEXT_STEP or SAME_STEP. "
                f"Got {autoreset_mode!r} instead."
            )
        self.config = config_from(config, options, owner)
        self.num_envs = check_int(num_envs, "num_envs", owner, minimum=1)
        self.render_mode = None
        self.metadata = {"autoreset_mode": mode, "render_modes": []}
        self._batch = ArmBatch(
            self.config, self.num_envs, check_int(workers, "workers", owner, minimum=1)
        )
        limit = self.config.limits
        low, high = self._batch.arrays.low, self._batch.arrays.high
        self.single_action_space = gym.spaces.Box(-limit, limit, dtype=np.float64)
        self.single_observation_space = gym.spaces.Box(low.copy(), high.copy(), dtype=np.float64)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self._generators: list[np.random.Generator | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._started = False

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, object] | None = None,
    ) -> tuple[F64, VectorInfo]:
        """Start every arm's episode.

        Parameters
        ----------
        seed : int or sequence of int or None, optional
            ``seed + i`` seeds arm ``i``'s generator; a sequence gives one per arm
            (None: a fresh random one); None keeps the generators of earlier
            resets (random ones the first time).
        options : dict, optional
            None or empty.

        Returns
        -------
        observations : ndarray, shape (num_envs, n_obs)
        info : dict
            ``time_s``, ``tracking_error_m`` (shape (num_envs,)), ``torque_Nm``
            (shape (num_envs, n_links)), each with its ``_key`` mask.
        """
        if options:
            raise InvalidValueError(
                f"The 'options' parameter of FlexibleArmVectorEnv.reset must be None or "
                f"empty. Got {options!r} instead."
            )
        n = self.num_envs
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, int | np.integer) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(n)]
        elif isinstance(seed, Sequence) and len(seed) == n:
            seeds = list(seed)
        else:
            raise InvalidTypeError(
                f"The 'seed' parameter of FlexibleArmVectorEnv.reset must be an int, None or "
                f"a sequence of {n} seeds. Got {seed!r} instead."
            )
        for i, s in enumerate(seeds):
            if s is not None or self._generators[i] is None:
                self._generators[i] = seeding.np_random(s)[0]
        self._batch.reset(np.ones(n, dtype=np.int64), self._generators)
        self._autoreset[:] = False
        self._started = True
        return self._batch.state.obs.copy(), self._info()

    def step(
        self, actions: ArrayLike
    ) -> tuple[F64, F64, NDArray[np.bool_], NDArray[np.bool_], VectorInfo]:
        """Hold ``actions`` (N m, shape (num_envs, n_links)) over one control period.

        Returns
        -------
        observations : ndarray, shape (num_envs, n_obs)
        rewards : ndarray, shape (num_envs,)
        terminations, truncations : ndarray of bool, shape (num_envs,)
        info : dict
            As :meth:`reset`'s (and ``final_obs``, ``final_info`` under ``SAME_STEP``).
        """
        if not self._started:
            raise InvalidValueError("FlexibleArmVectorEnv.step needs reset() first.")
        batch, st = self._batch, self._batch.state
        shape = (self.num_envs, self.config.arm.n_links)
        if np.shape(actions) != shape:
            raise InvalidValueError(
                f"The 'actions' parameter of FlexibleArmVectorEnv.step must be of shape "
                f"{shape} (joint torques, N m). Got shape {np.shape(actions)} instead."
            )
        np.copyto(batch.action, actions, casting="same_kind")
        resetting = self._autoreset.astype(np.int64)
        if resetting.any():  # NEXT_STEP: the episodes that ended last step start again
            batch.reset(resetting, self._generators)
        batch.step(1 - resetting, self._generators)
        obs = st.obs.copy()
        rewards = np.where(self._autoreset, 0.0, st.reward)
        terminated = (st.status == DIVERGED) & ~self._autoreset
        truncated = (st.status == TRUNCATED) & ~self._autoreset
        info = self._info()
        done = terminated | truncated
        if self.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP:
            if done.any():
                info["final_obs"] = obs.copy()
                info["final_info"] = self._info()
                info["_final_obs"] = done.copy()
                info["_final_info"] = done.copy()
                batch.reset(done.astype(np.int64), self._generators)
                obs[done] = st.obs[done]
                fresh = self._info()
                for key in ("time_s", "tracking_error_m", "torque_Nm"):
                    value, new = info[key], fresh[key]
                    assert isinstance(value, np.ndarray) and isinstance(new, np.ndarray)
                    value[done] = new[done]
        else:
            self._autoreset = done
        return obs, rewards, terminated, truncated, info

    def _info(self) -> VectorInfo:
        st = self._batch.state
        mask = np.ones(self.num_envs, dtype=bool)
        return {
            "time_s": st.k.astype(np.float64) * self.config.dt,
            "_time_s": mask,
            "tracking_error_m": st.error.copy(),
            "_tracking_error_m": mask.copy(),
            "torque_Nm": st.tau.copy(),
            "_torque_Nm": mask.copy(),
        }

    def close_extras(self, **kwargs: object) -> None:
        """Stop the batch's threads."""
        self._batch.close()
