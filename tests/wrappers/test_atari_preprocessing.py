# ruff: noqa: E501  (one bad-input case per line reads best in those tables)
"""``AtariPreprocessing``: Gymnasium's semantics without OpenCV.

Unit tests run on a scripted fake env (tests/wrappers/atari_helpers.py). The parity tests run
Gymnasium's own ``AtariPreprocessing`` on ale-py and ours on palaestra's Atari env, same seeds and
actions. Gymnasium's wrapper imports ``cv2``, which is not installed here, so those tests put a
minimal fake ``cv2`` in ``sys.modules`` whose ``resize`` is palaestra's ``resize_area`` (itself
pinned to OpenCV's ``INTER_AREA`` bytes by test_resize.py): they check the wrapper logic (no-op
starts, skipping, pooling, lives, grayscale source, scaling) byte for byte, not the resize. The
resize is checked against an independent float64 area average below.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
import pytest
from tests.wrappers.atari_helpers import FakeAtari, area_average, fake_cv2, frame_at, gray_at

import palaestra
from palaestra.wrappers import AtariPreprocessing
from palaestra.wrappers.resize import resize_area

SMALL = (8, 7)  # (width, height) for the 21x16 fake screen


def small(frame: np.ndarray) -> np.ndarray:
    return resize_area(frame, (SMALL[1], SMALL[0]))


def wrap(env: FakeAtari | None = None, **kwargs: Any) -> AtariPreprocessing:
    kwargs = {"noop_max": 0, "screen_size": SMALL, **kwargs}
    return AtariPreprocessing(env if env is not None else FakeAtari(), **kwargs)


# --- no-op starts -----------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_noop_reset_takes_a_seeded_random_number_of_noops(seed: int) -> None:
    fake = FakeAtari()
    obs, info = wrap(fake, noop_max=30).reset(seed=seed)
    noops = int(np.random.default_rng(seed).integers(1, 31))
    assert fake.actions == [0] * noops
    assert info == {"lives": 1, "frame": noops}  # reset info updated with the no-ops' infos
    np.testing.assert_array_equal(obs, small(gray_at(noops)))


def test_noop_max_zero_takes_no_steps() -> None:
    fake = FakeAtari()
    obs, info = wrap(fake, noop_max=0).reset(seed=0)
    assert fake.actions == [] and info == {"lives": 1, "frame": 0}
    np.testing.assert_array_equal(obs, small(gray_at(0)))


def test_a_noop_that_ends_the_game_resets_again() -> None:
    noops = int(np.random.default_rng(5).integers(1, 31))
    assert noops >= 3
    fake = FakeAtari(game_over=2)
    _, info = wrap(fake, noop_max=30).reset(seed=5)
    assert fake.resets == 1 + (noops // 2)
    assert info["frame"] == noops % 2


def test_noops_need_noop_as_action_zero() -> None:
    with pytest.raises(ValueError, match=r"first action meaning must be 'NOOP', got \['FIRE'"):
        wrap(FakeAtari(meanings=("FIRE", "NOOP", "LEFT")), noop_max=1)
    wrap(FakeAtari(meanings=("FIRE", "NOOP", "LEFT")), noop_max=0)  # no no-ops: fine


# --- frame skip and max-pool ------------------------------------------------------------------


@pytest.mark.parametrize("frame_skip", [2, 3, 4, 5])
def test_step_pools_the_last_two_of_frame_skip_frames(frame_skip: int) -> None:
    fake = FakeAtari(rewards={1: 0.5, 2: 2.0, 7: 3.0})
    env = wrap(fake, frame_skip=frame_skip)
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(2)
    assert fake.actions == [2] * frame_skip
    pooled = np.maximum(gray_at(frame_skip - 1), gray_at(frame_skip))
    assert not np.array_equal(pooled, gray_at(frame_skip))  # the pool matters here
    np.testing.assert_array_equal(obs, small(pooled))
    assert reward == sum(v for k, v in {1: 0.5, 2: 2.0, 7: 3.0}.items() if k <= frame_skip)
    assert type(reward) is float and (terminated, truncated) == (False, False)
    assert info == {"lives": 1, "frame": frame_skip}  # the last frame's info


def test_frame_skip_one_returns_the_frame_itself() -> None:
    env = wrap(frame_skip=1)
    env.reset(seed=0)
    obs = env.step(1)[0]
    np.testing.assert_array_equal(obs, small(gray_at(1)))


def test_frame_skip_one_accepts_an_env_that_skips_frames() -> None:
    wrap(FakeAtari(frameskip=4), frame_skip=1)  # as Gymnasium: only frame_skip > 1 checks


def test_reset_pools_against_a_blank_frame() -> None:
    env = wrap(frame_skip=4)
    env.reset(seed=0)
    env.step(0)
    obs, _ = env.reset(seed=0)  # the old second-to-last frame must not leak into the pool
    np.testing.assert_array_equal(obs, small(gray_at(0)))


def test_rgb_observations_pool_each_channel() -> None:
    env = wrap(frame_skip=4, grayscale_obs=False)
    env.reset(seed=0)
    obs = env.step(0)[0]
    assert obs.shape == (SMALL[1], SMALL[0], 3) and obs.dtype == np.uint8
    np.testing.assert_array_equal(obs, small(np.maximum(frame_at(3), frame_at(4))))


# --- lives and game over ----------------------------------------------------------------------


def test_life_loss_terminates_when_asked() -> None:
    fake = FakeAtari(life_loss=(2,))
    env = wrap(fake, terminal_on_life_loss=True)
    reset_obs, _ = env.reset(seed=0)
    obs, _, terminated, truncated, info = env.step(3)
    assert terminated and not truncated and env.game_over
    assert fake.actions == [3, 3]  # stops at the frame that lost the life
    assert info["lives"] == 1 and env.lives == 1
    # Gymnasium reads no frame on an ending step: the pool of the buffers as they stood
    np.testing.assert_array_equal(obs, reset_obs)


def test_life_loss_does_not_terminate_by_default() -> None:
    fake = FakeAtari(life_loss=(2,))
    env = wrap(fake)
    env.reset(seed=0)
    _, _, terminated, _, info = env.step(3)
    assert not terminated and len(fake.actions) == 4 and info["lives"] == 1


def test_game_over_ends_the_step_early() -> None:
    fake = FakeAtari(game_over=6, rewards={5: 1.0, 6: 1.0})
    env = wrap(fake)
    env.reset(seed=0)
    env.step(0)
    obs, reward, terminated, _, _ = env.step(0)
    assert terminated and reward == 2.0 and len(fake.actions) == 6
    np.testing.assert_array_equal(obs, small(np.maximum(gray_at(3), gray_at(4))))


# --- spaces, dtypes, scaling ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "shape", "dtype", "high"),
    [
        ({}, (7, 8), np.uint8, 255),
        ({"grayscale_newaxis": True}, (7, 8, 1), np.uint8, 255),
        ({"grayscale_obs": False}, (7, 8, 3), np.uint8, 255),
        ({"grayscale_obs": False, "grayscale_newaxis": True}, (7, 8, 3), np.uint8, 255),
        ({"scale_obs": True}, (7, 8), np.float32, 1),
        ({"screen_size": 5}, (5, 5), np.uint8, 255),
        ({"screen_size": (16, 21)}, (21, 16), np.uint8, 255),
    ],
)
def test_spaces_and_dtypes(kwargs: dict, shape: tuple, dtype: type, high: int) -> None:
    env = wrap(**kwargs)
    space = env.observation_space
    assert space.shape == shape and space.dtype == dtype
    assert np.all(space.low == 0) and np.all(space.high == high)
    obs, _ = env.reset(seed=0)
    assert obs in space and obs.shape == shape and obs.dtype == dtype
    assert env.step(0)[0] in space


def test_scale_obs_is_the_uint8_frame_over_255() -> None:
    raw, scaled = wrap(), wrap(scale_obs=True)
    raw.reset(seed=0), scaled.reset(seed=0)
    a, b = raw.step(1)[0], scaled.step(1)[0]
    assert b.dtype == np.float32 and 0 <= b.min() and b.max() <= 1
    np.testing.assert_array_equal(b, a.astype(np.float32) / np.float32(255))


def test_full_size_screen_is_the_pooled_grayscale_itself() -> None:
    env = wrap(screen_size=(16, 21))
    env.reset(seed=0)
    np.testing.assert_array_equal(env.step(0)[0], np.maximum(gray_at(3), gray_at(4)))


def test_observations_are_fresh_arrays() -> None:
    env = wrap()
    first, _ = env.reset(seed=0)
    kept = first.copy()
    env.step(0)
    np.testing.assert_array_equal(first, kept)


def test_registered_and_spec_records_arguments() -> None:
    assert palaestra.wrappers.AtariPreprocessing is AtariPreprocessing
    env = wrap(frame_skip=3, scale_obs=True)
    assert env._saved_kwargs["frame_skip"] == 3 and env._saved_kwargs["scale_obs"] is True


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "error", "message"),
    [
        (lambda: wrap(FakeAtari(frameskip=4)), ValueError, r"Disable frame-skipping .* frameskip=4, expected 1"),
        (lambda: wrap(frame_skip=0), ValueError, r"`frame_skip` to be positive, actually: 0"),
        (lambda: wrap(frame_skip=2.0), TypeError, r"`frame_skip` to be an int, actually: 2.0"),
        (lambda: wrap(noop_max=-1), ValueError, r"`noop_max` to be non-negative, actually: -1"),
        (lambda: wrap(screen_size=0), ValueError, r"`screen_size` to be positive, actually: 0"),
        (lambda: wrap(screen_size=-84), ValueError, r"`screen_size` to be positive, actually: -84"),
        (lambda: wrap(screen_size=(84, 0)), ValueError, r"actually: \(84, 0\)"),
        (lambda: wrap(screen_size=(8, 7, 1)), ValueError, r"actually: \(8, 7, 1\)"),
        (lambda: wrap(screen_size=[8, 7]), ValueError, r"actually: \[8, 7\]"),
        (lambda: wrap(screen_size=84), ValueError, r"only downscales: screen_size \(width, height\) = \(84, 84\) is larger than the 16x21 screen"),
        (lambda: wrap(FakeAtari(obs_type="ram")), ValueError, r"shape \(H, W\) or \(H, W, 3\), got \(128,\)"),
        (lambda: AtariPreprocessing(palaestra.make("CartPole-v1")), ValueError, r"requires an Atari environment .* got <CartPoleEnv"),
    ],
)  # fmt: skip
def test_bad_input(make: Any, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        make()


# --- the real emulator ------------------------------------------------------------------------


def test_grayscale_is_the_emulators_own() -> None:
    """Unresized, unskipped grayscale equals the env's ``obs_type="grayscale"`` screen."""
    pytest.importorskip("ale_py")
    kw = {"frameskip": 1, "repeat_action_probability": 0.0}
    ours = AtariPreprocessing(
        palaestra.make("ALE/Breakout-v5", **kw), noop_max=0, frame_skip=1, screen_size=(160, 210)
    )
    gray = palaestra.make("ALE/Breakout-v5", obs_type="grayscale", **kw)
    a, _ = ours.reset(seed=3)
    b, _ = gray.reset(seed=3)
    np.testing.assert_array_equal(a, b)
    for action in np.random.default_rng(0).integers(0, 4, 60):
        a, b = ours.step(int(action))[0], gray.step(int(action))[0]
        np.testing.assert_array_equal(a, b)


