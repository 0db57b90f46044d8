"""A batch of arms as one object: :class:`ArmBatch`, the machinery behind both environments.

:class:`ArmBatch` builds the compiled step's arrays from an :class:`EnvConfig`
once (:mod:`flexarm.envs.step`), resets chosen arms with their own random
generators and steps all of them in one compiled call, optionally split over
threads (the step releases the GIL). The single environment is a batch of
one; the vector environment a batch of many, so that the two share one code
path. Nothing here needs Gymnasium.
"""

from __future__ import annotations

import itertools
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .._types import F64, I64
from .._validation import check_int
from ..control.gravity_compensation import scratch_size
from ..errors import InvalidValueError
from ..model.arrays import make_workspace
from ..sensing.channels import channel_arrays
from .config import EnvConfig
from .step import BatchState, EnvArrays, Scratch, reset_batch, step_batch

__all__ = ["NOISE_BLOCK", "ArmBatch", "observation_bounds"]


NOISE_BLOCK = 256
"""Rows of standard normal draws refilled at a time per arm (the stream of draws does
not depend on it: a generator fills an array in order)."""


def observation_bounds(config: EnvConfig) -> tuple[F64, F64, int]:
    """Bounds ``(low, high)`` of the observation (shape (n_obs,)) and ``n_ch``.

    Angles: [-pi, pi] rad; joint rates: ``max_rate`` rad/s; positions: the reach
    (:attr:`EnvConfig.reach`), m; velocities: ``n_links * max_rate * reach``, m/s
    (every absolute link angle turns at most that fast before the arm counts as
    diverged; deflection rates add little before then).
    """
    arm = config.arm
    n_links = arm.n_links
    link = config.sensor.resolve(arm)[0]
    reach = config.reach
    speed = n_links * config.max_rate * reach
    if link < 0:
        sensed = np.r_[np.full(n_links, np.pi), np.full(n_links, config.max_rate)]
    else:
        sensed = np.array([reach, reach, speed, speed])
    high = np.r_[sensed, reach, reach, speed, speed]
    return -high, high, sensed.shape[0]


def _env_arrays(config: EnvConfig) -> EnvArrays:
    arm = config.arm
    n_links = arm.n_links
    low, high, _ = observation_bounds(config)
    channels = channel_arrays(arm, config.sensor, config.delay, config.dt / config.substeps)
    lengths = np.asarray(arm.link_lengths, dtype=float)
    times = np.arange(config.n_steps + 1) * config.dt
    position, velocity, _ = config.trajectory.evaluate(times)
    last = n_links - 1
    tip_phi = np.asarray(arm.modes[last].shape(float(lengths[last])), dtype=float)[:, 0]
    return EnvArrays(
        sensor=channels.arrays,
        target=np.ascontiguousarray(np.column_stack([position, velocity]), dtype=float),
        limit=config.limits,
        max_deflection=config.deflection_limits,
        tip_phi=np.ascontiguousarray(tip_phi),
        low=low,
        high=high,
        params=np.array(
            [
                config.dt,
                config.tracking_weight,
                config.effort_weight,
                config.divergence_penalty,
                config.max_rate,
            ]
        ),
        counts=np.array([config.substeps, config.n_steps], dtype=np.int64),
    )


