"""``VecNormalize``: running normalisation of observations and returns, saved without pickle.

Box observations get one ``RunningMeanStd``; ``Dict`` observations one per normalised key
(``obs_rms`` is then a dict, as in SB3), the other keys passing through untouched. The
statistics file is :mod:`palaestra.vec_env.normalize_file`'s (no pickle, checked on load).
"""

from __future__ import annotations

import copy
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from palaestra import error
from palaestra.spaces import Box, Dict, Space
from palaestra.vec_env import normalize_file
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper
from palaestra.wrappers.running_mean_std import RunningMeanStd


def _is_image(space: Space[Any]) -> bool:
    """SB3's ``is_image_space`` (uint8, rank 3, bounds 0..255), without the channel check."""
    return (
        isinstance(space, Box)
        and len(space.shape) == 3
        and space.dtype == np.uint8
        and bool(np.all(space.low == 0))
        and bool(np.all(space.high == 255))
    )


def checked_norm_obs_keys(
    space: Space[Any], norm_obs_keys: Sequence[str] | None
) -> list[str] | None:
    """The keys to normalise (all of a Dict's by default), after SB3's checks and messages:
    every key a ``Box`` (``ValueError``) and present (``KeyError``), no keys for a Box space,
    and nothing but Box and Dict spaces (``ValueError``)."""
    if isinstance(space, Dict):
        keys = list(space.spaces) if norm_obs_keys is None else list(norm_obs_keys)
        for key in keys:
            if key not in space.spaces:
                raise KeyError(
                    f"norm_obs_keys names {key!r}, which the observation space lacks: its keys "
                    f"are {list(space.spaces)}"
                )
            if not isinstance(space.spaces[key], Box):
                raise ValueError(
                    f"VecNormalize only supports `gym.spaces.Box` observation spaces but {key} "
                    f"is of type {space.spaces[key]}. You should probably explicitly pass the "
                    "observation keys  that should be normalized via the `norm_obs_keys` "
                    "parameter."
                )
        return keys
    if isinstance(space, Box):
        if norm_obs_keys is not None:
            raise ValueError(
                "`norm_obs_keys` param is applicable only with `gym.spaces.Dict` observation spaces"
            )
        return None
    raise ValueError(
        "VecNormalize only supports `gym.spaces.Box` and `gym.spaces.Dict` observation spaces, "
        f"not {space}"
    )


