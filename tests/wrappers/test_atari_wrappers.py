# ruff: noqa: E501  (one bad-input case per line reads best in those tables)
"""SB3's Atari wrappers (``palaestra.wrappers.atari``): semantics, errors and parity.

Unit tests use the scripted fake env of tests/wrappers/atari_helpers.py. Parity tests run SB3's
wrappers on ale-py (through Gymnasium) and ours on palaestra's Atari env with the same seeds and
actions. SB3's ``WarpFrame`` needs OpenCV, which is not installed here, so parity is checked two
ways: the whole pipeline without ``WarpFrame`` on both sides (no stand-in at all, every RGB byte
compared), and the whole ``AtariWrapper`` with a fake ``cv2`` in SB3's module whose ``cvtColor``
is OpenCV's fixed-point formula and whose ``resize`` is palaestra's ``resize_area`` (pinned to
OpenCV's bytes by test_resize.py). ``WarpFrame`` itself is compared with an independent float64
reference.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.wrappers.atari_helpers import (
    FakeAtari,
    area_average,
    fake_cv2,
    frame_at,
    opencv_gray,
)

import palaestra
from palaestra.wrappers.atari import (
    AtariWrapper,
    ClipRewardEnv,
    EpisodicLifeEnv,
    FireResetEnv,
    MaxAndSkipEnv,
    NoopResetEnv,
    StickyActionEnv,
    WarpFrame,
    rgb_to_gray,
)
from palaestra.wrappers.resize import resize_area


def chain_names(env: Any) -> list[str]:
    names = []
    while hasattr(env, "env"):
        names.append(type(env).__name__)
        env = env.env
    return names


# --- NoopResetEnv -----------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_noop_reset_counts(seed: int) -> None:
    fake = FakeAtari()
    obs, info = NoopResetEnv(fake, noop_max=30).reset(seed=seed)
    noops = int(np.random.default_rng(seed).integers(1, 31))
    assert fake.actions == [0] * noops
    np.testing.assert_array_equal(obs, frame_at(noops))  # the last no-op's observation
    assert info == {"lives": 1, "frame": noops}  # ... and its info


def test_noop_reset_override_and_game_over() -> None:
    fake = FakeAtari(game_over=3)
    env = NoopResetEnv(fake, noop_max=30)
    env.override_num_noops = 7
    _, info = env.reset(seed=0)
    # frames 1, 2, 3 (game over: reset), 1, 2, 3 (reset), 1: the reset's obs is replaced
    assert fake.actions == [0] * 7 and fake.resets == 3 and info["frame"] == 1


# --- FireResetEnv -----------------------------------------------------------------------------


def test_fire_reset_presses_fire_then_action_two() -> None:
    fake = FakeAtari()
    obs, info = FireResetEnv(fake).reset(seed=0)
    assert fake.actions == [1, 2] and info == {}
    np.testing.assert_array_equal(obs, frame_at(2))


def test_fire_reset_resets_when_fire_ends_the_game() -> None:
    fake = FakeAtari(game_over=1)
    obs, _ = FireResetEnv(fake).reset(seed=0)
    assert fake.actions == [1, 2] and fake.resets == 3  # both presses ended the game
    np.testing.assert_array_equal(obs, frame_at(1))  # SB3 returns the second press's frame


# --- EpisodicLifeEnv --------------------------------------------------------------------------


def test_episodic_life_ends_episodes_on_life_loss_but_resets_only_on_game_over() -> None:
    fake = FakeAtari(life_loss=(2, 4), game_over=6)
    env = EpisodicLifeEnv(fake)
    env.reset(seed=0)
    assert env.lives == 3 and fake.resets == 1
    assert env.step(0)[2] is False
    _, _, terminated, _, info = env.step(0)  # frame 2: a life lost
    assert terminated and not env.was_real_done and info["lives"] == 2
    obs, info = env.reset()  # not a real reset: one no-op step
    assert fake.resets == 1 and fake.actions == [0, 0, 0] and info["frame"] == 3
    np.testing.assert_array_equal(obs, frame_at(3))
    assert env.step(1)[2] is True  # frame 4: the second life
    env.reset()
    _, _, terminated, _, _ = env.step(1)  # frame 6: game over
    assert terminated and env.was_real_done
    obs, info = env.reset()
    assert fake.resets == 2 and info == {"lives": 3, "frame": 0} and env.lives == 3


def test_episodic_life_reset_noop_that_ends_the_game_resets() -> None:
    fake = FakeAtari(life_loss=(1,), game_over=2)
    env = EpisodicLifeEnv(fake)
    env.reset(seed=0)
    assert env.step(0)[2] is True
    _, info = env.reset()  # the no-op is frame 2, the game over: a real reset follows
    assert fake.resets == 2 and info["frame"] == 0


def test_episodic_life_does_not_end_on_the_last_life() -> None:
    fake = FakeAtari(life_loss=(2,))
    env = EpisodicLifeEnv(fake)
    env.reset(seed=0)
    fake.lives = env.lives = 1  # the loss at frame 2 takes lives to 0 (Qbert's case)
    env.step(0)
    assert env.step(0)[2] is False and env.lives == 0


# --- MaxAndSkipEnv, ClipRewardEnv, StickyActionEnv ---------------------------------------------


def test_max_and_skip_pools_and_sums() -> None:
    fake = FakeAtari(rewards={1: 1.0, 3: 2.5, 5: 4.0})
    env = MaxAndSkipEnv(fake, skip=4)
    env.reset(seed=0)
    obs, reward, terminated, _, info = env.step(3)
    assert fake.actions == [3] * 4 and reward == 3.5 and not terminated and info["frame"] == 4
    np.testing.assert_array_equal(obs, np.maximum(frame_at(3), frame_at(4)))


def test_clip_reward_is_the_sign() -> None:
    fake = FakeAtari(rewards={1: -3.5, 2: 0.0, 3: 2.0, 4: 0.1})
    env = ClipRewardEnv(fake)
    env.reset(seed=0)
    rewards = [env.step(0)[1] for _ in range(4)]
    assert rewards == [-1.0, 0.0, 1.0, 1.0] and all(type(r) is float for r in rewards)


@pytest.mark.parametrize("p", [0.0, 0.25, 0.5, 1.0])
def test_sticky_actions_follow_the_env_rng(p: float) -> None:
    fake = FakeAtari()
    env = StickyActionEnv(fake, action_repeat_probability=p)
    env.reset(seed=4)
    asked = [1, 2, 3, 2, 1, 3, 3, 2, 1, 2]
    for a in asked:
        env.step(a)
    coins = np.random.default_rng(4).random(len(asked))
    expected, sticky = [], 0
    for a, coin in zip(asked, coins):
        sticky = a if coin >= p else sticky
        expected.append(sticky)
    assert fake.actions == expected
    if p == 1.0:
        assert fake.actions == [0] * len(asked)  # NOOP after reset, repeated forever


# --- WarpFrame and rgb_to_gray ----------------------------------------------------------------


def test_rgb_to_gray_is_opencvs_formula_on_every_color() -> None:
    channel = np.arange(256, dtype=np.uint8)
    gb = np.stack(np.meshgrid(channel, channel, indexing="ij"), -1).reshape(256, 256, 2)
    for r in range(256):  # all 2**24 colors, one red value at a time
        frame = np.concatenate([np.full((256, 256, 1), r, np.uint8), gb], axis=-1)
        np.testing.assert_array_equal(rgb_to_gray(frame), opencv_gray(frame), err_msg=f"r={r}")


def test_opencv_gray_reference_is_the_installed_opencv() -> None:
    """The integer formula the tests compare with is what OpenCV computes, on all 2**24 colours
    (its documentation's 14-bit formula differs on 43,864 of them)."""
    cv2 = pytest.importorskip("cv2")
    code = np.arange(1 << 24, dtype=np.uint32)
    colors = np.stack([code >> 16, (code >> 8) & 255, code & 255], -1).astype(np.uint8)
    frame = colors.reshape(4096, 4096, 3)
    np.testing.assert_array_equal(opencv_gray(frame), cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY))


