"""Wrappers for vector environments (``gymnasium.wrappers.vector``).

``ArrayConversion`` and ``NumpyToTorch`` are loaded on first use (they may import torch).
"""

from typing import Any

from palaestra.vector.wrappers.episode_stats import DictInfoToList, RecordEpisodeStatistics
from palaestra.vector.wrappers.normalize import NormalizeObservation, NormalizeReward
from palaestra.vector.wrappers.rendering import HumanRendering, RecordVideo
from palaestra.vector.wrappers.transforms import (
    ClipReward,
    TransformAction,
    TransformObservation,
    TransformReward,
    VectorizeTransformAction,
    VectorizeTransformObservation,
    VectorizeTransformReward,
)
from palaestra.vector.wrappers.vectorize import (
    ClipAction,
    DtypeObservation,
    FilterObservation,
    FlattenObservation,
    GrayscaleObservation,
    RescaleAction,
    RescaleObservation,
    ReshapeObservation,
    ResizeObservation,
)

__all__ = [
    "ArrayConversion",
    "ClipAction",
    "ClipReward",
    "DictInfoToList",
    "DtypeObservation",
    "FilterObservation",
    "FlattenObservation",
    "GrayscaleObservation",
    "HumanRendering",
    "NormalizeObservation",
    "NormalizeReward",
    "NumpyToTorch",
    "RecordEpisodeStatistics",
    "RecordVideo",
    "RescaleAction",
    "RescaleObservation",
    "ReshapeObservation",
    "ResizeObservation",
    "TransformAction",
    "TransformObservation",
    "TransformReward",
    "VectorizeTransformAction",
    "VectorizeTransformObservation",
    "VectorizeTransformReward",
]


LAZY_NAMES = ("ArrayConversion", "NumpyToTorch")


def __getattr__(name: str) -> Any:  # PEP 562: keep torch out of `import palaestra.vector`
    if name in LAZY_NAMES:
        from palaestra.vector.wrappers import array_conversion

        return getattr(array_conversion, name)
    raise AttributeError(f"module 'palaestra.vector.wrappers' has no attribute {name!r}")
