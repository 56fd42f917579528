"""BipedalWalker: rendering, reward details, bad input."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error

pytest.importorskip("Box2D")


@pytest.mark.parametrize("hardcore", [False, True])
def test_rgb_array_frames_show_the_course(hardcore: bool) -> None:
    env = palaestra.make("BipedalWalker-v3", hardcore=hardcore, render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(4, dtype=np.float32))
    frame = env.render()
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8
    colors = {tuple(c) for c in frame.reshape(-1, 3)}
    for expected in [(215, 215, 255), (102, 153, 76), (255, 255, 255), (127, 51, 229)]:
        assert expected in colors  # sky, ground, clouds, hull
    env.close()
    env.close()


def test_frames_look_like_gymnasiums_and_scroll() -> None:
    gymnasium = pytest.importorskip("gymnasium")
    pytest.importorskip("pygame")
    ours = palaestra.make("BipedalWalkerHardcore-v3", render_mode="rgb_array")
    ref = gymnasium.make("BipedalWalkerHardcore-v3", render_mode="rgb_array")
    ours.reset(seed=5)
    ref.reset(seed=5)
    action = np.array([0.5, -0.5, -0.5, 0.5], dtype=np.float32)
    for _ in range(30):
        ours.step(action)
        ref.step(action)
    first = ours.render()
    assert (first == ref.render()).all(axis=-1).mean() >= 0.97
    # Further along the course (obstacles, overlapping clouds): still the same picture.
    ours.unwrapped.scroll = ref.unwrapped.scroll = 30.0
    later = ours.render()
    assert (later == ref.render()).all(axis=-1).mean() >= 0.97
    assert not np.array_equal(first, later)


def test_reward_is_computed_in_the_actions_float_type() -> None:
    """Gymnasium's torque cost runs in the action's dtype: float32 actions, float32 rewards."""
    env = palaestra.make("BipedalWalker-v3")
    env.reset(seed=0)
    reward = env.step(np.full(4, 0.3, dtype=np.float32))[1]
    assert type(reward) is float
    assert float(np.float32(reward)) == reward  # a float32 value, returned as a Python float
    env.reset(seed=0)
    reward64 = env.step(np.full(4, 0.3))[1]
    assert reward64 != reward and float(np.float32(reward64)) != reward64


@pytest.mark.parametrize(
    "action, match",
    [
        (1, r"expected shape \(4,\), got \(\) \(a discrete action given to a continuous env\?\)"),
        (np.zeros(2, dtype=np.float32), r"expected shape \(4,\), got \(2,\)"),
        (np.zeros((4, 1), dtype=np.float32), r"expected shape \(4,\), got \(4, 1\)"),
        (np.array([0.0, np.nan, 0.0, 0.0]), "must be finite"),
        (np.array([0.0, 0.0, 0.0, -np.inf], dtype=np.float32), "must be finite"),
        (["a", "b", "c", "d"], "expected real numeric values, got dtype <U1"),
    ],
)
def test_bad_actions(action: Any, match: str) -> None:
    env = palaestra.make("BipedalWalker-v3").unwrapped
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match) as info:
        env.step(action)
    assert "Box(-1.0, 1.0, (4,), float32)" in str(info.value)


def test_bad_kwargs_and_step_before_reset() -> None:
    with pytest.raises(TypeError, match=r"hardcore must be a bool, got 'yes' \(str\)"):
        palaestra.make("BipedalWalker-v3", hardcore="yes")
    with pytest.raises(error.ResetNeeded):
        palaestra.make("BipedalWalker-v3").unwrapped.step(np.zeros(4))
