"""PPO's policy names as classes, at SB3's path (``stable_baselines3.ppo.policies``): SB3's
aliases of the actor-critic policies, ``PPO(MlpPolicy, env)`` as ``PPO("MlpPolicy", env)``."""

from palaestra.algos.common.policies import (
    ActorCriticCnnPolicy,
    ActorCriticPolicy,
    MultiInputActorCriticPolicy,
)

__all__ = ["CnnPolicy", "MlpPolicy", "MultiInputPolicy"]

MlpPolicy = ActorCriticPolicy
CnnPolicy = ActorCriticCnnPolicy
MultiInputPolicy = MultiInputActorCriticPolicy
