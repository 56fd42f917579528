"""``VecNormalize``: running normalisation of observations and returns, saved without pickle.

The statistics and settings go to one ``.npz`` file of plain arrays plus a JSON string, written
atomically and read back without pickle: loading a file never runs code (SB3 pickles the whole
wrapper). Loading checks every member's size, dtype and shape before reading it and every value
after (finite means, non-negative variances, positive counts, settings of the right types),
so a damaged or crafted file is a ``ModelFileError`` naming the file and what is wrong.
"""

from __future__ import annotations

import json
import math
import os
import zipfile
import zlib
from typing import Any

import numpy as np

from palaestra.spaces import Box
from palaestra.utils.atomic_write import atomic_write
from palaestra.utils.bounded_zip import ModelFileError, check_members, read_npy, short
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper
from palaestra.wrappers.running_mean_std import RunningMeanStd

_FORMAT = "palaestra.VecNormalize/1"
_STATS = ("obs_mean", "obs_var", "ret_mean", "ret_var")
_MAX_SETTINGS = 1 << 16  # bytes of the settings JSON (a few hundred in practice)
_FLAGS = ("training", "norm_obs", "norm_reward")
_POSITIVE = ("clip_obs", "clip_reward", "epsilon", "obs_count", "ret_count")


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
        """``clip(reward / sqrt(return var + eps), ±clip_reward)`` (if ``norm_reward``), as
        float32 either way: SB3 casts (the statistics are float64, rewards float32)."""
        if self.norm_reward:
            reward = np.clip(
                reward / np.sqrt(self.ret_rms.var + self.epsilon),
                -self.clip_reward,
                self.clip_reward,
            )
        return reward.astype(np.float32)

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
        with atomic_write(save_path, "wb") as f:  # a crash mid-save keeps the old file
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
        """A ``VecNormalize`` around ``venv`` with the statistics saved at ``load_path``.

        Raises ``ModelFileError`` (a ``ValueError``) naming the file and the problem for a file
        that is not one ``save`` wrote, or whose statistics do not fit ``venv``.
        """
        name = str(load_path)
        try:
            with zipfile.ZipFile(load_path) as zf:
                members = check_members(zf, name)
                settings = _read_settings(zf, members, name)
                kwargs = {k: v for k, v in settings.items() if k not in ("obs_count", "ret_count")}
                norm = VecNormalize(venv, **kwargs)
                shapes = {
                    "obs_mean": norm.obs_rms.mean.shape,
                    "obs_var": norm.obs_rms.mean.shape,
                    "ret_mean": (),
                    "ret_var": (),
                }
                arrays = {key: _read_stat(zf, members, key, shapes[key], name) for key in _STATS}
        except zipfile.BadZipFile as e:
            if _is_pickle(load_path):
                raise ModelFileError(
                    f"{name} is a pickle (what Stable-Baselines3's VecNormalize.save writes); "
                    "palaestra never unpickles (a pickle can run code) and reads only the .npz "
                    "file its own VecNormalize.save writes. To carry SB3 statistics over, load "
                    "them with SB3 where you trust the file and set obs_rms/ret_rms (mean, var, "
                    "count) on a palaestra VecNormalize, then save that."
                ) from None
            raise ModelFileError(
                f"{name} is not a palaestra VecNormalize file (palaestra reads the .npz file "
                f"VecNormalize.save writes: {e})"
            ) from e
        except (EOFError, zlib.error) as e:
            raise ModelFileError(f"{name} is truncated or corrupt ({short(e)})") from e
        norm.obs_rms.mean, norm.obs_rms.var = arrays["obs_mean"], arrays["obs_var"]
        norm.obs_rms.count = float(settings["obs_count"])
        norm.ret_rms.mean, norm.ret_rms.var = arrays["ret_mean"][()], arrays["ret_var"][()]
        norm.ret_rms.count = float(settings["ret_count"])
        return norm


def _is_pickle(path: str | os.PathLike[str]) -> bool:
    """Whether the file starts like a pickle of protocol 2 or later (``0x80``, version)."""
    try:
        with open(path, "rb") as file:
            head = file.read(2)
    except OSError:
        return False
    return len(head) == 2 and head[0] == 0x80 and 2 <= head[1] <= 5


def _read_settings(
    zf: zipfile.ZipFile, members: dict[str, zipfile.ZipInfo], name: str
) -> dict[str, Any]:
    """The settings JSON, every key present with a value of the right type and range."""
    if "settings.npy" not in members:
        raise ModelFileError(f"{name} is not a palaestra VecNormalize file (no settings)")
    raw = read_npy(zf, members["settings.npy"], name, _MAX_SETTINGS, shape=())
    try:
        settings = json.loads(str(raw[()]))
    except (ValueError, RecursionError) as e:
        raise ModelFileError(f"{name}: its settings are not valid JSON ({short(e)})") from e
    if not isinstance(settings, dict) or settings.get("format") != _FORMAT:
        raise ModelFileError(f"{name} is not a palaestra VecNormalize file")
    for key in _FLAGS:
        if not isinstance(settings.get(key), bool):
            raise ModelFileError(
                f"{name}: setting {key!r} is {short(repr(settings.get(key)), 60)}, "
                "expected true or false"
            )
    for key in (*_POSITIVE, "gamma"):
        value = _number(settings.get(key))
        if value is None or (value <= 0 if key in _POSITIVE else not 0 <= value <= 1):
            want = "a finite number > 0" if key in _POSITIVE else "a number in [0, 1]"
            raise ModelFileError(
                f"{name}: setting {key!r} is {short(repr(settings.get(key)), 60)}, expected {want}"
            )
    return {
        **{k: settings[k] for k in _FLAGS},
        **{k: _number(settings[k]) for k in (*_POSITIVE, "gamma")},
    }


def _number(value: Any) -> float | None:
    """``value`` as a finite float, or None (for bools, strings, NaN, huge ints ...)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _read_stat(
    zf: zipfile.ZipFile,
    members: dict[str, zipfile.ZipInfo],
    key: str,
    shape: tuple[int, ...],
    name: str,
) -> np.ndarray:
    """One statistic: float, of the env's shape, finite, and a variance never negative."""
    if f"{key}.npy" not in members:
        raise ModelFileError(f"{name}: the {key!r} statistics are missing")
    # float64 of the expected shape, checked before reading (plus room to read a wrong shape
    # and say so)
    limit = 8 * math.prod(shape) + (1 << 16)
    array = read_npy(zf, members[f"{key}.npy"], name, limit, {"<f8", "<f4"})
    if array.shape != shape:
        raise ModelFileError(
            f"{name}: saved {key!r} statistics have shape {array.shape}, but the env's "
            f"{'observations have' if key.startswith('obs') else 'returns have'} shape {shape}"
        )
    if not np.all(np.isfinite(array)):
        raise ModelFileError(f"{name}: the {key!r} statistics hold NaN or infinite values")
    if key.endswith("_var") and np.any(array < 0):
        raise ModelFileError(f"{name}: the {key!r} statistics hold negative variances")
    return array.astype(np.float64)
