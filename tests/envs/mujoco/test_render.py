"""MuJoCo frames against Gymnasium 1.4.0's, on the same OpenGL backend: the same bytes.

Each test draws with ``MUJOCO_GL`` as set (``egl`` or ``osmesa`` where there is no display),
or, unset, the first backend that starts; where none can start the tests skip saying why.
"""

from __future__ import annotations

import copy
import pickle
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from tests.envs.mujoco.cases import MUJOCO_IDS

import palaestra
from palaestra import error

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("mujoco")

SIZE = {"width": 160, "height": 120}


# The per-env frame check of the rest runs with the slow tests (~3 s each: a GL context each).
FAST_FRAME_IDS = {"HalfCheetah-v5", "Humanoid-v5", "Reacher-v5"}


@pytest.fixture(scope="module", autouse=True)
def backend() -> Iterator[str]:
    """The backend the frames are drawn with, set as ``MUJOCO_GL`` for both libraries (with a
    display, Gymnasium would otherwise try glfw first); skip the module where none starts."""
    env = palaestra.make("InvertedPendulum-v5", render_mode="rgb_array", **SIZE)
    env.reset(seed=0)
    try:
        env.render()
    except error.DependencyNotInstalled as e:
        pytest.skip(f"no OpenGL backend for MuJoCo's renderer: {e}")
    renderer = env.unwrapped._renderer
    assert renderer is not None
    name = str(renderer.backend)
    env.close()
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MUJOCO_GL", name)
        yield name


def frames(lib: Any, env_id: str, mode: str, steps: int = 3, **kwargs: Any) -> list[Any]:
    """The frames after reset and after each of ``steps`` fixed actions."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the settotalmass deprecation of Gymnasium's cheetah
        env = lib.make(env_id, render_mode=mode, **SIZE, **kwargs)
    env.reset(seed=4)
    out = [env.render()]
    for _ in range(steps):
        env.step(np.full(env.action_space.shape, 0.3, np.float32))
        out.append(env.render())
    env.close()
    return out


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, tuple):
        return all(_same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes())


@pytest.mark.parametrize(
    "env_id",
    [i if i in FAST_FRAME_IDS else pytest.param(i, marks=pytest.mark.slow) for i in MUJOCO_IDS],
)
def test_rgb_frames_are_gymnasiums(env_id: str) -> None:
    ours, ref = frames(palaestra, env_id, "rgb_array"), frames(gymnasium, env_id, "rgb_array")
    assert ours[0].shape == (120, 160, 3) and ours[0].dtype == np.uint8
    assert ours[0].std() > 5  # a picture, not a blank buffer
    for t, (a, b) in enumerate(zip(ours, ref, strict=True)):
        assert _same(a, b), f"{env_id} frame {t}: {np.mean(a != b):.2%} of the bytes differ"


@pytest.mark.parametrize("env_id", ["Hopper-v5", "Pusher-v5"])
@pytest.mark.parametrize("mode", ["depth_array", "rgbd_tuple"])
def test_depth_frames_are_gymnasiums(env_id: str, mode: str) -> None:
    ours, ref = frames(palaestra, env_id, mode, 1), frames(gymnasium, env_id, mode, 1)
    depth = ours[0][1] if mode == "rgbd_tuple" else ours[0]
    assert depth.shape == (120, 160) and depth.dtype == np.float32
    assert 0 <= depth.min() < depth.max() <= 1
    assert all(_same(a, b) for a, b in zip(ours, ref, strict=True))


@pytest.mark.parametrize(
    "env_id, kwargs",
    [
        ("HalfCheetah-v5", {"camera_name": "track"}),
        ("Walker2d-v5", {"camera_id": 0}),
        ("Ant-v5", {"default_camera_config": {"distance": 6.0, "elevation": -40.0}}),
        ("Reacher-v5", {"visual_options": {2: True}}),  # mjVIS_JOINT: joints drawn
    ],
)
def test_camera_and_scene_options_are_gymnasiums(env_id: str, kwargs: dict[str, Any]) -> None:
    ours, ref = (
        frames(palaestra, env_id, "rgb_array", 1, **kwargs),
        frames(gymnasium, env_id, "rgb_array", 1, **kwargs),
    )
    assert all(_same(a, b) for a, b in zip(ours, ref, strict=True))
    default = frames(palaestra, env_id, "rgb_array", 1)
    assert not _same(ours[-1], default[-1])  # the option changed the picture


def test_a_copy_draws_the_same_frame_with_its_own_context() -> None:
    env = palaestra.make("Swimmer-v5", render_mode="rgb_array", **SIZE)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frame = env.render()
    for clone in (copy.deepcopy(env), pickle.loads(pickle.dumps(env))):
        assert clone.unwrapped._renderer is None
        assert _same(clone.render(), frame)
        clone.close()
    env.close()
    env.close()  # twice is harmless


def test_render_without_a_mode_warns_and_returns_none() -> None:
    env = palaestra.make("Reacher-v5")
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert env.render() is None


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"camera_name": "nope"}, r"camera_name 'nope' is not a camera of .*\['track'\]"),
        ({"camera_id": 5}, r"camera_id 5 is not a camera of .*\[0, 1\)"),
        ({"camera_id": 0, "camera_name": "track"}, "give camera_id .* or camera_name .*not both"),
        ({"width": 0}, "width must be a positive int, got 0"),
    ],
)
def test_bad_camera_arguments_raise_naming_them(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        palaestra.make("Hopper-v5", render_mode="rgb_array", **kwargs)