class VecNormalize(VecEnvWrapper):
    """SB3's ``VecNormalize``: same arguments, same arithmetic (``obs`` and ``rewards``).

    On a ``Dict`` observation space ``norm_obs_keys`` (default: every key, which must then all
    be ``Box``) picks the keys to normalise; each has its own ``RunningMeanStd`` in the dict
    ``obs_rms``. A normalised image key's space becomes ``Box(-clip_obs, clip_obs, float32)``
    as in SB3 (so policies do not scale it by 255 again); the wrapped env's space is left alone.
    """

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
        norm_obs_keys: Sequence[str] | None = None,
    ) -> None:
        super().__init__(venv)
        self.norm_obs_keys: list[str] | None = None
        self.obs_rms: RunningMeanStd | dict[str, RunningMeanStd]
        space = self.observation_space
        if norm_obs:
            self.norm_obs_keys = checked_norm_obs_keys(space, norm_obs_keys)
        elif norm_obs_keys is not None:
            self.norm_obs_keys = list(norm_obs_keys)  # kept, unused, as SB3 keeps it
        if norm_obs and isinstance(space, Dict):
            subs = space.spaces
            self.obs_rms = {
                k: RunningMeanStd(shape=subs[k].shape or ()) for k in self.norm_obs_keys or ()
            }
            if any(_is_image(subs[k]) for k in self.obs_rms):
                # a new Dict in the same key order (SB3 edits the wrapped env's space in place)
                self.observation_space = Dict(
                    [
                        (k, Box(-clip_obs, clip_obs, sub.shape, np.float32))
                        if k in self.obs_rms and _is_image(sub)
                        else (k, sub)
                        for k, sub in subs.items()
                    ]
                )
        else:
            self.obs_rms = RunningMeanStd(shape=(space.shape or ()) if norm_obs else ())
            if norm_obs and _is_image(space):
                # SB3 GH#1214: normalised images are floats, so a CnnPolicy that would scale
                # them as uint8 images (normalize_images=True) refuses them
                self.observation_space = Box(-clip_obs, clip_obs, space.shape, np.float32)
        self.ret_rms = RunningMeanStd(shape=())
        self.clip_obs, self.clip_reward = clip_obs, clip_reward
        self.gamma, self.epsilon = gamma, epsilon
        self.training, self.norm_obs, self.norm_reward = training, norm_obs, norm_reward
        self.returns = np.zeros(self.num_envs)  # [N] discounted return so far
        self.old_obs: Any = np.array([])
        self.old_reward = np.array([])

    def _update_obs_rms(self, obs: Any) -> None:
        if isinstance(self.obs_rms, dict):
            for key, rms in self.obs_rms.items():
                rms.update(obs[key])
        else:
            self.obs_rms.update(obs)

    def step_wait(self) -> StepReturn:
        """Step, update the statistics (when training) and normalise."""
        obs, rewards, dones, infos = self.venv.step_wait()
        self.old_obs, self.old_reward = obs, rewards
        if self.training and self.norm_obs:
            self._update_obs_rms(obs)
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
            self._update_obs_rms(obs)
        return self.normalize_obs(obs)

    def _scale(self, obs: Any, rms: RunningMeanStd) -> np.ndarray:
        scaled = (obs - rms.mean) / np.sqrt(rms.var + self.epsilon)
        return np.clip(scaled, -self.clip_obs, self.clip_obs).astype(np.float32)

    def normalize_obs(self, obs: Any) -> Any:
        """``clip((obs - mean) / sqrt(var + eps), ±clip_obs)`` as float32 (if ``norm_obs``); a
        dict gets its normalised keys scaled and copies of the others (SB3 deep-copies)."""
        if not self.norm_obs:
            return obs
        if isinstance(self.obs_rms, dict):
            rms = self.obs_rms
            return {
                k: self._scale(obs[k], rms[k]) if k in rms else copy.deepcopy(v)
                for k, v in _with_keys(obs, rms).items()
            }
        return self._scale(obs, self.obs_rms)

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
        if isinstance(self.obs_rms, dict):
            rms = self.obs_rms
            return {
                k: obs[k] * np.sqrt(rms[k].var + self.epsilon) + rms[k].mean
                if k in rms
                else copy.deepcopy(v)
                for k, v in _with_keys(obs, rms).items()
            }
        return obs * np.sqrt(self.obs_rms.var + self.epsilon) + self.obs_rms.mean

    def unnormalize_reward(self, reward: np.ndarray) -> np.ndarray:
        """Invert :meth:`normalize_reward` (up to clipping)."""
        if not self.norm_reward:
            return reward
        return reward * np.sqrt(self.ret_rms.var + self.epsilon)

    def get_original_obs(self) -> Any:
        """The last observations before normalisation (a copy; of every key for a dict)."""
        return copy.deepcopy(self.old_obs)

    def get_original_reward(self) -> np.ndarray:
        """The last rewards before normalisation."""
        return self.old_reward.copy()

    # -- pickling and set_venv (SB3's semantics) --------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        """The statistics and settings without the wrapped env (SB3 pickles it this way):
        attach one with :meth:`set_venv` before use."""
        state = self.__dict__.copy()
        del state["venv"], state["returns"]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.venv = None  # type: ignore[assignment]

    def set_venv(self, venv: VecEnv) -> None:
        """Wrap ``venv`` (after unpickling, which leaves the wrapper without one); its
        observation shapes must be the ones the statistics were gathered on, its number of
        envs may differ (the running returns start again at 0)."""
        if self.venv is not None:
            raise error.VecEnvAlreadySet(
                f"Trying to set venv of already initialized VecNormalize wrapper: it wraps "
                f"{self.venv!r}; set_venv({venv!r}) expects a VecNormalize without one "
                "(unpickled). Wrap the new env in VecNormalize, or VecNormalize.load the "
                "saved statistics around it."
            )
        if not isinstance(venv, VecEnv):
            raise error.NotAVecEnv(
                f"VecNormalize.set_venv expects a palaestra.vec_env.VecEnv, got {venv!r:.200}"
            )
        _check_same_shapes(self.observation_space, venv.observation_space)
        self.venv = venv
        self.num_envs = venv.num_envs
        self.render_mode = venv.render_mode
        self.metadata = venv.metadata
        self._reset_seeds()
        self._reset_options()
        self.returns = np.zeros(self.num_envs)

    # -- saving ---------------------------------------------------------------------------
    def save(self, save_path: str | os.PathLike[str]) -> None:
        """Write the statistics and settings to ``save_path`` (an ``.npz``; no pickle)."""
        normalize_file.save(self, save_path)

    @staticmethod
    def load(load_path: str | os.PathLike[str], venv: VecEnv) -> VecNormalize:
        """A ``VecNormalize`` around ``venv`` with the statistics saved at ``load_path``.

        Raises ``ModelFileError`` (a ``ValueError``) naming the file and the problem for a file
        that is not one ``save`` wrote, or whose statistics do not fit ``venv``.
        """
        return normalize_file.load(load_path, venv, VecNormalize)


def _check_same_shapes(ours: Space[Any], theirs: Space[Any]) -> None:
    """SB3's ``check_shape_equal``: the same ``Dict`` keys and ``Box`` shapes, recursively."""
    if isinstance(ours, Dict):
        if not isinstance(theirs, Dict) or set(ours.spaces) != set(theirs.spaces):
            raise error.InvalidObservation(
                f"VecNormalize.set_venv: the env's observation space {theirs} does not have the "
                f"keys of the one the statistics were gathered on, {ours}"
            )
        for key, sub in ours.spaces.items():
            _check_same_shapes(sub, theirs.spaces[key])
    elif isinstance(ours, Box) and ours.shape != theirs.shape:
        raise error.InvalidObservation(
            f"VecNormalize.set_venv: the env's observation space {theirs} has shape "
            f"{theirs.shape}, but the statistics were gathered on {ours} (shape {ours.shape})"
        )


def _with_keys(obs: Any, rms: dict[str, RunningMeanStd]) -> dict[str, Any]:
    """``obs`` as a dict holding every normalised key (else a ``KeyError`` naming it)."""
    if not isinstance(obs, dict):
        raise TypeError(
            f"expected a dict of observations (keys {list(rms)}), got {type(obs).__name__}"
        )
    missing = [k for k in rms if k not in obs]
    if missing:
        raise KeyError(f"the observations lack the normalised keys {missing}")
    return obs
