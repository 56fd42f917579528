"""``BitFlippingEnv`` against SB3's (``stable_baselines3.common.envs``) on the same seeds and
actions: the same observations, rewards, terminations, truncations and infos in every variant,
the same batched ``compute_reward``; palaestra's env contract (check_env, pickling, render)."""

from __future__ import annotations

import copy
import pickle
import warnings
from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error
from palaestra.envs.goal import BitFlippingEnv
from palaestra.utils.env_checker import check_env

sb3_envs = pytest.importorskip("stable_baselines3.common.envs")

VARIANTS = [
    {},
    {"continuous": True},
    {"discrete_obs_space": True},
    {"image_obs_space": True},
    {"image_obs_space": True, "channel_first": False},
    {"n_bits": 15, "max_steps": 7},
]
IDS = ["BitFlipping-v0", "BitFlippingContinuous-v0", "BitFlipping15-v0"]


def _same_obs(ours: dict[str, Any], theirs: dict[str, Any]) -> None:
    assert list(ours) == list(theirs)
    for key, value in theirs.items():
        assert type(ours[key]) is type(value), key
        np.testing.assert_array_equal(ours[key], value)
        assert np.asarray(ours[key]).dtype == np.asarray(value).dtype, key


@pytest.mark.parametrize("kwargs", VARIANTS)
def test_same_episodes_as_sb3(kwargs: dict[str, Any]) -> None:
    ours, theirs = BitFlippingEnv(**kwargs), sb3_envs.BitFlippingEnv(**kwargs)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    assert repr(ours.action_space) == repr(theirs.action_space)
    assert ours.max_steps == theirs.max_steps
    theirs.action_space.seed(1)
    for seed in range(6):
        obs, info = ours.reset(seed=seed)
        ref_obs, ref_info = theirs.reset(seed=seed)
        _same_obs(obs, ref_obs)
        assert info == ref_info
        for _ in range(ours.max_steps):
            action = theirs.action_space.sample()
            obs, reward, terminated, truncated, info = ours.step(action)
            ref = theirs.step(action)
            _same_obs(obs, ref[0])
            assert (reward, terminated, truncated, info) == ref[1:]
            assert type(reward) is float and type(terminated) is bool
            if terminated or truncated:
                break


@pytest.mark.parametrize("kwargs", VARIANTS[:5])
def test_compute_reward_batched_as_sb3(kwargs: dict[str, Any]) -> None:
    ours, theirs = BitFlippingEnv(n_bits=5, **kwargs), sb3_envs.BitFlippingEnv(n_bits=5, **kwargs)
    theirs.reset(seed=0)  # SB3 reads the state's length
    rng = np.random.default_rng(0)
    bits = rng.integers(0, 2, size=(8, 5)).astype(np.int8)
    bits[:3] = 1  # three achieved goals equal the desired one
    achieved = [theirs.convert_if_needed(b) for b in bits]
    desired = [theirs.convert_if_needed(np.ones(5, dtype=np.int8))] * 8
    if kwargs.get("discrete_obs_space"):  # as a buffer stores them: [batch, 1]
        batch_a, batch_d = np.array(achieved)[:, None], np.array(desired)[:, None]
    else:
        batch_a, batch_d = np.stack(achieved), np.stack(desired)
    expected = theirs.compute_reward(batch_a, batch_d, None)
    got = ours.compute_reward(batch_a, batch_d, [{}] * 8)
    assert got.dtype == expected.dtype == np.float32 and got.shape == (8,)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(got, [0, 0, 0, *-(bits[3:] != 1).any(axis=1).astype(float)])
    one = ours.compute_reward(achieved[0], desired[0], None)  # one pair: a batch of one
    np.testing.assert_array_equal(one, theirs.compute_reward(achieved[0], desired[0], None))


