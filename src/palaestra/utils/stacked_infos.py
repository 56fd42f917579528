"""``StackedInfos``: an engine's per-row infos kept as one array per key.

A native engine (ale-py's ``ALEVectorInterface``) hands back its infos already batched:
``{"lives": [N] int32, ...}``. Splitting them into N dicts only for :mod:`.infos` to stack them
again would cost a Python loop over rows every step. ``StackedInfos`` is still a sequence of
per-row dicts for the code that needs rows (final infos, the SB3 face's info list), and
:func:`palaestra.vector.infos.stack_infos` takes its arrays as they are.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, overload

import numpy as np


class StackedInfos(Sequence[dict[str, Any]]):
    """Row ``i``'s info is ``{key: arrays[key][i]}``, for the rows in ``rows`` (all if None).

    Rows outside ``rows`` (not reset by a partial reset) have the empty info ``{}``. Values stay
    numpy scalars, so stacking the rows again gives arrays of the same dtypes.
    """

    __slots__ = ("arrays", "num_envs", "rows")

    def __init__(
        self, arrays: dict[str, np.ndarray], num_envs: int, rows: np.ndarray | None = None
    ) -> None:
        self.arrays = arrays  # key -> [N, ...] array, one entry per row
        self.num_envs = num_envs
        self.rows = rows  # [N] bool, or None for every row

    def __len__(self) -> int:
        return self.num_envs

    @overload
    def __getitem__(self, i: int) -> dict[str, Any]: ...

    @overload
    def __getitem__(self, i: slice) -> list[dict[str, Any]]: ...

    def __getitem__(self, i: int | slice) -> dict[str, Any] | list[dict[str, Any]]:
        if isinstance(i, slice):
            return [self[j] for j in range(self.num_envs)[i]]
        if not -self.num_envs <= i < self.num_envs:
            raise IndexError(f"row {i} out of range for {self.num_envs} rows")
        if self.rows is not None and not self.rows[i]:
            return {}
        return {key: values[i] for key, values in self.arrays.items()}

    def stacked(self) -> dict[str, Any]:
        """Gymnasium's stacked form: each key's array beside its ``_key`` row mask."""
        out: dict[str, Any] = {}
        for key, values in self.arrays.items():
            if self.rows is None:
                out[key] = values
                out[f"_{key}"] = np.ones(self.num_envs, dtype=np.bool_)
            else:
                # Rows without an info read 0, as when stacking dicts (Gymnasium's rule).
                kept = np.zeros_like(values)
                kept[self.rows] = values[self.rows]
                out[key] = kept
                out[f"_{key}"] = self.rows.copy()
        return out
