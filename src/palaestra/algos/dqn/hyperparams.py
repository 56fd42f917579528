"""DQN's hyperparameter rules: what a model file or a run folder may hand ``DQN(...)``
(checked by :mod:`palaestra.algos.common.hyperparams`)."""

from palaestra.algos.common.hyperparams import (
    _COMMON,
    _LEARNING_RATE,
    _POLICY_COMMON,
    _PROBABILITY,
    _REPLAY,
    MAX_STEPS,
    _integer,
    declare_rules,
)

HYPERPARAMETERS = {
    **_COMMON,
    **_REPLAY,
    "target_update_interval": _integer(1, MAX_STEPS),
    "exploration_fraction": _PROBABILITY,
    "exploration_initial_eps": _PROBABILITY,
    "exploration_final_eps": _PROBABILITY,
}
declare_rules("DQN", HYPERPARAMETERS, _LEARNING_RATE, _POLICY_COMMON)