def test_resize_against_an_independent_area_average() -> None:
    """On real Breakout frames, 210x160 -> 84x84: a rounding (within 0.5) of the exact float64
    area average, and equal to its nearest integer except at float32 ties (measured over 200
    frames: off by 1 on 0.001% of pixels)."""
    pytest.importorskip("ale_py")
    env = palaestra.make("ALE/Breakout-v5", frameskip=1, repeat_action_probability=0.0)
    frames = [env.reset(seed=0)[0]]
    for action in np.random.default_rng(1).integers(0, 4, 120):
        frames.append(env.step(int(action))[0])
    ale = env.unwrapped.ale
    frames.append(ale.getScreenGrayscale())
    diffs = []
    for frame in frames[::10]:
        exact = area_average(frame, (84, 84))
        ours = resize_area(frame, (84, 84)).astype(np.float64)
        assert np.abs(ours - exact).max() <= 0.5 + 1e-6  # a correct rounding of the exact mean
        diffs.append(np.abs(ours - np.rint(exact)))
    d = np.concatenate([x.ravel() for x in diffs])
    assert d.max() <= 1 and d.mean() < 0.01


# --- parity with Gymnasium's AtariPreprocessing (fake cv2, see the module docstring) ----------

GYM_CASES = {
    "defaults": {},
    "life-loss": {"terminal_on_life_loss": True},
    "rgb": {"grayscale_obs": False},
    "newaxis-scaled": {"grayscale_newaxis": True, "scale_obs": True},
    "skip-3-noop-5-rect": {"frame_skip": 3, "noop_max": 5, "screen_size": (64, 100)},
    "skip-1": {"frame_skip": 1, "noop_max": 0},
}


