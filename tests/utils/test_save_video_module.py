"""``palaestra.utils.save_video`` at Gymnasium's path (issue 26): ``save_video(frames,
video_folder, ...)`` writes the files Gymnasium's writes (names, triggers, clip lengths), and
the module stays callable as palaestra's ``save_video(frames, path, fps)``. Gymnasium's own
function needs MoviePy (not installed): its file names and clip bounds are Gymnasium's rules,
restated here."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import palaestra.utils
from palaestra.utils.save_video import capped_cubic_video_schedule, save_video
from palaestra.utils.video import mp4_available

pytestmark = pytest.mark.skipif(not mp4_available(), reason="needs imageio-ffmpeg")


def _frames(n: int) -> list[np.ndarray]:
    return [np.full((16, 16, 3), 10 * i, dtype=np.uint8) for i in range(n)]


def _frame_count(path: Path) -> int:
    import imageio.v2 as imageio

    with imageio.get_reader(path) as reader:
        return sum(1 for _ in reader)


def test_episode_trigger_writes_gymnasiums_file(tmp_path: Path) -> None:
    save_video(_frames(10), tmp_path / "videos", fps=10, episode_index=8, video_length=4)
    written = sorted(p.name for p in (tmp_path / "videos").iterdir())
    assert written == ["rl-video-episode-8.mp4"]  # 8 is a cube: the default schedule picks it
    assert _frame_count(tmp_path / "videos" / written[0]) == 4
    save_video(_frames(10), str(tmp_path / "videos"), fps=10, episode_index=9)
    assert len(list((tmp_path / "videos").iterdir())) == 1  # 9 is not


def test_step_trigger_clips_start_after_the_reset_frame(tmp_path: Path) -> None:
    save_video(
        _frames(12),
        tmp_path,
        step_trigger=lambda step: step % 5 == 0,
        video_length=3,
        name_prefix="run",
        step_starting_index=10,
        fps=5,
    )
    # step i (from 10) is frame i - 10 + 1 (frames 1..11 are steps 10..20): steps 10, 15 and
    # 20 start clips of 3 frames, the last one cut at the end
    names = ["run-step-10.mp4", "run-step-15.mp4", "run-step-20.mp4"]
    assert sorted(p.name for p in tmp_path.iterdir()) == names
    assert [_frame_count(tmp_path / name) for name in names] == [3, 3, 1]


def test_arguments_gymnasium_passes_on_to_moviepy(tmp_path: Path) -> None:
    with pytest.raises(TypeError, match=r"needs fps="):
        save_video(_frames(2), tmp_path)
    with pytest.raises(TypeError, match=r"other MoviePy arguments \['durations'\]"):
        save_video(_frames(2), tmp_path, fps=5, durations=[1, 1])
    with pytest.raises(TypeError, match="Expected a list of frames, got a str"):
        save_video("frames", tmp_path, fps=5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="video_length must be a positive int"):
        save_video(_frames(2), tmp_path, fps=5, video_length=0)


def test_the_module_is_still_palaestras_save_video(tmp_path: Path) -> None:
    import palaestra.utils.save_video as module

    assert palaestra.utils.save_video is module
    out = palaestra.utils.save_video(_frames(3), tmp_path / "x.mp4", fps=4)
    assert out == tmp_path / "x.mp4" and _frame_count(out) == 3


def test_schedule_is_gymnasiums() -> None:
    try:
        import gymnasium.utils.save_video as gym_save_video
    except Exception as e:  # gymnasium's DependencyNotInstalled without MoviePy
        pytest.skip(f"gymnasium.utils.save_video needs MoviePy: {e}")
    for i in range(3000):
        assert capped_cubic_video_schedule(i) == gym_save_video.capped_cubic_video_schedule(i)


def test_both_imports_work_in_a_fresh_process() -> None:
    code = (
        "import palaestra.utils as u\n"
        "f = u.save_video\n"
        "from palaestra.utils.save_video import save_video\n"
        "print(callable(f), callable(u.save_video), save_video.__module__)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "True", "palaestra.utils.save_video"]
