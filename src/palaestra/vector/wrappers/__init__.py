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

__all__ = [
    "ClipReward",
    "DictInfoToList",
    "NormalizeObservation",
    "NormalizeReward",
    "RecordEpisodeStatistics",
    "TransformAction",
    "TransformObservation",
    "TransformReward",
    "VectorizeTransformAction",
    "VectorizeTransformObservation",
    "VectorizeTransformReward",
]
