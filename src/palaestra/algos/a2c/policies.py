"""A2C's policy names as classes, at SB3's path (``stable_baselines3.a2c.policies``): SB3's
aliases of the actor-critic policies, ``A2C(MlpPolicy, env)`` as ``A2C("MlpPolicy", env)``."""

from palaestra.algos.common.policies import (
    ActorCriticCnnPolicy,
    ActorCriticPolicy,
    MultiInputActorCriticPolicy,
)

__all__ = ["CnnPolicy", "MlpPolicy", "MultiInputPolicy"]

MlpPolicy = ActorCriticPolicy
CnnPolicy = ActorCriticCnnPolicy
MultiInputPolicy = MultiInputActorCriticPolicy
