"""Learning smoke tests: fixed seeds, CI-sized budgets (rl-zoo's CartPole settings for PPO)."""

from __future__ import annotations

import pytest

import palaestra as gym
from palaestra.algos import DQN, PPO, evaluate_policy
from palaestra.algos.schedules import LinearSchedule
from palaestra.vec_env import make_vec_env


def _score(model: object) -> float:
    env = gym.make("CartPole-v1")
    env.reset(seed=123)
    mean, _ = evaluate_policy(model, env, n_eval_episodes=10)
    return float(mean)


def test_ppo_learns_cartpole() -> None:
    """~12k steps (about 4 s on one core) from 8 native envs."""
    venv = make_vec_env("CartPole-v1", n_envs=8, seed=0)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=32,
        batch_size=256,
        gae_lambda=0.8,
        gamma=0.98,
        n_epochs=20,
        learning_rate=LinearSchedule(1e-3, 0.0),
        clip_range=LinearSchedule(0.2, 0.0),
        seed=0,
    )
    model.learn(12_000)
    assert _score(model) >= 150


def test_dqn_learns_cartpole() -> None:
    """8k steps from 4 native envs; random play scores about 22."""
    venv = make_vec_env("CartPole-v1", n_envs=4, seed=0)
    model = DQN(
        "MlpPolicy",
        venv,
        learning_rate=2e-3,
        learning_starts=500,
        batch_size=64,
        buffer_size=20_000,
        target_update_interval=100,
        train_freq=1,
        gradient_steps=1,
        exploration_fraction=0.3,
        gamma=0.98,
        seed=0,
    )
    model.learn(8_000)
    assert _score(model) >= 100


@pytest.mark.slow
def test_ppo_sb3_defaults_cartpole() -> None:
    """SB3's default PPO on one CartPole env, 50k steps."""
    model = PPO("MlpPolicy", "CartPole-v1", seed=0).learn(50_000)
    assert _score(model) >= 150


@pytest.mark.slow
def test_ppo_gsde_learns_pendulum() -> None:
    """gSDE with the RL Zoo's Pendulum-v1 settings (100k steps, about 20 s of CPU): random
    play scores about -1200, SB3 about -200 (BENCHMARKS.md, gSDE section)."""
    venv = make_vec_env("Pendulum-v1", n_envs=4, seed=0)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=1024,
        gae_lambda=0.95,
        gamma=0.9,
        n_epochs=10,
        learning_rate=1e-3,
        clip_range=0.2,
        use_sde=True,
        sde_sample_freq=4,
        seed=0,
    )
    model.learn(100_000)
    env = gym.make("Pendulum-v1")
    env.reset(seed=123)
    mean, _ = evaluate_policy(model, env, n_eval_episodes=10)
    assert mean >= -400
