"""Observation-reshaping ``VecEnv`` wrappers: ``VecFrameStack`` and ``VecTransposeImage``."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from typing import Any

import numpy as np

from palaestra.spaces import Box, Dict
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper
from palaestra.vec_env.stacked_observations import StackedObservations


def physical_memory() -> int | None:
    """This machine's RAM in bytes, or None where the OS does not say (Windows)."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, OSError, ValueError):
        return None


def check_n_stack(n_stack: Any, frame_bytes: int = 1, name: str = "n_stack") -> int:
    """``n_stack`` as an int, if it is a positive integer whose stack fits in memory.

    ``frame_bytes`` is what one more stacked frame costs (every env's observation, and the
    stacked space's bounds); 1 when unknown (a config checked before its env is built). Checked
    before allocating: numpy does not refuse ``np.repeat(low, 2**62)``, it crashes the process.
    """
    if isinstance(n_stack, bool) or not isinstance(n_stack, (int, np.integer)):
        raise TypeError(
            f"{name} must be a positive integer, got {n_stack!r} ({type(n_stack).__name__})"
        )
    if n_stack < 1:
        raise ValueError(f"{name} must be a positive integer, got {n_stack}")
    need = int(n_stack) * frame_bytes
    limit = physical_memory()
    if need > (sys.maxsize if limit is None else limit):
        raise ValueError(
            f"{name}={n_stack} would need {need:,} bytes for the stacked observations "
            f"({frame_bytes:,} per frame), more than this machine's "
            + ("address space" if limit is None else f"{limit:,} bytes of memory")
        )
    return int(n_stack)


def _is_image(space: Any) -> bool:
    return isinstance(space, Box) and len(space.shape) == 3 and space.dtype == np.uint8


class VecFrameStack(VecEnvWrapper):
    """Stack the last ``n_stack`` observations of each env along the channel axis.

    ``channels_order`` is "last" or "first"; None means "last" unless the observations are
    channel-first images (SB3's rule). A finished env's stack restarts from zeros.

    A ``Dict`` observation space has every key stacked by a :class:`StackedObservations` (SB3's
    Dict path): every key must be a ``Box`` (else ``TypeError``, as SB3), and
    ``channels_order`` may be one order for all keys or a dict of one per key.
    """

    RUN_STATE: tuple[str, ...] = ("venv", "stacked")  # exact resume (utils.run_state)

    def __init__(
        self,
        venv: VecEnv,
        n_stack: int,
        channels_order: str | Mapping[str, str | None] | None = None,
    ) -> None:
        space = venv.observation_space
        if isinstance(space, Dict):
            self._init_dict(venv, n_stack, space, channels_order)
            return
        if not isinstance(space, Box):
            raise ValueError(f"VecFrameStack supports Box and Dict observations only, got {space}")
        if isinstance(channels_order, Mapping):
            raise TypeError("When the observation space is Box, channels_order can't be a dict.")
        if channels_order is None:
            channels_first = (
                _is_image(space)
                and space.shape[0] in (1, 3, 4)
                and (space.shape[-1] not in (1, 3, 4))
            )
            channels_order = "first" if channels_first else "last"
        if channels_order not in ("first", "last"):
            raise ValueError(
                f"channels_order must be 'first', 'last' or None, got {channels_order}"
            )
        # The stack itself ([N, *shape] per frame) and the stacked space's low and high.
        frame_bytes = (venv.num_envs + 2) * int(np.prod(space.shape)) * space.dtype.itemsize
        self.n_stack = n_stack = check_n_stack(n_stack, max(frame_bytes, 1))
        self.axis = 0 if channels_order == "first" else -1
        low = np.repeat(space.low, n_stack, axis=self.axis)
        high = np.repeat(space.high, n_stack, axis=self.axis)
        stacked_space = Box(low=low, high=high, dtype=space.dtype)
        super().__init__(venv, observation_space=stacked_space)
        self.channels = space.shape[self.axis]
        # [N, *stacked_shape]
        self.stacked = np.zeros((venv.num_envs, *stacked_space.shape), dtype=space.dtype)

    def _init_dict(
        self,
        venv: VecEnv,
        n_stack: int,
        space: Dict,
        channels_order: str | Mapping[str, str | None] | None,
    ) -> None:
        boxes = [sub for sub in space.spaces.values() if isinstance(sub, Box)]
        frame_bytes = sum(
            (venv.num_envs + 2) * int(np.prod(sub.shape)) * sub.dtype.itemsize for sub in boxes
        )
        self.n_stack = check_n_stack(n_stack, max(frame_bytes, 1))
        # [N, *stacked_shape] per key, in stacked_obs.sub_stacked_observations
        self.stacked_obs = StackedObservations(venv.num_envs, self.n_stack, space, channels_order)
        super().__init__(venv, observation_space=self.stacked_obs.stacked_observation_space)
        self.RUN_STATE = ("venv", "stacked_obs")

    def _push(self, obs: np.ndarray) -> None:
        axis = self.axis if self.axis < 0 else 1  # batch axis comes first
        self.stacked = np.roll(self.stacked, shift=-self.channels, axis=axis)
        if axis == 1:
            self.stacked[:, -self.channels :] = obs
        else:
            self.stacked[..., -self.channels :] = obs

    def step_wait(self) -> StepReturn:
        """Step and push the new observations onto each env's stack."""
        obs, rewards, dones, infos = self.venv.step_wait()
        if isinstance(self.observation_space, Dict):
            # the stacks complete terminal observations in place: give them copies, so the
            # inner env's infos stay as it returned them
            infos = [
                {**info, "terminal_observation": dict(info["terminal_observation"])}
                if "terminal_observation" in info
                else info
                for info in infos
            ]
            stacked, infos = self.stacked_obs.update(obs, dones, infos)
            return _copies(stacked), rewards, dones, infos
        for i in np.flatnonzero(dones).tolist():
            if "terminal_observation" in infos[i]:
                last = np.roll(self.stacked[i], -self.channels, axis=self.axis)
                if self.axis == 0:
                    last[-self.channels :] = infos[i]["terminal_observation"]
                else:
                    last[..., -self.channels :] = infos[i]["terminal_observation"]
                infos[i] = {**infos[i], "terminal_observation": last}
            self.stacked[i] = 0
        self._push(obs)
        return self.stacked.copy(), rewards, dones, infos

    def reset(self) -> Any:
        """Reset; each stack is zeros then the first observation."""
        obs = self.venv.reset()
        if isinstance(self.observation_space, Dict):
            return _copies(self.stacked_obs.reset(obs))
        self.stacked[...] = 0
        self._push(obs)
        return self.stacked.copy()


