"""DQN (Mnih et al. 2015) as SB3's ``stable_baselines3.dqn``: the algorithm, its policies and
its objective (loss + VJP)."""

from palaestra.algos.dqn import hyperparams as hyperparams  # declares DQN's rules
from palaestra.algos.dqn.dqn import DQN
from palaestra.algos.dqn.policies import CnnPolicy, DQNPolicy, MlpPolicy, MultiInputPolicy, QNetwork

__all__ = ["DQN", "CnnPolicy", "DQNPolicy", "MlpPolicy", "MultiInputPolicy", "QNetwork"]
