"""``from_gymnasium`` and ``make("gymnasium:<id>")``: Gymnasium envs become palaestra envs that
palaestra's algorithms, wrappers, vector envs and checkers accept."""

from __future__ import annotations

import subprocess
import sys
import warnings

import gymnasium
import numpy as np
import pytest
from tests.compat.toys import GraphWalk

import palaestra
from palaestra import error, spaces
from palaestra.compat import PalaestraEnvAdapter, from_gymnasium, to_gymnasium
from palaestra.utils.env_checker import check_env


@pytest.fixture(autouse=True)
def _quiet() -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def test_spaces_and_spec_are_palaestra_ones() -> None:
    env = from_gymnasium(gymnasium.make("CartPole-v1"))
    assert isinstance(env, palaestra.Env) and isinstance(env, PalaestraEnvAdapter)
    assert env.observation_space == palaestra.make("CartPole-v1").observation_space
    assert env.action_space == spaces.Discrete(2)
    assert env.spec is not None and env.spec.id == "gymnasium:CartPole-v1"
    assert env.spec.max_episode_steps == 500 and env.spec.reward_threshold == 475.0
    assert env.metadata["render_fps"] == 50 and env.render_mode is None
    assert env.unwrapped is env
    assert str(env) == (
        "<PalaestraEnvAdapter<TimeLimit<OrderEnforcing<PassiveEnvChecker<CartPoleEnv"
        "<CartPole-v1>>>>>>"
    )


def test_passes_palaestra_check_env() -> None:
    check_env(from_gymnasium(gymnasium.make("CartPole-v1").unwrapped), skip_render_check=True)
    check_env(from_gymnasium(gymnasium.make("Taxi-v4").unwrapped), skip_render_check=True)


def test_same_seed_same_observations_as_palaestras_own_cartpole() -> None:
    # palaestra's CartPole reproduces Gymnasium's, so the two sides must agree step by step.
    theirs, ours = from_gymnasium(gymnasium.make("CartPole-v1")), palaestra.make("CartPole-v1")
    np.testing.assert_array_equal(theirs.reset(seed=7)[0], ours.reset(seed=7)[0])
    for t in range(30):
        a, b = theirs.step(t % 2), ours.step(t % 2)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:4] == b[1:4]


def test_generator_is_the_gymnasium_envs() -> None:
    gym_env = gymnasium.make("Taxi-v4")
    env = from_gymnasium(gym_env)
    env.reset(seed=4)
    assert env.np_random is gym_env.unwrapped.np_random and env.np_random_seed == 4
    assert env._np_random is gym_env.unwrapped._np_random


def test_palaestra_dqn_trains_on_gymnasium_cartpole() -> None:
    from palaestra.algos import DQN

    env = from_gymnasium(gymnasium.make("CartPole-v1"))
    model = DQN("MlpPolicy", env, learning_starts=100, train_freq=4, seed=0)
    model.learn(400)
    assert model.num_timesteps == 400 and model._n_updates > 0
    action, _ = model.predict(env.reset(seed=0)[0], deterministic=True)
    assert action in env.action_space


def test_palaestra_dqn_trains_on_gymnasium_taxi_discrete_observations() -> None:
    from palaestra.algos import DQN

    env = palaestra.make("gymnasium:Taxi-v4")
    assert env.observation_space == spaces.Discrete(500)
    model = DQN("MlpPolicy", env, learning_starts=100, seed=0)
    model.learn(300)
    assert model.num_timesteps == 300
    obs, _ = env.reset(seed=0)
    assert model.predict(obs, deterministic=True)[0] in env.action_space


def test_palaestra_wrappers_accept_it() -> None:
    from palaestra.wrappers import RecordEpisodeStatistics, TimeLimit

    env = RecordEpisodeStatistics(TimeLimit(palaestra.make("gymnasium:CartPole-v1"), 5))
    env.reset(seed=0)
    steps = [env.step(0) for _ in range(5)]
    assert [s[3] for s in steps] == [False] * 4 + [True]
    assert steps[-1][4]["episode"]["l"] == 5


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_of_gymnasium_ids(mode: str) -> None:
    vec = palaestra.make_vec("gymnasium:CartPole-v1", num_envs=3, vectorization_mode=mode)
    assert type(vec).__name__ == ("SyncVectorEnv" if mode == "sync" else "AsyncVectorEnv")
    obs, _ = vec.reset(seed=[1, 2, 3])
    assert obs.shape == (3, 4)
    np.testing.assert_array_equal(obs[1], gymnasium.make("CartPole-v1").reset(seed=2)[0])
    vec.close()


