"""PPO (Schulman et al. 2017) as SB3's ``stable_baselines3.ppo``: the algorithm and its
objective (loss + VJP); its policy classes (``policies``) are SB3's aliases of the
actor-critic."""

from palaestra.algos.ppo import hyperparams as hyperparams  # declares PPO's rules
from palaestra.algos.ppo.policies import CnnPolicy, MlpPolicy, MultiInputPolicy
from palaestra.algos.ppo.ppo import PPO

__all__ = ["PPO", "CnnPolicy", "MlpPolicy", "MultiInputPolicy"]
