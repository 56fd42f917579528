"""QR-DQN's hyperparameter rules: DQN's, with ``max_grad_norm`` optional (sb3-contrib's default
is None: no clipping) and the policy's ``n_quantiles`` bounded (the last layer has
``n_quantiles * n_actions`` units)."""

from palaestra.algos.common.hyperparams import (
    _COMMON,
    _LEARNING_RATE,
    _POLICY_COMMON,
    MAX_NET_WIDTH,
    _integer,
    _optional,
    declare_rules,
)
from palaestra.algos.dqn.hyperparams import HYPERPARAMETERS as DQN_HYPERPARAMETERS

HYPERPARAMETERS = {**DQN_HYPERPARAMETERS, "max_grad_norm": _optional(_COMMON["max_grad_norm"])}
POLICY_KWARGS = {**_POLICY_COMMON, "n_quantiles": _integer(1, MAX_NET_WIDTH)}
declare_rules("QRDQN", HYPERPARAMETERS, _LEARNING_RATE, POLICY_KWARGS)
