"""``AddRenderObservation`` (Gymnasium 1.x, once ``PixelObservationWrapper``): the frame as
the observation or beside it, side by side with Gymnasium's on CartPole."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra import spaces
from palaestra.core import Env
from palaestra.wrappers import AddRenderObservation

gymnasium = pytest.importorskip("gymnasium")


def _both(**kwargs: Any) -> tuple[Any, Any]:
    ours = AddRenderObservation(gym.make("CartPole-v1", render_mode="rgb_array"), **kwargs)
    theirs = gymnasium.wrappers.AddRenderObservation(
        gymnasium.make("CartPole-v1", render_mode="rgb_array"), **kwargs
    )
    return ours, theirs


@pytest.mark.parametrize(
    "kwargs",
    [{}, {"render_only": False}, {"render_only": False, "render_key": "rgb", "obs_key": "x"}],
)
def test_spaces_and_observations_as_gymnasium(kwargs: dict[str, Any]) -> None:
    ours, theirs = _both(**kwargs)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    for env in (ours, theirs):
        obs, _ = env.reset(seed=3)
        assert obs in env.observation_space
        obs2, *_ = env.step(0)
        assert obs2 in env.observation_space
    got, _ = ours.reset(seed=3)
    want, _ = theirs.reset(seed=3)
    if isinstance(want, dict):
        assert list(got) == list(want)
        state = kwargs.get("obs_key", "state")
        np.testing.assert_array_equal(got[state], want[state])  # the env's own observation
        frame = got[kwargs.get("render_key", "pixels")]
    else:
        frame = got
    assert frame.dtype == np.uint8 and frame.shape == (400, 600, 3)
    np.testing.assert_array_equal(frame, ours.render())
    assert ours.spec is not None and ours.spec.id == "CartPole-v1"


class _DictEnv(Env[Any, Any]):
    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self) -> None:
        self.render_mode = "rgb_array"
        self.observation_space = spaces.Dict({"b": spaces.Discrete(2), "a": spaces.Discrete(3)})
        self.action_space = spaces.Discrete(2)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        return {"a": 1, "b": 0}, {}

    def step(self, action: Any) -> Any:
        return {"a": 2, "b": 1}, 0.0, False, False, {}

    def render(self) -> np.ndarray:
        return np.full((2, 2, 3), 7, np.uint8)


def test_dict_observations_get_one_more_key() -> None:
    env = AddRenderObservation(_DictEnv(), render_only=False)
    assert list(env.observation_space.spaces) == ["a", "b", "pixels"]  # sorted, as Gymnasium
    obs, _ = env.reset()
    assert obs["a"] == 1 and obs["pixels"].shape == (2, 2, 3)
    with pytest.raises(ValueError, match="render_key 'a' already exists"):
        AddRenderObservation(_DictEnv(), render_only=False, render_key="a")


def test_bad_render_modes() -> None:
    with pytest.raises(ValueError, match="requires render_mode to be not None and not 'human'"):
        AddRenderObservation(gym.make("CartPole-v1"))

    class NoFrame(_DictEnv):
        def render(self) -> Any:
            return [[0]]

    with pytest.raises(TypeError, match=r"expects env.render\(\) to return a numpy array"):
        AddRenderObservation(NoFrame())
