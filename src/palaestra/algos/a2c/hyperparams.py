"""A2C's hyperparameter rules: what a model file or a run folder may hand ``A2C(...)``
(checked by :mod:`palaestra.algos.common.hyperparams`)."""

from palaestra.algos.common.hyperparams import (
    _COMMON,
    _LEARNING_RATE,
    _ON_POLICY_ACTOR_CRITIC,
    _PROBABILITY,
    _SDE,
    MAX_N_STEPS,
    _boolean,
    _integer,
    _number,
    declare_rules,
)

HYPERPARAMETERS = {
    **_COMMON,
    **_SDE,
    "n_steps": _integer(1, MAX_N_STEPS),
    "gae_lambda": _PROBABILITY,
    "ent_coef": _number(-1e6, 1e6),
    "vf_coef": _number(0.0, 1e6),
    "rms_prop_eps": _number(0.0, 1.0, low_open=True),
    "use_rms_prop": _boolean,
    "normalize_advantage": _boolean,
}
declare_rules("A2C", HYPERPARAMETERS, _LEARNING_RATE, _ON_POLICY_ACTOR_CRITIC)
