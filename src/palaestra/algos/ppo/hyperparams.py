"""PPO's hyperparameter rules: what a model file or a run folder may hand ``PPO(...)``
(checked by :mod:`palaestra.algos.common.hyperparams`)."""

from palaestra.algos.common.hyperparams import (
    _COMMON,
    _ON_POLICY_ACTOR_CRITIC,
    _PROBABILITY,
    _SDE,
    MAX_BATCH_SIZE,
    MAX_N_STEPS,
    _boolean,
    _integer,
    _number,
    _optional,
    declare_rules,
)

HYPERPARAMETERS = {
    **_COMMON,
    **_SDE,
    "n_steps": _integer(1, MAX_N_STEPS),
    "batch_size": _integer(1, MAX_BATCH_SIZE),
    "n_epochs": _integer(1, 10_000),
    "gae_lambda": _PROBABILITY,
    "normalize_advantage": _boolean,
    "ent_coef": _number(-1e6, 1e6),
    "vf_coef": _number(0.0, 1e6),
    "target_kl": _optional(_number(0.0, 1e6, low_open=True)),
}
SCHEDULES = {  # a clip range is >= 0; PPO refuses 0 for clip_range_vf
    "learning_rate": _number(0.0, 1e6),
    "clip_range": _number(0.0, 1e6),
    "clip_range_vf": _number(0.0, 1e6, low_open=True),
}
declare_rules("PPO", HYPERPARAMETERS, SCHEDULES, _ON_POLICY_ACTOR_CRITIC)
