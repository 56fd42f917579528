"""DDPG's policies, as SB3's ``stable_baselines3.ddpg.policies``: TD3's own classes."""

from palaestra.algos.td3.policies import CnnPolicy, MlpPolicy, MultiInputPolicy

__all__ = ["CnnPolicy", "MlpPolicy", "MultiInputPolicy"]
