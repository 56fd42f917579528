"""SAME_STEP ``final_obs`` is what the sub-env returned, as in Gymnasium (issue 16, item 9).

A Graph observation stays a ``GraphInstance`` in the space, a Python int stays an int, a Text a
str, a Tuple a tuple: the sync engine and the pickling process engine hand on the env's own
object (a copy), not a row rebuilt from the batch.
"""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import palaestra as gym
from palaestra import spaces
from palaestra.vector import AsyncVectorEnv, SyncVectorEnv


def _space(module, kind):
    if kind == "graph":
        return module.Graph(module.Box(0, 1, (2,)), module.Discrete(3))
    if kind == "discrete":
        return module.Discrete(5)
    if kind == "text":
        return module.Text(6)
    return module.Tuple((module.Discrete(4), module.Box(-1, 1, (2,))))


def _env_class(base, module, kind):
    class Ends(base):
        def __init__(self):
            self.observation_space = _space(module, kind)
            self.action_space = module.Discrete(2)

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.observation_space.seed(seed)
            return self.observation_space.sample(), {}

        def step(self, action):
            return self.observation_space.sample(), 0.0, True, False, {}

    return Ends


def _same(a, b):
    """Equal values, and the same kind of object (ours vs Gymnasium's class names)."""
    assert type(a).__name__ == type(b).__name__, (a, b)
    if isinstance(b, tuple):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    elif isinstance(b, np.ndarray):
        np.testing.assert_array_equal(a, b)
        assert a.dtype == b.dtype
    else:
        assert a == b


@pytest.mark.parametrize("kind", ["graph", "discrete", "text", "tuple"])
def test_sync_same_step_final_obs_is_the_envs_object_as_gymnasium(kind):
    ours_cls = _env_class(gym.Env, spaces, kind)
    theirs_cls = _env_class(gymnasium.Env, gymnasium.spaces, kind)
    ours = SyncVectorEnv([ours_cls] * 2, autoreset_mode="SameStep")
    theirs = gymnasium.vector.SyncVectorEnv(
        [theirs_cls] * 2, autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP
    )
    ours.reset(seed=3), theirs.reset(seed=3)
    _, _, _, _, info = ours.step(np.array([0, 1]))
    _, _, _, _, ref = theirs.step(np.array([0, 1]))
    assert info["final_obs"].dtype == ref["final_obs"].dtype == object
    for mine, their in zip(info["final_obs"], ref["final_obs"]):
        _same(mine, their)
        assert mine in ours.single_observation_space


def test_async_without_shared_memory_hands_on_graph_instances():
    cls = _env_class(gym.Env, spaces, "graph")
    envs = AsyncVectorEnv([cls] * 2, shared_memory=False, context="fork", autoreset_mode="SameStep")
    envs.reset(seed=0)
    _, _, _, _, info = envs.step(np.array([0, 1]))
    assert all(type(g).__name__ == "GraphInstance" for g in info["final_obs"])
    assert all(g in envs.single_observation_space for g in info["final_obs"])
    envs.close()