def _rollout(env: Any, actions: np.ndarray, seed: int) -> list[tuple]:
    out: list[tuple] = [("reset", *env.reset(seed=seed))]
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(int(action))
        out.append(("step", obs, reward, terminated, truncated, info))
        if terminated or truncated:
            out.append(("reset", *env.reset()))
    return out


def _check_gymnasium_parity(
    monkeypatch: pytest.MonkeyPatch, kwargs: dict, steps: int, env_id: str = "ALE/Breakout-v5"
) -> None:
    pytest.importorskip("ale_py")
    gymnasium = pytest.importorskip("gymnasium")
    import ale_py

    monkeypatch.setitem(sys.modules, "cv2", fake_cv2())
    gymnasium.register_envs(ale_py)
    from gymnasium.wrappers import AtariPreprocessing as GymAtariPreprocessing

    skip = {"frameskip": 1} if kwargs.get("frame_skip", 4) > 1 else {}
    ref = GymAtariPreprocessing(gymnasium.make(env_id, **skip), **kwargs)
    ours = AtariPreprocessing(palaestra.make(env_id, **skip), **kwargs)
    assert ours.observation_space.shape == ref.observation_space.shape
    assert ours.observation_space.dtype == ref.observation_space.dtype
    n = int(ours.action_space.n)
    actions = np.random.default_rng(2).integers(0, n, steps)
    a, b = _rollout(ours, actions, seed=11), _rollout(ref, actions, seed=11)
    assert len(a) == len(b)
    assert sum(t[0] == "reset" for t in a) >= 2  # an episode ended and restarted
    for t, (x, y) in enumerate(zip(a, b)):
        assert x[0] == y[0], t
        assert x[1].dtype == y[1].dtype and x[1].shape == y[1].shape, t
        np.testing.assert_array_equal(x[1], y[1], err_msg=f"transition {t}")
        assert x[2:] == y[2:], (t, x[2:], y[2:])


