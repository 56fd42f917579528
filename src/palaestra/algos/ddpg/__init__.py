"""DDPG (Lillicrap et al. 2016) as SB3's ``stable_baselines3.ddpg``: TD3 with one critic, no
target smoothing and no policy delay; its policies are TD3's."""

from palaestra.algos.ddpg import hyperparams as hyperparams  # declares DDPG's rules
from palaestra.algos.ddpg.ddpg import DDPG
from palaestra.algos.td3.policies import CnnPolicy, MlpPolicy, MultiInputPolicy, TD3Policy

__all__ = ["DDPG", "CnnPolicy", "MlpPolicy", "MultiInputPolicy", "TD3Policy"]