class ArmBatch:
    """``n`` arms of one :class:`EnvConfig`, stepped together by the compiled step.

    Parameters
    ----------
    config : EnvConfig
        The episode's definition (shared by every arm).
    n : int
        Number of arms (>= 1).
    workers : int
        Threads that step disjoint ranges of arms (>= 1; 1 steps in the calling
        thread).
    """

    def __init__(self, config: EnvConfig, n: int, workers: int = 1) -> None:
        self.config = config
        self.n = check_int(n, "n", "ArmBatch", minimum=1)
        self.workers = min(check_int(workers, "workers", "ArmBatch", minimum=1), self.n)
        arm = config.arm
        self.arrays = _env_arrays(config)
        n_dof, n_links = arm.n_dof, arm.n_links
        sensor = self.arrays.sensor
        n_ch = sensor.levels.shape[0]
        order = sensor.pade_ad.shape[0]
        noisy = bool(np.any(sensor.levels > 0))
        self.state = BatchState(
            q=np.zeros((n, n_dof)),
            dq=np.zeros((n, n_dof)),
            tau=np.zeros((n, n_links)),
            buffer=np.zeros((n, int(self.arrays.sensor.delay_steps[0]) + 1, n_ch)),
            cursor=np.zeros(n, dtype=np.int64),
            pade_x=np.zeros((n, n_ch, order)),
            noise=np.zeros((n, NOISE_BLOCK if noisy else 0, n_ch)),
            noise_row=np.zeros(n, dtype=np.int64),
            k=np.zeros(n, dtype=np.int64),
            obs=np.zeros((n, n_ch + 4)),
            reward=np.zeros(n),
            error=np.zeros(n),
            status=np.zeros(n, dtype=np.int64),
            angles=np.zeros((n, n_links)),
            gravity=np.zeros(
                (n, scratch_size(n_dof, n_links) + n_links if config.compensates_gravity else 0)
            ),
        )
        self._scratch = [
            Scratch(
                stages=np.zeros((6, n_dof)),
                ws=make_workspace(n_dof),
                signals=np.zeros(2 * n_ch + max(order, 1) + 4),
            )
            for _ in range(self.workers)
        ]
        bounds = np.linspace(0, self.n, self.workers + 1).round().astype(int)
        self._ranges = [(int(a), int(b)) for a, b in itertools.pairwise(bounds)]
        self._pool = (
            ThreadPoolExecutor(self.workers, thread_name_prefix="flexarm-env")
            if self.workers > 1
            else None
        )
        self._x0 = config.initial_rest_state()
        self._all = np.ones(self.n, dtype=np.int64)
        self.action = np.zeros((n, n_links))

    @property
    def n_obs(self) -> int:
        """Length of an observation."""
        return int(self.state.obs.shape[1])

    def reset(self, mask: I64, generators: list[np.random.Generator | None]) -> None:
        """Start new episodes of the arms with ``mask[i]`` (int64, shape (n,)); arm ``i``
        draws its initial perturbation and its noise from ``generators[i]``."""
        config, arm, st = self.config, self.config.arm, self.state
        n_dof, n_links = arm.n_dof, arm.n_links
        for i in np.flatnonzero(mask):
            x = self._x0.copy()
            rng = generators[i]
            if config.initial_angle_std > 0:
                if rng is None:
                    raise InvalidValueError(f"ArmBatch.reset needs a generator for arm {i}.")
                dtheta = config.initial_angle_std * rng.standard_normal(n_links)
                x[:n_links] += dtheta
                if arm.has_flexible_joints:
                    x[arm.motor_slice] += dtheta
            st.q[i], st.dq[i] = x[:n_dof], x[n_dof:]
            self._refill(int(i), generators[i])
        reset_batch(arm.arrays, self.arrays, st, mask, 0, self.n, self._scratch[0].signals)

    def _refill(self, i: int, rng: np.random.Generator | None) -> None:
        """Fresh normal draws for arm ``i``'s noise (no allocation: written in place)."""
        if self.state.noise.shape[1] == 0:
            return
        if rng is None:
            raise InvalidValueError(f"ArmBatch needs a generator for the noise of arm {i}.")
        rng.standard_normal(out=self.state.noise[i])
        self.state.noise_row[i] = 0

    def step(self, active: I64, generators: list[np.random.Generator | None]) -> None:
        """One control period of the arms with ``active[i]``, holding ``action``
        (N m, shape (n, n_links)); results in ``state``."""
        st = self.state
        if st.noise.shape[1]:
            for i in np.flatnonzero(st.noise_row >= st.noise.shape[1]):
                self._refill(int(i), generators[i])
        model = self.config.arm.arrays
        if self._pool is None:
            step_batch(model, self.arrays, st, self.action, active, 0, self.n, self._scratch[0])
            return
        futures = [
            self._pool.submit(step_batch, model, self.arrays, st, self.action, active, a, b, s)
            for (a, b), s in zip(self._ranges, self._scratch, strict=True)
        ]
        for f in futures:
            f.result()

    def close(self) -> None:
        """Stop the threads (if any)."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
