"""``env_wrapper`` runs and ``compare SETTINGS... --seeds``: the tutorial's reward-shaping
study as one command, on a tiny budget."""

from __future__ import annotations

import csv
import json
from collections.abc import Callable
from pathlib import Path

import pytest
from tests.algos.tutorial_blocks import SHAPING_WRAPPERS
from tests.cli.conftest import Result

# The tutorial's shaping wrappers (one copy of its text) and its two-action wrapper.
SHAPING = (
    SHAPING_WRAPPERS
    + '''

class TwoActions(gym.ActionWrapper):
    """The tutorial's SimplifiedActionWrapper: push left or right only."""

    def __init__(self, env):
        super().__init__(env)
        self.action_space = gym.spaces.Discrete(2)

    def action(self, action):
        return 0 if action == 0 else 2
'''
)
TINY = ("--timesteps", 300, "--set", "learning_starts=100")


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder holding ``shaping_mod.py`` as the current folder (the module is imported from
    there, as from a user's project folder)."""
    import sys

    name = "shaping_mod"
    (tmp_path / f"{name}.py").write_text(SHAPING, encoding="utf-8")
    (tmp_path / "better.yaml").write_text(f"env_wrapper: {name}:BetterRewardShaping\n")
    (tmp_path / "two.json").write_text(json.dumps({"env_wrapper": [f"{name}:TwoActions"]}))
    monkeypatch.chdir(tmp_path)
    monkeypatch.delitem(sys.modules, name, raising=False)
    monkeypatch.setattr(sys, "path", list(sys.path))  # the CLI may add the current folder
    return tmp_path


def _episode_returns(run: Path) -> list[float]:
    with open(run / "episodes.csv", newline="") as f:
        return [float(row["return"]) for row in csv.DictReader(f)]


def test_train_with_env_wrapper_logs_the_true_return(
    cli: Callable[..., Result], workdir: Path
) -> None:
    out = workdir / "run"  # 4 envs x 250 steps: 4 episodes cut at 200 steps
    r = cli("train", "dqn", "MountainCar-v0", "--timesteps", 1000, "--seed", 0, "--out", out,
            "--set", "env_wrapper=shaping_mod:BetterRewardShaping",
            "--progress", "none", "--eval-episodes", 1)  # fmt: skip
    assert r.code == 0, r.err
    assert json.loads((out / "config.json").read_text())["env_wrapper"] == (
        "shaping_mod:BetterRewardShaping"
    )
    # The wrapper sits over the Monitor: the log holds MountainCar's own -1 per step.
    returns = _episode_returns(out)
    assert returns == [-200.0] * 4


def test_an_action_wrapper_is_kept_for_eval_and_record(
    cli: Callable[..., Result], workdir: Path
) -> None:
    out = workdir / "run"
    # A settings file is data as a run folder is: its module is imported when allowed.
    r = cli("train", "dqn", "MountainCar-v0", *TINY, "--config", "two.json", "--seed", 0,
            "--out", out, "--progress", "none", "--eval-episodes", 0,
            "--allow-import", "shaping_mod")  # fmt: skip
    assert r.code == 0, r.err
    # The run folder names the module; eval and record import it only when asked to.
    assert "--allow-import shaping_mod" in cli("eval", out, "--episodes", 1).err
    r = cli("eval", out, "--episodes", 1, "--allow-import", "shaping_mod")
    assert r.code == 0, r.err
    assert "mean return: -200.00" in r.out
    assert "note: importing module 'shaping_mod' for env_wrapper 'shaping_mod:TwoActions'" in r.err
    r = cli("record", out, "--out", workdir / "agent.gif", "--episodes", 1,
            "--allow-import", "shaping_mod")  # fmt: skip
    assert r.code == 0, r.err
    assert (workdir / "agent.gif").stat().st_size > 0


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("nosuchmodule_xyz:Wrap", "cannot import module 'nosuchmodule_xyz' of env_wrapper"),
        ("shaping_mod:Missing", "module 'shaping_mod' has no class 'Missing' (env_wrapper)"),
        ("shaping_mod", "env_wrapper 'shaping_mod' names no module and class"),
        ("3", "env_wrapper must be 'module:Class', got 3"),
    ],
)
def test_bad_env_wrapper_is_one_line(
    cli: Callable[..., Result], workdir: Path, value: str, message: str
) -> None:
    r = cli("train", "dqn", "MountainCar-v0", *TINY, "--set", f"env_wrapper={value}",
            "--out", workdir / "run")  # fmt: skip
    assert r.code == 2
    assert r.err.count("\n") == 1 and message in r.err, r.err
    assert not (workdir / "run").exists()


