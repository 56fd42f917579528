"""Stable-Baselines3's Atari wrappers (``stable_baselines3.common.atari_wrappers``), no OpenCV.

The same classes, arguments, order and edge cases as SB3's, so that an SB3 Atari setup runs
unchanged: ``AtariWrapper(env)`` stacks sticky actions, no-op starts, frame skip with a max-pool,
episodic lives, fire on reset, an 84x84 grayscale warp and reward clipping. Where SB3 ``assert``s
a precondition, these raise ``ValueError`` naming what was expected.

``WarpFrame`` gives the bytes of SB3's ``cv2.cvtColor(RGB2GRAY)`` + ``cv2.resize(INTER_AREA)``:
:func:`rgb_to_gray` is OpenCV's fixed-point BT.601 luma and the resize is
:func:`palaestra.wrappers.resize.resize_area`.
"""

from __future__ import annotations

from typing import Any, SupportsFloat

import numpy as np

from palaestra.core import Env, ObservationWrapper, RewardWrapper, Wrapper
from palaestra.spaces import Box
from palaestra.wrappers.common import OrderEnforcing, PassiveEnvChecker, TimeLimit
from palaestra.wrappers.monitor import Monitor
from palaestra.wrappers.resize import resize_area, resize_area_f32
from palaestra.wrappers.stateful_observation import MaxAndSkipObservation

__all__ = [
    "AtariWrapper",
    "ClipRewardEnv",
    "EpisodicLifeEnv",
    "FireResetEnv",
    "MaxAndSkipEnv",
    "NoopResetEnv",
    "StickyActionEnv",
    "WarpFrame",
    "rgb_to_gray",
]

Step = tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]
Reset = tuple[np.ndarray, dict[str, Any]]

# OpenCV's RGB2GRAY weights for uint8: 0.299, 0.587, 0.114 in 15-bit fixed point (they sum to
# 2**15; OpenCV 5 uses these on every colour, where its documentation still gives a 14-bit
# formula that differs on 43,864 of the 2**24 colours), here pre-scaled by 2**-15. As float32
# every product and sum is an exact multiple of 2**-15 below 2**8 (23 bits), so a float
# matrix-vector product (fast in numpy, unlike integer matmul) gives OpenCV's luma exactly.
_GRAY_WEIGHTS = np.array([9798, 19235, 3735], dtype=np.float32) * np.float32(2.0**-15)


def rgb_to_gray(frame: np.ndarray) -> np.ndarray:
    """``cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)`` for an ``(H, W, 3)`` uint8 frame.

    >>> rgb_to_gray(np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]]], np.uint8))
    array([[ 76, 150,  29,   9]], dtype=uint8)
    """
    return _gray_f32(frame).astype(np.uint8)


def _gray_f32(frame: np.ndarray) -> np.ndarray:
    """:func:`rgb_to_gray`'s integers as ``[H, W]`` float32 (what the resize works on)."""
    luma = frame.reshape(-1, 3) @ _GRAY_WEIGHTS  # [H*W] float32, exact
    # OpenCV's CV_DESCALE, (luma + 2**14) >> 15, on the pre-scaled luma: exact in float32.
    luma += 0.5
    np.floor(luma, out=luma)
    return luma.reshape(frame.shape[:2])


def _action_meanings(env: Env[Any, Any], wrapper: str) -> list[str]:
    meanings = getattr(env.unwrapped, "get_action_meanings", None)
    if meanings is None:
        raise ValueError(
            f"{wrapper} requires an Atari environment (with `get_action_meanings`), "
            f"got {env.unwrapped}"
        )
    return list(meanings())


def _require_noop(env: Env[Any, Any], wrapper: str) -> None:
    meanings = _action_meanings(env, wrapper)
    if not meanings or meanings[0] != "NOOP":
        raise ValueError(f"{wrapper} requires action 0 to be 'NOOP', got actions {meanings}")