def test_conversions_as_sb3() -> None:
    for kwargs in VARIANTS[:5]:
        ours, theirs = (
            BitFlippingEnv(n_bits=6, **kwargs),
            sb3_envs.BitFlippingEnv(n_bits=6, **kwargs),
        )
        theirs.reset(seed=0)
        state = np.array([1, 0, 1, 1, 0, 1], dtype=np.int8)
        converted = ours.convert_if_needed(state)
        np.testing.assert_array_equal(converted, theirs.convert_if_needed(state))
        assert type(converted) is type(theirs.convert_if_needed(state))
        back = ours.convert_to_bit_vector(converted, 1)
        np.testing.assert_array_equal(back, theirs.convert_to_bit_vector(converted, 1))
        np.testing.assert_array_equal(back, state[None])
    ours = BitFlippingEnv(n_bits=6, discrete_obs_space=True)
    # a batch of integer goals is decoded to bits too (SB3 returns the integers)
    np.testing.assert_array_equal(
        ours.convert_to_bit_vector(np.array([[45], [3]]), 2),
        [[1, 0, 1, 1, 0, 1], [1, 1, 0, 0, 0, 0]],
    )


@pytest.mark.parametrize("env_id", IDS)
def test_registered_ids_pass_check_env_without_warnings(env_id: str) -> None:
    env = palaestra.make(env_id)
    assert env.spec is not None and env.spec.max_episode_steps is None  # it truncates itself
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    assert env.unwrapped.n_bits == (15 if "15" in env_id else 10)
    assert env.unwrapped.continuous == ("Continuous" in env_id)
    assert palaestra.make(env_id, n_bits=3).unwrapped.n_bits == 3


@pytest.mark.parametrize("kwargs", VARIANTS)
def test_pickle_and_deepcopy_continue_the_same_trajectory(kwargs: dict[str, Any]) -> None:
    env = BitFlippingEnv(render_mode=None, **kwargs)
    env.reset(seed=3)
    env.step(env.action_space.sample())
    copies = [pickle.loads(pickle.dumps(env)), copy.deepcopy(env)]
    env.action_space.seed(5)
    for action in [env.action_space.sample() for _ in range(4)]:
        ref = env.step(action)
        for twin in copies:
            got = twin.step(action)
            _same_obs(got[0], ref[0])
            assert got[1:] == ref[1:]
    ref_obs, _ = env.reset()  # the generator was copied too: the same next episode
    for twin in copies:
        _same_obs(twin.reset()[0], ref_obs)


def test_render_modes(capsys: pytest.CaptureFixture[str]) -> None:
    env = BitFlippingEnv(n_bits=3, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.dtype == np.uint8 and frame.shape == (32, 48, 3)
    np.testing.assert_array_equal(frame[0, ::16, 0], env.state.astype(int) * 255)  # state row
    np.testing.assert_array_equal(frame[16, ::16, 0], [255, 255, 255])  # desired goal row
    ansi = BitFlippingEnv(n_bits=3, render_mode="ansi")
    ansi.reset(seed=0)
    assert ansi.render() == "".join(str(b) for b in ansi.state)
    human = BitFlippingEnv(n_bits=3)  # SB3's default mode prints the bits
    assert human.render_mode == "human"
    human.reset(seed=0)
    assert human.render() is None
    assert capsys.readouterr().out.strip() == str(human.state)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_bits": 0}, "n_bits must be a positive integer, got 0"),
        ({"n_bits": 2.5}, "n_bits must be a positive integer, got 2.5"),
        ({"max_steps": 0}, "max_steps must be a positive integer or None, got 0"),
        (
            {"discrete_obs_space": True, "image_obs_space": True},
            "Cannot use both discrete and image observation spaces",
        ),
        ({"n_bits": 1297, "image_obs_space": True}, "at most 1296 bits, got n_bits=1297"),
        ({"render_mode": "rgb"}, r"render_mode must be None or one of .*, got 'rgb'"),
    ],
)
def test_bad_arguments(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        BitFlippingEnv(**kwargs)


def test_bad_actions() -> None:
    env = BitFlippingEnv(n_bits=4)
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=r"Invalid action 4 .*Discrete\(4\)"):
        env.step(4)
    cont = BitFlippingEnv(n_bits=4, continuous=True)
    cont.reset(seed=0)
    with pytest.raises(error.InvalidAction, match="expected 4 numbers"):
        cont.step(np.zeros(3))


def test_sb3_module_path() -> None:
    from palaestra.algos.common.envs.bit_flipping_env import BitFlippingEnv as Exported

    assert Exported is BitFlippingEnv
