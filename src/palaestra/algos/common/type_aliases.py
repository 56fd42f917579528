"""SB3's type aliases (``stable_baselines3.common.type_aliases``) for code that annotates
with them. Each name palaestra already has is that object (the buffers' sample tuples are
``palaestra.algos.buffers``' own, ``Schedule`` is ``palaestra.algos.schedules``'), never a
second copy; the rest are defined here with SB3's fields."""

from __future__ import annotations

from collections.abc import Callable
from enum import Enum
from typing import Any, NamedTuple, Protocol, SupportsFloat

import numpy as np
import torch

from palaestra.algos.common.buffers import (
    DictReplayBufferSamples,
    DictRolloutBufferSamples,
    ReplayBufferSamples,
    RolloutBufferSamples,
)
from palaestra.algos.common.callbacks import BaseCallback
from palaestra.algos.common.schedules import Schedule
from palaestra.core import Env
from palaestra.vec_env.base import VecEnv

__all__ = [
    "AtariResetReturn",
    "AtariStepReturn",
    "DictReplayBufferSamples",
    "DictRolloutBufferSamples",
    "GymEnv",
    "GymObs",
    "GymResetReturn",
    "GymStepReturn",
    "MaybeCallback",
    "OptimizerStateDict",
    "PolicyPredictor",
    "PyTorchObs",
    "ReplayBufferSamples",
    "RolloutBufferSamples",
    "RolloutReturn",
    "Schedule",
    "TensorDict",
    "TrainFreq",
    "TrainFrequencyUnit",
]

GymEnv = Env[Any, Any] | VecEnv
GymObs = tuple[Any, ...] | dict[str, Any] | np.ndarray | int
GymResetReturn = tuple[GymObs, dict[str, Any]]
AtariResetReturn = tuple[np.ndarray, dict[str, Any]]
GymStepReturn = tuple[GymObs, float, bool, bool, dict[str, Any]]
AtariStepReturn = tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]
TensorDict = dict[str, torch.Tensor]
OptimizerStateDict = dict[str, Any]
MaybeCallback = None | Callable[..., Any] | list[BaseCallback] | BaseCallback
PyTorchObs = torch.Tensor | TensorDict


class RolloutReturn(NamedTuple):
    """What an off-policy collection did: steps per env, episodes ended, and whether a
    callback let training go on."""

    episode_timesteps: int
    n_episodes: int
    continue_training: bool


class TrainFrequencyUnit(str, Enum):
    """``train_freq``'s unit. A ``str`` too (SB3's is a plain ``Enum``), so it equals the
    strings palaestra keeps in ``model.train_freq`` (``(4, "step")``)."""

    STEP = "step"
    EPISODE = "episode"


class TrainFreq(NamedTuple):
    """``train_freq`` as SB3 stores it: ``TrainFreq(4, TrainFrequencyUnit.STEP)``."""

    frequency: int
    unit: TrainFrequencyUnit


class PolicyPredictor(Protocol):
    """Anything with SB3's ``predict``: models and policies (``evaluate_policy`` takes one)."""

    def predict(
        self,
        observation: np.ndarray | dict[str, np.ndarray],
        state: tuple[np.ndarray, ...] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = False,
    ) -> tuple[np.ndarray, tuple[np.ndarray, ...] | None]:
        """The action for ``observation`` and the next hidden state (None: not recurrent)."""
        ...
