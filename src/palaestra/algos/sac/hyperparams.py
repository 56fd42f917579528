"""SAC's hyperparameter rules: what a model file or a run folder may hand ``SAC(...)``
(checked by :mod:`palaestra.algos.common.hyperparams`)."""

from typing import Any

from palaestra.algos.common.hyperparams import (
    _ACTOR_CRITIC,
    _COMMON_NO_CLIP,
    _LEARNING_RATE,
    _OFF_POLICY,
    _SDE,
    MAX_STEPS,
    _boolean,
    _integer,
    _number,
    declare_rules,
)


def _ent_coef(value: Any) -> str | None:
    """SAC's ``"auto"``, ``"auto_<init>"`` or a fixed coefficient > 0."""
    if isinstance(value, str):
        head, _, init = value.partition("_")
        try:
            ok = head == "auto" and (not init or 0 < float(init) < 1e6)
        except ValueError:
            ok = False
        return None if ok else '"auto", "auto_<value>" or a number > 0'
    return _number(0.0, 1e6, low_open=True)(value)


def _target_entropy(value: Any) -> str | None:
    return None if value == "auto" else _number(-1e6, 1e6)(value)


HYPERPARAMETERS = {
    **_COMMON_NO_CLIP,
    **_OFF_POLICY,
    **_SDE,
    "use_sde_at_warmup": _boolean,
    "ent_coef": _ent_coef,
    "target_update_interval": _integer(1, MAX_STEPS),
    "target_entropy": _target_entropy,
}
POLICY_KWARGS = {  # SACPolicy's gSDE keywords
    **_ACTOR_CRITIC,
    "use_sde": _boolean,
    "log_std_init": _number(-20.0, 20.0),
    "use_expln": _boolean,
    "clip_mean": _number(0.0, 1e6),
}
declare_rules("SAC", HYPERPARAMETERS, _LEARNING_RATE, POLICY_KWARGS)
