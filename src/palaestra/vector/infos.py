"""Gymnasium's info stacking: per-env info dicts -> one dict of arrays with ``_key`` masks.

``{"x": 1}`` from env 2 of 4 becomes ``{"x": array([0, 0, 1, 0]), "_x": array([F, F, T, F])}``;
nested dicts stack recursively; ``final_obs`` always goes in an object array.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from palaestra.utils.stacked_infos import StackedInfos
from palaestra.vector.autoreset import Transition


def add_info(infos: dict[str, Any], env_info: dict[str, Any], i: int, n: int) -> dict[str, Any]:
    """Fold env ``i``'s info into the stacked ``infos`` (in place; also returned)."""
    for key, value in env_info.items():
        if key == "final_obs":
            array = infos.get(key)
            if array is None:
                array = np.full(n, None, dtype=object)
            array[i] = value
        elif isinstance(value, dict):
            array = add_info(infos.get(key, {}), value, i, n)
        else:
            array = infos.get(key)
            if array is None:
                # Gymnasium's rule: Python scalars and numpy numbers get a typed array (np.bool_
                # is not a np.number, so it gets an object array, as there), arrays a stacked
                # array, anything else an object array.
                kind = type(value)
                if kind in (int, float, bool) or issubclass(kind, np.number):
                    array = np.zeros(n, dtype=kind)
                elif isinstance(value, np.ndarray):
                    array = np.zeros((n, *value.shape), dtype=value.dtype)
                else:
                    array = np.full(n, None, dtype=object)
            array[i] = value
        mask = infos.get(f"_{key}")
        if mask is None:
            mask = np.zeros(n, dtype=np.bool_)
        mask[i] = True
        infos[key], infos[f"_{key}"] = array, mask
    return infos


def stack_transition_infos(t: Transition, n: int) -> dict[str, Any]:
    """The stacked infos of a step, final obs/info first for rows that ended (Gymnasium order)."""
    infos: dict[str, Any] = {}
    finals: dict[int, int] = {}
    if t.final_rows is not None:
        finals = {row: j for j, row in enumerate(t.final_rows.tolist())}
    if isinstance(t.infos, StackedInfos) and not finals:
        return t.infos.stacked()  # an engine's arrays, already one per key
    if t.infos is None:
        # Fast path (native engines): only the rows that ended carry anything.
        for row, k in finals.items():
            add_info(infos, _final(t, k), row, n)
        return infos
    for i, env_info in enumerate(t.infos):
        j = finals.get(i)
        if j is not None:
            add_info(infos, _final(t, j), i, n)
        if env_info:
            add_info(infos, env_info, i, n)
    return infos


def stack_infos(raw: Sequence[dict[str, Any]] | None, n: int) -> dict[str, Any]:
    """Stack per-env reset infos."""
    if isinstance(raw, StackedInfos):
        return raw.stacked()
    infos: dict[str, Any] = {}
    if raw is not None:
        for i, env_info in enumerate(raw):
            if env_info:
                add_info(infos, env_info, i, n)
    return infos


def _final(t: Transition, j: int) -> dict[str, Any]:
    assert t.final_obs is not None and t.final_infos is not None
    return {"final_obs": t.final_obs[j], "final_info": t.final_infos[j]}