def _copies(stacked: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Copies of the stacks: the next reset zeroes them in place (SB3 hands out the stacks
    themselves, so an observation kept from before a reset changes under the caller)."""
    return {key: array.copy() for key, array in stacked.items()}


class VecTransposeImage(VecEnvWrapper):
    """``(H, W, C)`` image observations to ``(C, H, W)`` (what PyTorch convolutions want)."""

    def __init__(self, venv: VecEnv, skip: bool = False) -> None:
        space = venv.observation_space
        if not _is_image(space) and not skip:
            raise ValueError(f"VecTransposeImage needs (H, W, C) uint8 images, got {space}")
        self.skip = skip
        if skip:
            super().__init__(venv)
            return
        assert isinstance(space, Box)
        new = Box(
            low=np.transpose(space.low, (2, 0, 1)),
            high=np.transpose(space.high, (2, 0, 1)),
            dtype=space.dtype,
        )
        super().__init__(venv, observation_space=new)

    @staticmethod
    def transpose_image(image: np.ndarray) -> np.ndarray:
        """``[..., H, W, C]`` to ``[..., C, H, W]``."""
        if image.ndim == 3:
            return np.transpose(image, (2, 0, 1))
        return np.transpose(image, (0, 3, 1, 2))

    def step_wait(self) -> StepReturn:
        """Step and transpose (terminal observations too)."""
        obs, rewards, dones, infos = self.venv.step_wait()
        if self.skip:
            return obs, rewards, dones, infos
        for i in np.flatnonzero(dones).tolist():
            if "terminal_observation" in infos[i]:
                term = self.transpose_image(infos[i]["terminal_observation"])
                infos[i] = {**infos[i], "terminal_observation": term}
        return self.transpose_image(obs), rewards, dones, infos

    def reset(self) -> Any:
        """Reset and transpose."""
        obs = self.venv.reset()
        return obs if self.skip else self.transpose_image(obs)
