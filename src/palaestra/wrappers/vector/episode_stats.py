"""Vector wrappers over infos: ``RecordEpisodeStatistics`` and ``DictInfoToList``."""

from __future__ import annotations

import time
from collections import deque
from typing import Any

import numpy as np

from palaestra import logger
from palaestra.vector.autoreset import parse_reset_mask
from palaestra.vector.vector_env import AutoresetMode, StepReturn, VectorEnv, VectorWrapper


class RecordEpisodeStatistics(VectorWrapper[Any, Any, np.ndarray]):
    """Adds ``infos["episode"] = {"r", "l", "t"}`` arrays (masked by ``infos["_episode"]``)
    on the steps where sub-envs finish; keeps the last ``buffer_length`` of each in queues.
    """

    def __init__(
        self, env: VectorEnv[Any, Any, Any], buffer_length: int = 100, stats_key: str = "episode"
    ) -> None:
        super().__init__(env)
        self._stats_key = stats_key
        mode = env.metadata.get("autoreset_mode")
        if mode is None:
            logger.warn(
                f"{self} is missing `autoreset_mode` tag in its metadata, therefore, "
                "`RecordEpisodeStatistics` is assuming that the environment uses "
                "`AutoresetMode.NEXT_STEP`."
            )
            mode = AutoresetMode.NEXT_STEP
        elif not isinstance(mode, AutoresetMode):
            raise TypeError(
                f"Expected env.metadata['autoreset_mode'] to be an AutoresetMode, got {type(mode)}"
            )
        self._autoreset_mode = mode
        n = self.num_envs
        self.episode_count = 0
        self.episode_start_times = np.zeros(n)  # [N] perf_counter at episode start
        self.episode_returns = np.zeros(n)  # [N]
        self.episode_lengths = np.zeros(n, dtype=int)  # [N]
        self.prev_dones = np.zeros(n, dtype=bool)  # [N]
        self.time_queue: deque[float] = deque(maxlen=buffer_length)
        self.return_queue: deque[float] = deque(maxlen=buffer_length)
        self.length_queue: deque[int] = deque(maxlen=buffer_length)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset and restart the statistics of the reset sub-envs."""
        obs, infos = self.env.reset(seed=seed, options=options)
        mask = parse_reset_mask(options, self.num_envs)
        rows = slice(None) if mask is None else mask
        self.episode_start_times[rows] = time.perf_counter()
        self.episode_returns[rows] = 0
        self.episode_lengths[rows] = 0
        self.prev_dones[rows] = False
        return obs, infos

    def step(self, actions: Any) -> StepReturn:
        """Step, count, and report the episodes that ended."""
        obs, rewards, terminations, truncations, infos = self.env.step(actions)
        if not isinstance(infos, dict):
            raise TypeError(
                "`vector.RecordEpisodeStatistics` requires `info` type to be `dict`, its actual "
                f"type is {type(infos)}. This may be due to usage of other wrappers in the wrong "
                "order."
            )
        if self._autoreset_mode is AutoresetMode.SAME_STEP:
            self.episode_returns += rewards
            self.episode_lengths += 1
        else:
            # Under NEXT_STEP the step after an episode's end is its reset: it starts a new
            # episode and does not count.
            ended = self.prev_dones
            self.episode_returns[ended] = 0
            self.episode_lengths[ended] = 0
            self.episode_start_times[ended] = time.perf_counter()
            self.episode_returns[~ended] += rewards[~ended]
            self.episode_lengths[~ended] += 1
        self.prev_dones = dones = np.logical_or(terminations, truncations)
        if dones.any():
            key = self._stats_key
            if key in infos or f"_{key}" in infos:
                raise ValueError(
                    f"Attempted to add episode stats with key '{key}' but this key already "
                    f"exists in info: {list(infos.keys())}"
                )
            elapsed = np.round(time.perf_counter() - self.episode_start_times, 6)
            infos[key] = {
                "r": np.where(dones, self.episode_returns, 0.0),
                "l": np.where(dones, self.episode_lengths, 0),
                "t": np.where(dones, elapsed, 0.0),
            }
            infos[f"_{key}"] = dones
            self.episode_count += int(dones.sum())
            self.time_queue.extend(elapsed[dones])
            self.return_queue.extend(self.episode_returns[dones])
            self.length_queue.extend(self.episode_lengths[dones])
            if self._autoreset_mode is AutoresetMode.SAME_STEP:
                self.episode_returns[dones] = 0
                self.episode_lengths[dones] = 0
                self.episode_start_times[dones] = time.perf_counter()
        return obs, rewards, terminations, truncations, infos


class DictInfoToList(VectorWrapper[Any, Any, np.ndarray]):
    """Stacked infos (dict of arrays with ``_key`` masks) back to one dict per sub-env."""

    def reset(  # type: ignore[override]
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, list[dict[str, Any]]]:
        """Reset; infos as a list of dicts."""
        obs, infos = self.env.reset(seed=seed, options=options)
        return obs, self._to_list(infos)

    def step(self, actions: Any) -> Any:
        """Step; infos as a list of dicts."""
        obs, rewards, terminations, truncations, infos = self.env.step(actions)
        return obs, rewards, terminations, truncations, self._to_list(infos)

    def _to_list(self, infos: dict[str, Any]) -> list[dict[str, Any]]:
        if not isinstance(infos, dict):
            raise TypeError(f"DictInfoToList expects dict infos, got {type(infos)}")
        out: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for key, value in infos.items():
            if key.startswith("_"):
                continue
            mask = infos.get(f"_{key}")
            per_env = self._to_list(value) if isinstance(value, dict) else value
            if len(per_env) != self.num_envs:
                raise ValueError(
                    f"Info {key!r} has {len(per_env)} entries for {self.num_envs} envs"
                )
            for i in range(self.num_envs):
                if mask is None or mask[i]:
                    out[i][key] = per_env[i]
        return out
