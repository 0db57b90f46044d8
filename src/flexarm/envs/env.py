"""The Gymnasium environment of one flexible arm: :class:`FlexibleArmEnv`.

An episode follows a reference path (:class:`flexarm.control.trajectories.Square`
by default) from rest on its first point; an action is the joint torques (N m),
held over one control period ``dt`` (zero-order hold) while the compiled RK4
integrator advances the plant (:mod:`flexarm.envs.step`); the observation is
what the chosen sensor reads, through its transport delay, noise and
quantisation, and the reference's current position and velocity; the reward
penalises the end effector's tracking error and the effort
(:class:`flexarm.envs.config.EnvConfig` documents the weights). The episode is
truncated at the reference's end and terminated when the arm diverges.

The integration is that of :func:`flexarm.simulate_open_loop` with a held torque:
the same compiled RK4 step on the same operands, so a run of the environment
reproduces ``simulate_open_loop(arm, t, torques, substeps=...)`` bit for bit.

Examples
--------
>>> import gymnasium as gym
>>> import flexarm.envs
>>> env = gym.make("flexarm/FlexibleArm-v0", duration=0.05)
>>> obs, info = env.reset(seed=0)
>>> obs.shape                 # two angles, two rates, the reference's x, y, vx, vy
(8,)
>>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
"""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
from numpy.typing import ArrayLike

from .._types import F64
from ..errors import InvalidTypeError, InvalidValueError
from .config import EnvConfig
from .core import ArmBatch
from .step import DIVERGED, RUNNING, TRUNCATED

__all__ = ["FlexibleArmEnv", "config_from", "step_info"]

Info = dict[str, float | F64]


def config_from(config: EnvConfig | None, options: dict[str, object], owner: str) -> EnvConfig:
    """``config`` (default :class:`EnvConfig` ()) with the fields in ``options`` replaced;
    an unknown option is a TypeError naming ``owner``."""
    if config is not None and not isinstance(config, EnvConfig):
        raise InvalidTypeError(
            f"The 'config' parameter of {owner} must be an EnvConfig. "
            f"Got {type(config).__name__} instead."
        )
    fields = {f.name for f in dataclasses.fields(EnvConfig)}
    for key in options:
        if key not in fields:
            raise InvalidTypeError(
                f"{owner} got an unexpected keyword argument {key!r} (the options are the "
                f"fields of EnvConfig: {', '.join(sorted(fields))})."
            )
    base = EnvConfig() if config is None else config
    return dataclasses.replace(base, **options) if options else base  # type: ignore[arg-type]


def step_info(batch: ArmBatch, i: int) -> Info:
    """The info of arm ``i`` after a reset or a step (new objects on every call)."""
    st = batch.state
    return {
        "time_s": float(st.k[i]) * batch.config.dt,
        "tracking_error_m": float(st.error[i]),
        "torque_Nm": st.tau[i].copy(),
    }


class FlexibleArmEnv(gym.Env[F64, F64]):
    """A flexible arm tracking a reference, driven by joint torques (module docstring).

    Parameters
    ----------
    config : EnvConfig, optional
        The episode's definition (default :class:`EnvConfig` ()).
    render_mode : None
        No rendering (watch a run with :meth:`flexarm.SimulationResult.animate`).
    **options
        Fields of :class:`EnvConfig` replacing those of ``config``
        (``gymnasium.make("flexarm/FlexibleArm-v0", dt=0.005)``).

    Attributes
    ----------
    action_space : gymnasium.spaces.Box, shape (n_links,)
        Joint torques, N m, within ``[-torque_limit, torque_limit]`` (an action
        outside is clipped). Wrap the environment in
        ``gymnasium.wrappers.RescaleAction`` for a ``[-1, 1]`` action.
    observation_space : gymnasium.spaces.Box, shape (n_ch + 4,)
        :mod:`flexarm.envs.step`'s layout: the sensor's ``n_ch`` channels, the
        reference's position (m) and velocity (m/s); float64.
    """

    metadata = {"render_modes": [], "render_fps": 30}  # noqa: RUF012 - Gymnasium's convention

    def __init__(
        self, config: EnvConfig | None = None, *, render_mode: None = None, **options: object
    ) -> None:
        if render_mode is not None:
            raise InvalidValueError(
                f"The 'render_mode' parameter of FlexibleArmEnv must be None (no rendering). "
                f"Got {render_mode!r} instead."
            )
        self.render_mode = None
        self.config = config_from(config, options, "FlexibleArmEnv")
        self._batch = ArmBatch(self.config, 1)
        limit = self.config.limits
        low, high = self._batch.arrays.low, self._batch.arrays.high
        self.action_space = gym.spaces.Box(-limit, limit, dtype=np.float64)
        self.observation_space = gym.spaces.Box(low.copy(), high.copy(), dtype=np.float64)
        self._one = np.ones(1, dtype=np.int64)
        self._started = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[F64, Info]:
        """Start an episode at rest on the reference's first point.

        Parameters
        ----------
        seed : int, optional
            Seeds the environment's generator (``self.np_random``), the source of
            the sensor noise and the initial perturbation: the same seed gives
            the same episode for the same actions.
        options : dict, optional
            None or empty (there are no reset options).

        Returns
        -------
        observation : ndarray, shape (n_obs,)
        info : dict
            ``time_s`` (s), ``tracking_error_m`` (m), ``torque_Nm`` (N m, shape (n_links,)).
        """
        super().reset(seed=seed)
        if options:
            raise InvalidValueError(
                f"The 'options' parameter of FlexibleArmEnv.reset must be None or empty. "
                f"Got {options!r} instead."
            )
        self._batch.reset(self._one, [self.np_random])
        self._started = True
        return self._batch.state.obs[0].copy(), step_info(self._batch, 0)

    def step(self, action: ArrayLike) -> tuple[F64, float, bool, bool, Info]:
        """Hold ``action`` (N m, shape (n_links,)) over one control period.

        Returns
        -------
        observation : ndarray, shape (n_obs,)
            At the new instant (the last one before divergence on a diverging step).
        reward : float
            :class:`EnvConfig`'s Notes.
        terminated : bool
            The arm diverged (non-finite state, a tip deflection beyond
            ``max_deflection`` or a joint rate beyond ``max_rate``).
        truncated : bool
            The reference's end (``n_steps`` steps) was reached.
        info : dict
            As :meth:`reset`'s.
        """
        st = self._batch.state
        if not self._started or st.status[0] != RUNNING:
            raise InvalidValueError(
                "FlexibleArmEnv.step needs a running episode: call reset() first (and after "
                "an episode terminates or is truncated)."
            )
        n_links = self.config.arm.n_links
        if np.shape(action) != (n_links,):
            raise InvalidValueError(
                f"The 'action' parameter of FlexibleArmEnv.step must be of shape ({n_links},) "
                f"(joint torques, N m). Got shape {np.shape(action)} instead."
            )
        np.copyto(self._batch.action[0], action, casting="same_kind")
        self._batch.step(self._one, [self.np_random])
        status = int(st.status[0])
        return (
            st.obs[0].copy(),
            float(st.reward[0]),
            status == DIVERGED,
            status == TRUNCATED,
            step_info(self._batch, 0),
        )

    def close(self) -> None:
        """Release the batch's threads (none for one arm)."""
        self._batch.close()