@pytest.mark.parametrize("case", list(GYM_CASES))
def test_parity_with_gymnasium(monkeypatch: pytest.MonkeyPatch, case: str) -> None:
    steps = 150 if case == "life-loss" else 400
    _check_gymnasium_parity(monkeypatch, GYM_CASES[case], steps)


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ["ALE/Pong-v5", "ALE/SpaceInvaders-v5", "ALE/Qbert-v5"])
def test_parity_with_gymnasium_long(monkeypatch: pytest.MonkeyPatch, env_id: str) -> None:
    _check_gymnasium_parity(monkeypatch, {"terminal_on_life_loss": True}, 3000, env_id)


def test_env_skips_screen_reads_only_when_nothing_below_uses_them() -> None:
    """AtariPreprocessing reads frames from the emulator; the env's own screen copy is skipped
    unless a wrapper below the preprocessing could look at observations."""
    pytest.importorskip("ale_py")
    from palaestra.wrappers import TransformObservation

    env = palaestra.make("ALE/Pong-v5", frameskip=1)
    wrapped = AtariPreprocessing(env)
    obs, _ = env.reset(seed=0)
    assert not obs.any()
    assert wrapped.reset(seed=0)[0].any()  # the preprocessed frame is real

    user = TransformObservation(palaestra.make("ALE/Pong-v5", frameskip=1), lambda o: o, None)
    AtariPreprocessing(user)
    assert user.reset(seed=0)[0].any()
