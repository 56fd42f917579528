"""``VecExtractDictObs``: one key of Dict observations as the observation (SB3's wrapper)."""

from __future__ import annotations

from typing import Any

from palaestra.spaces import Dict
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper


class VecExtractDictObs(VecEnvWrapper):
    """Observations (and ``terminal_observation``) become ``obs[key]``."""

    def __init__(self, venv: VecEnv, key: str) -> None:
        if not isinstance(venv.observation_space, Dict):
            raise TypeError(
                "VecExtractDictObs can only be used with Dict obs space, not "
                f"{venv.observation_space}"
            )
        if key not in venv.observation_space.spaces:
            raise KeyError(
                f"VecExtractDictObs: no key {key!r} in {venv.observation_space} "
                f"(keys: {list(venv.observation_space.spaces)})"
            )
        self.key = key
        super().__init__(venv, observation_space=venv.observation_space.spaces[key])

    def reset(self) -> Any:
        """Reset; the ``key`` part of the observations."""
        return self.venv.reset()[self.key]

    def step_wait(self) -> StepReturn:
        """Step; the ``key`` part of the observations and terminal observations."""
        obs, rewards, dones, infos = self.venv.step_wait()
        for info in infos:
            if "terminal_observation" in info:
                info["terminal_observation"] = info["terminal_observation"][self.key]
        return obs[self.key], rewards, dones, infos
