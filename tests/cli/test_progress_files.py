"""The run folder's growing logs after a crash: ``episodes.csv`` and ``progress.csv`` written
by a run that was killed mid-row are resumed cleanly (the torn row cut, the header kept)."""

from __future__ import annotations

from pathlib import Path

from palaestra.runs.curves import read_episodes
from palaestra.runs.logs import AppendingCSV, EpisodeLog


def test_episode_log_header_then_resume_after_a_torn_row(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    log = EpisodeLog(path)
    assert path.read_bytes() == b"steps,return,length,terminated,time_s\r\n"  # on disk at once
    log.writer.writerow([200, -200.0, 200, 0, 1.5])
    log.close()
    with open(path, "ab") as file:
        file.write(b"350,-15")  # the process died here
    log = EpisodeLog(path)
    log.writer.writerow([400, -100.0, 200, 1, 2.5])
    log.close()
    assert path.read_bytes() == (
        b"steps,return,length,terminated,time_s\r\n200,-200.0,200,0,1.5\r\n400,-100.0,200,1,2.5\r\n"
    )
    episodes = read_episodes(tmp_path)
    assert episodes.steps.tolist() == [200, 400]
    assert episodes.times is not None and episodes.times.tolist() == [1.5, 2.5]


def test_progress_csv_resume_after_a_torn_row(tmp_path: Path) -> None:
    path = tmp_path / "progress.csv"
    first = AppendingCSV(str(path))
    first.write({"time/total_timesteps": 100, "rollout/ep_rew_mean": -200.0}, {}, 100)
    first.write({"time/total_timesteps": 200, "rollout/ep_rew_mean": -180.0}, {}, 200)
    first.close()
    with open(path, "a", encoding="utf-8") as file:
        file.write("300,-1")  # torn
    resumed = AppendingCSV(str(path))
    resumed.write({"time/total_timesteps": 300, "rollout/ep_rew_mean": -150.0}, {}, 300)
    resumed.write({"time/total_timesteps": 400, "rollout/ep_rew_mean": -120.0, "x/new": 1}, {}, 400)
    resumed.close()
    assert path.read_text(encoding="utf-8").splitlines() == [
        "time/total_timesteps,rollout/ep_rew_mean,x/new",
        "100,-200.0,",
        "200,-180.0,",
        "300,-150.0,",
        "400,-120.0,1",
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["progress.csv"]  # no temp left
