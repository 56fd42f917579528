"""One contract for every registered id, plus Gymnasium's specs for the classic ones."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from tests.envs.cases import CLASSIC_IDS

from palaestra import error
from palaestra.core import Env
from palaestra.envs.registration import make, registry

# Every Atari id is the same env class and each make loads a ROM (~80 ms): three stand for all
# here; tests/envs/atari makes every one of them (marked slow).
ATARI_SAMPLE = {"ALE/Breakout-v5", "ALE/Pong-v5", "BreakoutNoFrameskip-v4"}
# CarRacing draws every observation (~0.1 s a step): its 50-step contract runs with the slow
# tests; tests/envs/box2d checks it briefly in the fast suite.
SLOW_IDS = {"CarRacing-v3"}
ALL_IDS = [
    pytest.param(i, marks=pytest.mark.slow) if i in SLOW_IDS else i
    for i in sorted(
        i
        for i, s in registry.items()
        if i in ATARI_SAMPLE or not str(s.entry_point).startswith("palaestra.envs.atari")
    )
]
pytestmark = pytest.mark.filterwarnings("ignore:.*is out of date")


def _assert_same_obs(obs: Any, other: Any) -> None:
    """Equal observations, entry by entry for Dict ones (the goal envs')."""
    if isinstance(obs, dict):
        assert list(obs) == list(other)
        for key in obs:
            np.testing.assert_array_equal(obs[key], other[key], err_msg=key)
    else:
        np.testing.assert_array_equal(obs, other)


def _make(env_id: str, **kwargs: Any) -> Env:
    try:
        return make(env_id, **kwargs)
    except error.DependencyNotInstalled as e:  # e.g. an optional extra such as atari
        pytest.skip(str(e))


def test_every_classic_id_is_registered() -> None:
    assert set(CLASSIC_IDS) <= set(registry)


@pytest.mark.parametrize("env_id", ALL_IDS)
def test_contract(env_id: str) -> None:
    env, twin = _make(env_id), _make(env_id)
    assert env.spec is not None and env.spec.id == env_id
    obs, info = env.reset(seed=0)
    twin_obs, _ = twin.reset(seed=0)
    assert isinstance(info, dict)
    assert obs in env.observation_space, f"{obs} not in {env.observation_space}"
    _assert_same_obs(obs, twin_obs)
    env.action_space.seed(0)
    for _ in range(50):
        action = env.action_space.sample()
        obs, reward, terminated, truncated, info = env.step(action)
        twin_obs, twin_reward, *_ = twin.step(action)
        assert obs in env.observation_space
        _assert_same_obs(obs, twin_obs)  # seeded runs are deterministic
        assert float(reward) == float(twin_reward)
        assert type(terminated) is bool and type(truncated) is bool
        assert isinstance(info, dict)
        if terminated or truncated:
            env.reset()
            twin.reset()
    env.close()
    env.close()  # closing twice is harmless


@pytest.mark.parametrize("env_id", CLASSIC_IDS)
def test_classic_spec_matches_gymnasium(env_id: str) -> None:
    gymnasium = pytest.importorskip("gymnasium")
    ours, ref = registry[env_id], gymnasium.spec(env_id)
    assert ours.max_episode_steps == ref.max_episode_steps
    assert ours.reward_threshold == ref.reward_threshold
    assert ours.entry_point.split(":")[1] == ref.entry_point.split(":")[1]  # class name
    env, ref_env = _make(env_id), gymnasium.make(env_id)
    assert repr(env.observation_space) == repr(ref_env.observation_space)
    assert repr(env.action_space) == repr(ref_env.action_space)
    assert env.unwrapped.metadata == ref_env.unwrapped.metadata
    assert str(env) == str(ref_env)


@pytest.mark.parametrize("env_id", CLASSIC_IDS)
def test_time_limit_truncates(env_id: str) -> None:
    env = _make(env_id, max_episode_steps=5)
    env.reset(seed=0)
    flags = [env.step(env.action_space.sample())[3] for _ in range(5)]
    assert flags == [False] * 4 + [True]


@pytest.mark.parametrize("env_id", CLASSIC_IDS)
def test_check_env(env_id: str) -> None:
    env_checker = pytest.importorskip("palaestra.utils.env_checker")
    env = _make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env_checker.check_env(env.unwrapped)
    # Only the space warnings Gymnasium's checker gives its own envs: CartPole's infinite
    # velocity bounds and Pendulum's [-2, 2] action box.
    expected = ("infinity", "symmetric", "normalised")
    messages = [str(w.message) for w in caught]
    assert [m for m in messages if not any(e in m for e in expected)] == [], messages


def test_tutorial_reward_shaping_reads_unwrapped_state() -> None:
    env = _make("MountainCar-v0")
    obs, _ = env.reset(seed=0)
    state = env.unwrapped.state
    assert state.dtype == np.float64 and state.shape == (2,)
    assert np.float32(state[0]) == obs[0]
    obs, *_ = env.step(2)
    assert np.float32(env.unwrapped.state[0]) == obs[0]


@pytest.mark.parametrize("env_id", ["CartPole-v1", "Acrobot-v1", "Pendulum-v1"])
def test_unwrapped_params_are_settable(env_id: str) -> None:
    """``env.unwrapped.dt = 0.05`` (Acrobot's docs) changes the dynamics, as in Gymnasium."""
    name = {"CartPole-v1": "tau", "Acrobot-v1": "dt", "Pendulum-v1": "dt"}[env_id]
    fast, slow = _make(env_id), _make(env_id)
    setattr(slow.unwrapped, name, getattr(slow.unwrapped, name) / 4)
    fast.reset(seed=0)
    slow.reset(seed=0)
    action = fast.action_space.sample()
    assert fast.step(action)[0].tobytes() != slow.step(action)[0].tobytes()


@pytest.mark.parametrize("env_id", CLASSIC_IDS)
def test_copy_and_pickle_keep_the_trajectory(env_id: str) -> None:
    import copy
    import pickle

    env = _make(env_id)
    env.reset(seed=0)
    clones = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    action = env.action_space.sample()
    obs = env.step(action)[0]
    for clone in clones:
        assert clone.step(action)[0].tobytes() == obs.tobytes()


# ALE keeps the previous action of its sticky actions outside the state it clones, so a copy
# of a v5 id (repeat_action_probability=0.25) drifts from its original; ale-py's own env under
# Gymnasium drifts alike (docs/differences.md).
_STICKY_ALE = pytest.mark.xfail(
    strict=True, reason="ALE's cloned state lacks the sticky-action history (as in ale-py)"
)
COPY_IDS = [
    pytest.param(p, marks=_STICKY_ALE) if isinstance(p, str) and p.startswith("ALE/") else p
    for p in ALL_IDS
]


@pytest.mark.parametrize("env_id", COPY_IDS)
def test_every_id_copies_and_pickles_mid_episode(env_id: str) -> None:
    """Issue 26: each native env (Box2D's too) deep-copies and pickles, and the copy continues
    the same trajectory: same observations, rewards and flags for the same actions."""
    import copy
    import pickle

    env = _make(env_id)
    env.reset(seed=4)
    env.action_space.seed(4)
    for _ in range(5):
        env.step(env.action_space.sample())
    clones = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    actions = [env.action_space.sample() for _ in range(5)]
    want = [env.step(a)[:3] for a in actions]
    for clone in clones:
        got = [clone.step(a)[:3] for a in actions]
        for (obs, reward, term), (want_obs, want_reward, want_term) in zip(got, want):
            _assert_same_obs(obs, want_obs)
            assert (float(reward), bool(term)) == (float(want_reward), bool(want_term))
