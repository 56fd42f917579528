"""SB3's test envs (``palaestra.algos.envs``) side by side with SB3's own: the same spaces,
and for the same seeds and actions the same observations, rewards, ends and infos; both pass
SB3's ``check_env`` with the same warnings; palaestra's algorithms train on them."""

from __future__ import annotations

import copy
import warnings
from typing import Any

import numpy as np
import pytest
import stable_baselines3.common.envs as sb3_envs
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from palaestra import error
from palaestra.algos import A2C, DQN, PPO, envs
from palaestra.algos.env_checker import check_env
from palaestra.algos.evaluation import evaluate_policy
from palaestra.wrappers import Monitor

CASES: list[tuple[str, dict[str, Any]]] = [
    ("IdentityEnv", {"dim": 4, "ep_length": 7}),
    ("IdentityEnv", {}),
    ("IdentityEnvBox", {"eps": 0.5, "ep_length": 6}),
    ("IdentityEnvBox", {"low": 0.0, "high": 3.0}),
    ("IdentityEnvMultiDiscrete", {"dim": 3, "ep_length": 9}),
    ("IdentityEnvMultiBinary", {"dim": 2, "ep_length": 5}),
    ("FakeImageEnv", {"screen_height": 12, "screen_width": 10, "n_channels": 3}),
    ("FakeImageEnv", {"discrete": False, "channel_first": True}),
    ("SimpleMultiObsEnv", {}),
    ("SimpleMultiObsEnv", {"random_start": False, "channel_last": False}),
    ("SimpleMultiObsEnv", {"discrete_actions": False, "num_col": 3}),
]
IDS = [f"{name}-{'-'.join(f'{k}={v}' for k, v in kw.items())}" for name, kw in CASES]


def _pair(name: str, kwargs: dict[str, Any]) -> tuple[Any, Any]:
    """palaestra's env and SB3's, built from the same global numpy state (SimpleMultiObsEnv
    draws its grid there) and with their spaces seeded alike (the others draw states there)."""
    built = []
    for module in (envs, sb3_envs):
        np.random.seed(1234)  # noqa: NPY002 - SimpleMultiObsEnv draws there, as SB3's
        env = getattr(module, name)(**kwargs)
        env.action_space.seed(5)
        env.observation_space.seed(6)
        built.append(env)
    return built[0], built[1]


def _same(ours: Any, theirs: Any) -> None:
    if isinstance(theirs, dict):
        assert ours.keys() == theirs.keys()
        for key in theirs:
            _same(ours[key], theirs[key])
    else:
        np.testing.assert_array_equal(ours, theirs, strict=True)


@pytest.mark.parametrize(("name", "kwargs"), CASES, ids=IDS)
def test_spaces_and_attributes_are_sb3s(name: str, kwargs: dict[str, Any]) -> None:
    ours, theirs = _pair(name, kwargs)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    assert repr(ours.action_space) == repr(theirs.action_space)
    for attr in ("ep_length", "eps", "num_resets", "max_count", "img_size", "observation_shape"):
        assert getattr(ours, attr, None) == getattr(theirs, attr, None), attr


@pytest.mark.parametrize(("name", "kwargs"), CASES, ids=IDS)
def test_same_seed_and_actions_give_sb3s_episodes(name: str, kwargs: dict[str, Any]) -> None:
    ours, theirs = _pair(name, kwargs)
    actions = copy.deepcopy(ours.action_space)  # one sequence of actions for both
    actions.seed(7)
    steps = 0
    for episode in range(3):
        np.random.seed(100 + episode)  # noqa: NPY002 - SimpleMultiObsEnv's random start
        obs, info = ours.reset()
        np.random.seed(100 + episode)  # noqa: NPY002
        sb3_obs, sb3_info = theirs.reset()
        _same(obs, sb3_obs)
        assert info == sb3_info
        done = False
        while not done:
            # half the time the right answer, so the identity envs' reward is not always 0
            rewarded = isinstance(ours, envs.IdentityEnv) and steps % 2 == 0
            action = obs if rewarded else actions.sample()
            step = ours.step(action)
            sb3_step = theirs.step(action)
            _same(step[0], sb3_step[0])
            assert step[1:] == sb3_step[1:], (step[1:], sb3_step[1:])
            assert type(step[1]) is float
            obs, done, steps = step[0], step[2] or step[3], steps + 1
            assert steps < 500
    assert steps > 3 * (5 if "Multi" not in name else 1)


def test_the_identity_rewards_the_identity() -> None:
    env = envs.IdentityEnvBox(eps=0.05)
    obs, _ = env.reset()
    assert env.step(obs + np.float32(0.04))[1] == 1.0
    obs = env.state
    assert env.step(obs + np.float32(0.06))[1] == 0.0
    env = envs.IdentityEnv(dim=3, ep_length=2)
    obs, _ = env.reset()
    assert env.step(obs)[1:4] == (1.0, False, False)
    assert env.step((env.state + 1) % 3)[1:4] == (0.0, False, True)


