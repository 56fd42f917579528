"""The numpy PPO update equals the torch update (float32 rounding) and logs the same values."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import torch

from palaestra.algos import PPO
from palaestra.algos.callbacks import BaseCallback

from .toys import Toy


@pytest.mark.parametrize(
    ("env", "kwargs"),
    [
        ("CartPole-v1", {"ent_coef": 0.01}),
        ("CartPole-v1", {"clip_range_vf": 0.1, "normalize_advantage": False}),
        ("Pendulum-v1", {"ent_coef": 0.01, "clip_range_vf": 0.2}),
        (Toy(), {"policy_kwargs": {"activation_fn": torch.nn.ReLU}}),
    ],
)
def test_numpy_update_matches_torch(env: object, kwargs: dict) -> None:
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=16, n_epochs=3, seed=0, **kwargs)
    assert model._numpy_trainer is not None
    model.learn(128)
    twin = copy.deepcopy(model)
    twin._numpy_trainer = None  # the torch path
    twin._rng.bit_generator.state = model._rng.bit_generator.state
    model.train()
    twin.train()
    for key, value in model.policy.state_dict().items():
        torch.testing.assert_close(value, twin.policy.state_dict()[key], atol=1e-6, rtol=1e-5)
    for key in ("train/approx_kl", "train/clip_fraction", "train/value_loss", "train/entropy_loss"):
        ours, theirs = model.logger.name_to_value[key], twin.logger.name_to_value[key]
        assert ours == pytest.approx(theirs, rel=1e-4, abs=1e-6), key


def test_numpy_trainer_only_where_it_applies() -> None:
    assert PPO("MlpPolicy", Toy(action="multidiscrete"))._numpy_trainer is None
    assert PPO("MlpPolicy", Toy(action="multibinary"))._numpy_trainer is None
    assert PPO("CnnPolicy", Toy(obs="image"))._numpy_trainer is None
    sgd = {"optimizer_class": torch.optim.SGD}
    assert PPO("MlpPolicy", "CartPole-v1", policy_kwargs=sgd)._numpy_trainer is None


class _ValuesAtRolloutEnd(BaseCallback):
    """Compares the buffer's values with the torch value head at the end of each rollout."""

    def __init__(self) -> None:
        super().__init__()
        self.checked = 0

    def _on_rollout_end(self) -> None:
        buf = self.model.rollout_buffer
        obs = torch.as_tensor(buf.observations.reshape(-1, *buf.obs_shape))
        with torch.no_grad():
            expected = self.model.policy.predict_values(obs).numpy().reshape(buf.values.shape)
        np.testing.assert_allclose(buf.values, expected, rtol=1e-5, atol=1e-6)
        self.checked += 1


@pytest.mark.parametrize("env", ["CartPole-v1", "Pendulum-v1"])
def test_rollout_values_come_from_the_rollout_policy(env: str) -> None:
    """With numpy acting the values are computed once per rollout, batched: they must be the
    value head's outputs on the stored observations under the rollout's parameters."""
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=16, n_epochs=2, seed=0)
    assert model._numpy is not None
    check = _ValuesAtRolloutEnd()
    model.learn(3 * 32, callback=check)
    assert check.checked == 3
