"""``palaestra eval`` and ``palaestra record`` on the tiny trained runs."""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra.algos import DQN, PPO, evaluate_policy
from palaestra.cli.evaluate import ascii_histogram

from .conftest import Result, run_cli


class _SeedFirstReset(gym.Wrapper):  # type: ignore[type-arg]
    """The first reset gets ``seed``, later ones continue its generator."""

    def __init__(self, env: Any, seed: int) -> None:
        super().__init__(env)
        self._seed: int | None = seed

    def reset(self, *, seed: int | None = None, options: Any = None) -> Any:
        seed, self._seed = self._seed, None
        return self.env.reset(seed=seed, options=options)


def _mean_std(text: str) -> tuple[float, float]:
    match = re.search(r"^mean return: (-?[\d.]+) ± ([\d.]+)$", text, re.M)
    assert match is not None, text
    return float(match[1]), float(match[2])


def test_eval_matches_evaluate_policy(ppo_run: tuple[Path, Result]) -> None:
    out, _ = ppo_run
    result = run_cli("eval", out / "model.zip", "--episodes", 5, "--seed", 7)
    assert result.code == 0, result.err
    assert result.out.splitlines()[0] == (
        f"PPO {out / 'model.zip'} on CartPole-v1: 5 episodes, deterministic, seed 7"
    )
    mean, std = _mean_std(result.out)
    model = PPO.load(out / "model.zip")
    returns, lengths = evaluate_policy(
        model, _SeedFirstReset(gym.make("CartPole-v1"), 7), 5, return_episode_rewards=True
    )
    assert mean == pytest.approx(np.mean(returns), abs=0.005)
    assert std == pytest.approx(np.std(returns), abs=0.005)
    # The histogram counts every episode; CartPole's lengths equal its returns.
    counts = [int(line.rsplit(maxsplit=1)[-1]) for line in result.out.splitlines() if " | " in line]
    assert sum(counts) == 5
    lo, hi = min(lengths), max(lengths)
    assert f"episode lengths (min {lo}, mean {np.mean(lengths):.1f}, max {hi}):" in result.out


def test_eval_goal_env_success_rate(dqn_run: tuple[Path, Result]) -> None:
    out, _ = dqn_run
    result = run_cli("eval", out, "--episodes", 3, "--stochastic")
    assert result.code == 0, result.err
    assert "3 episodes, stochastic, seed 0" in result.out
    rate = re.search(r"^success rate: ([\d.]+)% \((\d+)/3 episodes reached the goal\)$",
                     result.out, re.M)  # fmt: skip
    assert rate is not None and 0.0 <= float(rate[1]) <= 100.0
    assert float(rate[1]) == pytest.approx(100 * int(rate[2]) / 3, abs=0.05)


def test_eval_with_env_flag_and_no_run_config(tmp_path: Path, ppo_run: tuple[Path, Result]) -> None:
    out, _ = ppo_run
    shutil.copy(out / "model.zip", tmp_path / "m.zip")  # no config.json beside it
    result = run_cli("eval", tmp_path / "m.zip", "--env", "CartPole-v1", "--episodes", 2)
    assert result.code == 0, result.err
    assert "on CartPole-v1: 2 episodes" in result.out


def test_ascii_histogram() -> None:
    assert ascii_histogram([5, 5, 5], width=3) == ["  5 | ###  3"]
    rows = ascii_histogram([1, 2, 2, 30], bins=3, width=10)
    assert rows == ["   1-10 | ##########  3", "  11-20 |             0", "  21-30 | ###         1"]


def test_record_gif_frame_count(tmp_path: Path, ppo_run: tuple[Path, Result]) -> None:
    from PIL import Image

    out, _ = ppo_run
    gif = tmp_path / "agent.gif"
    result = run_cli("record", out, "--out", gif, "--episodes", 2, "--seed", 3)
    assert result.code == 0, result.err
    model = PPO.load(out / "model.zip")
    env = _SeedFirstReset(gym.make("CartPole-v1"), 3)
    _, lengths = evaluate_policy(model, env, 2, return_episode_rewards=True)
    frames = sum(lengths) + 2  # each episode: its reset frame and one per step
    assert result.out.strip().startswith(f"wrote {gif}: {frames} frames at 50 fps, 2 episode(s)")
    # Pillow stores a run of identical frames (the cart moved less than a pixel) as one
    # longer frame, so the playing time counts the frames: 20 ms each at 50 fps.
    durations = []
    with Image.open(gif) as image:
        assert image.size == (600, 400) and 1 < image.n_frames <= frames
        for i in range(image.n_frames):
            image.seek(i)
            durations.append(image.info["duration"])
    assert sum(durations) == 20 * frames


