"""The MuJoCo environments (v5), on the ``mujoco`` package.

Ant, HalfCheetah, Hopper, Humanoid, HumanoidStandup, InvertedDoublePendulum, InvertedPendulum,
Pusher, Reacher, Swimmer and Walker2d, with Gymnasium 1.4.0's constructor arguments, spaces,
rewards, infos, terminations and reset noise. The models are palaestra's own MJCF files
(``assets/``, written by :mod:`palaestra.envs.mujoco._model_table` from a table of the
published models' numbers) and compile to the same ``MjModel`` as Gymnasium's, so the same
seed and actions give Gymnasium's observations, rewards and infos bit for bit (checked on
mujoco 4.0.0, ``_base.PARITY_MUJOCO_VERSION``). ``mujoco`` is imported when an env is
constructed, never by ``import palaestra``; without it the constructor raises
``DependencyNotInstalled`` naming ``pip install "palaestra[mujoco]"``.
"""

from palaestra.envs.mujoco.fixed_base import (
    InvertedDoublePendulumEnv,
    InvertedPendulumEnv,
    PusherEnv,
    ReacherEnv,
)
from palaestra.envs.mujoco.locomotion import (
    AntEnv,
    HalfCheetahEnv,
    HopperEnv,
    HumanoidEnv,
    HumanoidStandupEnv,
    SwimmerEnv,
    Walker2dEnv,
)

__all__ = [
    "AntEnv",
    "HalfCheetahEnv",
    "HopperEnv",
    "HumanoidEnv",
    "HumanoidStandupEnv",
    "InvertedDoublePendulumEnv",
    "InvertedPendulumEnv",
    "PusherEnv",
    "ReacherEnv",
    "SwimmerEnv",
    "Walker2dEnv",
]
