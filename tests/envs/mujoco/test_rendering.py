"""Rendering of the MuJoCo envs: frames against Gymnasium 1.4.0's, depth, cameras, errors.

The frames of all eleven envs (and of the camera and frame keywords) must equal Gymnasium's
byte for byte when both draw on the same OpenGL backend: each library draws in its own
interpreter (palaestra's with ``gymnasium`` blocked) with the same ``MUJOCO_GL``. The backend is
``MUJOCO_GL`` when set (CI sets ``egl``, see ``.ci/run``): then rendering must work and no test
here skips. Otherwise ``egl`` or ``osmesa``, whichever works; only where neither does are these
tests skipped, saying why.
"""

from __future__ import annotations

import copy
import functools
import os
import pickle
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.envs.mujoco.frames import CASES, MUJOCO_IDS

import palaestra
from palaestra import error

mujoco = pytest.importorskip("mujoco")

ROOT = Path(__file__).resolve().parents[3]
PACKAGE = ROOT / "src" / "palaestra"

_PROBE = "from mujoco.{0} import GLContext; c = GLContext(8, 8); c.make_current(); c.free()"


@functools.cache
def gl_backend() -> str:
    """The ``MUJOCO_GL`` value both libraries render with here, or skip saying why not."""
    chosen = os.environ.get("MUJOCO_GL")
    if chosen:
        return chosen  # chosen on purpose (CI): a broken backend must fail the tests
    answers = []
    for backend in ("egl", "osmesa"):
        probe = subprocess.run(
            [sys.executable, "-c", _PROBE.format(backend)],
            env={**os.environ, "MUJOCO_GL": backend},
            capture_output=True,
            text=True,
            timeout=120,
        )
        if probe.returncode == 0:
            return backend
        answers.append(f"{backend}: {probe.stderr.strip().splitlines()[-1:]}")
    pytest.skip(
        "no headless OpenGL backend works here and MUJOCO_GL is unset ("
        + "; ".join(answers)
        + "): install libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri (see .ci/system-deps)"
    )


@pytest.fixture
def gl(monkeypatch: pytest.MonkeyPatch) -> str:
    """Render in this process on :func:`gl_backend`."""
    backend = gl_backend()
    monkeypatch.setenv("MUJOCO_GL", backend)
    return backend


def _draw(backend: str, which: str, folder: Path) -> list[dict[str, np.ndarray]]:
    """Both sides' frames, drawn at once in two interpreters."""
    env = {**os.environ, "MUJOCO_GL": backend, "PYTHONPATH": f"{PACKAGE.parent}{os.pathsep}{ROOT}"}
    outs = [folder / f"{side}-{which}.npz" for side in ("palaestra", "gymnasium")]
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "tests.envs.mujoco.frames", side, str(out), which],
            env=env,
            cwd=folder,  # MuJoCo writes MUJOCO_LOG.TXT where it runs (Gymnasium's Ant warns)
        )
        for side, out in zip(("palaestra", "gymnasium"), outs)
    ]
    for proc in procs:
        assert proc.wait(timeout=900) == 0, proc.args
    result = []
    for out in outs:
        with np.load(out) as data:
            result.append({key: data[key] for key in data.files})
    return result


_drawn: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {}


