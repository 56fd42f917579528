"""SB3's ``check_env`` (``palaestra.algos.env_checker``) against SB3's own, env by env.

Each case is one env written once for both libraries; both checkers must give the same warnings
(same text) and raise the same error type with the same message.
"""

from __future__ import annotations

import warnings

import gymnasium
import numpy as np
import pytest
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import palaestra
from palaestra import spaces
from palaestra.algos.env_checker import check_env


def _env(base, module, obs_space, action_space, obs_fn=None, reward=0.0, seedless=False):
    obs_space, action_space = obs_space(module), action_space(module)

    class Case(base):
        metadata = {"render_modes": []}

        def __init__(self):
            self.observation_space, self.action_space = obs_space, action_space

        def _obs(self):
            if obs_fn is not None:
                return obs_fn(self.observation_space)
            return self.observation_space.sample()

        if seedless:

            def reset(self, options=None):
                return self._obs(), {}

        else:

            def reset(self, *, seed=None, options=None):
                super().reset(seed=seed)
                self.observation_space.seed(seed)
                return self._obs(), {}

        def step(self, action):
            return self._obs(), reward, False, False, {}

    return Case()


def _box(low, high, shape, dtype=np.float32):
    return lambda m: m.Box(low, high, shape, dtype)


CASES = {
    "good": (_box(-1, 1, (4,)), lambda m: m.Discrete(2), {}),
    "unnormalized float64 action": (_box(-1, 1, (4,)), _box(0, 2, (2,), np.float64), {}),
    "infinite action bounds": (_box(-1, 1, (4,)), _box(-np.inf, np.inf, (2,)), {}),
    "image float32": (_box(0, 1, (3, 20, 20)), lambda m: m.Discrete(2), {}),
    "image channels last": (_box(0, 255, (40, 40, 3), np.uint8), lambda m: m.Discrete(2), {}),
    "2d box": (_box(-1, 1, (4, 4)), lambda m: m.Discrete(2), {}),
    "non-zero start": (lambda m: m.Discrete(3, start=1), lambda m: m.Discrete(2, start=-1), {}),
    "nested dict": (
        lambda m: m.Dict({"a": m.Dict({"b": m.Discrete(2)}), "c": m.Box(-1, 1, (2,))}),
        lambda m: m.Discrete(2),
        {},
    ),
    "tuple obs": (lambda m: m.Tuple((m.Discrete(2), m.Discrete(3))), lambda m: m.Discrete(2), {}),
    "sequence obs": (lambda m: m.Sequence(m.Discrete(2)), lambda m: m.Discrete(2), {}),
    "dict action": (_box(-1, 1, (2,)), lambda m: m.Dict({"a": m.Discrete(2)}), {}),
    "2d multidiscrete": (lambda m: m.MultiDiscrete([[2, 3], [2, 2]]), lambda m: m.Discrete(2), {}),
    "obs out of bounds": (
        _box(-1, 1, (3,)),
        lambda m: m.Discrete(2),
        {"obs_fn": lambda s: np.array([0.0, 2.0, -3.0], np.float32)},
    ),
    "obs wrong shape": (
        _box(-1, 1, (3,)),
        lambda m: m.Discrete(2),
        {"obs_fn": lambda s: np.zeros(2, np.float32)},
    ),
    "obs not an array": (
        _box(-1, 1, (2,)),
        lambda m: m.Discrete(2),
        {"obs_fn": lambda s: [0.0, 0.0]},
    ),
    "nan obs": (
        _box(-np.inf, np.inf, (2,)),
        lambda m: m.Discrete(2),
        {"obs_fn": lambda s: np.array([np.nan, 0.0], np.float32)},
    ),
    "inf obs (VecCheckNan)": (
        _box(-np.inf, np.inf, (2,)),
        lambda m: m.Discrete(2),
        {"obs_fn": lambda s: np.array([np.inf, 0.0], np.float32)},
    ),
    "numpy reward": (_box(-1, 1, (2,)), lambda m: m.Discrete(2), {"reward": np.float32(1.0)}),
    "reset without seed": (_box(-1, 1, (2,)), lambda m: m.Discrete(2), {"seedless": True}),
}


def _outcome(checker, env):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            checker(env)
            error = None
        except (AssertionError, TypeError) as e:
            error = (type(e).__name__, str(e).replace("gymnasium", "palaestra"))
    messages = [
        " ".join(str(w.message).split())  # SB3 wraps some messages across lines
        for w in caught
        if "passive_env_checker" not in str(w.filename) and "WARN:" not in str(w.message)
    ]
    return messages, error


@pytest.mark.parametrize("case", sorted(CASES))
def test_sb3_check_env_matches_sb3(case):
    obs_space, action_space, kwargs = CASES[case]
    ours = _outcome(check_env, _env(palaestra.Env, spaces, obs_space, action_space, **kwargs))
    theirs = _outcome(
        sb3_check_env, _env(gymnasium.Env, gymnasium.spaces, obs_space, action_space, **kwargs)
    )
    assert ours == theirs
    if case == "good":
        assert ours == ([], None)
    if case == "inf obs (VecCheckNan)":
        assert ours[0] and ours[0][0].startswith("found inf in observations")


def test_a_gymnasium_env_is_refused_with_the_adapter_named():
    with pytest.raises(AssertionError, match=r"palaestra\.compat\.from_gymnasium"):
        check_env(gymnasium.make("CartPole-v1"))


def test_builtin_envs_pass():
    for env_id in ("CartPole-v1", "MountainCarContinuous-v0", "Pendulum-v1"):
        env = palaestra.make(env_id)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped, warn=False)
