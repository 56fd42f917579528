"""Gymnasium's vector observation/action wrappers at ``palaestra.wrappers.vector``, with the
same spaces and batches as ``gymnasium.wrappers.vector`` on the same envs and seeds."""

from __future__ import annotations

import gymnasium
import gymnasium.wrappers.vector as gym_vector
import numpy as np
import pytest

import palaestra
import palaestra.wrappers.vector as ours_vector


def _dict_env(base, module):
    class DictEnv(base):
        def __init__(self):
            self.observation_space = module.Dict(
                {"a": module.Box(-1, 1, (2,), np.float32), "b": module.Discrete(3)}
            )
            self.action_space = module.Discrete(2)

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.observation_space.seed(seed)
            return self.observation_space.sample(), {}

        def step(self, action):
            return self.observation_space.sample(), 0.0, False, False, {}

    return DictEnv


def _image_env(base, module):
    class ImageEnv(base):
        def __init__(self):
            self.observation_space = module.Box(0, 255, (12, 16, 3), np.uint8)
            self.action_space = module.Discrete(2)

        def reset(self, *, seed=None, options=None):
            super().reset(seed=seed)
            self.observation_space.seed(seed)
            return self.observation_space.sample(), {}

        def step(self, action):
            return self.observation_space.sample(), 0.0, False, False, {}

    return ImageEnv


OBSERVATION_CASES = {
    "FlattenObservation": ("dict", {}),
    "FilterObservation": ("dict", {"filter_keys": ["a"]}),
    "GrayscaleObservation": ("image", {"keep_dim": True}),
    "ResizeObservation": ("image", {"shape": (6, 8)}),
    "ReshapeObservation": ("cartpole", {"shape": (2, 2)}),
    "RescaleObservation": ("pendulum", {"min_obs": 0.0, "max_obs": 1.0}),
    "DtypeObservation": ("cartpole", {"dtype": np.float64}),
}


def _envs(lib, kind):
    if kind == "cartpole":
        return lib.vector.SyncVectorEnv([lambda: lib.make("CartPole-v1")] * 3)
    if kind == "pendulum":
        return lib.vector.SyncVectorEnv([lambda: lib.make("Pendulum-v1")] * 3)
    factory = _dict_env if kind == "dict" else _image_env
    cls = factory(lib.Env, lib.spaces)
    return lib.vector.SyncVectorEnv([cls] * 3)


def _equal(a, b):
    if isinstance(b, dict):
        assert list(a) == list(b)
        for key in b:
            _equal(a[key], b[key])
    else:
        np.testing.assert_array_equal(a, b)
        assert a.dtype == b.dtype


@pytest.mark.parametrize("name", sorted(OBSERVATION_CASES))
def test_vector_observation_wrappers_match_gymnasium(name):
    kind, kwargs = OBSERVATION_CASES[name]
    ours = getattr(ours_vector, name)(_envs(palaestra, kind), **kwargs)
    theirs = getattr(gym_vector, name)(_envs(gymnasium, kind), **kwargs)
    assert str(ours.single_observation_space) == str(theirs.single_observation_space)
    assert str(ours.observation_space) == str(theirs.observation_space)
    obs, _ = ours.reset(seed=5)
    ref, _ = theirs.reset(seed=5)
    _equal(obs, ref)
    for _ in range(3):
        actions = np.array([0, 1, 0]) if kind != "pendulum" else np.zeros((3, 1), np.float32)
        obs = ours.step(actions)[0]
        ref = theirs.step(actions)[0]
        _equal(obs, ref)


class _Recorder:
    def __init__(self, lib):
        class Env(lib.Env):
            def __init__(self):
                self.observation_space = lib.spaces.Discrete(2)
                self.action_space = lib.spaces.Box(-2, 2, (2,), np.float32)
                self.last = None

            def reset(self, *, seed=None, options=None):
                return 0, {}

            def step(self, action):
                self.last = np.asarray(action)
                return 0, 0.0, False, False, {}

        self.envs = lib.vector.SyncVectorEnv([Env] * 2)


@pytest.mark.parametrize(
    ("name", "kwargs"),
    [("ClipAction", {}), ("RescaleAction", {"min_action": -1.0, "max_action": 1.0})],
)
def test_vector_action_wrappers_match_gymnasium(name, kwargs):
    ours_envs, theirs_envs = _Recorder(palaestra).envs, _Recorder(gymnasium).envs
    ours = getattr(ours_vector, name)(ours_envs, **kwargs)
    theirs = getattr(gym_vector, name)(theirs_envs, **kwargs)
    assert str(ours.single_action_space) == str(theirs.single_action_space)
    ours.reset(seed=0), theirs.reset(seed=0)
    actions = np.array([[0.5, -3.0], [1.0, 0.25]], np.float32)
    ours.step(actions.copy()), theirs.step(actions.copy())
    for mine, ref in zip(ours_envs.envs, theirs_envs.envs):
        np.testing.assert_array_equal(mine.last, ref.last)


def test_every_gymnasium_vector_observation_and_action_wrapper_is_here_or_listed():
    missing = set(gym_vector.__all__) - set(ours_vector.__all__)
    # Documented in docs/differences.md: not implemented yet.
    assert missing <= {
        "HumanRendering",
        "RecordVideo",
        "ArrayConversion",
        "JaxToNumpy",
        "JaxToTorch",
        "NumpyToTorch",
    }, missing
