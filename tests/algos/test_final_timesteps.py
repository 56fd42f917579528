"""``model.final_timesteps(total)``: where ``learn`` really stops (SB3's loops finish the
rollout or the ``train_freq`` collection under way), also for a run stopped mid-rollout."""

from __future__ import annotations

from typing import Any

import pytest

from palaestra.algos import A2C, DQN, PPO
from palaestra.algos.callbacks import BaseCallback
from palaestra.algos.common.base import round_up_steps
from palaestra.vec_env import make_vec_env


class _StopAt(BaseCallback):
    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def _on_step(self) -> bool:
        return self.num_timesteps < self.at


CASES = [
    (PPO, {"n_steps": 16, "batch_size": 32}, 100, 128),  # rollouts of 16 x 2 = 32 steps
    (PPO, {"n_steps": 16, "batch_size": 32}, 96, 96),
    (A2C, {}, 101, 110),  # n_steps 5 x 2
    (DQN, {"train_freq": 4, "learning_starts": 10}, 101, 104),  # collections of 4 x 2
    (DQN, {"train_freq": 1, "learning_starts": 10}, 101, 102),  # whole steps of 2 envs
]


@pytest.mark.parametrize(("cls", "kwargs", "total", "end"), CASES)
def test_final_timesteps_is_where_learn_stops(
    cls: Any, kwargs: dict[str, Any], total: int, end: int
) -> None:
    model = cls("MlpPolicy", make_vec_env("CartPole-v1", n_envs=2, seed=0), seed=0, **kwargs)
    assert model.final_timesteps(total) == end
    model.learn(total)
    assert model.num_timesteps == end


@pytest.mark.parametrize(("cls", "kwargs"), [(PPO, CASES[0][1]), (DQN, CASES[3][1])])
def test_final_timesteps_after_a_stop_mid_rollout(cls: Any, kwargs: dict[str, Any]) -> None:
    """A stop keeps the partial rollout (collection); the next learn completes it, so the end
    counts from where the open one began."""
    model = cls("MlpPolicy", make_vec_env("CartPole-v1", n_envs=2, seed=0), seed=0, **kwargs)
    model.learn(200, callback=_StopAt(38))  # stops inside a rollout (collection)
    assert model.num_timesteps == 38
    end = model.final_timesteps(101)
    assert end == (128 if cls is PPO else 104)
    model.learn(101 - model.num_timesteps, reset_num_timesteps=False)
    assert model.num_timesteps == end


def test_episode_collections_give_a_lower_bound() -> None:
    model = DQN("MlpPolicy", make_vec_env("CartPole-v1", n_envs=2, seed=0), seed=0,
                train_freq=(1, "episode"), learning_starts=10)  # fmt: skip
    assert model.final_timesteps(101) == 102
    model.learn(101)
    assert model.num_timesteps >= 102


def test_round_up_steps() -> None:
    assert round_up_steps(0, 0, 5000, 4096) == 8192
    assert round_up_steps(96, 97, 400, 4) == 400
    assert round_up_steps(0, 4096, 4000, 4096) == 4096  # already there: learn does nothing
