"""The run API: a RunSpec is plain JSON validated in one place, and ``palaestra train`` /
``eval`` are a few lines of Python with the same results."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from tests.cli.conftest import run_cli

from palaestra.runs import RunError, RunSpec, evaluate_run, resume_run, train_run


def _weights(run_dir: Path) -> dict[str, np.ndarray]:
    from palaestra.runs import load_model

    model = load_model(run_dir / "model.zip")
    return {k: v.detach().numpy().copy() for k, v in model.policy.state_dict().items()}


def test_spec_round_trips_through_json_and_config() -> None:
    spec = RunSpec.from_preset("ppo", "CartPole-v1", seed=3, n_timesteps=1024)
    assert spec.preset == "default" and spec.n_envs == 8 and spec.hyperparams["n_steps"] == 32
    assert RunSpec.from_json(spec.to_json()) == spec
    assert RunSpec.from_config(spec.to_config()) == spec
    again = spec.replace(seed=4)
    assert again.seed == 4 and spec.seed == 3


def test_preset_config_and_overrides_merge_in_order(tmp_path: Path) -> None:
    config = tmp_path / "c.json"
    config.write_text(json.dumps({"gamma": 0.9, "policy_kwargs": {"net_arch": [16]}}))
    spec = RunSpec.from_preset(
        "ppo", "CartPole-v1", config=config,
        overrides={"hyperparams": {"gamma": 0.95}, "n_envs": 2},
    )  # fmt: skip
    assert spec.hyperparams["gamma"] == 0.95 and spec.n_envs == 2
    assert spec.hyperparams["policy_kwargs"] == {"net_arch": [16]}
    assert spec.hyperparams["n_steps"] == 32  # the preset's, untouched


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: RunSpec.from_preset("a3c", "CartPole-v1"), "unknown algorithm 'a3c'"),
        (
            lambda: RunSpec.from_preset("ppo", "CartPole-v9"),
            "version `v9` for environment `CartPole`",
        ),
        (lambda: RunSpec.from_preset("ppo", "CartPole-v1", n_envs=0), "n_envs must be a positive"),
        (
            lambda: RunSpec.from_preset("ppo", "CartPole-v1", overrides={"gama": 0.9}),
            "unknown ppo setting 'gama'",
        ),
        (lambda: RunSpec("ppo", "CartPole-v1", atari=True).validate(), "not an Atari game"),
        (
            lambda: RunSpec.from_config({"algo": "ppo", "env_id": "CartPole-v1", "n_envs": 10**9}),
            "n_envs must be an integer from 1 to 4096",
        ),
        (
            lambda: RunSpec.from_config({"algo": "ppo", "env_id": "x", "hook": "os:system"}),
            "unknown key(s) ['hook']",
        ),
        (lambda: RunSpec.from_json("[1, 2]"), "a run description is a JSON object"),
    ],
)
def test_bad_descriptions_raise_run_error_naming_the_value(build: object, message: str) -> None:
    with pytest.raises(RunError) as info:
        build()  # type: ignore[operator]
    assert message in str(info.value)
    assert isinstance(info.value, ValueError)  # what callers of a bad value catch


def test_a_described_run_does_not_import_what_it_names_unless_allowed() -> None:
    data = {"algo": "ppo", "env_id": "CartPole-v1", "env_wrapper": "evil_mod:Wrap"}
    with pytest.raises(RunError, match="would import module 'evil_mod'"):
        RunSpec.from_config(data, allow_import=[])


def test_train_run_is_what_palaestra_train_does(tmp_path: Path) -> None:
    """The same spec through the library and through the CLI: the same config.json and the
    same trained bits, and evaluate_run reports what ``palaestra eval`` prints."""
    spec = RunSpec.from_preset("ppo", "CartPole-v1", seed=0, n_timesteps=512)
    result = train_run(spec, tmp_path / "lib")
    assert result.status == "finished" and result.num_timesteps == 512
    assert (tmp_path / "lib" / "model.zip").is_file()
    flags = ("--progress", "none", "--eval-episodes", 0)
    cli = run_cli("train", "ppo", "CartPole-v1", "--seed", 0, "--timesteps", 512,
                  "--out", tmp_path / "cli", *flags)  # fmt: skip
    assert cli.code == 0, cli.err
    ours = json.loads((tmp_path / "lib/config.json").read_text())
    theirs = json.loads((tmp_path / "cli/config.json").read_text())
    assert ours == theirs
    for name, value in _weights(tmp_path / "lib").items():
        np.testing.assert_array_equal(value, _weights(tmp_path / "cli")[name])
    played = evaluate_run(tmp_path / "lib", episodes=3, seed=5)
    assert len(played.returns) == 3 and played.lengths == [int(r) for r in played.returns]
    shown = run_cli("eval", tmp_path / "cli", "--episodes", 3, "--seed", 5)
    assert f"mean return: {np.mean(played.returns):.2f} ± {np.std(played.returns):.2f}" in shown.out


def test_resume_run_extends_a_finished_run(tmp_path: Path) -> None:
    spec = RunSpec.from_preset("a2c", "CartPole-v1", seed=1, n_timesteps=400)
    train_run(spec, tmp_path / "r")
    with pytest.raises(RunError, match="already trained"):
        resume_run(tmp_path / "r")
    result = resume_run(tmp_path / "r", n_timesteps=800)
    assert result.status == "finished" and result.num_timesteps == 800
    assert result.session_steps == 400
    status = json.loads((tmp_path / "r/status.json").read_text())
    assert status["num_timesteps"] == 800 and status["status"] == "finished"


def test_a_callback_that_stops_leaves_an_interrupted_resumable_run(tmp_path: Path) -> None:
    from palaestra.algos.callbacks import BaseCallback

    class StopAt(BaseCallback):
        def _on_step(self) -> bool:
            return self.num_timesteps < 200

    spec = RunSpec.from_preset("a2c", "CartPole-v1", seed=2, n_timesteps=400)
    result = train_run(spec, tmp_path / "r", callbacks=[StopAt()])
    assert result.status == "interrupted" and 200 <= result.num_timesteps < 400
    assert resume_run(tmp_path / "r").status == "finished"


def test_evaluation_during_training_does_not_change_the_run(tmp_path: Path) -> None:
    """``on_evaluate`` ends ``learn`` between two steps and continues exactly (the sweep's
    pruner relies on it)."""
    from palaestra.runs import open_run

    spec = RunSpec.from_preset("ppo", "CartPole-v1", seed=0, n_timesteps=768)
    seen: list[int] = []
    run = open_run(spec, tmp_path / "a")
    run.train(
        checkpoint_every=0,
        evaluate_every=256,
        on_evaluate=lambda m: not seen.append(m.num_timesteps),
    )
    train_run(spec, tmp_path / "b", checkpoint_every=0)
    assert seen == [256, 512]
    for name, value in _weights(tmp_path / "a").items():
        np.testing.assert_array_equal(value, _weights(tmp_path / "b")[name])


DATA = Path(__file__).parent / "data"


def test_a_run_folder_written_before_the_run_api_evaluates_and_resumes_the_same(
    tmp_path: Path,
) -> None:
    """``old_ppo_run`` was written by ``palaestra train`` at commit d6d8e8f (before the run
    API); its ``eval`` output and the weights its resume to 512 steps reached then are kept."""
    import shutil

    run = tmp_path / "run"
    shutil.copytree(DATA / "old_ppo_run", run)
    shown = run_cli("eval", run, "--episodes", 5, "--seed", 3)
    expected = (
        (DATA / "old_ppo_run_eval.txt")
        .read_text()
        .replace("/tmp/oldtiny/ppo/model.zip", str(run / "model.zip"))
    )
    assert shown.code == 0 and shown.out == expected
    resumed = run_cli("train", "--resume", run, "--timesteps", 512, "--progress", "none",
                      "--eval-episodes", 0)  # fmt: skip
    assert resumed.code == 0, resumed.err
    reference = np.load(DATA / "old_ppo_run_resumed_512.npz")
    weights = _weights(run)
    assert sorted(reference.files) == sorted(weights)
    for name in reference.files:
        np.testing.assert_array_equal(weights[name], reference[name])
