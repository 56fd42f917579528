"""Vector ``HumanRendering`` and ``RecordVideo`` side by side with Gymnasium's (issue 16).

Both libraries get the same frames: Gymnasium's wrappers wrap a ``gymnasium`` vector env of
palaestra envs (``palaestra.compat.to_gymnasium``). Gymnasium's need OpenCV (resizing) and
MoviePy (writing), not installed here: stand-ins for those two modules resize with
palaestra's filter and record the frames, so what is compared is the tiling, the triggers
and the episode bookkeeping."""

from __future__ import annotations

import sys
import types
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra.utils import video
from palaestra.vector import AutoresetMode, SyncVectorEnv
from palaestra.wrappers.vector import HumanRendering, RecordVideo
from palaestra.wrappers.vector.rendering import _scale

gymnasium = pytest.importorskip("gymnasium")
pygame = pytest.importorskip("pygame")
to_gymnasium = pytest.importorskip("palaestra.compat").to_gymnasium


def _ours(n: int, mode: AutoresetMode = AutoresetMode.NEXT_STEP) -> Any:
    return SyncVectorEnv(
        [lambda: gym.make("CartPole-v1", render_mode="rgb_array")] * n, autoreset_mode=mode
    )


def _theirs(n: int, mode: Any = None) -> Any:
    mode = mode or gymnasium.vector.AutoresetMode.NEXT_STEP
    return gymnasium.vector.SyncVectorEnv(
        [lambda: to_gymnasium(gym.make("CartPole-v1", render_mode="rgb_array"))] * n,
        autoreset_mode=mode,
    )


@pytest.fixture
def fake_cv2_and_moviepy(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, list[Any]]]:
    """cv2.resize through palaestra's filter; moviepy's clip records (path, frames)."""
    cv2 = types.ModuleType("cv2")
    cv2.resize = lambda image, size: _scale(image, size[1], size[0])  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "cv2", cv2)
    written: list[tuple[str, list[Any]]] = []

    class Clip:
        def __init__(self, frames: list[Any], fps: float) -> None:
            self.frames = [np.array(f) for f in frames]

        def write_videofile(self, path: str, logger: Any = None) -> None:
            written.append((Path(path).stem, self.frames))

    for name in ("moviepy", "moviepy.video", "moviepy.video.io"):
        monkeypatch.setitem(sys.modules, name, types.ModuleType(name))
    clip_module = types.ModuleType("moviepy.video.io.ImageSequenceClip")
    clip_module.ImageSequenceClip = Clip  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "moviepy.video.io.ImageSequenceClip", clip_module)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    return written


@pytest.mark.filterwarnings("ignore:.*opens no window")
@pytest.mark.parametrize(("n", "screen_size"), [(4, None), (3, (300, 400)), (5, (900, 700))])
def test_human_rendering_tiles_as_gymnasium(
    fake_cv2_and_moviepy: Any, monkeypatch: pytest.MonkeyPatch, n: int, screen_size: Any
) -> None:
    shown: list[np.ndarray] = []
    make_surface = pygame.surfarray.make_surface
    monkeypatch.setattr(
        pygame.surfarray, "make_surface", lambda a: shown.append(np.array(a)) or make_surface(a)
    )
    theirs = gymnasium.wrappers.vector.HumanRendering(_theirs(n), screen_size=screen_size)
    theirs.metadata["render_fps"] = 1000
    theirs.reset(seed=1)
    theirs.step(np.zeros(n, dtype=np.int64))
    theirs.close()
    ours = HumanRendering(_ours(n), screen_size=screen_size, backend="matplotlib")
    ours.reset(seed=1)
    first = ours.tiled_frame()
    ours.step(np.zeros(n, dtype=np.int64))
    second = ours.tiled_frame()
    ours.close()
    assert (ours.num_rows, ours.num_cols) == (theirs.num_rows, theirs.num_cols)
    assert ours.scaled_subenv_size == theirs.scaled_subenv_size
    # Gymnasium's merged array is (width, height, 3): the window's picture transposed. (The
    # stand-in resizes Gymnasium's transposed frames: float sums in another order, +-1.)
    for ours_frame, theirs_frame in [(first, shown[0]), (second, shown[1])]:
        diff = ours_frame.astype(int) - theirs_frame.transpose(1, 0, 2).astype(int)
        assert np.abs(diff).max() <= 1 and np.count_nonzero(diff) < 10
    assert ours.render_mode == "human" and "human" in ours.metadata["render_modes"]


@pytest.mark.filterwarnings("ignore:.*autoreset mode is same-step")
@pytest.mark.parametrize("mode", ["NEXT_STEP", "SAME_STEP"])
@pytest.mark.parametrize(
    "kwargs",
    [
        {"episode_trigger": lambda e: e % 2 == 0},
        {"step_trigger": lambda s: s % 15 == 0, "video_length": 7},
        {"episode_trigger": lambda e: True, "video_length": 5},
        {"record_first_only": True, "video_aspect_ratio": (16, 9)},
    ],
)
def test_record_video_as_gymnasium(
    fake_cv2_and_moviepy: Any,
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    mode: str,
    kwargs: dict[str, Any],
) -> None:
    written = fake_cv2_and_moviepy
    saved: list[tuple[str, list[Any]]] = []
    monkeypatch.setattr(
        video, "save_video", lambda frames, path, fps: saved.append((Path(path).stem, frames))
    )
    theirs = gymnasium.wrappers.vector.RecordVideo(
        _theirs(2, getattr(gymnasium.vector.AutoresetMode, mode)), str(tmp_path / "g"), **kwargs
    )
    ours = RecordVideo(_ours(2, getattr(AutoresetMode, mode)), str(tmp_path / "p"), **kwargs)
    for env in (theirs, ours):
        env.reset(seed=2)
        rng = np.random.default_rng(0)
        for _ in range(40):  # a few episodes of env 0
            env.step(rng.integers(0, 2, size=2))
        env.close()
    assert [name for name, _ in saved] == [name for name, _ in written] and saved
    for (name, mine), (_, reference) in zip(saved, written):
        assert len(mine) == len(reference), name
        for a, b in zip(mine, reference):
            np.testing.assert_array_equal(a, b)


def test_record_video_writes_files(tmp_path: Path) -> None:
    env = RecordVideo(
        SyncVectorEnv([lambda: gym.make("CartPole-v1", render_mode="rgb_array")] * 2),
        str(tmp_path),
        step_trigger=lambda s: s == 0,
        video_length=3,
        video_format="gif",
    )
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(2, dtype=np.int64))
    env.close()
    assert [p.name for p in tmp_path.iterdir()] == ["rl-video-step-0.gif"]


def test_bad_render_modes() -> None:
    with pytest.raises(ValueError, match=r"Expected env\.render_mode to be one of"):
        HumanRendering(SyncVectorEnv([lambda: gym.make("CartPole-v1")]))
    with pytest.raises(ValueError, match="incompatible with RecordVideo"):
        RecordVideo(SyncVectorEnv([lambda: gym.make("CartPole-v1")]), "unused")
