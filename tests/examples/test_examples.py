"""Each example's ``--quick`` mode runs in a fresh interpreter, exits 0, prints its figures and
writes its files."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
NUMBER = r"-?\d[\d,]*(?:\.\d+)?"


def run_example(name: str, *args: str | Path) -> str:
    """stdout of ``python examples/<name> --quick *args``; fails with stderr on a non-zero exit."""
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / name), "--quick", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_every_example_has_a_docstring_with_how_to_run() -> None:
    for path in sorted(EXAMPLES.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        assert text.startswith('"""'), f"{path.name} has no module docstring"
        assert f"examples/{path.name}" in text.split('"""')[1], f"{path.name}: how to run it?"


def test_custom_env(tmp_path: Path) -> None:
    from PIL import Image

    out = run_example("custom_env.py", "--out", tmp_path)
    assert "check_env: GridTargetEnv passes" in out
    assert "observation space: Box(0.0, 1.0, (4,), float32)" in out
    assert "action space: Discrete(4)" in out
    assert "spec: max_episode_steps=50" in out
    assert re.search(rf"PPO +mean return +{NUMBER}, reached the target in \d+%", out), out
    assert re.search(rf"random mean return +{NUMBER}", out), out
    with Image.open(tmp_path / "episode.gif") as gif:
        assert gif.size == (160, 160) and gif.n_frames >= 2


def test_reward_shaping(tmp_path: Path) -> None:
    from PIL import Image

    out = run_example("reward_shaping.py", "--out", tmp_path)
    for variant in ("baseline", "naive", "progress"):
        played = re.findall(rf"^  {variant} +seed \d: return +({NUMBER}), success", out, re.M)
        assert len(played) == 2, out
        row = (
            rf"^{variant} +2 +({NUMBER}) \[ *({NUMBER}), *({NUMBER})\] +\d+% +{NUMBER}  "
            rf"({NUMBER}) ({NUMBER})$"
        )
        match = re.search(row, out, re.M)
        assert match, out
        value, low, high, *per_seed = match.groups()
        assert per_seed == played
        # Two seeds: the IQM is their mean and the 95% percentile bootstrap their [min, max]
        # (the same floats, printed alike), never the t-interval's impossible returns.
        seeds = sorted(float(v) for v in played)
        assert [float(low), float(high)] == seeds
        assert float(value) == pytest.approx(sum(seeds) / 2, abs=0.051)
    assert re.search(r"^variant +seeds +IQM return \[95% CI\] +success +train s  ", out, re.M)
    assert (
        "(return: each seed's mean over its 5 evaluation episodes; IQM: interquartile mean "
        "(25% trimmed mean; the plain mean below 4 seeds), over seeds; CI: percentile "
        "bootstrap over seeds (scipy.stats.bootstrap), 9,999 resamples, none with one seed)\n"
    ) in out
    with Image.open(tmp_path / "learning_curves.png") as png:
        assert png.format == "PNG" and png.size[0] > 300


def test_vectorized_training() -> None:
    out = run_example("vectorized_training.py")
    for n_envs in (1, 8, 64, 256):
        assert re.search(rf"^ +{n_envs} +{NUMBER} +{NUMBER} +{NUMBER}x$", out, re.M), out
    for name in ("DummyVecEnv", "native"):
        assert re.search(rf"^{name} +{NUMBER} +{NUMBER} +{NUMBER}$", out, re.M), out
    # Seeded alike, the native batch and the loop give the same episodes, hence the same agent.
    assert "same trained weights from both vec envs: True" in out


def test_tabular_mountain_car(tmp_path: Path) -> None:
    from PIL import Image

    out = run_example("tabular_mountain_car.py", "--out", tmp_path)
    assert re.search(rf"^trained on 200,000 MountainCar steps in {NUMBER} s", out, re.M), out
    greedy = rf"greedy policy over 100 episodes: success (\d+)%, mean length ({NUMBER})"
    match = re.search(greedy, out)
    assert match, out
    assert 0 <= int(match[1]) <= 100 and 1 <= float(match[2]) <= 200
    with Image.open(tmp_path / "mountain_car.gif") as gif:
        assert gif.size == (600, 400) and gif.n_frames >= 2
    with Image.open(tmp_path / "learning_curve.png") as png:
        assert png.format == "PNG"


def test_robot_arm_sac() -> None:
    out = run_example("robot_arm_sac.py")
    assert re.search(
        rf"SAC, 300 steps in {NUMBER} s: reaches the target in \d+% of 3 test episodes "
        r"\(random actions: \d+%\)",
        out,
    ), out


def _robot_arm() -> Any:
    sys.path.insert(0, str(EXAMPLES))
    try:
        import robot_arm_sac
    finally:
        sys.path.remove(str(EXAMPLES))
    return robot_arm_sac


def test_reaching_arm_passes_check_env_and_rewards_reaching() -> None:
    from palaestra.utils.env_checker import check_env

    env = _robot_arm().ReachingArm()
    check_env(env)
    env.reset(seed=0)
    env.angles[:] = 0.0  # arm stretched along x: elbow (0.4, 0), wrist (0.7, 0), tip (0.9, 0)
    env.target[:] = (0.5, 0.3)
    obs, reward, terminated, truncated, info = env.step(np.zeros(3, np.float32))
    np.testing.assert_allclose(obs[6:12], [0.4, 0, 0.7, 0, 0.9, 0], atol=1e-7)
    np.testing.assert_allclose(obs[12:], [0.5, 0.3, -0.4, 0.3], atol=1e-7)
    assert not terminated and not truncated and not info["is_success"]
    assert reward == pytest.approx(-(1.0 + 0.5))  # the step cost plus the distance
    env.target[:] = (0.9, 0.02)
    _, reward, terminated, truncated, info = env.step(np.zeros(3, np.float32))
    assert terminated and not truncated and info["is_success"] and reward == 0.0


@pytest.mark.slow
def test_robot_arm_sac_reaches_the_target() -> None:
    """The example's full run: SAC's deterministic policy reaches >= 90% of 100 test targets."""
    arm = _robot_arm()
    model = arm.train(arm.STEPS)
    rate = arm.success_rate(lambda obs: model.predict(obs, deterministic=True)[0], 100, 10_000)
    rng = np.random.default_rng(0)
    random_rate = arm.success_rate(lambda _: rng.uniform(-1, 1, 3), 100, 10_000)
    assert rate >= 0.9 and random_rate <= 0.1, (rate, random_rate)


def test_tabular_q_learning(tmp_path: Path) -> None:
    from PIL import Image

    out = run_example("tabular_q_learning.py", "--out", tmp_path)
    for env_id in ("FrozenLake-v1", "Taxi-v4"):
        head = rf"^{env_id}: trained on [\d,]+ steps \(64 envs\) in {NUMBER} s, [\d,]+ episodes$"
        assert re.search(head, out, re.M), out
    # Seeded, so the figures are fixed; the exact expected returns come from the P tables.
    assert re.search(r"expected 0\.7\d\d \(optimum 0\.744, threshold 0\.7\): solved", out), out
    assert re.search(r"expected 7\.930 \(optimum 7\.930, threshold 8\): solved", out), out
    with Image.open(tmp_path / "learning_curves.png") as png:
        assert png.format == "PNG" and png.size[0] > 500