def test_record_needs_imageio_ffmpeg_for_mp4(
    tmp_path: Path, ppo_run: tuple[Path, Result], monkeypatch: pytest.MonkeyPatch
) -> None:
    import palaestra.utils.video as video

    monkeypatch.setattr(video, "mp4_available", lambda: False)
    result = run_cli("record", ppo_run[0], "--out", tmp_path / "a.mp4")
    assert result.code == 1 and not (tmp_path / "a.mp4").exists()
    assert result.err == (
        "palaestra: error: imageio-ffmpeg is not installed, run `pip install "
        '"palaestra[video]"` (needed for writing MP4 files)\n'
    )


def test_eval_and_record_bad_input(tmp_path: Path, ppo_run: tuple[Path, Result]) -> None:
    out, _ = ppo_run
    missing = run_cli("eval", tmp_path / "nope.zip")
    assert (missing.code, missing.err) == (2, (
        f"palaestra: error: no model file at '{tmp_path / 'nope.zip'}' "
        "(pass a model.zip or a run folder written by train)\n"
    ))  # fmt: skip
    mismatch = run_cli("eval", out, "--env", "MountainCar-v0")
    assert mismatch.code == 2
    assert mismatch.err.startswith("palaestra: error: the model expects observations Box(")
    assert mismatch.err.endswith("(pass --env with the env the model was trained on)\n")
    shutil.copy(out / "model.zip", tmp_path / "m.zip")
    no_env = run_cli("eval", tmp_path / "m.zip")
    assert no_env.code == 2 and no_env.err.endswith("(pass --env ID)\n")
    (tmp_path / "bad.zip").write_bytes(b"not a zip at all")
    corrupt = run_cli("eval", tmp_path / "bad.zip", "--env", "CartPole-v1")
    assert corrupt.code == 2 and "is corrupt or not a palaestra model file" in corrupt.err
    avi = run_cli("record", out, "--out", tmp_path / "a.avi")
    assert avi.code == 2 and avi.err.endswith("(end --out in .gif or .mp4)\n")
    for result in (missing, mismatch, no_env, corrupt, avi):
        assert len(result.err.splitlines()) == 1 and "Traceback" not in result.err


def test_eval_detects_the_algorithm(dqn_run: tuple[Path, Result]) -> None:
    from palaestra.runs import load_model

    assert isinstance(load_model(dqn_run[0] / "model.zip"), DQN)


def test_normalized_run_evaluates_on_normalized_observations(tmp_path: Path) -> None:
    from palaestra.vec_env import VecNormalize, make_vec_env

    out = tmp_path / "run"
    result = run_cli("train", "ppo", "Pendulum-v1", "--timesteps", 256, "--set", "n_steps=64",
                     "--set", "batch_size=32", "--set", "normalize={'norm_reward': False}",
                     "--out", out, "--progress", "none", "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert "vecnormalize.npz" in result.out and (out / "vecnormalize.npz").is_file()
    evaluated = run_cli("eval", out, "--episodes", 1, "--seed", 5)
    assert evaluated.code == 0, evaluated.err
    stats = VecNormalize.load(str(out / "vecnormalize.npz"), make_vec_env("Pendulum-v1"))
    stats.training = False
    model, env = PPO.load(out / "model.zip"), gym.make("Pendulum-v1")
    obs, _ = env.reset(seed=5)
    total, done = 0.0, False
    while not done:
        action, _ = model.predict(stats.normalize_obs(obs), deterministic=True)
        obs, reward, terminated, truncated, _ = env.step(action)
        total, done = total + float(reward), terminated or truncated
    assert _mean_std(evaluated.out)[0] == pytest.approx(total, abs=0.005)
