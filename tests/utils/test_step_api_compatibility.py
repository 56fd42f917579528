"""``palaestra.utils.step_api_compatibility`` converts as Gymnasium's does (side by side on
the same step returns, single and vector, list and dict infos)."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from palaestra.utils import step_api_compatibility as ours

theirs = pytest.importorskip("gymnasium.utils.step_api_compatibility")

T, F = True, False
CASES: list[tuple[tuple[Any, ...], bool]] = [
    ((0, 1.0, F, {}), F),
    ((0, 1.0, T, {}), F),
    ((0, 1.0, T, {"TimeLimit.truncated": True}), F),
    ((0, 1.0, F, F, {}), F),
    ((0, 1.0, T, F, {"a": 1}), F),
    ((0, 1.0, F, T, {}), F),
    ((0, 1.0, T, T, {}), F),
    ((np.zeros(3), np.ones(3), np.array([T, F, T]), [{}, {}, {"TimeLimit.truncated": T}]), T),
    (
        (
            np.zeros(3),
            np.ones(3),
            np.array([T, F, T]),
            {"TimeLimit.truncated": np.array([F, F, T])},
        ),
        T,
    ),
    ((np.zeros(2), np.ones(2), np.array([F, F]), {}), T),
    ((np.zeros(3), np.ones(3), np.array([T, F, F]), np.array([T, F, T]), [{}, {}, {}]), T),
    ((np.zeros(3), np.ones(3), np.array([T, F, F]), np.array([T, F, T]), {}), T),
    ((np.zeros(2), np.ones(2), np.array([F, F]), np.array([F, F]), {}), T),
]


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return ("array", value.dtype.kind, value.tolist())
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_plain(v) for v in value)
    return value


@pytest.mark.parametrize(("returns", "vector"), CASES)
@pytest.mark.parametrize("new_api", [True, False])
def test_conversions_equal_gymnasium(returns: tuple[Any, ...], vector: bool, new_api: bool) -> None:
    mine = ours.step_api_compatibility(copy.deepcopy(returns), new_api, is_vector_env=vector)
    want = theirs.step_api_compatibility(copy.deepcopy(returns), new_api, is_vector_env=vector)
    assert _plain(mine) == _plain(want)
    assert len(mine) == (5 if new_api else 4)


def test_bad_returns() -> None:
    with pytest.raises(ValueError, match=r"must have 4 items .* or 5 .* got 3"):
        ours.step_api_compatibility((0, 1.0, {}))
    with pytest.raises(TypeError, match="expects `infos` to be a list or dict"):
        ours.convert_to_terminated_truncated_step_api((0, 0, np.array([F]), "info"), True)
    with pytest.raises(TypeError, match="expects `infos` to be a list or dict"):
        ours.convert_to_done_step_api((0, 0, np.array([F]), np.array([F]), 7), True)