def test_compare_trains_variants_then_reuses_them(
    cli: Callable[..., Result], workdir: Path
) -> None:
    args = ("compare", "preset", "better.yaml", "--algo", "dqn", "--env", "MountainCar-v0",
            "--seeds", 0, 1, "--timesteps", 1000, "--out", "cmp.png",
            "--allow-import", "shaping_mod")  # fmt: skip
    refused = cli(*args[:-2])
    assert refused.code == 2 and "pass --allow-import shaping_mod to allow it" in refused.err
    assert not (workdir / "runs").exists()
    r = cli(*args)
    assert r.code == 0, r.err
    root = workdir / "runs" / "compare-dqn-MountainCar-v0"
    for variant in ("preset", "better"):
        for seed in (0, 1):
            assert f"{variant} seed {seed}: training -> " in r.out
            config = json.loads((root / variant / f"seed{seed}" / "config.json").read_text())
            assert config["seed"] == seed and config["n_timesteps"] == 1000
    assert "env_wrapper" not in json.loads((root / "preset/seed0/config.json").read_text())
    table = [line.split() for line in r.out.splitlines()]
    # No car reaches the flag in 250 steps: the true return of every episode is -200.
    assert ["preset", "2", "-200.00"] in [row[:3] for row in table]
    assert ["better", "2", "-200.00"] in [row[:3] for row in table]
    assert (workdir / "cmp.png").stat().st_size > 0
    again = cli(*args)
    assert again.code == 0, again.err
    assert "better seed 1: reusing" in again.out and "training ->" not in again.out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("preset", "--seeds", 0), "training the variants ['preset'] needs --algo, --env"),
        (("preset", "--algo", "dqn", "--env", "MountainCar-v0"), "needs --algo, --env and --seeds"),
        (("preset", "--algo", "dqn", "--env", "MountainCar-v0", "--seeds", 1, 1),
         "--seeds repeats a seed"),
        (("a.yaml", "sub/a.json", "--algo", "dqn", "--env", "MountainCar-v0", "--seeds", 1),
         "two variants share a name"),
        (("runs/x", "--seeds", 0), "--seeds only apply to variants to train"),
    ],
)  # fmt: skip
def test_compare_variant_errors(
    cli: Callable[..., Result], workdir: Path, args: tuple[object, ...], message: str
) -> None:
    r = cli("compare", *args)
    assert r.code == 2 and message in r.err and r.err.count("\n") == 1, r.err


def test_compare_refuses_an_unfinished_variant_run(
    cli: Callable[..., Result], workdir: Path
) -> None:
    run = workdir / "runs" / "compare-dqn-MountainCar-v0" / "preset" / "seed0"
    run.mkdir(parents=True)
    (run / "config.json").write_text("{}")
    r = cli("compare", "preset", "--algo", "dqn", "--env", "MountainCar-v0", "--seeds", 0)
    assert r.code == 2 and "holds an unfinished run" in r.err and "--resume" in r.err


def test_eval_of_a_normalized_run_with_env_wrapper_normalizes(workdir: Path) -> None:
    """An env_wrapper run is evaluated on its pipeline: the saved VecNormalize statistics must
    be applied there too, exactly as on the plain single-env path."""
    from tests.cli.conftest import run_cli

    from palaestra.algos import PPO
    from palaestra.runs import evaluate_run
    from palaestra.vec_env import VecNormalize, make_vec_env

    (workdir / "same.py").write_text(
        "import palaestra as gym\n\nclass Same(gym.Wrapper):\n    pass\n", encoding="utf-8"
    )
    out = workdir / "run"
    r = run_cli("train", "ppo", "CartPole-v1", "--timesteps", 2048, "--seed", 0, "--out", out,
                "--set", "normalize=true", "--set", "env_wrapper=same:Same",
                "--progress", "none", "--eval-episodes", 0)  # fmt: skip
    assert r.code == 0, r.err
    model = PPO.load(out / "model.zip")
    piped = evaluate_run(out, 5, seed=3, allow_import=["same"])

    import palaestra

    stats = VecNormalize.load(str(out / "vecnormalize.npz"), make_vec_env("CartPole-v1"))
    stats.training = False

    def play(normalize: bool) -> tuple[list[float], list[int]]:
        """The reference loop: one plain env, first reset seeded, observations normalized."""
        env, returns, lengths = palaestra.make("CartPole-v1"), [], []
        obs, _ = env.reset(seed=3)
        for _ in range(5):
            total, length, done = 0.0, 0, False
            while not done:
                seen = stats.normalize_obs(obs[None])[0] if normalize else obs
                obs, reward, terminated, truncated, _ = env.step(
                    model.predict(seen, deterministic=True)[0]
                )
                total, length, done = total + float(reward), length + 1, terminated or truncated
            returns.append(total)
            lengths.append(length)
            obs, _ = env.reset()
        return returns, lengths

    expected, unnormalized = play(True), play(False)
    assert piped.lengths == expected[1]
    assert piped.returns == expected[0]
    assert expected[1] != unnormalized[1]  # the statistics change what it plays
