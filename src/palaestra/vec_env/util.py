"""Finding and syncing ``VecEnvWrapper`` layers (``stable_baselines3.common.vec_env``'s helpers).

``sync_envs_normalization`` is what ``EvalCallback`` calls before each evaluation, so that an
evaluation env under its own ``VecNormalize`` scales observations with the training env's
statistics instead of its own (which never update: evaluation envs have ``training=False``).
"""

from __future__ import annotations

from copy import deepcopy
from typing import Any, TypeVar

import numpy as np

from palaestra import spaces
from palaestra.vec_env.base import VecEnv, VecEnvObs, VecEnvWrapper
from palaestra.vec_env.normalize import VecNormalize

__all__ = [
    "dict_to_obs",
    "is_vecenv_wrapped",
    "obs_space_info",
    "sync_envs_normalization",
    "unwrap_vec_normalize",
    "unwrap_vec_wrapper",
]

WrapperT = TypeVar("WrapperT", bound=VecEnvWrapper)


def unwrap_vec_wrapper(env: VecEnv, vec_wrapper_class: type[WrapperT]) -> WrapperT | None:
    """The outermost layer of ``env`` that is a ``vec_wrapper_class``, or None.

    >>> from palaestra.vec_env import VecMonitor, VecNormalize, make_vec_env
    >>> venv = VecNormalize(make_vec_env("CartPole-v1", n_envs=2))
    >>> type(unwrap_vec_wrapper(venv, VecMonitor)).__name__
    'VecMonitor'
    """
    layer: VecEnv = env
    while isinstance(layer, VecEnvWrapper):
        if isinstance(layer, vec_wrapper_class):
            return layer
        layer = layer.venv
    return None


def unwrap_vec_normalize(env: VecEnv) -> VecNormalize | None:
    """The ``VecNormalize`` layer of ``env``, or None."""
    return unwrap_vec_wrapper(env, VecNormalize)


def is_vecenv_wrapped(env: VecEnv, vec_wrapper_class: type[VecEnvWrapper]) -> bool:
    """Whether some layer of ``env`` is a ``vec_wrapper_class``."""
    return unwrap_vec_wrapper(env, vec_wrapper_class) is not None


def sync_envs_normalization(env: VecEnv, eval_env: VecEnv) -> None:
    """Copy the statistics of every ``VecNormalize`` layer of ``env`` to the same layer of
    ``eval_env`` (both wrapped the same way).

    Raises ``AssertionError`` (SB3's type, which its callers catch) when ``eval_env`` is not
    wrapped like ``env``.
    """
    train_layer, eval_layer = env, eval_env
    while isinstance(train_layer, VecEnvWrapper):
        if not isinstance(eval_layer, VecEnvWrapper):
            raise AssertionError(
                "Error while synchronizing normalization stats: expected the eval env to be a "
                f"VecEnvWrapper but got {eval_layer} instead. This is probably due to the "
                "training env not being wrapped the same way as the evaluation env. Training "
                f"env type: {train_layer}."
            )
        if isinstance(train_layer, VecNormalize):
            if not isinstance(eval_layer, VecNormalize):
                raise AssertionError(
                    "Error while synchronizing normalization stats: expected the eval env to be "
                    f"a VecNormalize but got {eval_layer} instead. This is probably due to the "
                    "training env not being wrapped the same way as the evaluation env. "
                    f"Training env type: {train_layer}."
                )
            eval_layer.obs_rms = deepcopy(train_layer.obs_rms)
            eval_layer.ret_rms = deepcopy(train_layer.ret_rms)
        train_layer, eval_layer = train_layer.venv, eval_layer.venv


def check_for_nested_spaces(obs_space: spaces.Space[Any]) -> None:
    """``NotImplementedError`` (SB3's words) for a Dict/Tuple inside a Dict/Tuple: the
    algorithms store and flatten one level of keys only (SB3's ``preprocessing`` helper,
    here so that vector-env code uses it without torch)."""
    if isinstance(obs_space, spaces.Dict):
        subs: Any = obs_space.spaces.values()
    elif isinstance(obs_space, spaces.Tuple):
        subs = obs_space.spaces
    else:
        return
    for sub in subs:
        if isinstance(sub, (spaces.Dict, spaces.Tuple)):
            raise NotImplementedError(
                "Nested observation spaces are not supported (Tuple/Dict space inside "
                f"Tuple/Dict space): {obs_space}"
            )


def obs_space_info(
    obs_space: spaces.Space[Any],
) -> tuple[list[Any], dict[Any, tuple[int, ...]], dict[Any, np.dtype[Any]]]:
    """``(keys, shapes, dtypes)`` of an observation space: a Dict's keys, a Tuple's indices,
    or the one key ``None`` for any other space (SB3's helper). Nested spaces raise
    ``NotImplementedError``."""
    check_for_nested_spaces(obs_space)
    subspaces: dict[Any, spaces.Space[Any]]
    if isinstance(obs_space, spaces.Dict):
        subspaces = dict(obs_space.spaces)
    elif isinstance(obs_space, spaces.Tuple):
        subspaces = dict(enumerate(obs_space.spaces))
    elif hasattr(obs_space, "spaces"):
        raise TypeError(f"Unsupported structured space '{type(obs_space)}'")
    else:
        subspaces = {None: obs_space}
    keys = list(subspaces)
    shapes = {key: sub.shape for key, sub in subspaces.items()}
    dtypes = {key: sub.dtype for key, sub in subspaces.items()}
    return keys, shapes, dtypes  # type: ignore[return-value]


def dict_to_obs(obs_space: spaces.Space[Any], obs_dict: dict[Any, np.ndarray]) -> VecEnvObs:
    """The observation ``obs_space`` describes from ``obs_space_info``'s keyed arrays: the
    dict itself (Dict), a tuple in index order (Tuple), ``obs_dict[None]`` otherwise."""
    if isinstance(obs_space, spaces.Dict):
        return obs_dict
    if isinstance(obs_space, spaces.Tuple):
        if len(obs_dict) != len(obs_space.spaces):
            raise ValueError(
                f"size of observation does not match size of observation space: "
                f"{len(obs_dict)} keys for {obs_space}"
            )
        return tuple(obs_dict[i] for i in range(len(obs_space.spaces)))
    if set(obs_dict) != {None}:
        raise ValueError(
            "multiple observation keys for unstructured observation space: "
            f"{sorted(map(repr, obs_dict))} for {obs_space}"
        )
    return obs_dict[None]
