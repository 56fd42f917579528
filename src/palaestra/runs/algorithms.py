"""The algorithms a run can train: their names, classes and hyperparameter names.

:mod:`palaestra.runs.settings` re-exports these names (``settings.ALGOS``...)."""

from __future__ import annotations

import inspect
from typing import Any

from palaestra.runs.errors import RunError

__all__ = ["ALGOS", "ALGO_CLASSES", "algo_class", "check_algo", "hyperparameter_names"]

# The algorithms the CLI trains, compares and evaluates: name -> class name in palaestra.algos.
# Adding one (sac, td3, ddpg) is one line here, plus its presets.
ALGO_CLASSES = {
    "dqn": "DQN",
    "ppo": "PPO",
    "a2c": "A2C",
    "sac": "SAC",
    "td3": "TD3",
    "ddpg": "DDPG",
}
ALGOS = tuple(ALGO_CLASSES)
# Constructor arguments the CLI sets itself (or that make no sense from a command line).
_NOT_HYPERPARAMS = {"self", "policy", "env", "_init_setup_model", "verbose", "seed", "device"}
_NOT_HYPERPARAMS |= {"tensorboard_log"}


def check_algo(algo: str) -> str:
    """``"PPO"`` -> ``"ppo"``; ``RunError`` for anything not in ``ALGOS``."""
    key = algo.lower()
    if key not in ALGOS:
        raise RunError(f"unknown algorithm {algo!r}", f"choose one of: {', '.join(ALGOS)}")
    return key


def algo_class(algo: str) -> Any:
    """The algorithm's class, e.g. ``DQN`` (imports torch)."""
    from palaestra import algos  # lazy: import-time — torch

    return getattr(algos, ALGO_CLASSES[check_algo(algo)])


def hyperparameter_names(algo: str) -> list[str]:
    """Constructor keywords that ``hyperparams`` (and ``--set``) may name."""
    params = inspect.signature(algo_class(algo).__init__).parameters
    return sorted(name for name in params if name not in _NOT_HYPERPARAMS)
