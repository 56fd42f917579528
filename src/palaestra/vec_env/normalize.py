"""``VecNormalize``: running normalisation of observations and returns, saved without pickle.

The statistics and settings go to one ``.npz`` file of plain arrays plus a JSON string, read back
with ``allow_pickle=False``: loading a file never runs code (SB3 pickles the whole wrapper).
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from palaestra.spaces import Box
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper
from palaestra.wrappers.running_mean_std import RunningMeanStd

_FORMAT = "palaestra.VecNormalize/1"


class VecNormalize(VecEnvWrapper):
    """SB3's ``VecNormalize``: same arguments, same arithmetic (``obs`` and ``rewards``)."""

    RUN_STATE = ("venv", "obs_rms", "ret_rms", "returns")  # exact resume (utils.run_state)

    def __init__(
        self,
        venv: VecEnv,
        training: bool = True,
        norm_obs: bool = True,
        norm_reward: bool = True,
        clip_obs: float = 10.0,
        clip_reward: float = 10.0,
        gamma: float = 0.99,
        epsilon: float = 1e-8,
    ) -> None:
        super().__init__(venv)
        if norm_obs and not isinstance(self.observation_space, Box):
            raise ValueError(
                f"VecNormalize normalises Box observations only, got {self.observation_space}; "
                "pass norm_obs=False"
            )
        shape = self.observation_space.shape if norm_obs else ()
        self.obs_rms = RunningMeanStd(shape=shape or ())
        self.ret_rms = RunningMeanStd(shape=())
        self.clip_obs, self.clip_reward = clip_obs, clip_reward
        self.gamma, self.epsilon = gamma, epsilon
        self.training, self.norm_obs, self.norm_reward = training, norm_obs, norm_reward
        self.returns = np.zeros(self.num_envs)  # [N] discounted return so far
        self.old_obs: Any = np.array([])
        self.old_reward = np.array([])

    def step_wait(self) -> StepReturn:
        """Step, update the statistics (when training) and normalise."""
        obs, rewards, dones, infos = self.venv.step_wait()
        self.old_obs, self.old_reward = obs, rewards
        if self.training and self.norm_obs:
            self.obs_rms.update(obs)
        obs = self.normalize_obs(obs)
        if self.training:
            self.returns = self.returns * self.gamma + rewards
            self.ret_rms.update(self.returns)
        rewards = self.normalize_reward(rewards)
        for i in np.flatnonzero(dones).tolist():
            if "terminal_observation" in infos[i]:
                infos[i] = dict(infos[i])
                infos[i]["terminal_observation"] = self.normalize_obs(
                    infos[i]["terminal_observation"]
                )
        self.returns[dones] = 0
        return obs, rewards, dones, infos

    def reset(self) -> Any:
        """Reset, update the statistics with the first observations, normalise."""
        obs = self.venv.reset()
        self.old_obs = obs
        self.returns = np.zeros(self.num_envs)
        if self.training and self.norm_obs:
            self.obs_rms.update(obs)
        return self.normalize_obs(obs)

    def normalize_obs(self, obs: Any) -> Any:
        """``clip((obs - mean) / sqrt(var + eps), ±clip_obs)`` as float32 (if ``norm_obs``)."""
        if not self.norm_obs:
            return obs
        scaled = (obs - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        return np.clip(scaled, -self.clip_obs, self.clip_obs).astype(np.float32)

    def normalize_reward(self, reward: np.ndarray) -> np.ndarray:
        """``clip(reward / sqrt(return var + eps), ±clip_reward)`` (if ``norm_reward``)."""
        if not self.norm_reward:
            return reward
        scaled = reward / np.sqrt(self.ret_rms.var + self.epsilon)
        return np.clip(scaled, -self.clip_reward, self.clip_reward)

    def unnormalize_obs(self, obs: Any) -> Any:
        """Invert :meth:`normalize_obs` (up to clipping)."""
        if not self.norm_obs:
            return obs
        return obs * np.sqrt(self.obs_rms.var + self.epsilon) + self.obs_rms.mean

    def unnormalize_reward(self, reward: np.ndarray) -> np.ndarray:
        """Invert :meth:`normalize_reward` (up to clipping)."""
        if not self.norm_reward:
            return reward
        return reward * np.sqrt(self.ret_rms.var + self.epsilon)

    def get_original_obs(self) -> Any:
        """The last observations before normalisation."""
        return self.old_obs.copy()

    def get_original_reward(self) -> np.ndarray:
        """The last rewards before normalisation."""
        return self.old_reward.copy()

    # -- saving ---------------------------------------------------------------------------
    def save(self, save_path: str | os.PathLike[str]) -> None:
        """Write the statistics and settings to ``save_path`` (an ``.npz``; no pickle)."""
        settings = {
            "format": _FORMAT,
            "training": self.training,
            "norm_obs": self.norm_obs,
            "norm_reward": self.norm_reward,
            "clip_obs": self.clip_obs,
            "clip_reward": self.clip_reward,
            "gamma": self.gamma,
            "epsilon": self.epsilon,
            "obs_count": float(self.obs_rms.count),
            "ret_count": float(self.ret_rms.count),
        }
        with open(save_path, "wb") as f:
            np.savez(
                f,
                settings=np.array(json.dumps(settings)),
                obs_mean=self.obs_rms.mean,
                obs_var=self.obs_rms.var,
                ret_mean=np.asarray(self.ret_rms.mean),
                ret_var=np.asarray(self.ret_rms.var),
            )

    @staticmethod
    def load(load_path: str | os.PathLike[str], venv: VecEnv) -> VecNormalize:
        """A ``VecNormalize`` around ``venv`` with the statistics saved at ``load_path``."""
        try:
            with np.load(load_path, allow_pickle=False) as data:
                settings = json.loads(str(data["settings"]))
                arrays = {k: data[k] for k in ("obs_mean", "obs_var", "ret_mean", "ret_var")}
        except (ValueError, KeyError, OSError, json.JSONDecodeError) as e:
            raise ValueError(f"{load_path} is not a palaestra VecNormalize file: {e}") from e
        if settings.get("format") != _FORMAT:
            raise ValueError(f"{load_path} is not a palaestra VecNormalize file")
        norm = VecNormalize(
            venv,
            training=settings["training"],
            norm_obs=settings["norm_obs"],
            norm_reward=settings["norm_reward"],
            clip_obs=settings["clip_obs"],
            clip_reward=settings["clip_reward"],
            gamma=settings["gamma"],
            epsilon=settings["epsilon"],
        )
        if norm.norm_obs and arrays["obs_mean"].shape != norm.obs_rms.mean.shape:
            raise ValueError(
                f"Saved observation statistics have shape {arrays['obs_mean'].shape}, but the "
                f"env's observations have shape {norm.obs_rms.mean.shape}"
            )
        norm.obs_rms.mean, norm.obs_rms.var = arrays["obs_mean"], arrays["obs_var"]
        norm.obs_rms.count = settings["obs_count"]
        norm.ret_rms.mean, norm.ret_rms.var = arrays["ret_mean"][()], arrays["ret_var"][()]
        norm.ret_rms.count = settings["ret_count"]
        return norm
