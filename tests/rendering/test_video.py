"""save_video: GIF round trip, MP4 when imageio-ffmpeg is present, validation, missing deps."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from palaestra.error import DependencyNotInstalled
from palaestra.rendering import scenes
from palaestra.utils.video import mp4_available, save_video, validate_frames


def _frames(n: int = 5) -> list[np.ndarray]:
    return [scenes.render_mountain_car(-1.0 + 0.2 * i, 0.5) for i in range(n)]


def test_gif_round_trip(tmp_path):
    Image = pytest.importorskip("PIL.Image")
    frames = _frames(6)
    out = save_video(frames, tmp_path / "sub" / "car.gif", fps=20)
    assert out == tmp_path / "sub" / "car.gif"
    with Image.open(out) as gif:
        assert gif.n_frames == 6
        assert gif.size == (600, 400)
        assert gif.info["loop"] == 0
        assert gif.info["duration"] == 50
        gif.seek(3)
        back = np.asarray(gif.convert("RGB"))
    # the octree palette keeps colours within a few levels (white comes back as 254)
    diff = np.abs(back.astype(int) - frames[3])
    assert diff.mean() < 2.0 and (diff.max(axis=2) > 32).mean() < 0.001


def test_accepts_a_stacked_array_and_str_paths(tmp_path):
    pytest.importorskip("PIL")
    save_video(np.stack(_frames(2)), str(tmp_path / "x.GIF"))
    assert (tmp_path / "x.GIF").stat().st_size > 0


@pytest.mark.parametrize(
    ("frames", "error", "match"),
    [
        ([], ValueError, "at least one frame"),
        ([np.zeros((4, 4, 3), np.float32)], ValueError, r"expected \(H, W, 3\) uint8"),
        ([np.zeros((4, 4), np.uint8)], ValueError, "frame 0 has shape"),
        ([np.zeros((4, 4, 4), np.uint8)], ValueError, "frame 0"),
        ([np.zeros((4, 4, 3), np.uint8), np.zeros((4, 5, 3), np.uint8)], ValueError, "same size"),
        ([[[0, 0, 0]]], TypeError, "numpy array"),
    ],
)
def test_bad_frames_are_named(frames, error, match):
    with pytest.raises(error, match=match):
        validate_frames(frames)


def test_bad_suffix_and_fps(tmp_path):
    with pytest.raises(ValueError, match=r"\.gif, \.mp4"):
        save_video(_frames(1), tmp_path / "x.avi")
    with pytest.raises(ValueError, match="fps"):
        save_video(_frames(1), tmp_path / "x.gif", fps=0)
    assert not list(tmp_path.iterdir())


def test_missing_pillow_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "PIL", None)  # makes `import PIL` raise ImportError
    with pytest.raises(DependencyNotInstalled, match=r'pip install "palaestra\[video\]"'):
        save_video(_frames(1), tmp_path / "x.gif")


def test_missing_ffmpeg_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    assert not mp4_available()
    with pytest.raises(DependencyNotInstalled, match=r"imageio-ffmpeg.*palaestra\[video\]"):
        save_video(_frames(1), tmp_path / "x.mp4")


def test_mp4_when_available(tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    iio = pytest.importorskip("imageio.v2")
    out = save_video(_frames(4), tmp_path / "car.mp4", fps=10)
    reader = iio.get_reader(out)
    assert reader.get_data(0).shape == (400, 600, 3)
    assert reader.count_frames() == 4


def test_mp4_writer_call_with_a_fake_backend(tmp_path, monkeypatch):
    """The MP4 path without imageio-ffmpeg installed: check what reaches imageio."""
    import types

    iio = pytest.importorskip("imageio.v2")
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", types.ModuleType("imageio_ffmpeg"))
    calls: dict = {"frames": []}

    class FakeWriter:
        def __enter__(self):
            return self

        def __exit__(self, *exc):
            calls["closed"] = True

        def append_data(self, frame):
            calls["frames"].append(frame.shape)

    def fake_get_writer(path, **kwargs):
        calls.update(path=path, **kwargs)
        return FakeWriter()

    monkeypatch.setattr(iio, "get_writer", fake_get_writer)
    save_video(_frames(3), tmp_path / "v.mp4", fps=12)
    # ffmpeg writes a hidden temporary .mp4 beside the target, moved into place when done.
    temp = calls["path"]
    assert temp.parent == tmp_path and temp.name.startswith(".v.mp4.") and temp.suffix == ".mp4"
    assert (tmp_path / "v.mp4").exists() and not temp.exists() and calls["fps"] == 12
    assert calls["macro_block_size"] == 2 and calls["codec"] == "libx264"
    assert calls["frames"] == [(400, 600, 3)] * 3 and calls["closed"]
