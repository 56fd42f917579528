"""evaluate_policy on a single env, with and without Monitor; the torch-missing error."""

import subprocess
import sys
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra.algos import evaluate_policy
from palaestra.wrappers.monitor import Monitor


class AlwaysRight:
    """A stand-in model: ``predict`` with SB3's signature."""

    def predict(
        self, obs: Any, state: Any = None, episode_start: Any = None, deterministic: bool = False
    ) -> tuple[np.ndarray, Any]:
        return np.int64(1), state


class Doubled(gym.RewardWrapper):
    def reward(self, reward: Any) -> float:
        return 2 * float(reward)


def test_single_env_returns_and_lengths() -> None:
    env = gym.make("CartPole-v1")
    env.reset(seed=0)
    rewards, lengths = evaluate_policy(
        AlwaysRight(), env, n_eval_episodes=3, return_episode_rewards=True
    )
    assert len(rewards) == 3 and rewards == [float(n) for n in lengths]
    mean, std = evaluate_policy(AlwaysRight(), env, n_eval_episodes=2)
    assert 5 <= mean <= 20 and std >= 0


def test_monitor_statistics_win_over_reward_wrappers() -> None:
    env = Doubled(Monitor(gym.make("CartPole-v1")))
    rewards, lengths = evaluate_policy(
        AlwaysRight(), env, n_eval_episodes=2, return_episode_rewards=True
    )
    assert rewards == [float(n) for n in lengths]  # Monitor saw the undoubled reward


def test_threshold_and_bad_arguments() -> None:
    env = gym.make("CartPole-v1")
    with pytest.raises(AssertionError, match="below threshold"):
        evaluate_policy(AlwaysRight(), env, n_eval_episodes=1, reward_threshold=400)
    with pytest.raises(ValueError):
        evaluate_policy(AlwaysRight(), env, n_eval_episodes=0)
    with pytest.raises(TypeError):
        evaluate_policy(AlwaysRight(), "CartPole-v1")


def test_missing_torch_names_the_extra() -> None:
    code = (
        "import sys; sys.modules['torch'] = None\n"
        "import palaestra\n"
        "try:\n    import palaestra.algos\n"
        "except palaestra.error.DependencyNotInstalled as e:\n    print(e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert 'pip install "palaestra[train]"' in out.stdout, out.stderr


def test_vec_env_evaluation_spreads_episodes() -> None:
    import warnings

    from palaestra.vec_env import DummyVecEnv, make_vec_env

    class Batch(AlwaysRight):
        def predict(
            self,
            obs: Any,
            state: Any = None,
            episode_start: Any = None,
            deterministic: bool = False,
        ) -> tuple[np.ndarray, Any]:
            return np.ones(len(obs), dtype=np.int64), state

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a VecMonitor counts as monitored: no warning
        rewards, lengths = evaluate_policy(
            Batch(),
            make_vec_env("CartPole-v1", n_envs=3, seed=0),
            n_eval_episodes=5,
            return_episode_rewards=True,
        )
    assert len(rewards) == 5 and rewards == [float(n) for n in lengths]
    with pytest.warns(UserWarning, match="Monitor"):
        evaluate_policy(Batch(), DummyVecEnv([lambda: gym.make("CartPole-v1")]), n_eval_episodes=1)
