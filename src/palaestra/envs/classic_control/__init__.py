"""The classic-control environments: one array physics per env, two faces.

Each module holds a frozen params dataclass, a pure ``step_state(ops, params, *state, action)``
written once against :mod:`._ops`, the single env (Gymnasium's class name, the Python-float
fast path) and the batched engine (``*Batch``, N envs as arrays).
"""

from palaestra.envs.classic_control.acrobot import AcrobotBatch, AcrobotEnv
from palaestra.envs.classic_control.batched import BatchedEnv
from palaestra.envs.classic_control.cartpole import CartPoleBatch, CartPoleEnv
from palaestra.envs.classic_control.continuous_mountain_car import (
    Continuous_MountainCarEnv,
    ContinuousMountainCarBatch,
)
from palaestra.envs.classic_control.mountain_car import MountainCarBatch, MountainCarEnv
from palaestra.envs.classic_control.pendulum import PendulumBatch, PendulumEnv

__all__ = [
    "AcrobotBatch",
    "AcrobotEnv",
    "BatchedEnv",
    "CartPoleBatch",
    "CartPoleEnv",
    "ContinuousMountainCarBatch",
    "Continuous_MountainCarEnv",
    "MountainCarBatch",
    "MountainCarEnv",
    "PendulumBatch",
    "PendulumEnv",
]
