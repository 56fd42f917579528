"""The RL Zoo's ``callback`` key (issue 26): SB3's callback names map through the one table
(``palaestra.runs.known_names.CALLBACKS``) and run in ``learn``; any other module (the Zoo's
``rl_zoo3.callbacks``, the user's own) needs ``--allow-import``; SB3's callbacks a file cannot
build are refused naming what does their job. The same ``callback`` setting works in
palaestra's own settings files and is kept in the run's ``config.json`` for a resume."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from tests.cli.conftest import run_cli

from palaestra.runs import RunError, resolve_spec, train_run
from palaestra.runs.run_callbacks import REFUSED_CALLBACKS, build_callbacks

pytest.importorskip("torch")

QUIET = ("--progress", "none", "--eval-episodes", 0, "--checkpoint-every", 0)
GATE = "palaestra runs no code named by a settings file"


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _zoo_file(workdir: Path, callback: str) -> Path:
    path = workdir / "ppo.yml"
    path.write_text(
        "CartPole-v1:\n  n_timesteps: 4096\n  policy: MlpPolicy\n  n_envs: 1\n  n_steps: 32\n"
        "  batch_size: 32\n"
        f"  callback:\n{callback}"
    )
    return path


def test_sb3s_callback_from_a_zoo_file_stops_training(workdir: Path) -> None:
    stop = "    - stable_baselines3.common.callbacks.StopTrainingOnMaxEpisodes:\n"
    path = _zoo_file(workdir, stop + "        max_episodes: 2\n")
    spec, _ = resolve_spec("ppo", "CartPole-v1", config=path, seed=0)
    assert spec.callback == [
        {"stable_baselines3.common.callbacks.StopTrainingOnMaxEpisodes": {"max_episodes": 2}}
    ]
    result = train_run(spec, workdir / "run", checkpoint_every=0)
    # SB3's StopTrainingOnMaxEpisodes stops after the second episode ends: a CartPole episode
    # of a random policy lasts tens of steps, far below the budget.
    assert result.status == "interrupted"
    assert 2 <= result.num_timesteps < 1000
    assert len(result.model.ep_info_buffer) == 2
    config = json.loads((workdir / "run" / "config.json").read_text())
    assert config["callback"] == spec.callback  # kept for a resume


def test_the_table_maps_sb3s_names_to_palaestras_classes() -> None:
    from palaestra.algos.callbacks import StopTrainingOnMaxEpisodes

    (built,) = build_callbacks(
        {
            "callback": {
                "stable_baselines3.common.callbacks.StopTrainingOnMaxEpisodes": {"max_episodes": 3}
            }
        }
    )
    assert type(built) is StopTrainingOnMaxEpisodes and built.max_episodes == 3
    own = build_callbacks(
        {"callback": [{"palaestra.algos.callbacks:StopTrainingOnMaxEpisodes": {"max_episodes": 1}}]}
    )
    assert [type(c) for c in own] == [StopTrainingOnMaxEpisodes] and own[0].max_episodes == 1


def test_a_zoo_callback_module_needs_allow_import(workdir: Path) -> None:
    path = _zoo_file(workdir, "    - rl_zoo3.callbacks.ParallelTrainCallback\n")
    with pytest.raises(RunError) as caught:
        resolve_spec("ppo", "CartPole-v1", config=path)
    assert caught.value.what == (
        f"config file {str(path)!r} section 'CartPole-v1' names callback "
        "'rl_zoo3.callbacks.ParallelTrainCallback', which would import module "
        f"'rl_zoo3.callbacks'; {GATE}"
    )
    assert caught.value.fix == (
        "pass --allow-import rl_zoo3.callbacks to allow it; callback names in "
        "palaestra.runs.known_names (docs/known_names.md) need no flag"
    )


def test_a_users_callback_runs_when_allowed(workdir: Path) -> None:
    (workdir / "mycallbacks.py").write_text(
        "from palaestra.algos.callbacks import BaseCallback\n"
        "class StopAt(BaseCallback):\n"
        "    def __init__(self, steps):\n"
        "        super().__init__()\n"
        "        self.steps = steps\n"
        "    def _on_step(self):\n"
        "        return self.num_timesteps < self.steps\n"
    )
    path = _zoo_file(workdir, "    - mycallbacks.StopAt: {steps: 50}\n")
    out = workdir / "run"
    result = run_cli("train", "ppo", "CartPole-v1", "--config", path, "--seed", 0, "--out", out,
                     *QUIET)  # fmt: skip
    assert result.code == 2 and "--allow-import mycallbacks" in result.err
    result = run_cli("train", "ppo", "CartPole-v1", "--config", path, "--seed", 0, "--out", out,
                     "--allow-import", "mycallbacks", *QUIET)  # fmt: skip
    # the callback stopped learn: the CLI's "interrupted" exit, with the checkpoint at 50
    assert result.code == 130, result.err
    assert "palaestra: interrupted at 50/4,096 steps" in result.err
    status = json.loads((out / "status.json").read_text())
    assert status["num_timesteps"] == 50
    # a resume reads the callback from config.json: the same gate
    result = run_cli("train", "--resume", out, *QUIET)
    assert result.code == 2 and "--allow-import mycallbacks" in result.err


@pytest.mark.parametrize("name", sorted(REFUSED_CALLBACKS))
def test_callbacks_a_file_cannot_build_are_refused_with_why(workdir: Path, name: str) -> None:
    path = _zoo_file(workdir, f"    - stable_baselines3.common.callbacks.{name}\n")
    with pytest.raises(RunError) as caught:
        resolve_spec("ppo", "CartPole-v1", config=path)
    assert caught.value.what == (
        f"callback 'stable_baselines3.common.callbacks.{name}' is refused: "
        f"{REFUSED_CALLBACKS[name]}"
    )


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (
            {"palaestra.algos.callbacks:StopTrainingOnMaxEpisodes": {"episodes": 2}},
            "callback 'palaestra.algos.callbacks:StopTrainingOnMaxEpisodes' does not take "
            "{'episodes': 2}: ",
        ),
        (
            "palaestra.algos.callbacks:NoSuchCallback",
            "callback 'palaestra.algos.callbacks:NoSuchCallback' is missing, not a palaestra "
            "callback class",
        ),
        (
            "palaestra.algos.callbacks:convert_callback",
            "callback 'palaestra.algos.callbacks:convert_callback' is a function, not a "
            "palaestra callback class",
        ),
        ("NoModule", "callback 'NoModule' names no module and class"),
    ],
)
def test_bad_callbacks_are_named(value: object, message: str) -> None:
    with pytest.raises(RunError) as caught:
        build_callbacks({"callback": value})
    assert caught.value.what.startswith(message)


def test_a_malformed_callback_setting_is_refused(workdir: Path) -> None:
    path = workdir / "settings.yaml"
    path.write_text("callback: 3\n")
    with pytest.raises(RunError, match=r"callback"):
        resolve_spec("ppo", "CartPole-v1", config=path)
