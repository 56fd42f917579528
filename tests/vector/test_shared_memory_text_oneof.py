"""Shared memory for ``Text`` and ``OneOf`` observations (issue 16): Gymnasium's layout and
results for ``create_shared_memory``/``write_to_shared_memory``/``read_from_shared_memory``,
and ``AsyncVectorEnv(shared_memory=True)`` giving what ``shared_memory=False`` gives."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra import spaces
from palaestra.vector import AsyncVectorEnv, SyncVectorEnv
from palaestra.vector.utils import (
    batch_space,
    create_shared_memory,
    read_from_shared_memory,
    write_to_shared_memory,
)

gym_utils = pytest.importorskip("gymnasium.vector.utils")
to_gym = pytest.importorskip("palaestra.compat").to_gymnasium_space

TEXT = spaces.Text(6, min_length=1, charset="abc")
ONEOF = spaces.OneOf([spaces.Discrete(3), spaces.Box(-1, 1, (2,))])
NESTED = spaces.Dict({"name": TEXT, "pos": spaces.Box(-1, 1, (2,)), "pick": ONEOF})


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


@pytest.mark.parametrize("space", [TEXT, ONEOF, NESTED], ids=["text", "oneof", "dict"])
def test_functions_as_gymnasium(space: Any) -> None:
    n = 3
    ours_memory = create_shared_memory(space, n=n)
    theirs_space = to_gym(space)
    theirs_memory = gym_utils.create_shared_memory(theirs_space, n=n)
    space.seed(5)
    samples = [space.sample() for _ in range(n)]
    for index, sample in enumerate(samples):
        write_to_shared_memory(space, index, sample, ours_memory)
        gym_utils.write_to_shared_memory(theirs_space, index, sample, theirs_memory)
    got = read_from_shared_memory(space, ours_memory, n=n)
    want = gym_utils.read_from_shared_memory(theirs_space, theirs_memory, n=n)
    assert _plain(got) == _plain(want) == _plain(_batched(space, samples))
    assert got in batch_space(space, n)


def _batched(space: Any, samples: list[Any]) -> Any:
    if isinstance(space, spaces.Dict):
        return {k: _batched(space[k], [s[k] for s in samples]) for k in space.spaces}
    if isinstance(space, spaces.Box):
        return np.stack(samples)
    return tuple(samples)


class _Words(gym.Env[Any, Any]):
    """Text (or OneOf) observations that change every step; episodes of 3 steps."""

    def __init__(self, space: Any = TEXT) -> None:
        # a copy each: envs in one process must not share a space's generator
        self.observation_space, self.action_space = copy.deepcopy(space), spaces.Discrete(2)
        self.t = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        if seed is not None:  # (seed(None) would draw fresh entropy)
            self.observation_space.seed(seed)
        self.t = 0
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> Any:
        self.t += 1
        return self.observation_space.sample(), 1.0, False, self.t >= 3, {}


@pytest.mark.parametrize("space", [TEXT, ONEOF, NESTED], ids=["text", "oneof", "dict"])
def test_async_shared_memory_gives_what_pipes_give(space: Any) -> None:
    runs = []
    makers = [lambda: _Words(space)] * 2
    envs = [
        AsyncVectorEnv(makers, shared_memory=True, context="fork"),
        AsyncVectorEnv(makers, shared_memory=False, context="fork"),
        SyncVectorEnv(makers),
    ]
    for env in envs:
        obs, _ = env.reset(seed=[3, 4])
        seen = [_plain(obs)]
        for _ in range(5):
            obs, *_ = env.step(np.zeros(2, dtype=np.int64))
            seen.append(_plain(obs))
        env.close()
        runs.append(seen)
    assert runs[0] == runs[1] == runs[2]
    assert len({str(step) for step in runs[0]}) > 3  # the observations do change
