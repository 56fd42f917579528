"""DDPG's hyperparameter rules: TD3's without the three DDPG fixes (checked by
:mod:`palaestra.algos.common.hyperparams`)."""

from palaestra.algos.common.hyperparams import _ACTOR_CRITIC, _LEARNING_RATE, declare_rules
from palaestra.algos.td3 import hyperparams as td3

HYPERPARAMETERS = {
    k: v
    for k, v in td3.HYPERPARAMETERS.items()
    if k not in ("policy_delay", "target_policy_noise", "target_noise_clip")  # DDPG's fixes
}
declare_rules("DDPG", HYPERPARAMETERS, _LEARNING_RATE, _ACTOR_CRITIC)
