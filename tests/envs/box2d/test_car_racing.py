"""CarRacing against the installed Gymnasium 1.4, plus rendering and bad input.

Physics, rewards, flags and ``info`` must be identical; the observation is a picture drawn
without pygame, and at least 97% of its pixels must equal Gymnasium's on every frame (what
differs is the score's font: ~0.5% of the 96x96 frame).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error

pytest.importorskip("Box2D")

MIN_EQUAL_PIXELS = 0.97


def _action(env: Any, rng: np.random.Generator, t: int) -> Any:
    if not env.unwrapped.continuous:
        return int(rng.integers(5))
    steer = 0.6 * np.sin(t / 15) + rng.normal(0, 0.3)
    return np.array([steer, rng.uniform(0.2, 1.0), rng.uniform(0, 0.15)], dtype=np.float32)


def run_both(kwargs: dict[str, Any], seed: int, steps: int) -> dict[str, Any]:
    """Lockstep run with resets; returns the pixel-equality shares and how episodes ended."""
    gymnasium = pytest.importorskip("gymnasium")
    pytest.importorskip("pygame")
    ours, ref = palaestra.make("CarRacing-v3", **kwargs), gymnasium.make("CarRacing-v3", **kwargs)
    obs, _ = ours.reset(seed=seed)
    ref_obs, _ = ref.reset(seed=seed)
    shares = [float((obs == ref_obs).all(axis=-1).mean())]
    rng = np.random.default_rng(seed)
    endings = []
    for t in range(steps):
        action = _action(ours, rng, t)
        obs, reward, term, trunc, info = ours.step(action)
        ref_obs, ref_reward, ref_term, ref_trunc, ref_info = ref.step(action)
        where = f"{kwargs} seed {seed} step {t}"
        assert obs.shape == (96, 96, 3) and obs.dtype == np.uint8
        assert type(reward) is float and reward == float(ref_reward), where
        assert (term, trunc) == (ref_term, ref_trunc), where
        assert info == ref_info, where
        car, ref_car = ours.unwrapped.car.hull, ref.unwrapped.car.hull
        assert (car.position.x, car.position.y, car.angle) == (
            ref_car.position.x, ref_car.position.y, ref_car.angle), where  # fmt: skip
        shares.append(float((obs == ref_obs).all(axis=-1).mean()))
        if term or trunc:
            endings.append(info.get("lap_finished"))
            obs, _ = ours.reset()
            ref_obs, _ = ref.reset()
            shares.append(float((obs == ref_obs).all(axis=-1).mean()))
    assert ours.unwrapped.tile_visited_count == ref.unwrapped.tile_visited_count
    return {"shares": np.array(shares), "endings": endings}


def test_short_parity() -> None:
    shares = run_both({}, seed=0, steps=6)["shares"]
    assert shares.min() >= MIN_EQUAL_PIXELS, shares


@pytest.mark.slow
@pytest.mark.parametrize(
    "kwargs, seed, steps",
    [
        ({}, 1, 460),
        ({"continuous": False}, 2, 300),
        ({"domain_randomize": True}, 3, 200),
        ({"lap_complete_percent": 0.0}, 4, 40),  # every step completes a "lap": resets
    ],
)
def test_long_parity(kwargs: dict[str, Any], seed: int, steps: int) -> None:
    result = run_both(kwargs, seed, steps)
    shares = result["shares"]
    print(f"{kwargs}: equal pixels min {shares.min():.4f} mean {shares.mean():.4f}")
    assert shares.min() >= MIN_EQUAL_PIXELS, shares.min()
    if kwargs.get("lap_complete_percent") == 0.0:
        assert result["endings"] and all(result["endings"])  # lap_finished=True


@pytest.mark.slow  # two resets and a 600x400 frame of the zoomed-out start: ~1-3 s
def test_frames_and_render_modes() -> None:
    env = palaestra.make("CarRacing-v3", render_mode="rgb_array")
    obs, _ = env.reset(seed=0)
    assert obs.shape == (96, 96, 3)
    frame = env.render()
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8
    colors = {tuple(c) for c in frame.reshape(-1, 3)}
    assert (0, 0, 0) in colors and (102, 204, 102) in colors  # dashboard, grass
    pixels = palaestra.make("CarRacing-v3", render_mode="state_pixels")
    first, _ = pixels.reset(seed=0)
    assert np.array_equal(pixels.render(), first)
    env.close()
    env.close()


def test_reset_options_keep_or_redraw_colours() -> None:
    env = palaestra.make("CarRacing-v3", domain_randomize=True).unwrapped
    env.reset(seed=0)
    colours = env.road_color.copy()
    env.reset(options={"randomize": False})
    assert np.array_equal(env.road_color, colours)
    env.reset()
    assert not np.array_equal(env.road_color, colours)


@pytest.mark.parametrize(
    "kwargs, action, match",
    [
        ({}, 1, r"expected shape \(3,\), got \(\) \(a discrete action given to a continuous"),
        ({}, np.zeros(2, dtype=np.float32), r"expected shape \(3,\), got \(2,\)"),
        ({}, np.array([0.0, np.nan, 0.0]), "must be finite"),
        ({"continuous": False}, np.zeros(3), r"array given to a discrete env\? use continuous"),
        ({"continuous": False}, 5, "Invalid action 5"),
    ],
)
def test_bad_actions(kwargs: dict[str, Any], action: Any, match: str) -> None:
    env = palaestra.make("CarRacing-v3", **kwargs).unwrapped
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=match):
        env.step(action)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (
            {"lap_complete_percent": 1.5},
            ValueError,
            r"lap_complete_percent must be in \[0, 1\].*got 1.5",
        ),
        ({"lap_complete_percent": -0.1}, ValueError, "got -0.1"),
        ({"lap_complete_percent": "95%"}, TypeError, "lap_complete_percent must be a real number"),
        ({"domain_randomize": "yes"}, TypeError, "domain_randomize must be a bool, got 'yes'"),
        ({"continuous": 0}, TypeError, r"continuous must be a bool, got 0 \(int\)"),
    ],
)
def test_bad_kwargs(kwargs: dict[str, Any], exc: type, match: str) -> None:
    with pytest.raises(exc, match=match):
        palaestra.make("CarRacing-v3", **kwargs)


def test_step_before_reset() -> None:
    with pytest.raises(error.ResetNeeded):
        palaestra.make("CarRacing-v3").unwrapped.step(np.zeros(3))


@pytest.mark.slow  # three 600x400 frames of the zoomed-out start: ~1-3 s
def test_human_mode_shows_video_frames(monkeypatch: pytest.MonkeyPatch) -> None:
    from palaestra.rendering import window

    shown: list[np.ndarray] = []

    class FakeWindow:
        def __init__(self, title: str, fps: int) -> None:
            assert (title, fps) == ("CarRacing-v3", 50)

        def show(self, frame: np.ndarray) -> None:
            shown.append(frame)

        def close(self) -> None:
            shown.append(np.zeros(0))

    monkeypatch.setattr(window, "HumanWindow", FakeWindow)
    env = palaestra.make("CarRacing-v3", render_mode="human")
    env.reset(seed=0)
    env.step(np.array([0.0, 1.0, 0.0], dtype=np.float32))
    # Gymnasium renders in reset, in the step reset takes, and in each step.
    assert [f.shape for f in shown] == [(400, 600, 3)] * 3
    env.close()
    assert shown[-1].size == 0
