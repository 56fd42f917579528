"""Wrappers for vector environments (``gymnasium.wrappers.vector``)."""

from palaestra.vector.wrappers.episode_stats import DictInfoToList, RecordEpisodeStatistics
from palaestra.vector.wrappers.normalize import NormalizeObservation, NormalizeReward
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
    "ClipAction",
    "ClipReward",
    "DictInfoToList",
    "DtypeObservation",
    "FilterObservation",
    "FlattenObservation",
    "GrayscaleObservation",
    "NormalizeObservation",
    "NormalizeReward",
    "RecordEpisodeStatistics",
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
