"""SAC (Haarnoja et al. 2018) as SB3's ``stable_baselines3.sac``: the algorithm, its policies
and its objectives (losses + VJPs)."""

from palaestra.algos.sac import hyperparams as hyperparams  # declares SAC's rules
from palaestra.algos.sac.policies import CnnPolicy, MlpPolicy, MultiInputPolicy, SACPolicy
from palaestra.algos.sac.sac import SAC

__all__ = ["SAC", "CnnPolicy", "MlpPolicy", "MultiInputPolicy", "SACPolicy"]
