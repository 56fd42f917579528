"""A2C (Mnih et al. 2016) as SB3's ``stable_baselines3.a2c``: the algorithm and its objective
(loss + VJP); its policy classes (``policies``) are SB3's aliases of the actor-critic."""

from palaestra.algos.a2c import hyperparams as hyperparams  # declares A2C's rules
from palaestra.algos.a2c.a2c import A2C
from palaestra.algos.a2c.policies import CnnPolicy, MlpPolicy, MultiInputPolicy

__all__ = ["A2C", "CnnPolicy", "MlpPolicy", "MultiInputPolicy"]
