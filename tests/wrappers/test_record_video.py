"""RecordVideo on a toy env: triggers, file names, lengths, formats (Gymnasium 1.x semantics)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from palaestra.core import Env
from palaestra.wrappers.record_video import RecordVideo

Image = pytest.importorskip("PIL.Image")

# tmp_path exists already, so every wrapper warns that it may overwrite videos (as Gymnasium's)
pytestmark = pytest.mark.filterwarnings("ignore:.*Overwriting existing videos")


class Counter(Env):
    """Episodes of ``length`` steps; each frame shows the global step count (all distinct)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, render_mode="rgb_array", length=5):
        from palaestra.spaces import Discrete

        self.render_mode = render_mode
        self.length = length
        self.action_space = self.observation_space = Discrete(2)
        self.t = self.total = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return 0, {}

    def step(self, action):
        self.t += 1
        self.total += 1
        return 0, 1.0, self.t >= self.length, False, {}

    def render(self):
        frame = np.zeros((16, 24, 3), np.uint8)
        frame[:, :, 0] = self.total % 256  # distinct frames: Pillow would merge equal ones
        frame[:, :, 1] = self.total // 256
        frame[:, :, 2] = self.t  # a reset frame differs from the last step's
        return frame


def run_episodes(env, n):
    for _ in range(n):
        env.reset()
        done = False
        while not done:
            _, _, term, trunc, _ = env.step(0)
            done = term or trunc
    env.close()


def gif_frames(path) -> int:
    with Image.open(path) as gif:
        return gif.n_frames


@pytest.fixture(autouse=True)
def gif_only(monkeypatch):
    # Force the Pillow path so the test is the same with or without imageio-ffmpeg.
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)


def test_default_trigger_is_capped_cubic(tmp_path):
    env = RecordVideo(Counter(), str(tmp_path))
    assert env.video_format == "gif"
    run_episodes(env, 10)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["rl-video-episode-0.gif", "rl-video-episode-1.gif", "rl-video-episode-8.gif"]
    # reset frame + 5 steps
    assert gif_frames(tmp_path / "rl-video-episode-8.gif") == 6


def test_episode_trigger_and_prefix(tmp_path):
    env = RecordVideo(
        Counter(), str(tmp_path), episode_trigger=lambda e: e % 2 == 0, name_prefix="cp"
    )
    run_episodes(env, 5)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cp-episode-0.gif",
        "cp-episode-2.gif",
        "cp-episode-4.gif",
    ]


def test_step_trigger_with_video_length_spans_episodes(tmp_path):
    env = RecordVideo(Counter(), str(tmp_path), step_trigger=lambda s: s == 3, video_length=8)
    run_episodes(env, 4)
    assert [p.name for p in tmp_path.iterdir()] == ["rl-video-step-3.gif"]
    # Gymnasium stops once more than video_length frames were taken
    assert gif_frames(tmp_path / "rl-video-step-3.gif") == 9


def test_close_saves_a_recording_in_progress(tmp_path):
    env = RecordVideo(Counter(length=100), str(tmp_path), episode_trigger=lambda e: True)
    env.reset()
    for _ in range(3):
        env.step(0)
    assert env.recording
    env.close()
    assert gif_frames(tmp_path / "rl-video-episode-0.gif") == 4
    assert not env.recording


def test_fps_from_metadata_or_argument(tmp_path):
    assert RecordVideo(Counter(), str(tmp_path / "a")).frames_per_sec == 25
    env = RecordVideo(Counter(), str(tmp_path / "b"), fps=10, episode_trigger=lambda e: True)
    run_episodes(env, 1)
    with Image.open(tmp_path / "b" / "rl-video-episode-0.gif") as gif:
        assert gif.info["duration"] == 100


def test_mp4_chosen_when_ffmpeg_is_importable(tmp_path, monkeypatch):
    import types

    pytest.importorskip("imageio")
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", types.ModuleType("imageio_ffmpeg"))
    assert RecordVideo(Counter(), str(tmp_path)).video_format == "mp4"
    assert RecordVideo(Counter(), str(tmp_path), video_format="gif").video_format == "gif"


@pytest.mark.parametrize("mode", [None, "human", "ansi"])
def test_rejects_non_image_render_modes(tmp_path, mode):
    with pytest.raises(ValueError, match="incompatible with RecordVideo"):
        RecordVideo(Counter(render_mode=mode), str(tmp_path))


def test_rejects_unknown_format(tmp_path):
    with pytest.raises(ValueError, match="video_format"):
        RecordVideo(Counter(), str(tmp_path), video_format="avi")


def test_records_a_real_env_without_pygame(tmp_path):
    import palaestra

    if not hasattr(palaestra, "make"):
        pytest.skip("palaestra.make not available yet")
    env = RecordVideo(
        palaestra.make("CartPole-v1", render_mode="rgb_array"),
        str(tmp_path),
        episode_trigger=lambda e: e == 0,
    )
    env.reset(seed=0)
    for _ in range(10):
        env.step(env.action_space.sample())
    env.close()
    with Image.open(tmp_path / "rl-video-episode-0.gif") as gif:
        assert gif.size == (600, 400)
        # Pillow merges identical consecutive frames (a pole that did not move by a pixel)
        # into one longer frame, so check the playing time: 11 frames at 50 fps.
        durations = []
        for i in range(gif.n_frames):
            gif.seek(i)
            durations.append(gif.info["duration"])
    assert sum(durations) == 11 * 20


def test_records_a_frame_list_env_and_keeps_its_frames_for_the_user(tmp_path):
    from palaestra.wrappers.rendering import RenderCollection

    env = RecordVideo(RenderCollection(Counter()), str(tmp_path), episode_trigger=lambda e: True)
    env.reset()
    env.step(0)
    env.step(0)
    # the user's render() still gets every frame, although RecordVideo consumed them
    assert [int(f[0, 0, 0]) for f in env.render()] == [0, 1, 2]
    env.close()
    assert gif_frames(tmp_path / "rl-video-episode-0.gif") == 3
