"""SB3's ``stable_baselines3.common.envs.bit_flipping_env`` path: the goal env palaestra ships
as ``palaestra.envs.goal.BitFlippingEnv`` (registered as ``BitFlipping-v0``)."""

from palaestra.envs.goal.bit_flipping import BitFlippingEnv

__all__ = ["BitFlippingEnv"]