def test_simple_multi_obs_env_walks_sb3s_grid() -> None:
    env = envs.SimpleMultiObsEnv(random_start=False)
    env.reset()
    # 0 -> right x3 -> 3, down x3 -> 15 (the goal); walls stop the other moves
    rewards = [env.step(a)[1] for a in (3, 0, 2, 2, 2, 1, 1)]
    assert env.state == 15 - 4 and rewards == [-0.1] * 7
    obs, reward, terminated, truncated, info = env.step(1)
    assert (reward, terminated, truncated, info) == (1.0, True, False, {"got_to_end": True})
    assert env.log == "Went down in state 11, got to state 15"
    obs["img"][:] = 0  # a copy: the grid keeps its image
    assert env.state_mapping[15]["img"].any()


def test_simple_multi_obs_env_truncates_after_101_steps() -> None:
    env = envs.SimpleMultiObsEnv(random_start=False)
    env.reset()
    ends = [env.step(3)[3] for _ in range(101)]
    assert ends == [False] * 100 + [True]


@pytest.mark.parametrize(
    ("env", "action", "message"),
    [
        (envs.IdentityEnv(dim=3), 3, r"Invalid action 3 \(int\) for action space Discrete\(3\)"),
        (envs.IdentityEnvBox(), np.array([np.nan]), r"actions must be finite"),
        (envs.IdentityEnvBox(), np.zeros(2), r"expected shape \(1,\), got \(2,\)"),
        (envs.IdentityEnvMultiDiscrete(dim=2), np.array([0, 2]), r"MultiDiscrete\(\[2 2\]\)"),
        (envs.IdentityEnvMultiBinary(dim=2), np.array([1, 2]), r"MultiBinary\(2\)"),
        (envs.FakeImageEnv(action_dim=2), -1, r"Invalid action -1 \(int\) .* Discrete\(2\)"),
        (envs.FakeImageEnv(discrete=False), np.zeros(4), r"expected shape \(5,\)"),
        (envs.SimpleMultiObsEnv(), 4, r"Invalid action 4 \(int\) for action space Discrete\(4\)"),
        (envs.SimpleMultiObsEnv(discrete_actions=False), "up", r"expected real values"),
    ],
    ids=lambda v: type(v).__name__ if isinstance(v, envs.IdentityEnv | envs.FakeImageEnv) else None,
)
def test_an_action_outside_the_space_is_refused(env: Any, action: Any, message: str) -> None:
    env.reset()
    with pytest.raises(error.InvalidAction, match=message):
        env.step(action)


def test_dim_and_space_together_are_refused() -> None:
    from palaestra import spaces

    with pytest.raises(ValueError, match=r"both 'dim' \(2\) and 'space' \(Discrete\(3\)\)"):
        envs.IdentityEnv(dim=2, space=spaces.Discrete(3))


@pytest.mark.parametrize(("name", "kwargs"), CASES, ids=IDS)
def test_check_env_says_what_sb3s_says(name: str, kwargs: dict[str, Any]) -> None:
    ours, theirs = _pair(name, kwargs)
    caught = []
    for checker, env in ((check_env, ours), (sb3_check_env, theirs)):
        with warnings.catch_warnings(record=True) as record:
            warnings.simplefilter("always")
            checker(env)
        caught.append(sorted({str(w.message) for w in record}))
    assert caught[0] == caught[1]


def test_ppo_learns_the_identity() -> None:
    env = envs.IdentityEnv(dim=2, ep_length=10)
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, learning_rate=3e-3, seed=0)
    model.learn(1024)
    evaluation = Monitor(envs.IdentityEnv(dim=2, ep_length=10))
    mean, _ = evaluate_policy(model, evaluation, n_eval_episodes=5)
    assert mean >= 9.0


def test_a2c_and_dqn_run_on_the_other_envs() -> None:
    """Each policy kind goes through: a Dict grid (MultiInputPolicy), images (CnnPolicy),
    MultiBinary and MultiDiscrete identities."""
    A2C("MultiInputPolicy", envs.SimpleMultiObsEnv(), n_steps=8, seed=0).learn(16)
    image = envs.FakeImageEnv(screen_height=36, screen_width=36)
    DQN("CnnPolicy", image, learning_starts=4, buffer_size=100, seed=0).learn(12)
    PPO("MlpPolicy", envs.IdentityEnvMultiBinary(dim=3), n_steps=16, batch_size=16).learn(16)
    PPO("MlpPolicy", envs.IdentityEnvMultiDiscrete(dim=3), n_steps=16, batch_size=16).learn(16)
    PPO("MlpPolicy", envs.IdentityEnvBox(), n_steps=16, batch_size=16).learn(16)
