"""``AtariPreprocessing``: Gymnasium's Atari preprocessing (Machado et al., 2018), no OpenCV.

The same steps, order and edge cases as ``gymnasium.wrappers.AtariPreprocessing``: no-op
starts, frame skipping with a max over the last two frames, optional termination on life loss,
grayscale read straight from the emulator (ALE's own palette luminance, as Gymnasium does), area
resize and optional scaling. The resize is :func:`palaestra.wrappers.resize.resize_area`, which
gives OpenCV ``INTER_AREA``'s bytes, so the observations equal Gymnasium's.
"""

from __future__ import annotations

from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import Env, Wrapper
from palaestra.spaces import Box
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.wrappers.common import OrderEnforcing, PassiveEnvChecker, TimeLimit
from palaestra.wrappers.resize import resize_area

__all__ = ["AtariPreprocessing"]


def _is_int(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, np.integer))


def _check_screen_size(screen_size: Any) -> tuple[int, int]:
    """``(width, height)`` from an int or a ``(width, height)`` tuple (cv2's ``dsize`` order)."""
    if _is_int(screen_size) and screen_size > 0:
        return int(screen_size), int(screen_size)
    if (
        isinstance(screen_size, tuple)
        and len(screen_size) == 2
        and all(_is_int(s) and s > 0 for s in screen_size)
    ):
        return int(screen_size[0]), int(screen_size[1])
    raise ValueError(
        f"Expect the `screen_size` to be positive, actually: {screen_size!r} (expected an int "
        "> 0 or a (width, height) tuple of ints > 0)"
    )


def _check_count(value: Any, name: str, minimum: int, what: str) -> int:
    if not _is_int(value):
        raise TypeError(f"Expect the `{name}` to be an int, actually: {value!r}")
    if value < minimum:
        raise ValueError(f"Expect the `{name}` to be {what}, actually: {value}")
    return int(value)


