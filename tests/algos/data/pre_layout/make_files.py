"""Writes the model files in this folder with the code from before ``algos/`` was split into
``common/`` and one package per algorithm (commit 69c9b20), and the predictions they made then.

Each file names classes by ``module:qualname`` as that code wrote them (a policy class passed
by reference, a features extractor, an optimizer), so loading them tests the alias table that
keeps old model files loading after the move. Kept for the record; rerunning it after the move
would record the new paths and prove nothing.

Run from the repository root: ``python tests/algos/data/pre_layout/make_files.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch

from palaestra.algos import A2C, DDPG, DQN, PPO, SAC, TD3
from palaestra.algos.networks import FlattenExtractor
from palaestra.algos.off_policy_policies import DQNPolicy, SACPolicy, TD3Policy
from palaestra.algos.policies import ActorCriticPolicy

HERE = Path(__file__).parent
NET = {"net_arch": [8], "features_extractor_class": FlattenExtractor}


def main() -> None:
    models = {
        "dqn": DQN(
            DQNPolicy,
            "CartPole-v1",
            learning_starts=50,
            train_freq=4,
            policy_kwargs={**NET, "optimizer_class": torch.optim.Adam},
            seed=0,
        ),
        "ppo": PPO(
            ActorCriticPolicy,
            "CartPole-v1",
            n_steps=32,
            batch_size=16,
            n_epochs=2,
            policy_kwargs=NET,
            seed=0,
        ),
        "a2c": A2C("MlpPolicy", "CartPole-v1", n_steps=8, policy_kwargs=NET, seed=0),
        "sac": SAC(
            SACPolicy, "Pendulum-v1", learning_starts=20, batch_size=16, policy_kwargs=NET, seed=0
        ),
        "td3": TD3(
            TD3Policy, "Pendulum-v1", learning_starts=20, batch_size=16, policy_kwargs=NET, seed=0
        ),
        "ddpg": DDPG(
            TD3Policy, "Pendulum-v1", learning_starts=20, batch_size=16, policy_kwargs=NET, seed=0
        ),
    }
    rng = np.random.default_rng(0)
    cartpole = rng.normal(size=(8, 4)).astype(np.float32)
    pendulum = rng.uniform(-1, 1, size=(8, 3)).astype(np.float32)
    predictions = {}
    for name, model in models.items():
        model.learn(100)
        model.save(HERE / f"{name}.zip")
        obs = cartpole if name in ("dqn", "ppo", "a2c") else pendulum
        actions = model.predict(obs, deterministic=True)[0]
        predictions[name] = {"obs": obs.tolist(), "actions": np.asarray(actions).tolist()}
    (HERE / "predictions.json").write_text(json.dumps(predictions, indent=1) + "\n")


if __name__ == "__main__":
    main()
