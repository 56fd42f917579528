"""Episode bookkeeping wrappers: ``RecordEpisodeStatistics`` and ``Autoreset`` (Gymnasium 1.x)."""

from __future__ import annotations

import time
from collections import deque
from typing import Any, SupportsFloat

from palaestra.core import ActType, Env, ObsType, Wrapper
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["Autoreset", "RecordEpisodeStatistics"]


class RecordEpisodeStatistics(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """At the end of each episode put ``{"r": return, "l": length, "t": seconds}`` in
    ``info[stats_key]`` and append them to :attr:`return_queue`, :attr:`length_queue` and
    :attr:`time_queue` (the last ``buffer_length`` episodes). ``t`` is the episode's own
    duration, rounded to microseconds.

    >>> import palaestra as gym
    >>> env = RecordEpisodeStatistics(gym.make("CartPole-v1"))
    >>> _ = env.reset(seed=0)
    >>> done = False
    >>> while not done:
    ...     _, _, terminated, truncated, info = env.step(1)
    ...     done = terminated or truncated
    >>> info["episode"]["r"], info["episode"]["l"], list(env.length_queue)
    (8.0, 8, [8])
    """

    def __init__(
        self, env: Env[ObsType, ActType], buffer_length: int = 100, stats_key: str = "episode"
    ) -> None:
        RecordConstructorArgs.__init__(self, buffer_length=buffer_length, stats_key=stats_key)
        Wrapper.__init__(self, env)
        self._stats_key = stats_key
        self.episode_count = 0
        self.episode_start_time: float = -1
        self.episode_returns: Any = 0.0  # float, or the reward's numpy type once added
        self.episode_lengths: int = 0
        self.time_queue: deque[float] = deque(maxlen=buffer_length)
        self.return_queue: deque[float] = deque(maxlen=buffer_length)
        self.length_queue: deque[int] = deque(maxlen=buffer_length)

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and record the episode when it ends."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.episode_returns += reward
        self.episode_lengths += 1
        if terminated or truncated:
            if self._stats_key in info:
                raise ValueError(
                    f"info already has the key {self._stats_key!r} that RecordEpisodeStatistics "
                    "writes to; pass another `stats_key`"
                )
            elapsed = round(time.perf_counter() - self.episode_start_time, 6)
            info[self._stats_key] = {
                "r": self.episode_returns,
                "l": self.episode_lengths,
                "t": elapsed,
            }
            self.time_queue.append(elapsed)
            self.return_queue.append(self.episode_returns)
            self.length_queue.append(self.episode_lengths)
            self.episode_count += 1
            self.episode_start_time = time.perf_counter()
        return obs, reward, terminated, truncated, info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env and the running episode totals."""
        obs, info = self.env.reset(seed=seed, options=options)
        self.episode_start_time = time.perf_counter()
        self.episode_returns = 0.0
        self.episode_lengths = 0
        return obs, info


class Autoreset(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Reset automatically on the step *after* an episode ends (Gymnasium 1.x's next-step mode).

    The step that ends an episode is returned unchanged; the following ``step`` ignores its
    action and returns ``(reset_obs, 0.0, False, False, reset_info)``.

    >>> import palaestra as gym
    >>> env = Autoreset(gym.make("CartPole-v1"))
    >>> _ = env.reset(seed=0)
    >>> [env.step(1)[2] for _ in range(9)]  # terminated on the 8th step, reset on the 9th
    [False, False, False, False, False, False, False, True, False]
    """

    def __init__(self, env: Env[ObsType, ActType]) -> None:
        RecordConstructorArgs.__init__(self)
        Wrapper.__init__(self, env)
        self.autoreset = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env; the next step is a normal step."""
        self.autoreset = False
        return self.env.reset(seed=seed, options=options)

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env, or reset it if the previous step ended the episode."""
        if self.autoreset:
            obs, info = self.env.reset()
            reward: SupportsFloat = 0.0
            terminated = truncated = False
        else:
            obs, reward, terminated, truncated, info = self.env.step(action)
        self.autoreset = terminated or truncated
        return obs, reward, terminated, truncated, info
