"""QR-DQN (Dabney et al. 2018) as sb3-contrib's ``sb3_contrib.qrdqn``: the algorithm, its
policies and its objective (quantile Huber loss + VJP)."""

from palaestra.algos.qrdqn import hyperparams as hyperparams  # declares QRDQN's rules
from palaestra.algos.qrdqn.policies import (
    CnnPolicy,
    MlpPolicy,
    MultiInputPolicy,
    QRDQNPolicy,
    QuantileNetwork,
)
from palaestra.algos.qrdqn.qrdqn import QRDQN

__all__ = ["QRDQN", "CnnPolicy", "MlpPolicy", "MultiInputPolicy", "QRDQNPolicy", "QuantileNetwork"]