def _check_int(value: Any, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an int, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    return int(value)


def _lives(env: Env[Any, Any]) -> int:
    return int(env.unwrapped.ale.lives())  # type: ignore[attr-defined]


class StickyActionEnv(Wrapper[np.ndarray, int, np.ndarray, int]):
    """With probability ``action_repeat_probability``, repeat the previous action instead
    (Machado et al., 2018); the first action of an episode defaults to NOOP."""

    def __init__(self, env: Env[Any, Any], action_repeat_probability: float) -> None:
        super().__init__(env)
        p = action_repeat_probability
        if isinstance(p, bool) or not isinstance(p, (int, float, np.number)) or not 0 <= p <= 1:
            raise ValueError(f"action_repeat_probability must be in [0, 1], got {p!r}")
        _require_noop(env, "StickyActionEnv")
        self.action_repeat_probability = float(p)
        self._sticky_action = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Reset:
        """Reset the env; the sticky action becomes NOOP."""
        self._sticky_action = 0
        return self.env.reset(seed=seed, options=options)

    def step(self, action: int) -> Step:
        """Step with ``action``, or with the previous one if the coin says so."""
        if self.np_random.random() >= self.action_repeat_probability:
            self._sticky_action = action
        return self.env.step(self._sticky_action)


class NoopResetEnv(Wrapper[np.ndarray, int, np.ndarray, int]):
    """Start each episode with ``np_random.integers(1, noop_max + 1)`` no-ops (action 0);
    ``override_num_noops`` fixes the count. Returns the last no-op's observation and info."""

    def __init__(self, env: Env[Any, Any], noop_max: int = 30) -> None:
        super().__init__(env)
        self.noop_max = _check_int(noop_max, "noop_max", 1)
        _require_noop(env, "NoopResetEnv")
        self.override_num_noops: int | None = None
        self.noop_action = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Reset:
        """Reset, then take the no-ops; an episode that ends during them is reset again."""
        self.env.reset(seed=seed, options=options)
        if self.override_num_noops is not None:
            noops = self.override_num_noops
        else:
            noops = int(self.unwrapped.np_random.integers(1, self.noop_max + 1))
        if noops <= 0:
            raise ValueError(f"NoopResetEnv needs at least one no-op, got {noops}")
        obs: np.ndarray = np.zeros(0)
        info: dict[str, Any] = {}
        for _ in range(noops):
            obs, _, terminated, truncated, info = self.env.step(self.noop_action)
            if terminated or truncated:
                obs, info = self.env.reset(seed=seed, options=options)
        return obs, info


class FireResetEnv(Wrapper[np.ndarray, int, np.ndarray, int]):
    """Press FIRE (action 1), then action 2, after each reset: games that stand still until
    fired. Like SB3, the info returned by reset is empty."""

    def __init__(self, env: Env[Any, Any]) -> None:
        super().__init__(env)
        meanings = _action_meanings(env, "FireResetEnv")
        if len(meanings) < 3 or meanings[1] != "FIRE":
            raise ValueError(
                f"FireResetEnv requires action 1 to be 'FIRE' and at least 3 actions, "
                f"got actions {meanings}"
            )

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Reset:
        """Reset, then step actions 1 and 2 (resetting again if either ends the episode)."""
        self.env.reset(seed=seed, options=options)
        obs, _, terminated, truncated, _ = self.env.step(1)
        if terminated or truncated:
            self.env.reset(seed=seed, options=options)
        obs, _, terminated, truncated, _ = self.env.step(2)
        if terminated or truncated:
            self.env.reset(seed=seed, options=options)
        return obs, {}


class EpisodicLifeEnv(Wrapper[np.ndarray, int, np.ndarray, int]):
    """A lost life ends the episode (``terminated=True``), but only a game over resets the
    game: the next ``reset()`` after a life loss is one no-op step (DeepMind's DQN setup)."""

    def __init__(self, env: Env[Any, Any]) -> None:
        super().__init__(env)
        if not hasattr(env.unwrapped, "ale"):
            raise ValueError(
                f"EpisodicLifeEnv requires an Atari environment (with `unwrapped.ale`), "
                f"got {env.unwrapped}"
            )
        self.lives = 0
        self.was_real_done = True

    def step(self, action: int) -> Step:
        """Step; a drop in lives (to a count above 0) is reported as a termination."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.was_real_done = terminated or truncated
        lives = _lives(self.env)
        # Lives above 0 only: some games (Qbert) sit at 0 lives for a few frames before the
        # game over, and the episode must end once, there.
        if 0 < lives < self.lives:
            terminated = True
        self.lives = lives  # after the check, so that bonus lives are counted
        return obs, reward, terminated, truncated, info

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Reset:
        """Reset the game after a game over; after a lost life, take one no-op step instead."""
        if self.was_real_done:
            obs, info = self.env.reset(seed=seed, options=options)
        else:
            obs, _, terminated, truncated, info = self.env.step(0)
            if terminated or truncated:  # the no-op can end the game: reset, as SB3 does
                obs, info = self.env.reset(seed=seed, options=options)
        self.lives = _lives(self.env)
        return obs, info


class MaxAndSkipEnv(MaxAndSkipObservation[np.ndarray, int, np.ndarray]):
    """Repeat each action ``skip`` times, sum the rewards, return the max of the last two
    frames (SB3's name for :class:`~palaestra.wrappers.MaxAndSkipObservation`, ``skip >= 2``).

    The frames before the last two are never looked at: when nothing between this wrapper and
    the Atari env looks at observations either, the env skips reading the screen for them (a
    screen read costs about a quarter of an emulated frame), and the last two are kept by
    reference instead of copied (the env's frames are fresh arrays that nobody else holds).
    The results are unchanged.
    """

    def __init__(self, env: Env[Any, Any], skip: int = 4) -> None:
        super().__init__(env, skip=skip)
        base = env.unwrapped
        quiet = _observations_unused_below(env) and hasattr(base, "skip_screen_observations")
        self._screen_source: Any = base if quiet else None
        # The last two frames on the quiet path: like the buffer's slots, one left from an
        # earlier step stays when an episode ends before the second-to-last repeat.
        self._last_two: list[np.ndarray] = [self._obs_buffer[0], self._obs_buffer[1]]

    def step(self, action: int) -> Step:
        """Step ``skip`` times (fewer if the episode ends) with ``action``."""
        base = self._screen_source
        if base is None or base.screen_observations_skipped or self._skip <= 2:
            return super().step(action)
        total_reward = 0.0
        terminated = truncated = False
        info: dict[str, Any] = {}
        base.skip_screen_observations(True)
        try:
            for i in range(self._skip):
                if i == self._skip - 2:
                    base.skip_screen_observations(False)  # the two frames that are max-pooled
                obs, reward, terminated, truncated, info = self.env.step(action)
                if i >= self._skip - 2:
                    self._last_two[i - self._skip + 2] = obs
                total_reward += float(reward)
                if terminated or truncated:
                    break
        finally:
            base.skip_screen_observations(False)
        pooled = np.maximum(self._last_two[0], self._last_two[1])  # half max(axis=0)'s time
        return pooled, total_reward, terminated, truncated, info


def _observations_unused_below(env: Env[Any, Any]) -> bool:
    """Whether every layer between ``env`` and its base env passes steps through without
    looking at observations (``make``'s wrappers, ``Monitor``, the action-side SB3 wrappers)."""
    passive = (OrderEnforcing, PassiveEnvChecker, TimeLimit, Monitor, StickyActionEnv, NoopResetEnv)
    layer: Any = env
    while isinstance(layer, Wrapper):
        if type(layer) not in passive:
            return False
        layer = layer.env
    return True


class ClipRewardEnv(RewardWrapper[np.ndarray, int]):
    """Replace each reward by its sign: -1.0, 0.0 or +1.0."""

    def reward(self, reward: SupportsFloat) -> float:
        """The sign of ``reward``."""
        return float(np.sign(float(reward)))


class WarpFrame(ObservationWrapper[np.ndarray, int, np.ndarray]):
    """RGB frames to ``(height, width, 1)`` grayscale, area-downscaled (the Nature DQN input)."""

    def __init__(self, env: Env[Any, Any], width: int = 84, height: int = 84) -> None:
        super().__init__(env)
        space = env.observation_space
        if not isinstance(space, Box):
            raise TypeError(f"WarpFrame requires a Box observation space, got {space}")
        if len(space.shape) != 3 or space.shape[2] != 3 or space.dtype != np.uint8:
            raise ValueError(
                f"WarpFrame requires (H, W, 3) uint8 RGB frames, got {space.shape} {space.dtype}"
            )
        self.width = _check_int(width, "width", 1)
        self.height = _check_int(height, "height", 1)
        if self.height > space.shape[0] or self.width > space.shape[1]:
            raise ValueError(
                f"WarpFrame only downscales: {self.width}x{self.height} is larger than the "
                f"{space.shape[1]}x{space.shape[0]} frame"
            )
        self.observation_space = Box(0, 255, (self.height, self.width, 1), space.dtype)

    def observation(self, frame: np.ndarray) -> np.ndarray:
        """The warped frame, ``[height, width, 1]`` uint8: SB3's ``cvtColor`` then
        ``resize(INTER_AREA)``, byte for byte."""
        h, w = frame.shape[:2]
        if h % self.height or w % self.width:
            # The general area path works in float32: hand it the grayscale in float32 (the
            # same integers), skipping a uint8 round trip (Atari's 210x160 -> 84x84 case).
            out = resize_area_f32(_gray_f32(frame), self.height, self.width)
            return out.reshape(self.height, self.width, 1)
        return resize_area(rgb_to_gray(frame), (self.height, self.width))[:, :, None]


class AtariWrapper(Wrapper[np.ndarray, int, np.ndarray, int]):
    """SB3's standard Atari preprocessing, innermost first: sticky actions (if
    ``action_repeat_probability > 0``), no-op starts, frame skip with max-pool (if
    ``frame_skip > 1``), episodic lives (if ``terminal_on_life_loss``), fire on reset (games
    with FIRE), an 84x84 grayscale warp and reward clipping (if ``clip_reward``).

    Use it on an env without frame skip or sticky actions of its own, e.g.
    ``make("BreakoutNoFrameskip-v4")`` or ``make("ALE/Breakout-v5", frameskip=1,
    repeat_action_probability=0.0)``.
    """

    def __init__(
        self,
        env: Env[Any, Any],
        noop_max: int = 30,
        frame_skip: int = 4,
        screen_size: int = 84,
        terminal_on_life_loss: bool = True,
        clip_reward: bool = True,
        action_repeat_probability: float = 0.0,
    ) -> None:
        noop_max = _check_int(noop_max, "noop_max", 0)
        frame_skip = _check_int(frame_skip, "frame_skip", 1)
        screen_size = _check_int(screen_size, "screen_size", 1)
        if action_repeat_probability > 0.0:
            env = StickyActionEnv(env, action_repeat_probability)
        if noop_max > 0:
            env = NoopResetEnv(env, noop_max=noop_max)
        if frame_skip > 1:  # 1 means no action repeat
            env = MaxAndSkipEnv(env, skip=frame_skip)
        if terminal_on_life_loss:
            env = EpisodicLifeEnv(env)
        if "FIRE" in _action_meanings(env, "AtariWrapper"):
            env = FireResetEnv(env)
        env = WarpFrame(env, width=screen_size, height=screen_size)
        if clip_reward:
            env = ClipRewardEnv(env)
        super().__init__(env)
