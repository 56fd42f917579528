"""What every native batch checks in the arguments of its ``reset`` and ``step``: the seeds,
one per row, and the bool masks that pick rows."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from palaestra.utils import seeding


def row_seeds(seed: int | Sequence[int | None] | None, num_envs: int) -> list[int | None]:
    """One seed per row: None for every row, an int ``s`` (row i gets ``s + i``) or N seeds."""
    return seeding.row_seeds(seed, num_envs, "Expected {num_envs} seeds, got {length}")


def row_mask(mask: np.ndarray, num_envs: int, name: str) -> np.ndarray:
    """``mask`` as a bool ``[num_envs]`` array, else ``ValueError`` naming the argument."""
    mask = np.asarray(mask)
    if mask.shape != (num_envs,) or mask.dtype != np.bool_:
        raise ValueError(f"{name} must be a bool array of shape ({num_envs},)")
    return mask
