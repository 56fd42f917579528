"""``AddWhiteNoise`` and ``ObstructView`` against Gymnasium's (issue 26): the same frames for the
same inner frame and seed (draws from the env's ``np_random`` in Gymnasium's order), the same
errors; grey noise stays uint8 where Gymnasium's frame widens to uint64."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error
from palaestra.wrappers import AddWhiteNoise, ObstructView
from palaestra.wrappers.render_noise import _patch_mask

gymnasium = pytest.importorskip("gymnasium")
gym_rendering = pytest.importorskip("gymnasium.wrappers.rendering")

FRAME = np.random.default_rng(0).integers(0, 256, size=(37, 53, 3), dtype=np.uint8)


def _still(lib: Any) -> Any:
    """An env of ``lib`` whose frame is FRAME, seeded 7."""

    class Still(lib.Env):
        metadata = {"render_modes": ["rgb_array"], "render_fps": 4}
        observation_space = lib.spaces.Discrete(2)
        action_space = lib.spaces.Discrete(2)
        render_mode = "rgb_array"

        def reset(self, *, seed: Any = None, options: Any = None) -> Any:
            super().reset(seed=seed)
            return 0, {}

        def step(self, action: Any) -> Any:
            return 0, 0.0, False, False, {}

        def render(self) -> np.ndarray:
            return FRAME.copy()

    env = Still()
    env.reset(seed=7)
    return env


@pytest.mark.parametrize("grey", [False, True])
@pytest.mark.parametrize("probability", [0.0, 0.3, 0.999])
def test_add_white_noise_frames_equal_gymnasiums(probability: float, grey: bool) -> None:
    ours = AddWhiteNoise(_still(palaestra), probability, is_noise_grayscale=grey)
    theirs = gym_rendering.AddWhiteNoise(_still(gymnasium), probability, is_noise_grayscale=grey)
    for _ in range(3):
        got, want = ours.render(), theirs.render()
        assert got.shape == want.shape == FRAME.shape and got.dtype == np.uint8
        np.testing.assert_array_equal(got, want)  # Gymnasium's grey frame is uint64
    if grey:
        changed = (got != FRAME).any(axis=-1)
        assert (got[changed][:, 0] == got[changed][:, 2]).all()


@pytest.mark.parametrize(("ratio", "width"), [(0.0, 1), (0.2, 1), (0.5, 4), (0.9, 9), (0.3, 60)])
@pytest.mark.parametrize("grey", [False, True])
def test_obstruct_view_frames_equal_gymnasiums(ratio: float, width: int, grey: bool) -> None:
    ours = ObstructView(_still(palaestra), ratio, width, is_noise_grayscale=grey)
    theirs = gym_rendering.ObstructView(_still(gymnasium), ratio, width, is_noise_grayscale=grey)
    for _ in range(2):
        got, want = ours.render(), theirs.render()
        assert got.dtype == np.uint8 and got.shape == want.shape
        np.testing.assert_array_equal(got, want)


def test_patch_mask_matches_painting_patch_by_patch() -> None:
    rng = np.random.default_rng(3)
    rows, cols = rng.integers(0, 20, 40), rng.integers(0, 30, 40)
    for size in (1, 2, 5, 50):
        want = np.zeros((20, 30), bool)
        low, high = size // 2, size - size // 2
        for r, c in zip(rows, cols):
            want[max(r - low, 0) : min(r + high, 20), max(c - low, 0) : min(c + high, 30)] = True
        np.testing.assert_array_equal(_patch_mask(rows, cols, size, 20, 30), want)


def test_noise_is_drawn_from_the_env_generator() -> None:
    env = AddWhiteNoise(_still(palaestra), 0.5)
    state = env.unwrapped.np_random.bit_generator.state
    env.render()
    assert env.unwrapped.np_random.bit_generator.state != state  # as Gymnasium's


@pytest.mark.parametrize("probability", [-0.1, 1.0, 2, float("nan")])
def test_add_white_noise_refuses_a_probability_outside_0_1(probability: float) -> None:
    with pytest.raises(gymnasium.error.InvalidProbability):
        gym_rendering.AddWhiteNoise(_still(gymnasium), probability)
    with pytest.raises(error.InvalidProbability, match=r"\[0,1\). Received " + repr(probability)):
        AddWhiteNoise(_still(palaestra), probability)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"obstructed_pixels_ratio": 1.0, "obstruction_width": 3}, ValueError, r"\[0,1\)"),
        ({"obstructed_pixels_ratio": -0.5, "obstruction_width": 3}, ValueError, r"-0.5"),
        ({"obstructed_pixels_ratio": 0.5, "obstruction_width": 0}, ValueError, "larger or equal"),
    ],
)
def test_obstruct_view_errors_as_gymnasium(kwargs: dict[str, Any], exc: type, match: str) -> None:
    with pytest.raises(exc):
        gym_rendering.ObstructView(_still(gymnasium), **kwargs)
    with pytest.raises(exc, match=match):
        ObstructView(_still(palaestra), **kwargs)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda env: AddWhiteNoise(env, "0.5"), "must be a real number in"),
        (lambda env: AddWhiteNoise(env, 0.5, is_noise_grayscale="yes"), "must be a bool"),
        (lambda env: ObstructView(env, 0.5, 2.5), "must be an integer number of pixels"),
        (lambda env: ObstructView(env, True, 2), "must be a real number in"),
    ],
)
def test_wrong_types_are_named(make: Any, match: str) -> None:
    with pytest.raises(TypeError, match=match):
        make(_still(palaestra))


def test_an_env_without_rgb_array_frames_is_named() -> None:
    env = AddWhiteNoise(palaestra.make("CartPole-v1"), 0.5)
    env.reset(seed=0)
    with pytest.raises(TypeError, match=r"needs env.render\(\) to return an \(H, W, C\) image"):
        with pytest.warns(UserWarning, match="without specifying any render mode"):
            env.render()


def test_on_a_real_env_with_add_render_observation() -> None:
    env = palaestra.make("CartPole-v1", render_mode="rgb_array")
    env = palaestra.wrappers.AddRenderObservation(ObstructView(env, 0.3, 20), render_only=True)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (400, 600, 3) and obs.dtype == np.uint8
    assert env.spec.additional_wrappers[0].kwargs == {
        "obstructed_pixels_ratio": 0.3,
        "obstruction_width": 20,
        "is_noise_grayscale": False,
    }
