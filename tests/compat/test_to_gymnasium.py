"""``to_gymnasium``: palaestra envs pass Gymnasium's and SB3's checkers, SB3 trains on them, and
they draw exactly what the palaestra env draws."""

from __future__ import annotations

import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gymnasium_check_env
from tests.compat.toys import GraphWalk, ReachDict

import palaestra
from palaestra.compat import GymnasiumEnvAdapter, from_gymnasium, to_gymnasium

CHECKED = {
    "CartPole-v1": lambda: palaestra.make("CartPole-v1"),
    "MountainCar-v0": lambda: palaestra.make("MountainCar-v0"),
    "ReachDict": ReachDict,
}


@pytest.fixture(autouse=True)
def _quiet() -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Box bound is infinity", "no spec to test modes"
        yield


@pytest.mark.parametrize("name", list(CHECKED))
def test_passes_gymnasium_check_env(name: str) -> None:
    env = to_gymnasium(CHECKED[name]())
    assert isinstance(env, gymnasium.Env)
    gymnasium_check_env(env, skip_render_check=True)


@pytest.mark.parametrize("name", list(CHECKED))
def test_passes_sb3_check_env(name: str) -> None:
    from stable_baselines3.common.env_checker import check_env

    check_env(to_gymnasium(CHECKED[name]()), warn=True, skip_render_check=True)


def test_gymnasium_render_check_with_rgb_array() -> None:
    env = to_gymnasium(palaestra.make("CartPole-v1", render_mode="rgb_array"))
    env.reset(seed=0)
    gymnasium.utils.passive_env_checker.env_render_passive_checker(env)
    ours = palaestra.make("CartPole-v1", render_mode="rgb_array")
    ours.reset(seed=0)
    np.testing.assert_array_equal(env.render(), ours.render())
    assert env.render_mode == "rgb_array" and env.metadata["render_fps"] == 50


def test_sb3_ppo_learns_on_it() -> None:
    from stable_baselines3 import PPO

    model = PPO("MlpPolicy", to_gymnasium(palaestra.make("CartPole-v1")), n_steps=128, seed=0)
    model.learn(256)
    assert model.num_timesteps == 256


def test_sb3_multi_input_policy_on_dict_observations() -> None:
    from stable_baselines3 import PPO

    model = PPO("MultiInputPolicy", to_gymnasium(ReachDict()), n_steps=64, batch_size=32, seed=0)
    model.learn(64)
    action, _ = model.predict(to_gymnasium(ReachDict()).reset(seed=0)[0], deterministic=True)
    assert action in (0, 1, 2, 3)


@pytest.mark.parametrize("env_id", ["CartPole-v1", "MountainCar-v0", "Acrobot-v1", "Pendulum-v1"])
def test_same_seed_same_observations_as_the_raw_env(env_id: str) -> None:
    adapted, raw = to_gymnasium(palaestra.make(env_id)), palaestra.make(env_id)
    obs_a, _ = adapted.reset(seed=123)
    obs_b, _ = raw.reset(seed=123)
    np.testing.assert_array_equal(obs_a, obs_b)
    adapted.action_space.seed(5)
    for _ in range(50):
        action = adapted.action_space.sample()
        step_a, step_b = adapted.step(action), raw.step(action)
        np.testing.assert_array_equal(step_a[0], step_b[0])
        assert step_a[1:4] == step_b[1:4]
        if step_a[2] or step_a[3]:
            break


def test_generator_is_the_palaestra_envs() -> None:
    raw = palaestra.make("CartPole-v1")
    env = to_gymnasium(raw)
    env.reset(seed=9)
    assert env.np_random is raw.np_random and env.np_random_seed == 9
    assert env.unwrapped is env and env.unwrapped._np_random is raw.unwrapped.np_random
    rng = np.random.default_rng(1)
    env.np_random = rng
    assert raw.np_random is rng and raw.np_random_seed == -1


def test_spec_rebuilds_through_gymnasium_make_with_one_time_limit() -> None:
    env = to_gymnasium(palaestra.make("MountainCar-v0", goal_velocity=0.01))
    assert env.spec.id == "MountainCar-v0" and env.spec.max_episode_steps == 200
    assert env.spec.kwargs == {"goal_velocity": 0.01}
    remade = gymnasium.make(env.spec)
    assert str(remade) == (
        "<TimeLimit<OrderEnforcing<PassiveEnvChecker<GymnasiumEnvAdapter"
        "<MountainCarEnv<MountainCar-v0>>>>>>"
    )
    assert remade.unwrapped.palaestra_env.unwrapped.goal_velocity == 0.01
    remade.reset(seed=0)
    steps = 0
    while not any(remade.step(0)[2:4]):
        steps += 1
    assert steps == 199  # the 200th step truncates, once


def test_unregistered_env_has_no_spec_and_closes_through() -> None:
    toy = ReachDict()
    env = to_gymnasium(toy)
    assert env.spec is None
    env.close()
    assert toy.closed == 1
    assert str(env) == "<GymnasiumEnvAdapter<ReachDict instance>>"


def test_graph_observations_and_oneof_actions_are_converted() -> None:
    toy = GraphWalk()
    env = to_gymnasium(toy)
    obs, _ = env.reset(seed=0)
    assert type(obs) is gymnasium.spaces.GraphInstance and obs in env.observation_space
    env.action_space.seed(0)
    for _ in range(4):
        obs, *_ = env.step(env.action_space.sample())
        assert obs in env.observation_space
    assert all(a in toy.action_space for a in toy.actions)


def test_adapters_unwrap_instead_of_stacking() -> None:
    raw = palaestra.make("CartPole-v1")
    assert from_gymnasium(to_gymnasium(raw)) is raw
    gym_env = gymnasium.make("CartPole-v1")
    assert to_gymnasium(from_gymnasium(gym_env)) is gym_env


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (lambda: gymnasium.make("CartPole-v1"), r"already is a Gymnasium env: use it as it is"),
        (lambda: "CartPole-v1", r"expects a palaestra.Env, got 'CartPole-v1' of type builtins"),
        (lambda: palaestra.make_vec("CartPole-v1", 2), r"expects a palaestra.Env, got .*Vector"),
    ],
)
def test_wrong_kind_of_object(bad: object, message: str) -> None:
    with pytest.raises(TypeError, match=message):
        to_gymnasium(bad())  # type: ignore[operator]


def test_adapter_class_is_exported() -> None:
    assert isinstance(to_gymnasium(ReachDict()), GymnasiumEnvAdapter)


@pytest.mark.parametrize("algo", ["PPO", "DQN"])
def test_sb3_learns_bit_for_bit_what_it_learns_on_gymnasiums_cartpole(algo: str) -> None:
    # palaestra's CartPole reproduces Gymnasium's and the adapter forwards SB3's seeding to it,
    # so the same seed must give the very same weights.
    import stable_baselines3
    import torch

    cls = getattr(stable_baselines3, algo)
    kwargs = {"n_steps": 128, "batch_size": 64} if algo == "PPO" else {"learning_starts": 100}

    def weights(env: gymnasium.Env) -> dict[str, torch.Tensor]:
        return cls("MlpPolicy", env, seed=3, **kwargs).learn(512).policy.state_dict()

    ours = weights(to_gymnasium(palaestra.make("CartPole-v1")))
    theirs = weights(gymnasium.make("CartPole-v1"))
    assert list(ours) == list(theirs)
    for key in theirs:
        assert torch.equal(ours[key], theirs[key]), key
