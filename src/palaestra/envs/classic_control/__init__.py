"""The classic-control environments: one physics per env, two faces.

Each module holds a frozen params dataclass, a pure ``step_state(ops, params, *state, action)``
and a ``reset_state(uniforms, ...)`` written once against :mod:`._ops`, the single env
(Gymnasium's class name and arguments) and the batched engine (``*Batch``, N envs as arrays).

The single env runs ``step_state`` on Python floats rather than as a batch of one: measured
on MountainCar, a batch of one steps ~40k times/s (a dozen numpy calls on 1-element arrays)
against ~400k/s for the float path, and both give the same bits (see ``_ops``).

>>> from palaestra.envs.classic_control import MountainCarBatch, MountainCarEnv
>>> engine = MountainCarBatch(3)
>>> obs = engine.reset(seed=42)
>>> obs.shape, obs.dtype
((3, 2), dtype('float32'))
>>> single, _ = MountainCarEnv().reset(seed=43)  # row i behaves like a single env seeded 42 + i
>>> bool((obs[1] == single).all())
True
>>> obs, reward, terminated = engine.step([2, 2, 0])
>>> reward.tolist(), terminated.tolist()
([-1.0, -1.0, -1.0], [False, False, False])
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
