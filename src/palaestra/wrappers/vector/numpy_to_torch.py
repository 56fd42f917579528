"""Gymnasium's ``gymnasium.wrappers.vector.numpy_to_torch`` path for the vector ``NumpyToTorch``
(written in :mod:`palaestra.wrappers.vector.array_conversion`); torch is imported on first use."""

from palaestra.wrappers.vector.array_conversion import NumpyToTorch

__all__ = ["NumpyToTorch"]