class AtariPreprocessing(Wrapper[np.ndarray, int, np.ndarray, int], RecordConstructorArgs):
    """Atari 2600 preprocessing (Gymnasium's signature and semantics), without OpenCV.

    - ``noop_max``: reset takes ``np_random.integers(1, noop_max + 1)`` no-ops (0: none).
    - ``frame_skip``: each step repeats the action this many times; the observation is the
      max of the last two frames. The base env must have ``frameskip=1``.
    - ``screen_size``: an int, or a ``(width, height)`` tuple as in ``cv2.resize``; area
      downscaling only (no upscaling).
    - ``terminal_on_life_loss``: ``terminated=True`` when a life is lost.
    - ``grayscale_obs`` / ``grayscale_newaxis``: ALE's grayscale screen, ``(h, w)`` or
      ``(h, w, 1)``; otherwise RGB ``(h, w, 3)``.
    - ``scale_obs``: ``float32`` in ``[0, 1]`` instead of ``uint8``.

    >>> import palaestra as gym
    >>> env = AtariPreprocessing(gym.make("ALE/Pong-v5", frameskip=1))  # doctest: +SKIP
    >>> env.observation_space  # doctest: +SKIP
    Box(0, 255, (84, 84), uint8)
    """

    def __init__(
        self,
        env: Env[Any, Any],
        noop_max: int = 30,
        frame_skip: int = 4,
        screen_size: int | tuple[int, int] = 84,
        terminal_on_life_loss: bool = False,
        grayscale_obs: bool = True,
        grayscale_newaxis: bool = False,
        scale_obs: bool = False,
    ) -> None:
        RecordConstructorArgs.__init__(
            self,
            noop_max=noop_max,
            frame_skip=frame_skip,
            screen_size=screen_size,
            terminal_on_life_loss=terminal_on_life_loss,
            grayscale_obs=grayscale_obs,
            grayscale_newaxis=grayscale_newaxis,
            scale_obs=scale_obs,
        )
        Wrapper.__init__(self, env)
        self.frame_skip = _check_count(frame_skip, "frame_skip", 1, "positive")
        self.screen_size = _check_screen_size(screen_size)
        self.noop_max = _check_count(noop_max, "noop_max", 0, "non-negative")
        base = env.unwrapped
        if not hasattr(base, "ale"):
            raise ValueError(
                f"AtariPreprocessing requires an Atari environment (one with `unwrapped.ale`, "
                f"e.g. make('ALE/Pong-v5', frameskip=1)), got {base}"
            )
        base_skip = getattr(base, "_frameskip", None)
        if self.frame_skip > 1 and base_skip != 1:
            raise ValueError(
                "Disable frame-skipping in the original env. Otherwise, more than one frame-skip "
                f"will happen as through this wrapper: the env has frameskip={base_skip!r}, "
                "expected 1 (e.g. make('ALE/Pong-v5', frameskip=1))"
            )
        if self.noop_max > 0 and base.get_action_meanings()[0] != "NOOP":  # type: ignore[attr-defined]
            raise ValueError(
                "When noop_max > 0, the first action meaning must be 'NOOP', got "
                f"{base.get_action_meanings()}"  # type: ignore[attr-defined]
            )
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(
                f"AtariPreprocessing wrapper requires a Box observation space, got {type(space)}"
            )
        if len(space.shape) not in (2, 3) or space.shape[2:] not in ((), (3,)):
            raise ValueError(
                "AtariPreprocessing requires screen observations of shape (H, W) or (H, W, 3), "
                f"got {space.shape} (make the env with obs_type='rgb' or 'grayscale', not 'ram')"
            )
        height, width = space.shape[:2]
        if self.screen_size[0] > width or self.screen_size[1] > height:
            raise ValueError(
                f"AtariPreprocessing only downscales: screen_size (width, height) = "
                f"{self.screen_size} is larger than the {width}x{height} screen"
            )
        # Every frame this wrapper uses is read from the emulator, so when nothing between it
        # and the Atari env looks at observations, the env can skip reading screens for it.
        if _observations_unused_below(env) and hasattr(base, "skip_screen_observations"):
            base.skip_screen_observations()
        self.terminal_on_life_loss = terminal_on_life_loss
        self.grayscale_obs = grayscale_obs
        self.grayscale_newaxis = grayscale_newaxis
        self.scale_obs = scale_obs

        # The two most recent frames, for the max-pool; ALE writes into them in place.
        frame_shape = (height, width) if grayscale_obs else (height, width, 3)
        self.obs_buffer = [np.empty(frame_shape, np.uint8), np.empty(frame_shape, np.uint8)]
        self.lives = 0
        self.game_over = False

        out_shape: tuple[int, ...] = (self.screen_size[1], self.screen_size[0])
        if not grayscale_obs:
            out_shape += (3,)
        elif grayscale_newaxis:
            out_shape += (1,)
        if scale_obs:
            self.observation_space = Box(0, 1, out_shape, np.float32)
        else:
            self.observation_space = Box(0, 255, out_shape, np.uint8)

    @property
    def ale(self) -> Any:
        """The base env's emulator (``ale_py.ALEInterface``)."""
        return self.env.unwrapped.ale  # type: ignore[attr-defined]

    def _grab(self, slot: int) -> None:
        if self.grayscale_obs:
            self.ale.getScreenGrayscale(self.obs_buffer[slot])
        else:
            self.ale.getScreenRGB(self.obs_buffer[slot])

    def step(self, action: int) -> tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]:
        """Repeat ``action`` ``frame_skip`` times (fewer if the episode ends); sum the rewards."""
        total_reward, terminated, truncated = 0.0, False, False
        info: dict[str, Any] = {}
        for t in range(self.frame_skip):
            _, reward, terminated, truncated, info = self.env.step(action)
            total_reward += reward  # type: ignore[operator]
            self.game_over = terminated
            if self.terminal_on_life_loss:
                lives = self.ale.lives()
                terminated = terminated or lives < self.lives
                self.game_over = terminated
                self.lives = lives
            if terminated or truncated:
                # Like Gymnasium: the frames of an ending step are not read, the observation
                # is the pool of the buffers as they stand.
                break
            if t == self.frame_skip - 2:
                self._grab(1)
            elif t == self.frame_skip - 1:
                self._grab(0)
        return self._get_obs(), total_reward, terminated, truncated, info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset, then take a random number of no-ops (Gymnasium's no-op starts)."""
        _, reset_info = self.env.reset(seed=seed, options=options)
        noops = self.env.unwrapped.np_random.integers(1, self.noop_max + 1) if self.noop_max else 0
        for _ in range(noops):
            _, _, terminated, truncated, step_info = self.env.step(0)
            reset_info.update(step_info)
            if terminated or truncated:
                _, reset_info = self.env.reset(seed=seed, options=options)
        self.lives = self.ale.lives()
        self._grab(0)
        self.obs_buffer[1].fill(0)
        return self._get_obs(), reset_info

    def _get_obs(self) -> np.ndarray:
        frame = self.obs_buffer[0]
        if self.frame_skip > 1:
            # In place, as Gymnasium: a step that ends early pools this result again.
            np.maximum(frame, self.obs_buffer[1], out=frame)
        obs = resize_area(frame, (self.screen_size[1], self.screen_size[0]))  # a fresh array
        if self.grayscale_obs and self.grayscale_newaxis:
            obs = obs[..., None]
        if self.scale_obs:
            return obs.astype(np.float32) / np.float32(255.0)
        return obs


def _observations_unused_below(env: Env[Any, Any]) -> bool:
    """Whether every layer between ``env`` and its base env ignores observations."""
    layer: Any = env
    while isinstance(layer, Wrapper):
        if type(layer) not in (OrderEnforcing, PassiveEnvChecker, TimeLimit):
            return False
        layer = layer.env
    return True
