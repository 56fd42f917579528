"""``VecMonitor``: episode return/length/time for every env of a ``VecEnv``, with arrays."""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper
from palaestra.wrappers.monitor import Monitor, ResultsWriter

if TYPE_CHECKING:
    from palaestra.wrappers.monitor import ResultsWriter


class VecMonitor(VecEnvWrapper):
    """Adds ``infos[i]["episode"] = {"r", "l", "t"}`` when env i finishes (SB3's ``Monitor``
    keys) and, with ``filename``, logs each episode to a ``monitor.csv``.

    >>> from palaestra.vec_env import make_vec_env
    >>> venv = make_vec_env("CartPole-v1", n_envs=2, seed=0)  # a VecMonitor already
    >>> isinstance(venv, VecMonitor)
    True
    """

    RUN_STATE = ("venv", "episode_count", "episode_returns", "episode_lengths")

    def __init__(
        self, venv: VecEnv, filename: str | None = None, info_keywords: tuple[str, ...] = ()
    ) -> None:
        super().__init__(venv)

        try:
            monitored = venv.env_is_wrapped(Monitor)[0]
        except (AttributeError, NotImplementedError):
            monitored = False
        if monitored:
            # SB3's warning: each episode would be counted (and logged) twice.
            warnings.warn(
                "The environment is already wrapped with a `Monitor` wrapper but you are "
                "wrapping it with a `VecMonitor` wrapper, the `Monitor` statistics will be "
                "overwritten by the `VecMonitor` ones.",
                UserWarning,
                stacklevel=2,
            )
        self.t_start = time.time()
        self.info_keywords = info_keywords
        self.episode_count = 0
        self.episode_returns = np.zeros(self.num_envs, dtype=np.float32)  # [N], SB3's dtype
        self.episode_lengths = np.zeros(self.num_envs, dtype=np.int32)  # [N]
        self.results_writer: ResultsWriter | None = None
        # One writer per env instead, when make_vec_env(monitor_dir=...) asks for SB3's
        # layout (<rank>.monitor.csv per env); None: all episodes go to results_writer.
        self._env_writers: list[ResultsWriter] | None = None
        if filename is not None:
            self.results_writer = self._writer(filename)

    def _writer(self, filename: str, override_existing: bool = True) -> ResultsWriter:
        spec = getattr(self.venv.unwrapped, "spec", None)
        env_id = None if spec is None else spec.id
        return ResultsWriter(
            filename,
            header={"t_start": self.t_start, "env_id": str(env_id)},
            extra_keys=self.info_keywords,
            override_existing=override_existing,
        )

    def log_per_env(self, filenames: Sequence[str], override_existing: bool = True) -> None:
        """Log env i's episodes to ``filenames[i]`` (what ``make_vec_env(monitor_dir=...)``
        gives a native batch: one ``<rank>.monitor.csv`` per env, as SB3's ``Monitor`` does)."""
        if len(filenames) != self.num_envs:
            raise ValueError(f"Expected {self.num_envs} monitor file names, got {len(filenames)}")
        self._env_writers = [self._writer(name, override_existing) for name in filenames]

    def reset(self) -> Any:
        """Reset and start counting new episodes."""
        obs = self.venv.reset()
        self.episode_returns[:] = 0
        self.episode_lengths[:] = 0
        return obs

    def step_wait(self) -> StepReturn:
        """Step; add ``episode`` to the infos of envs that finished."""
        obs, rewards, dones, infos = self.venv.step_wait()
        self.episode_returns += rewards
        self.episode_lengths += 1
        if np.count_nonzero(dones):  # dones.any() costs ~3x more per step
            now = round(time.time() - self.t_start, 6)
            for i in np.flatnonzero(dones).tolist():
                info = dict(infos[i])
                episode = {
                    "r": float(self.episode_returns[i]),
                    "l": int(self.episode_lengths[i]),
                    "t": now,
                }
                for key in self.info_keywords:
                    episode[key] = info[key]
                info["episode"] = episode
                infos[i] = info
                self.episode_count += 1
                self.episode_returns[i] = 0
                self.episode_lengths[i] = 0
                if self._env_writers is not None:
                    self._env_writers[i].write_row(episode)
                elif self.results_writer is not None:
                    self.results_writer.write_row(episode)
        return obs, rewards, dones, infos

    def close(self) -> None:
        """Close the log file and the inner env."""
        for writer in [self.results_writer, *(self._env_writers or [])]:
            if writer is not None:
                writer.close()
        self.results_writer = None
        self._env_writers = None
        self.venv.close()
