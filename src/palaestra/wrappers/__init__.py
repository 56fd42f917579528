"""Standard wrappers, imported on first use so that ``import palaestra`` stays fast.

Each public name maps to the submodule that defines it; ``palaestra.wrappers.TimeLimit`` imports
``palaestra.wrappers.common`` the first time it is read.
"""

from __future__ import annotations

import importlib
from typing import Any

from palaestra.error import DeprecatedWrapper

# name -> submodule of palaestra.wrappers that defines it
_LAZY: dict[str, str] = {
    # applied by make()
    "TimeLimit": "common",
    "OrderEnforcing": "common",
    "PassiveEnvChecker": "common",
    # episode bookkeeping
    "Autoreset": "episode_stats",
    "RecordEpisodeStatistics": "episode_stats",
    "Monitor": "monitor",
    # observations
    "TransformObservation": "transform_observation",
    "FilterObservation": "transform_observation",
    "FlattenObservation": "transform_observation",
    "GrayscaleObservation": "transform_observation",
    "ReshapeObservation": "transform_observation",
    "RescaleObservation": "transform_observation",
    "DtypeObservation": "transform_observation",
    "AddRenderObservation": "transform_observation",
    "DiscretizeObservation": "discretize",
    "ResizeObservation": "resize",
    "DelayObservation": "stateful_observation",
    "TimeAwareObservation": "stateful_observation",
    "NormalizeObservation": "stateful_observation",
    "MaxAndSkipObservation": "stateful_observation",
    "FrameStackObservation": "frame_stack",
    "AtariPreprocessing": "atari_preprocessing",
    "AtariWrapper": "atari",  # SB3's; its parts are in palaestra.wrappers.atari
    # actions
    "TransformAction": "transform_action",
    "ClipAction": "transform_action",
    "RescaleAction": "transform_action",
    "DiscretizeAction": "discretize",
    "StickyAction": "stateful_action",
    "RepeatAction": "stateful_action",
    # rewards
    "TransformReward": "transform_reward",
    "ClipReward": "transform_reward",
    "NormalizeReward": "stateful_reward",
    # array modules (torch imported on first use)
    "ArrayConversion": "array_conversion",
    "NumpyToTorch": "array_conversion",
    # rendering
    "RecordVideo": "record_video",
    "RenderCollection": "rendering",
    "HumanRendering": "rendering",
    "AddWhiteNoise": "rendering",
    "ObstructView": "rendering",
}

# Names that Gymnasium 0.x had, and what Gymnasium 1.x (and palaestra) call them.
_RENAMED: dict[str, str] = {
    "AutoResetWrapper": "Autoreset",
    "FrameStack": "FrameStackObservation",
    "PixelObservationWrapper": "AddRenderObservation",
    "VectorListInfo": "vector.DictInfoToList",
}

# "vector" as in Gymnasium's list: the submodule of vector wrappers, loaded on first use
__all__ = sorted([*_LAZY, "vector"])


def __getattr__(name: str) -> Any:  # PEP 562 module attribute, not wrapper forwarding
    if name == "vector":  # gymnasium.wrappers.vector: the submodule re-exporting them
        value = importlib.import_module("palaestra.wrappers.vector")  # lazy: import-time — vector
        globals()[name] = value
        return value
    module = _LAZY.get(name)
    if name in _RENAMED:
        # Gymnasium's words. An ImportError (DeprecatedWrapper), not an AttributeError, so that
        # `from palaestra.wrappers import FrameStack` shows them too: Python replaces an
        # AttributeError there with a bare "cannot import name".
        raise DeprecatedWrapper(f"{name!r} has been renamed with `wrappers.{_RENAMED[name]}`")
    if module is None:
        raise AttributeError(f"module 'palaestra.wrappers' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"palaestra.wrappers.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | {"vector"})