def test_warp_frame_is_gray_then_area_resize() -> None:
    env = WarpFrame(FakeAtari(), width=8, height=7)
    assert env.observation_space.shape == (7, 8, 1) and env.observation_space.dtype == np.uint8
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(obs[:, :, 0], resize_area(opencv_gray(frame_at(0)), (7, 8)))
    assert obs in env.observation_space


def test_warp_frame_against_an_independent_reference() -> None:
    """Real Breakout frames: our WarpFrame vs float64 BT.601 luma then exact area average,
    rounded (measured over 200 frames: off by 1 on 0.1% of pixels, where gray rounding differs)."""
    pytest.importorskip("ale_py")
    env = WarpFrame(palaestra.make("BreakoutNoFrameskip-v4"))
    ale = env.unwrapped.ale
    pairs = [(env.reset(seed=0)[0], ale.getScreenRGB())]
    for action in np.random.default_rng(0).integers(0, 4, 200):
        pairs.append((env.step(int(action))[0], ale.getScreenRGB()))
    diffs = []
    for obs, rgb in pairs[::20]:
        luma = rgb.astype(np.float64) @ np.array([0.299, 0.587, 0.114])
        diffs.append(np.abs(obs[:, :, 0] - np.rint(area_average(luma, (84, 84)))))
    diff = np.concatenate(diffs)
    assert diff.max() <= 1 and diff.mean() < 0.01


