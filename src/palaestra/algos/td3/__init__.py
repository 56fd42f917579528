"""TD3 (Fujimoto et al. 2018) as SB3's ``stable_baselines3.td3``: the algorithm, its policies
(DDPG's too) and its objectives (losses + VJPs)."""

from palaestra.algos.td3 import hyperparams as hyperparams  # declares TD3's rules
from palaestra.algos.td3.policies import CnnPolicy, MlpPolicy, MultiInputPolicy, TD3Policy
from palaestra.algos.td3.td3 import TD3

__all__ = ["TD3", "CnnPolicy", "MlpPolicy", "MultiInputPolicy", "TD3Policy"]
