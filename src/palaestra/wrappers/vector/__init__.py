"""Wrappers for vector environments, at Gymnasium's path (``gymnasium.wrappers.vector``).

``from palaestra.wrappers.vector import DictInfoToList`` works as the Gymnasium import does, and
``palaestra.wrappers.vector`` is an attribute of ``palaestra.wrappers`` read on first use. They
sit under ``wrappers/`` because most are built on the single-env wrappers; ``palaestra.vector``
(the vector envs) imports none of them. ``ArrayConversion`` and ``NumpyToTorch`` are loaded on
first use (they may import torch).
"""

from typing import Any

from palaestra.wrappers.vector.episode_stats import DictInfoToList, RecordEpisodeStatistics
from palaestra.wrappers.vector.normalize import NormalizeObservation, NormalizeReward
from palaestra.wrappers.vector.rendering import HumanRendering, RecordVideo
from palaestra.wrappers.vector.transforms import (
    ClipReward,
    TransformAction,
    TransformObservation,
    TransformReward,
    VectorizeTransformAction,
    VectorizeTransformObservation,
    VectorizeTransformReward,
)
from palaestra.wrappers.vector.vectorize import (
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


def __getattr__(name: str) -> Any:  # PEP 562 module attribute
    if name in LAZY_NAMES:
        from palaestra.wrappers.vector import array_conversion  # lazy: import-time — torch

        return getattr(array_conversion, name)
    raise AttributeError(f"module 'palaestra.wrappers.vector' has no attribute {name!r}")
