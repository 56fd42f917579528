"""The numpy DQN update equals the torch update (float32 rounding), Adam state included."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import torch

import palaestra as gym
from palaestra.algos import DQN

from .toys import Toy


@pytest.mark.parametrize("activation", [torch.nn.ReLU, torch.nn.Tanh])
def test_numpy_update_matches_torch(activation: type) -> None:
    model = DQN(
        "MlpPolicy",
        gym.make("CartPole-v1"),
        learning_starts=50,
        batch_size=64,
        seed=0,
        max_grad_norm=0.5,
        policy_kwargs={"activation_fn": activation},
    )
    assert model._numpy_trainer is not None
    model.learn(400)
    twin = copy.deepcopy(model)
    twin._numpy_trainer = None  # the torch path
    twin._rng.bit_generator.state = model._rng.bit_generator.state
    model.train(5, 64)
    twin.train(5, 64)
    for key, value in model.policy.state_dict().items():
        torch.testing.assert_close(value, twin.policy.state_dict()[key], atol=1e-6, rtol=1e-5)
    for p, q in zip(model._q_params, twin._q_params):
        ours, theirs = model.optimizer.state[p], twin.optimizer.state[q]
        assert float(ours["step"]) == float(theirs["step"])
        torch.testing.assert_close(ours["exp_avg_sq"], theirs["exp_avg_sq"], atol=1e-8, rtol=1e-4)


def test_numpy_trainer_only_where_it_applies() -> None:
    assert DQN("MlpPolicy", "CartPole-v1")._numpy_trainer is not None
    assert DQN("MlpPolicy", Toy(obs="image"))._numpy_trainer is None  # /255 preprocessing
    assert DQN("CnnPolicy", Toy(obs="image"))._numpy_trainer is None
    sgd = {"optimizer_class": torch.optim.SGD}
    assert DQN("MlpPolicy", "CartPole-v1", policy_kwargs=sgd)._numpy_trainer is None
    decay = {"optimizer_kwargs": {"weight_decay": 1e-4}}
    assert DQN("MlpPolicy", "CartPole-v1", policy_kwargs=decay)._numpy_trainer is None
    assert np.isfinite(
        DQN("MlpPolicy", "CartPole-v1", learning_starts=10).learn(100).exploration_rate
    )