def test_make_passes_kwargs_and_adds_no_palaestra_wrappers() -> None:
    env = palaestra.make("gymnasium:MountainCar-v0", goal_velocity=0.01, max_episode_steps=7)
    assert isinstance(env, PalaestraEnvAdapter)  # no TimeLimit/OrderEnforcing of palaestra's
    assert env.gymnasium_env.unwrapped.goal_velocity == 0.01
    assert env.spec.max_episode_steps == 7 and env.spec.kwargs == {"goal_velocity": 0.01}
    env.reset(seed=0)
    truncated = [env.step(1)[3] for _ in range(7)]
    assert truncated == [False] * 6 + [True]


def test_make_of_an_adapters_spec_rebuilds_it_with_palaestra_wrappers() -> None:
    from palaestra.wrappers import ClipReward

    env = ClipReward(palaestra.make("gymnasium:CartPole-v1", max_episode_steps=9), 0.0, 0.5)
    remade = palaestra.make(env.spec)
    assert str(remade) == str(env)
    assert remade.spec.max_episode_steps == 9
    remade.reset(seed=0)
    assert remade.step(0)[1] == 0.5


def test_graph_observations_are_converted_back() -> None:
    # A Gymnasium wrapper around the adapter: from_gymnasium cannot just unwrap it.
    env = from_gymnasium(gymnasium.Wrapper(to_gymnasium(GraphWalk())))
    assert isinstance(env, PalaestraEnvAdapter)
    obs, _ = env.reset(seed=1)
    assert type(obs) is spaces.GraphInstance and obs in env.observation_space
    env.action_space.seed(1)
    obs, *_ = env.step(env.action_space.sample())
    assert obs in env.observation_space


@pytest.mark.parametrize(
    ("env_id", "exc", "message"),
    [
        ("gymnasium:Foo-v0", error.NameNotFound, r"'Foo-v0' is not in Gymnasium's registry"),
        ("gymnasium:CartPol-v1", error.NameNotFound, r"Did you mean: `CartPole`\?"),
        ("gymnasium:Taxi-v9", error.VersionNotFound, r"'Taxi-v9' is not in Gymnasium's regis"),
        ("gymnasium:nope/Foo-v0", error.NamespaceNotFound, r"not in Gymnasium's registry"),
        ("gymnasium:Taxi-v3", error.DeprecatedEnv, r"'Taxi-v3' is deprecated in Gymnasium's"),
        ("gymnasium:", error.Error, r"Expected an environment id after 'gymnasium:'"),
    ],
)
def test_unknown_ids_say_gymnasiums_registry(env_id: str, exc: type, message: str) -> None:
    with pytest.raises(exc, match=message):
        palaestra.make(env_id)


def test_make_vec_refuses_vector_entry_point_mode() -> None:
    with pytest.raises(error.Error, match=r"use vectorization_mode='sync' or 'async'"):
        palaestra.make_vec("gymnasium:CartPole-v1", 2, vectorization_mode="vector_entry_point")


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (lambda: palaestra.make("CartPole-v1"), r"already is a palaestra env: use it as it is"),
        (lambda: gymnasium.make_vec("CartPole-v1", 2), r"a vector env: adapt each sub-env"),
        (lambda: 42, r"expects a gymnasium.Env, got 42 of type builtins.int$"),
    ],
)
def test_wrong_kind_of_object(bad: object, message: str) -> None:
    with pytest.raises(TypeError, match=message):
        from_gymnasium(bad())  # type: ignore[operator]


def test_without_gymnasium_the_error_names_the_pip_install() -> None:
    code = (
        "import sys; sys.modules['gymnasium'] = None\n"
        "import palaestra, palaestra.compat  # importing compat itself needs nothing\n"
        "for call in (lambda: palaestra.make('gymnasium:Taxi-v4'),\n"
        "             lambda: palaestra.compat.to_gymnasium):\n"
        "    try:\n"
        "        call()\n"
        "    except palaestra.error.DependencyNotInstalled as e:\n"
        "        print(e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    lines = out.stdout.strip().splitlines()
    assert lines == [
        "gymnasium is not installed, run `pip install gymnasium` (needed for making "
        "'gymnasium:Taxi-v4')",
        "gymnasium is not installed, run `pip install gymnasium` (needed for palaestra.compat's "
        "Gymnasium interop)",
    ], out.stderr
