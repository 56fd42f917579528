"""Finding and syncing ``VecEnvWrapper`` layers (``stable_baselines3.common.vec_env``'s helpers).

``sync_envs_normalization`` is what ``EvalCallback`` calls before each evaluation, so that an
evaluation env under its own ``VecNormalize`` scales observations with the training env's
statistics instead of its own (which never update: evaluation envs have ``training=False``).
"""

from __future__ import annotations

from copy import deepcopy
from typing import TypeVar

from palaestra.vec_env.base import VecEnv, VecEnvWrapper
from palaestra.vec_env.normalize import VecNormalize

__all__ = [
    "is_vecenv_wrapped",
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
