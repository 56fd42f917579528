"""A toy env written once against both palaestra and gymnasium, for exact vector comparisons.

Env ``k`` (its ``length`` argument) terminates after ``length`` steps; every step's info has
an int, a float, a bool, an array, a string and a nested dict, so info stacking is exercised.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def make_counter_class(base: Any, spaces: Any) -> type:
    """A ``Counter`` env class deriving from ``base`` (palaestra.Env or gymnasium.Env)."""

    class Counter(base):  # type: ignore[misc,valid-type]
        metadata = {"render_modes": []}

        def __init__(self, length: int = 3, fail_on: int | None = None) -> None:
            self.length = length
            self.fail_on = fail_on
            self.observation_space = spaces.Box(-100, 100, shape=(2,), dtype=np.float32)
            self.action_space = spaces.Discrete(3)
            self.t = 0

        def reset(self, *, seed: int | None = None, options: dict | None = None) -> Any:
            super().reset(seed=seed)
            self.t = 0
            start = float(self.np_random.integers(10))
            self.s = start
            info = {"reset_start": start}
            if options and "offset" in options:
                info["offset"] = options["offset"]
            return np.array([self.s, 0.0], dtype=np.float32), info

        def step(self, action: Any) -> Any:
            if self.fail_on is not None and int(action) == self.fail_on:
                raise ValueError(f"boom: action {int(action)} is forbidden")
            self.t += 1
            self.s += float(action)
            terminated = self.t >= self.length
            info = {
                "t": self.t,
                "half": self.t / 2,
                "even": self.t % 2 == 0,
                "vec": np.array([self.t, -self.t]),
                "name": f"step{self.t}",
                "nested": {"a": self.t * 10},
            }
            obs = np.array([self.s, float(self.t)], dtype=np.float32)
            return obs, float(action) - 1.0, terminated, False, info

    return Counter


def pal_counter(length: int = 3, **kwargs: Any) -> Any:
    """A palaestra Counter."""
    import palaestra
    from palaestra import spaces

    return make_counter_class(palaestra.Env, spaces)(length, **kwargs)


def gym_counter(length: int = 3, **kwargs: Any) -> Any:
    """A gymnasium Counter."""
    import gymnasium
    from gymnasium import spaces

    return make_counter_class(gymnasium.Env, spaces)(length, **kwargs)


def assert_infos_equal(ours: Any, theirs: Any, path: str = "infos") -> None:
    """Same keys in the same order, same values and dtypes (object arrays compared per item)."""
    assert isinstance(ours, dict) and isinstance(theirs, dict), path
    assert list(ours) == list(theirs), f"{path}: {list(ours)} != {list(theirs)}"
    for key in theirs:
        a, b = ours[key], theirs[key]
        where = f"{path}[{key!r}]"
        if isinstance(b, dict):
            assert_infos_equal(a, b, where)
        elif isinstance(b, np.ndarray):
            assert isinstance(a, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, where
            if b.dtype == object:
                for x, y in zip(a, b):
                    if isinstance(y, dict):
                        assert_infos_equal(x, y, where)
                    else:
                        np.testing.assert_array_equal(x, y, err_msg=where)
            else:
                np.testing.assert_array_equal(a, b, err_msg=where)
        else:
            assert a == b, where
