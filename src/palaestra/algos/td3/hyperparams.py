"""TD3's hyperparameter rules: what a model file or a run folder may hand ``TD3(...)``
(checked by :mod:`palaestra.algos.common.hyperparams`)."""

from palaestra.algos.common.hyperparams import (
    _ACTOR_CRITIC,
    _COMMON_NO_CLIP,
    _LEARNING_RATE,
    _OFF_POLICY,
    MAX_STEPS,
    _integer,
    _number,
    declare_rules,
)

HYPERPARAMETERS = {
    **_COMMON_NO_CLIP,
    **_OFF_POLICY,
    "policy_delay": _integer(1, MAX_STEPS),
    "target_policy_noise": _number(0.0, 1e6),
    "target_noise_clip": _number(0.0, 1e6),
}
declare_rules("TD3", HYPERPARAMETERS, _LEARNING_RATE, _ACTOR_CRITIC)