def drawn(which: str, folder: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``which`` (fast or slow) cases of ``frames.CASES`` drawn by palaestra and by
    Gymnasium, once per test session."""
    pytest.importorskip("gymnasium")
    if which not in _drawn:
        ours, theirs = _draw(gl_backend(), which, folder)
        _drawn[which] = ours, theirs
    return _drawn[which]


@pytest.fixture(scope="module")
def frames_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("frames")


def test_palaestra_side_is_palaestra(frames_folder: Path) -> None:
    ours, _ = drawn("fast", frames_folder)
    assert str(ours["package"]).startswith(str(PACKAGE))
    assert list(ours["gymnasium_loaded"]) == []
    assert str(ours["backend"]) == gl_backend()


@pytest.mark.parametrize(
    "case",
    [pytest.param(name, marks=[pytest.mark.slow] if slow else []) for name, _, _, slow in CASES],
)
def test_frames_equal_gymnasium(case: str, frames_folder: Path) -> None:
    slow = {name: is_slow for name, _, _, is_slow in CASES}[case]
    ours, theirs = drawn("slow" if slow else "fast", frames_folder)
    keys = sorted(k for k in theirs if k.startswith(case + "/"))
    assert keys and keys == sorted(k for k in ours if k.startswith(case + "/"))
    for key in keys:
        a, b = ours[key], theirs[key]
        assert (a.shape, a.dtype) == (b.shape, b.dtype), key
        differ = np.count_nonzero(a != b)
        assert differ == 0, f"{key}: {differ} of {a.size} values differ"
    first, last = ours[keys[0]], ours[keys[-1]]
    if first.dtype == np.uint8:  # a picture, not a blank: many colours, and the steps moved it
        assert len(np.unique(first.reshape(-1, 3), axis=0)) > 20
    assert not np.array_equal(first, last) or case.startswith("Pusher"), case


def _make(env_id: str = "Hopper-v5", **kwargs: Any) -> Any:
    return palaestra.make(env_id, render_mode="rgb_array", **kwargs)


@pytest.mark.usefixtures("gl")
def test_rgb_and_depth_arrays() -> None:
    env = _make()
    env.reset(seed=0)
    rgb = env.render()
    assert rgb.shape == (480, 480, 3) and rgb.dtype == np.uint8 and rgb.flags.c_contiguous
    env.close()
    env = palaestra.make("Hopper-v5", render_mode="depth_array", width=200, height=120)
    env.reset(seed=0)
    depth = env.render()
    assert depth.shape == (120, 200) and depth.dtype == np.float32 and depth.flags.c_contiguous
    assert 0.0 < depth.min() < depth.max() <= 1.0
    env.close()
    env = palaestra.make("Hopper-v5", render_mode="rgbd_tuple")
    env.reset(seed=0)
    pair = env.render()
    assert isinstance(pair, tuple) and [a.shape for a in pair] == [(480, 480, 3), (480, 480)]
    np.testing.assert_array_equal(pair[0], rgb)
    env.close()


@pytest.mark.usefixtures("gl")
def test_depth_to_meters_is_the_distance_along_the_view() -> None:
    """The middle pixel's depth, in meters, is how far the camera's axis runs to the first geom
    it meets (MuJoCo's ``mj_ray``): 1.9400 against 1.9406 with llvmpipe's depth buffer, which
    resolves about 0.3 mm there (0.1% is allowed; far objects resolve worse)."""
    from palaestra.envs.mujoco.rendering import depth_to_meters

    env = palaestra.make("InvertedPendulum-v5", render_mode="depth_array", width=201, height=201)
    env.reset(seed=0)
    depth = env.render()
    unwrapped = env.unwrapped
    camera = unwrapped._renderer._gl["scene"].camera[0]  # where MuJoCo drew from
    eye = np.asarray(camera.pos, dtype=np.float64)
    forward = np.asarray(camera.forward, dtype=np.float64)
    geom = np.zeros(1, np.int32)
    hit = mujoco.mj_ray(unwrapped.model, unwrapped.data, eye, forward, None, 1, -1, geom)
    assert hit > 0 and geom[0] >= 0
    meters = depth_to_meters(depth, unwrapped.model)
    assert meters.dtype == np.float64 and meters.shape == depth.shape
    assert meters[100, 100] == pytest.approx(hit, rel=1e-3)
    assert meters.max() > 10 * hit  # the background is far away
    env.close()


@pytest.mark.usefixtures("gl")
def test_camera_arguments() -> None:
    def frame(**kwargs: Any) -> np.ndarray:
        env = _make(**kwargs)
        env.reset(seed=1)
        image = env.render()
        env.close()
        return image

    default = frame()
    np.testing.assert_array_equal(frame(camera_id=-1), default)
    track = frame(camera_name="track")
    np.testing.assert_array_equal(frame(camera_id=0), track)
    assert not np.array_equal(track, default)
    assert not np.array_equal(frame(default_camera_config={"distance": 1.5}), default)
    assert frame(width=64, height=40).shape == (40, 64, 3)


@pytest.mark.parametrize(
    ("kwargs", "kind", "message"),
    [
        (
            {"camera_id": 0, "camera_name": "track"},
            ValueError,
            "Both `camera_id` and `camera_name` cannot be specified at the same time "
            "(got camera_id=0, camera_name='track').",
        ),
        (
            {"camera_name": "side"},
            ValueError,
            "camera_name='side': the model has no camera of that name (its named cameras: "
            "['track']; camera_id=-1 is the free camera)",
        ),
        (
            {"camera_id": 1},
            ValueError,
            "camera_id=1 is out of range: the model has 1 camera(s) ['track'], so camera_id "
            "must be in [-1, 0] (-1 is the free camera)",
        ),
        ({"camera_id": -2}, ValueError, "camera_id=-2 is out of range"),
        ({"camera_id": "0"}, TypeError, "camera_id must be an int, got '0'"),
        ({"camera_name": 0}, TypeError, "camera_name must be a str, got 0"),
        ({"width": 0}, ValueError, "width must be >= 1, got 0"),
        ({"height": 2.5}, TypeError, "height must be an int, got 2.5"),
        ({"max_geom": -1}, ValueError, "max_geom must be >= 1, got -1"),
        (
            {"default_camera_config": {"zoom": 2}},
            ValueError,
            "default_camera_config has unknown key(s) ['zoom']",
        ),
        (
            {"default_camera_config": {"lookat": [1, 2]}},
            ValueError,
            "default_camera_config={'lookat': [1, 2]} cannot be applied",
        ),
        ({"default_camera_config": 3}, TypeError, "default_camera_config must be a dict"),
        ({"visual_options": {99: True}}, ValueError, "visual_options key 99 is not a MuJoCo"),
        ({"visual_options": {"com": True}}, ValueError, "visual_options key 'com' is not"),
        ({"render_mode": "rgb"}, error.UnsupportedMode, "render_mode='rgb' is not one of"),
    ],
)
def test_bad_render_arguments(kwargs: dict[str, Any], kind: type, message: str) -> None:
    """Checked when the env is made, whatever the render mode; no GL needed."""
    with pytest.raises(kind) as info:
        palaestra.make("Hopper-v5", **kwargs)
    assert str(info.value).startswith(message)


def test_envs_without_cameras_name_none() -> None:
    with pytest.raises(ValueError, match=r"its named cameras: \[\]"):
        palaestra.make("Reacher-v5", camera_name="track")
    with pytest.raises(ValueError, match=r"the model has 0 camera\(s\) \[\], so camera_id"):
        palaestra.make("Pusher-v5", camera_id=0)


def test_bad_mujoco_gl(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "vulkan")
    env = _make()
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match=r"^MUJOCO_GL='vulkan' is not an OpenGL backend"):
        env.render()
    env.close()


def test_render_without_mode_warns() -> None:
    env = palaestra.make("Hopper-v5")
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert env.render() is None
    env.close()


def test_render_modes_metadata() -> None:
    env = palaestra.make("Swimmer-v5")
    assert env.metadata["render_modes"] == ["human", "rgb_array", "depth_array", "rgbd_tuple"]
    assert env.metadata["render_fps"] == 25
    env.close()


@pytest.mark.usefixtures("gl")
def test_close_frees_and_a_later_frame_reopens() -> None:
    env = _make()
    env.reset(seed=0)
    first = env.render()
    renderer = env.unwrapped._renderer
    assert renderer._gl is not None
    env.close()
    assert renderer._gl is None
    env.close()  # twice is harmless
    np.testing.assert_array_equal(env.render(), first)
    env.close()


@pytest.mark.usefixtures("gl")
@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copies_render_the_same_frames(how: str) -> None:
    """A copy draws with its own GL resources and keeps the free camera where the original
    put it on its first frame (HalfCheetah's look-at point is where the geoms were then)."""
    env = palaestra.make("HalfCheetah-v5", render_mode="rgb_array")
    env.reset(seed=2)
    env.render()  # fixes the camera
    env.action_space.seed(0)
    for _ in range(30):
        env.step(env.action_space.sample())
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    assert twin.unwrapped._renderer._gl is None
    np.testing.assert_array_equal(twin.render(), env.render())
    action = np.full(env.action_space.shape, 0.5, np.float32)
    env.step(action)
    twin.step(action)
    np.testing.assert_array_equal(twin.render(), env.render())
    assert twin.unwrapped._renderer._gl is not env.unwrapped._renderer._gl
    twin.close()
    env.close()


@pytest.mark.usefixtures("gl")
def test_two_envs_render_in_turn() -> None:
    """Each frame makes its own env's context current."""
    a, b = _make(), _make("Walker2d-v5")
    a.reset(seed=0)
    b.reset(seed=0)
    alone = [a.render(), b.render()]
    for _ in range(2):
        np.testing.assert_array_equal(a.render(), alone[0])
        np.testing.assert_array_equal(b.render(), alone[1])
    a.close()
    b.close()


@pytest.mark.usefixtures("gl")
def test_human_shows_every_reset_and_step(monkeypatch: pytest.MonkeyPatch) -> None:
    import palaestra.envs.rendered as rendered

    shown: list[tuple[str, int, np.ndarray]] = []

    class Window:
        def __init__(self, title: str, fps: int) -> None:
            self.title, self.fps = title, fps

        def show(self, frame: np.ndarray) -> None:
            shown.append((self.title, self.fps, frame))

        def close(self) -> None:
            shown.append(("closed", 0, np.zeros(0)))

    monkeypatch.setattr(rendered.window, "HumanWindow", Window)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = palaestra.make("InvertedPendulum-v5", render_mode="human")
    reference = palaestra.make("InvertedPendulum-v5", render_mode="rgb_array")
    expected = []
    for e in (env, reference):
        e.reset(seed=3)
        if e is reference:
            expected.append(e.render())
        for _ in range(2):
            e.step(np.array([0.4], np.float32))
            if e is reference:
                expected.append(e.render())
    assert [(t, f) for t, f, _ in shown] == [("InvertedPendulum-v5", 25)] * 3
    for (_, _, frame), want in zip(shown, expected, strict=True):
        np.testing.assert_array_equal(frame, want)
    assert env.render() is None
    env.close()
    assert shown[-1][0] == "closed"
    reference.close()


def test_human_without_a_display_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    import palaestra.envs.mujoco.rendering as rendering

    monkeypatch.setattr(rendering.platform, "system", lambda: "Linux")
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(name, raising=False)
    with pytest.raises(error.UnsupportedMode, match=r"^render_mode='human' needs a display"):
        palaestra.make("Hopper-v5", render_mode="human")


def test_every_env_is_covered() -> None:
    fast = {env_id for _, env_id, kwargs, slow in CASES if not slow}
    assert fast == set(MUJOCO_IDS)  # the default suite draws every env


@pytest.mark.slow
@pytest.mark.usefixtures("gl")
def test_record_writes_a_trained_agent(tmp_path: Path) -> None:
    """``palaestra train`` a tiny PPO on InvertedPendulum-v5, then ``palaestra record`` it to
    a GIF and an MP4 of MuJoCo's frames: one per step plus the reset's, at the env's 25 fps."""
    from PIL import Image
    from tests.cli.conftest import run_cli

    run = tmp_path / "run"
    trained = run_cli(
        *("train", "ppo", "InvertedPendulum-v5", "--timesteps", 2048, "--n-envs", 1),
        *("--set", "n_steps=512", "--seed", 0, "--out", run, "--progress", "none"),
    )
    assert trained.code == 0, trained.err
    gif = tmp_path / "agent.gif"
    result = run_cli("record", run, "--out", gif, "--seed", 7)
    assert result.code == 0, result.err
    frames = int(result.out.split(": ")[1].split()[0])
    assert result.out.startswith(f"wrote {gif}: {frames} frames at 25 fps, 1 episode(s)")
    with Image.open(gif) as image:
        assert image.size == (480, 480) and 1 < image.n_frames <= frames
        image.seek(0)
        first = np.asarray(image.convert("RGB"))
    env = palaestra.make("InvertedPendulum-v5", render_mode="rgb_array")
    env.reset(seed=7)
    reset_frame = env.render()
    env.close()
    # GIF's palette rounds colours: the reset frame, to within the palette's error
    assert np.abs(first.astype(int) - reset_frame.astype(int)).mean() < 3.0
    mp4 = tmp_path / "agent.mp4"
    result = run_cli("record", run, "--out", mp4, "--seed", 7)
    assert result.code == 0, result.err
    assert result.out.startswith(f"wrote {mp4}: {frames} frames at 25 fps")
    assert mp4.stat().st_size > 1000
