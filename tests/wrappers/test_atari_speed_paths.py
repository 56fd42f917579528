"""The fast paths of SB3's Atari stack change no byte (issue 16, item 14).

``WarpFrame`` computes the grayscale in float32 and resizes it with two small matrix products
(``tests/wrappers/test_resize_products.py`` checks those on their own): equal to OpenCV's
``cvtColor`` + ``resize(INTER_AREA)``. ``MaxAndSkipEnv`` lets the env skip reading the screen
for the frames it never looks at and keeps the last two by reference: the same observations,
rewards and flags as with every screen read and copy.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import palaestra
from palaestra.core import Wrapper
from palaestra.wrappers.atari import AtariWrapper, MaxAndSkipEnv, WarpFrame

pytest.importorskip("ale_py")


def _frames(n=120):
    env = palaestra.make("ALE/Breakout-v5")
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    frames = []
    for _ in range(n):
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(4)))
        frames.append(obs)
        if terminated or truncated:
            env.reset()
    return frames


def test_warp_frame_equals_opencv_on_game_frames():
    cv2 = pytest.importorskip("cv2")
    warp = WarpFrame(palaestra.make("BreakoutNoFrameskip-v4"))
    for frame in _frames():
        gray = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
        expected = cv2.resize(gray, (84, 84), interpolation=cv2.INTER_AREA)[:, :, None]
        assert np.array_equal(warp.observation(frame), expected)


@pytest.mark.parametrize("size", [(84, 84), (64, 48), (105, 80), (70, 40)])
def test_warp_frame_sizes_equal_opencv(size):
    cv2 = pytest.importorskip("cv2")
    height, width = size
    warp = WarpFrame(palaestra.make("BreakoutNoFrameskip-v4"), width=width, height=height)
    frame = _frames(5)[-1]
    expected = cv2.resize(
        cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY), (width, height), interpolation=cv2.INTER_AREA
    )
    assert np.array_equal(warp.observation(frame)[:, :, 0], expected)


class _Looks(Wrapper):
    """A wrapper that looks at observations: screen reads must not be skipped below it."""

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.last_sum = int(obs.sum())
        return obs, reward, terminated, truncated, info


def _rollout(env, steps=300):
    env.reset(seed=0)
    rng = np.random.default_rng(1)
    out = []
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(int(rng.integers(4)))
        out.append((obs.tobytes(), reward, terminated, truncated))
        if terminated or truncated:
            env.reset()
    return out


def _counted(env):
    """``env`` whose base counts its screen reads in ``env.reads``."""
    base = env.unwrapped
    read = base._observe
    reads = []

    def counting():
        reads.append(1)
        return read()

    base._observe = counting
    return env, reads


def test_skipped_screen_reads_change_nothing():
    fast, fast_reads = _counted(palaestra.make("BreakoutNoFrameskip-v4"))
    slow, slow_reads = _counted(palaestra.make("BreakoutNoFrameskip-v4"))
    fast, slow = AtariWrapper(fast), AtariWrapper(_Looks(slow))
    assert _rollout(fast) == _rollout(slow)
    assert 0 < len(fast_reads) < 0.6 * len(slow_reads)  # 2 of every 4 frames (+ resets)
    for env, reads, expected in ((fast, fast_reads, 2), (slow, slow_reads, 4)):
        env.reset(seed=0)
        reads.clear()
        env.step(0)
        assert len(reads) == expected


def test_max_and_skip_restores_screen_reads_after_an_error():
    env = palaestra.make("BreakoutNoFrameskip-v4")
    env.reset(seed=0)
    wrapper = MaxAndSkipEnv(env, skip=4)
    with pytest.raises(palaestra.error.InvalidAction):
        wrapper.step(99)
    assert not env.unwrapped.screen_observations_skipped


def test_quiet_max_and_skip_returns_frames_nobody_else_holds():
    def pooled_frames(scribble):
        env = MaxAndSkipEnv(palaestra.make("BreakoutNoFrameskip-v4"), skip=4)
        assert env._screen_source is not None  # the quiet path: last two kept by reference
        env.reset(seed=0)
        frames = []
        for action in (1, 0, 3, 2, 0):
            obs = env.step(action)[0]
            frames.append(obs.copy())
            if scribble:
                obs[...] = 255  # the caller owns what it got: later steps must not see this
        return frames

    for mine, theirs in zip(pooled_frames(True), pooled_frames(False)):
        np.testing.assert_array_equal(mine, theirs)


def test_quiet_stack_trips_no_env_checker_warning():
    """The skipped frames are fresh arrays: the passive checker (inside ``make``) compares the
    first steps' observations and warns about shared objects."""
    env = AtariWrapper(palaestra.make("BreakoutNoFrameskip-v4"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _rollout(env, steps=20)
