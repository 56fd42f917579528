"""``palaestra train --eval-freq N --eval-episodes K``: evaluations during training
(``evaluations.csv``, ``best_model.zip``, the evaluation series of the learning curve), continued
by ``--resume``; and the smaller train items of issue 24: the ``--timesteps`` aliases, a
progress total that is the real end of the run, the note on a preset that fell short."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from palaestra import presets
from palaestra.algos.callbacks import BaseCallback
from palaestra.cli import build_parser, progress, train
from palaestra.runs import RunSpec, evaluate_run, open_resume, open_run
from palaestra.runs import curves as curves_mod
from palaestra.runs.checkpoint import trim_logs
from palaestra.runs.errors import RunError

from .conftest import Result, run_cli

# PPO on CartPole with 2 envs: rollouts of 32 x 2 = 64 steps; 4 evaluations of 3 episodes.
PPO_EVAL = ("train", "ppo", "CartPole-v1", "--n-envs", 2, "--timesteps", 512, "--seed", 0,
            "--set", "batch_size=64", "--eval-freq", 128, "--eval-episodes", 3,
            "--progress", "none")  # fmt: skip


SMALL = {"n_steps": 32, "batch_size": 64}  # rollouts of 64 steps with 2 envs


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def _evaluations(run: Path) -> list[tuple[int, list[float]]]:
    return [
        (int(r["timesteps"]), [float(x) for x in r["returns"].split()])
        for r in _rows(run / "evaluations.csv")
    ]


def _untimed(run: Path) -> list[dict[str, str]]:
    return [{k: v for k, v in r.items() if k != "time_s"} for r in _rows(run / "episodes.csv")]


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Result]:
    out = tmp_path_factory.mktemp("eval") / "run"
    result = run_cli(*PPO_EVAL, "--out", out)
    assert result.code == 0, result.err
    return out, result


def test_evaluations_csv_counts_steps_over_all_envs(evaluated: tuple[Path, Result]) -> None:
    run, result = evaluated
    rows = _rows(run / "evaluations.csv")
    assert list(rows[0]) == ["timesteps", "mean_return", "std_return", "mean_length", "returns"]
    assert [int(r["timesteps"]) for r in rows] == [128, 256, 384, 512]  # env steps, 2 envs
    for row in rows:
        returns = [float(x) for x in row["returns"].split()]
        assert len(returns) == 3
        assert float(row["mean_return"]) == pytest.approx(np.mean(returns), abs=1e-12)
        assert float(row["std_return"]) == pytest.approx(np.std(returns), abs=1e-12)
        assert float(row["mean_length"]) == pytest.approx(np.mean(returns))  # CartPole: 1/step
    config = json.loads((run / "config.json").read_text())
    assert config["evaluation"] == {"every": 128, "episodes": 3}
    means = [float(r["mean_return"]) for r in rows]
    best = int(np.argmax(means))
    assert (
        f"evaluations during training: 4, the last {means[-1]:.2f} at 512 steps, the best "
        f"{means[best]:.2f} at {rows[best]['timesteps']} steps (best_model.zip)"
    ) in result.out
    assert "evaluations.csv, best_model.zip" in result.out
    # The eval env is seeded 0 before every evaluation, as `palaestra eval` seeds: the final
    # evaluation (3 episodes, seed 0) of the model at 512 steps replays the last row.
    assert f"mean return: {means[-1]:.2f} ± {float(rows[-1]['std_return']):.2f}" in result.out


def test_best_model_is_the_best_evaluation(evaluated: tuple[Path, Result]) -> None:
    run, _ = evaluated
    rows = _evaluations(run)
    means = [np.mean(r) for _, r in rows]
    assert len(set(means)) > 1  # the best is not simply the first or the last by chance
    best = rows[int(np.argmax(means))]
    replay = evaluate_run(run / "best_model.zip", 3, seed=0)
    assert replay.returns == best[1]
    from palaestra.algos import PPO

    assert PPO.load(run / "best_model.zip").num_timesteps == best[0]


def test_evaluations_change_nothing_in_training(
    evaluated: tuple[Path, Result], tmp_path: Path
) -> None:
    """Deterministic evaluation draws from no generator the training uses."""
    plain = tmp_path / "plain"
    args = [a for a in PPO_EVAL if a not in ("--eval-freq", 128)]
    result = run_cli(*args, "--out", plain)
    assert result.code == 0, result.err
    assert not (plain / "evaluations.csv").exists() and not (plain / "best_model.zip").exists()
    assert "evaluation" not in json.loads((plain / "config.json").read_text())
    assert _untimed(plain) == _untimed(evaluated[0])
    from palaestra.algos import PPO

    a, b = PPO.load(plain / "model.zip"), PPO.load(evaluated[0] / "model.zip")
    for (name, x), y in zip(a.policy.state_dict().items(), b.policy.state_dict().values()):
        assert np.array_equal(x.numpy(), y.numpy()), name


def test_learning_curve_shows_the_evaluations(
    evaluated: tuple[Path, Result], monkeypatch: pytest.MonkeyPatch
) -> None:
    run, _ = evaluated
    figures: list[Any] = []

    def keep(fig: Any, path: Path) -> None:
        figures.append(fig)

    monkeypatch.setattr(curves_mod, "save_figure", keep)
    assert curves_mod.draw_learning_curve(run, "PPO on CartPole-v1", background=False) is None
    (fig,) = figures
    (ax,) = fig.axes
    lines = {line.get_label(): line for line in ax.get_lines()}
    label = "evaluation: mean of 3 deterministic episodes"
    assert label in [t.get_text() for t in ax.get_legend().get_texts()]
    line = lines[label]
    rows = _evaluations(run)
    assert line.get_xdata().tolist() == [s for s, _ in rows]
    assert line.get_ydata().tolist() == [np.mean(r) for _, r in rows]
    assert line.get_marker() == "o"
    import matplotlib.pyplot as plt

    plt.close(fig)


class _StopAt(BaseCallback):
    """A graceful stop (as after the first Ctrl-C): ``learn`` ends at step ``at``."""

    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def _on_step(self) -> bool:
        return self.num_timesteps < self.at


class _KillAt(BaseCallback):
    """A stop at once (as after a second Ctrl-C): nothing saved past the last checkpoint."""

    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.at:
            raise KeyboardInterrupt
        return True


def test_resume_continues_the_schedule(
    evaluated: tuple[Path, Result], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run = tmp_path / "run"
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_StopAt(300)])
    result = run_cli(*PPO_EVAL, "--out", run)
    assert result.code == 130, result.err
    assert [s for s, _ in _evaluations(run)] == [128, 256]
    best = max(np.mean(r) for _, r in _evaluations(run))
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [])
    result = run_cli("train", "--resume", run, "--progress", "none", "--eval-episodes", 3)
    assert result.code == 0, result.err
    assert (
        "note: evaluating every 128 steps on 3 episodes as before: next at 384 steps; best mean "
        f"return so far {best:.2f}"
    ) in result.err
    # Appended (one header), and the same evaluations as the run never stopped.
    assert (run / "evaluations.csv").read_text().count("timesteps") == 1
    assert _evaluations(run) == _evaluations(evaluated[0])
    assert (run / "best_model.zip").is_file()


def test_a_stop_at_once_replays_the_evaluations_past_the_checkpoint(
    evaluated: tuple[Path, Result], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run = tmp_path / "run"
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [_KillAt(300)])
    result = run_cli(*PPO_EVAL, "--out", run, "--checkpoint-every", 192)
    assert result.code == 130, result.err
    assert [s for s, _ in _evaluations(run)] == [128, 256]  # 256 is past the checkpoint at 192
    monkeypatch.setattr(train, "EXTRA_CALLBACKS", [])
    result = run_cli("train", "--resume", run, "--progress", "none", "--eval-episodes", 0)
    assert result.code == 0, result.err
    assert "next at 256 steps" in result.err
    assert _evaluations(run) == _evaluations(evaluated[0])  # 256 once, evaluated again


def test_resume_keeps_a_better_best_model(evaluated: tuple[Path, Result], tmp_path: Path) -> None:
    """The best so far comes back from evaluations.csv: a later, worse evaluation does not
    replace best_model.zip."""
    run = tmp_path / "run"
    shutil.copytree(evaluated[0], run)
    path = run / "evaluations.csv"
    lines = path.read_text().splitlines(keepends=True)
    cells = lines[2].split(",")  # the evaluation at 256 steps
    lines[2] = ",".join([cells[0], "1000000.0", *cells[2:]])
    path.write_text("".join(lines))
    kept = (run / "best_model.zip").read_bytes()
    result = run_cli("train", "--resume", run, "--timesteps", 768, "--progress", "none",
                     "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert "next at 640 steps; best mean return so far 1000000.00" in result.err
    assert [s for s, _ in _evaluations(run)] == [128, 256, 384, 512, 640, 768]
    assert (run / "best_model.zip").read_bytes() == kept


def test_a_normalized_run_evaluates_with_the_training_statistics(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from palaestra.algos import evaluation

    seen: list[tuple[Any, Any, Any]] = []
    play = evaluation.evaluate_policy

    def spy(model: Any, env: Any, *args: Any, **kwargs: Any) -> Any:
        training = model.get_env()
        seen.append((env, training.obs_rms.mean.copy(), training.obs_rms.var.copy()))
        assert not env.training and not env.norm_reward  # frozen statistics, raw returns
        assert np.array_equal(env.obs_rms.mean, training.obs_rms.mean)
        assert np.array_equal(env.obs_rms.var, training.obs_rms.var)
        assert env.obs_rms is not training.obs_rms  # a copy: evaluating does not update it
        return play(model, env, *args, **kwargs)

    monkeypatch.setattr(evaluation, "evaluate_policy", spy)
    run = tmp_path / "run"
    result = run_cli(*PPO_EVAL, "--set", "normalize=true", "--out", run, "--eval-episodes", 2)
    assert result.code == 0, result.err
    assert len(seen) == 4 + 1  # four evaluations during training, then the final one
    assert not np.array_equal(seen[0][1], seen[1][1])  # the statistics moved between them
    # best_model.zip is evaluated with the statistics of its evaluation, not the final ones.
    rows = _evaluations(run)
    best = rows[int(np.argmax([np.mean(r) for _, r in rows]))]
    saved = np.load(run / "best_vecnormalize.npz")
    index = [s for s, _ in rows].index(best[0])
    assert np.array_equal(saved["obs_mean"], seen[index][1])
    monkeypatch.setattr(evaluation, "evaluate_policy", play)
    assert evaluate_run(run / "best_model.zip", 2, seed=0).returns == best[1]


def test_eval_flag_errors(tmp_path: Path, evaluated: tuple[Path, Result]) -> None:
    base = ("train", "ppo", "CartPole-v1", "--out", tmp_path / "x")
    for extra, line in [
        (("--eval-freq", -1), "palaestra: error: --eval-freq must be >= 0, got -1 (e.g. 10000 "
         "(0: never))"),
        (("--eval-freq", 100, "--eval-episodes", 0), "palaestra: error: --eval-freq needs "
         "--eval-episodes of 1 or more, got 0 (e.g. --eval-episodes 5)"),
    ]:  # fmt: skip
        result = run_cli(*base, *extra)
        assert (result.code, result.err.strip()) == (2, line)
    assert not (tmp_path / "x").exists()
    result = run_cli("train", "--resume", evaluated[0], "--eval-freq", 64)
    assert result.code == 2
    assert "--eval-freq cannot change them" in result.err


def test_run_api_takes_and_checks_the_eval_settings(tmp_path: Path) -> None:
    spec = RunSpec("ppo", "CartPole-v1", n_timesteps=128, n_envs=2, seed=1, hyperparams=SMALL)
    for kwargs, message in [
        ({"eval_freq": "100"}, "eval_freq must be an integer, got '100'"),
        ({"eval_freq": 100, "eval_episodes": 0}, "eval_episodes must be from 1 to 100,000, got 0"),
        ({"eval_freq": True}, "eval_freq must be an integer, got True"),
    ]:
        with pytest.raises(RunError, match=f"^{message}$"):
            open_run(spec, tmp_path / "bad", **kwargs)
    assert not (tmp_path / "bad").exists()
    run = open_run(spec, tmp_path / "run", eval_freq=64, eval_episodes=2)
    assert run.train(checkpoint_every=0).status == "finished"
    assert [s for s, _ in _evaluations(tmp_path / "run")] == [64, 128]


def test_a_run_folder_evaluation_entry_is_checked(tmp_path: Path) -> None:
    spec = RunSpec("ppo", "CartPole-v1", n_timesteps=128, n_envs=2, seed=1, hyperparams=SMALL)
    run_dir = tmp_path / "run"
    run = open_run(spec, run_dir, eval_freq=64, eval_episodes=2)
    run.train([_StopAt(64)], checkpoint_every=0)
    config = json.loads((run_dir / "config.json").read_text())
    for value, message in [
        ({"every": 64}, "evaluation must be a mapping with keys 'every' and 'episodes', got "
         "{'every': 64}"),
        ({"every": 0, "episodes": 2}, "evaluation.every must be from 1 to "
         "1,000,000,000,000,000, got 0"),
        ({"every": 64, "episodes": "2"}, "evaluation.episodes must be an integer, got '2'"),
    ]:  # fmt: skip
        (run_dir / "config.json").write_text(json.dumps({**config, "evaluation": value}))
        with pytest.raises(RunError) as info:
            open_resume(run_dir)
        assert str(info.value).startswith(f"{run_dir / 'config.json'}: {message}")


def test_trim_drops_evaluations_past_the_checkpoint(tmp_path: Path) -> None:
    header = "timesteps,mean_return,std_return,mean_length,returns\r\n"
    rows = [f"{s},1.0,0.0,1.0,1.0\r\n" for s in (128, 256, 384)]
    (tmp_path / "evaluations.csv").write_text(header + "".join(rows), newline="")
    trim_logs(tmp_path, 300)
    assert (tmp_path / "evaluations.csv").read_bytes().decode() == header + "".join(rows[:2])


# -- --timesteps aliases --------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["train", "compare", "sweep"])
@pytest.mark.parametrize("flag", ["--timesteps", "--total-timesteps", "--n-timesteps"])
def test_timesteps_aliases(command: str, flag: str) -> None:
    argv = {"train": ["train", "ppo", "CartPole-v1"], "compare": ["compare", "algos"],
            "sweep": ["sweep", "space.yaml", "--algo", "ppo", "--env", "CartPole-v1",
                      "--trials", "2"]}[command]  # fmt: skip
    args = build_parser().parse_args([*argv, flag, "1234"])
    assert args.timesteps == 1234


def test_an_alias_trains_to_its_budget(tmp_path: Path) -> None:
    result = run_cli("train", "ppo", "CartPole-v1", "--n-envs", 2, "--n-timesteps", 128,
                     "--set", "batch_size=64", "--out", tmp_path / "run", "--progress", "none",
                     "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert json.loads((tmp_path / "run" / "config.json").read_text())["n_timesteps"] == 128


# -- the progress total ---------------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["bar", "line"])
def test_progress_counts_to_the_real_end(
    mode: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    shown: list[progress.LiveProgress] = []

    class Spy(progress.LiveProgress):
        def close(self) -> None:
            if self.bar is not None:
                shown.append(self)
                self.last_bar = (self.bar.n, self.bar.total)
            super().close()

        def _on_training_end(self) -> None:
            shown.append(self)
            self.last_line = self.status_line(1e9)

    monkeypatch.setattr(progress, "LiveProgress", Spy)
    if mode == "bar":
        pytest.importorskip("tqdm")
    result = run_cli("train", "ppo", "CartPole-v1", "--n-envs", 2, "--timesteps", 100,
                     "--set", "batch_size=64", "--out", tmp_path / "run", "--progress", mode,
                     "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert (
        "note: PPO trains on whole rollouts of n_steps 32 x 2 envs = 64 steps: the run ends at "
        "128, not 100\n"
        f"training ppo on CartPole-v1 (2 envs, preset default) to 128 steps -> {tmp_path / 'run'}"
    ) in result.err
    spy = shown[-1]
    assert spy.total == 128
    if mode == "bar":
        assert spy.last_bar == (128, 128)
    else:
        assert spy.last_line.startswith("      128/128 steps")


def test_rounding_notes_name_the_algorithm_s_unit(tmp_path: Path) -> None:
    def notes(algo: str, n_timesteps: int, **hyper: Any) -> list[str]:
        spec = RunSpec(algo, "CartPole-v1", n_timesteps=n_timesteps, n_envs=2, hyperparams=hyper)
        run = open_run(spec, tmp_path / f"{algo}-{n_timesteps}-{len(hyper)}")
        return [n for n in run.notes if "trains on" in n or "collects" in n]

    assert notes("a2c", 101) == [
        "A2C trains on whole rollouts of n_steps 5 x 2 envs = 10 steps: the run ends at 110, "
        "not 101"
    ]
    assert notes("a2c", 100) == []
    assert notes("dqn", 101, train_freq=4) == [
        "DQN trains on whole collections of train_freq 4 x 2 envs = 8 steps: the run ends at "
        "104, not 101"
    ]
    assert notes("dqn", 100, train_freq=[1, "episode"]) == [
        "DQN collects whole episodes between updates (train_freq 1 episode): the run ends "
        "when the episodes under way at 100 steps end"
    ]


# -- the note on a preset that fell short ---------------------------------------------------------
def test_a_preset_that_fell_short_says_so(tmp_path: Path) -> None:
    result = run_cli("train", "ddpg", "Pendulum-v1", "--timesteps", 2, "--seed", 0,
                     "--out", tmp_path / "run", "--progress", "none",
                     "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert (
        "note: the ddpg preset 'default' for Pendulum-v1 fell short of its target on some "
        "seeds when measured: seed 0 ended at -471.6 (target -200; mean return of 100 "
        "deterministic episodes after training); 4 of 5 seeds reached it, median -164.9; this "
        "run uses seed 0\n"
    ) in result.err
    assert result.err.index("note: the ddpg preset") < result.err.index("training ddpg on")


def test_the_note_names_every_short_seed() -> None:
    assert presets.measured_shortfall("sac", "LunarLanderContinuous-v3", "default", 1) == (
        "the sac preset 'default' for LunarLanderContinuous-v3 fell short of its target on some "
        "seeds when measured: seeds 2, 3 ended at -10.4, -11.2 (target 200; mean return of 100 "
        "deterministic episodes after training); 3 of 5 seeds reached it, median 226.2; "
        "recorded as TARGET NOT MET"
    )
    assert presets.measured_shortfall("a2c", "CartPole-v1", "default", 0) is None  # 5/5
    assert presets.measured_shortfall("dqn", "ALE/Breakout-v5", "default", 0) is None  # no target
    assert presets.measured_shortfall("a2c", "CartPole-v1", None) is None  # no preset used


def test_a_preset_that_met_its_target_says_nothing(tmp_path: Path) -> None:
    result = run_cli("train", "a2c", "CartPole-v1", "--timesteps", 16, "--out", tmp_path / "r",
                     "--progress", "none", "--eval-episodes", 0)  # fmt: skip
    assert result.code == 0, result.err
    assert "fell short" not in result.err
