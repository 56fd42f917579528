"""Hyperparameters the tutorial trains MountainCar-v0 with, shared by the training benchmarks.

The issue's targets are stated for exactly these settings, so every script uses this one copy.
"""

from __future__ import annotations

from typing import Any

# "Training with Stable-Baselines3": DQN("MlpPolicy", env, ...) on MountainCar-v0.
DQN_KWARGS: dict[str, Any] = dict(
    learning_rate=1e-3,
    buffer_size=50_000,
    learning_starts=1000,
    batch_size=128,
    tau=1.0,
    gamma=0.99,
    train_freq=4,
    gradient_steps=1,
    target_update_interval=250,
    exploration_fraction=0.2,
    exploration_final_eps=0.05,
)