# --- AtariWrapper -----------------------------------------------------------------------------


def test_atari_wrapper_chain_matches_sb3_order() -> None:
    env = AtariWrapper(FakeAtari(), screen_size=7, action_repeat_probability=0.25)
    assert chain_names(env) == [
        "AtariWrapper",
        "ClipRewardEnv",
        "WarpFrame",
        "FireResetEnv",
        "EpisodicLifeEnv",
        "MaxAndSkipEnv",
        "NoopResetEnv",
        "StickyActionEnv",
    ]
    assert env.observation_space.shape == (7, 7, 1)
    obs, info = env.reset(seed=0)
    assert obs.shape == (7, 7, 1) and obs.dtype == np.uint8 and info == {}


def test_atari_wrapper_optional_parts() -> None:
    fake = FakeAtari(meanings=("NOOP", "UP", "DOWN"))
    env = AtariWrapper(
        fake,
        noop_max=0,
        frame_skip=1,
        screen_size=5,
        terminal_on_life_loss=False,
        clip_reward=False,
    )
    assert chain_names(env) == ["AtariWrapper", "WarpFrame"]
    assert palaestra.wrappers.AtariWrapper is AtariWrapper


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "error", "message"),
    [
        (lambda: NoopResetEnv(FakeAtari(), noop_max=0), ValueError, r"noop_max must be >= 1, got 0"),
        (lambda: NoopResetEnv(FakeAtari(meanings=("FIRE", "NOOP", "UP"))), ValueError, r"action 0 to be 'NOOP', got actions \['FIRE'"),
        (lambda: NoopResetEnv(palaestra.make("CartPole-v1")), ValueError, r"requires an Atari environment .* got <CartPoleEnv"),
        (lambda: FireResetEnv(FakeAtari(meanings=("NOOP", "UP", "FIRE"))), ValueError, r"action 1 to be 'FIRE' and at least 3 actions, got actions \['NOOP', 'UP', 'FIRE'\]"),
        (lambda: FireResetEnv(FakeAtari(meanings=("NOOP", "FIRE"))), ValueError, r"at least 3 actions"),
        (lambda: EpisodicLifeEnv(palaestra.make("CartPole-v1")), ValueError, r"requires an Atari environment"),
        (lambda: StickyActionEnv(FakeAtari(), 1.5), ValueError, r"action_repeat_probability must be in \[0, 1\], got 1.5"),
        (lambda: MaxAndSkipEnv(FakeAtari(), skip=1), ValueError, r"skip needs to be at least 2, actual value: 1"),
        (lambda: WarpFrame(FakeAtari(obs_type="grayscale")), ValueError, r"\(H, W, 3\) uint8 RGB frames, got \(21, 16\)"),
        (lambda: WarpFrame(FakeAtari()), ValueError, r"only downscales: 84x84 is larger than the 16x21 frame"),
        (lambda: AtariWrapper(FakeAtari(), noop_max=-1), ValueError, r"noop_max must be >= 0, got -1"),
        (lambda: AtariWrapper(FakeAtari(), frame_skip=0), ValueError, r"frame_skip must be >= 1, got 0"),
        (lambda: AtariWrapper(FakeAtari(), screen_size=0), ValueError, r"screen_size must be >= 1, got 0"),
        (lambda: AtariWrapper(FakeAtari(), screen_size=8.0), TypeError, r"screen_size must be an int, got 8.0"),
    ],
)  # fmt: skip
def test_bad_input(make: Any, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        make()


# --- parity with SB3 on the real emulator -----------------------------------------------------


def _sb3_atari() -> Any:
    pytest.importorskip("ale_py")
    gymnasium = pytest.importorskip("gymnasium")
    sb3_atari = pytest.importorskip("stable_baselines3.common.atari_wrappers")
    import ale_py

    gymnasium.register_envs(ale_py)
    return gymnasium, sb3_atari


def _unwarped(env: Any, lib: Any, sticky: float) -> Any:
    """SB3's AtariWrapper stack minus WarpFrame, built from ``lib``'s classes."""
    if sticky:
        env = lib.StickyActionEnv(env, sticky)
    env = lib.EpisodicLifeEnv(lib.MaxAndSkipEnv(lib.NoopResetEnv(env, noop_max=30), skip=4))
    return lib.ClipRewardEnv(lib.FireResetEnv(env))


def _rollout(env: Any, actions: np.ndarray, seed: int) -> list[tuple]:
    out: list[tuple] = [("reset", *env.reset(seed=seed))]
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(int(action))
        out.append(("step", obs, reward, terminated, truncated, info))
        if terminated or truncated:
            out.append(("reset", *env.reset()))
    return out


def _assert_same(a: list[tuple], b: list[tuple]) -> None:
    assert len(a) == len(b)
    assert sum(t[0] == "reset" for t in a) >= 3  # lives lost and games restarted
    for t, (x, y) in enumerate(zip(a, b)):
        assert x[0] == y[0], t
        assert x[1].shape == y[1].shape and x[1].dtype == y[1].dtype, t
        np.testing.assert_array_equal(x[1], y[1], err_msg=f"transition {t}")
        assert x[2:] == y[2:], (t, x[2:], y[2:])


@pytest.mark.parametrize("sticky", [0.0, 0.25])
def test_unwarped_pipeline_equals_sb3(sticky: float) -> None:
    gymnasium, sb3_atari = _sb3_atari()
    import palaestra.wrappers.atari as ours

    env_id = "BreakoutNoFrameskip-v4"
    actions = np.random.default_rng(7).integers(0, 4, 300)
    a = _rollout(_unwarped(palaestra.make(env_id), ours, sticky), actions, seed=5)
    b = _rollout(_unwarped(gymnasium.make(env_id), sb3_atari, sticky), actions, seed=5)
    _assert_same(a, b)


def _check_atari_wrapper(monkeypatch: pytest.MonkeyPatch, env_id: str, steps: int) -> None:
    gymnasium, sb3_atari = _sb3_atari()
    monkeypatch.setattr(sb3_atari, "cv2", fake_cv2())
    kwargs = {"action_repeat_probability": 0.25}
    actions = np.random.default_rng(3).integers(0, 4, steps)
    a = _rollout(AtariWrapper(palaestra.make(env_id), **kwargs), actions, seed=9)
    b = _rollout(sb3_atari.AtariWrapper(gymnasium.make(env_id), **kwargs), actions, seed=9)
    _assert_same(a, b)


def test_atari_wrapper_equals_sb3(monkeypatch: pytest.MonkeyPatch) -> None:
    _check_atari_wrapper(monkeypatch, "BreakoutNoFrameskip-v4", 300)


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ["QbertNoFrameskip-v4", "SpaceInvadersNoFrameskip-v4"])
def test_atari_wrapper_equals_sb3_long(monkeypatch: pytest.MonkeyPatch, env_id: str) -> None:
    _check_atari_wrapper(monkeypatch, env_id, 3000)
