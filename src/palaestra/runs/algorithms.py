"""The registry of the algorithms a run can train: one line per algorithm.

Everything outside an algorithm's own package reads the algorithm list from here: the CLI
(``--algo`` choices, ``compare``), run folders and checkpoints (whether a replay buffer is saved
with the model), the presets and the tests that iterate over every algorithm. Reading it
imports no torch: a line names its class by ``module:qualname`` and the class is imported only
by :func:`algo_class`. :mod:`palaestra.runs.settings` re-exports the derived names
(``settings.ALGOS``, ``ALGO_CLASSES``, ``REPLAY_ALGOS``).

Adding an algorithm (QR-DQN, for example) is:

1. a new package ``palaestra/algos/qrdqn/`` holding its class, policies and objective, and its
   hyperparameter rules in ``qrdqn/hyperparams.py`` (a ``declare_rules("QRDQN", ...)`` call of
   ``palaestra.algos.common.hyperparams``, imported by the package's ``__init__``);
2. one registration line below: ``Algorithm("qrdqn", "palaestra.algos.qrdqn:QRDQN", replay=True)``;
3. its presets and its own tests; the shared tests pick it up from :data:`REGISTRY`.

``replay`` says whether the algorithm learns from a replay buffer (an off-policy algorithm,
whose buffer is saved with each checkpoint) or from rollouts; a test checks it against the
class (``OffPolicyAlgorithm`` subclass or not).
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any, NamedTuple

from palaestra.runs.errors import RunError

__all__ = [
    "ALGOS",
    "ALGO_CLASSES",
    "REGISTRY",
    "REPLAY_ALGOS",
    "Algorithm",
    "algo_class",
    "check_algo",
    "hyperparameter_names",
]


class Algorithm(NamedTuple):
    """One registered algorithm: its CLI name, its class as ``module:qualname`` and whether it
    learns from a replay buffer (True) or from rollouts (False)."""

    name: str
    ref: str
    replay: bool

    @property
    def class_name(self) -> str:
        return self.ref.partition(":")[2]


# The algorithms the CLI trains, compares and evaluates, in the order the CLI lists them.
REGISTRY: tuple[Algorithm, ...] = (
    Algorithm("dqn", "palaestra.algos.dqn:DQN", replay=True),
    Algorithm("ppo", "palaestra.algos.ppo:PPO", replay=False),
    Algorithm("a2c", "palaestra.algos.a2c:A2C", replay=False),
    Algorithm("sac", "palaestra.algos.sac:SAC", replay=True),
    Algorithm("td3", "palaestra.algos.td3:TD3", replay=True),
    Algorithm("ddpg", "palaestra.algos.ddpg:DDPG", replay=True),
    Algorithm("qrdqn", "palaestra.algos.qrdqn:QRDQN", replay=True),
)
_BY_NAME = {entry.name: entry for entry in REGISTRY}
# name -> class name in palaestra.algos
ALGO_CLASSES = {entry.name: entry.class_name for entry in REGISTRY}
ALGOS = tuple(ALGO_CLASSES)
# Off-policy algorithms: their replay buffer is saved with each checkpoint and the final model.
REPLAY_ALGOS = tuple(entry.name for entry in REGISTRY if entry.replay)
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
    module, _, qualname = _BY_NAME[check_algo(algo)].ref.partition(":")
    return getattr(importlib.import_module(module), qualname)  # lazy: import-time — torch


def hyperparameter_names(algo: str) -> list[str]:
    """Constructor keywords that ``hyperparams`` (and ``--set``) may name."""
    params = inspect.signature(algo_class(algo).__init__).parameters
    return sorted(name for name in params if name not in _NOT_HYPERPARAMS)
