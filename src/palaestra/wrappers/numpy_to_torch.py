"""Gymnasium's ``gymnasium.wrappers.numpy_to_torch`` path: ``NumpyToTorch`` and its converters.

They are written once, in :mod:`palaestra.wrappers.array_conversion`; this module gives them
Gymnasium's import path. Unlike Gymnasium's, importing it does not import torch: torch is
imported by the first conversion to it.
"""

from palaestra.wrappers.array_conversion import (
    Device,
    NumpyToTorch,
    numpy_to_torch,
    torch_to_numpy,
)

__all__ = ["Device", "NumpyToTorch", "numpy_to_torch", "torch_to_numpy"]
