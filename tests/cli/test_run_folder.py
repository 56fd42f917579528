"""A run folder is data: ``eval``, ``record`` and ``train --resume`` import no module that its
``config.json`` names unless ``--allow-import`` names it too, and its values are checked
before they reach a constructor."""

from __future__ import annotations

import json
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from palaestra.runs.settings import ALGOS

from .conftest import Result, run_cli

# A wrapper module that leaves a marker file when it is imported: proof that code ran.
MODULE = """
from pathlib import Path
import palaestra as gym

Path({marker!r}).write_text("imported")

class Wrap(gym.Wrapper):
    pass

def make():
    return gym.make("CartPole-v1")

if __name__ == "evil_rf":
    gym.register("Foo-v0", entry_point=make)
"""
REFUSED = "palaestra runs no code named by a run folder"
QUIET = ("--progress", "none", "--eval-episodes", 0)
QUIET = ("--progress", "none", "--eval-episodes", 0)


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The current folder, holding ``shaping_rf.py`` and ``evil_rf.py`` (marker modules)."""
    from palaestra.envs.registration import registry

    for name in ("shaping_rf", "evil_rf"):
        marker = tmp_path / f"{name}.imported"
        (tmp_path / f"{name}.py").write_text(MODULE.format(marker=str(marker)), encoding="utf-8")
        monkeypatch.delitem(sys.modules, name, raising=False)
    monkeypatch.chdir(tmp_path)
    # As under `python -m palaestra`: the current folder first on the path, so the modules
    # are importable (the CLI adds it for env_wrapper itself).
    monkeypatch.setattr(sys, "path", [str(tmp_path), *sys.path])
    yield tmp_path
    registry.pop("Foo-v0", None)  # registered by evil_rf once imported


def _tampered(ppo_run: tuple[Path, Result], workdir: Path, **changes: Any) -> Path:
    """A copy of the tiny PPO run whose config.json got ``changes`` (a shared run folder)."""
    run = workdir / "shared"
    shutil.copytree(ppo_run[0], run)
    config = json.loads((run / "config.json").read_text())
    config.update(changes)
    (run / "config.json").write_text(json.dumps(config))
    return run


TABLE_HINT = "; wrapper names in palaestra.runs.known_names (docs/known_names.md) need no flag"


def _refusal(run: Path, setting: str, value: str, module: str, flags: str = "") -> str:
    hint = TABLE_HINT if setting == "env_wrapper" else ""
    return (
        f"palaestra: error: {run / 'config.json'} names {setting} {value!r}, which would "
        f"import module {module!r}; {REFUSED} (pass {flags or '--allow-import ' + module} "
        f"to allow it{hint})\n"
    )


def _commands(run: Path, workdir: Path) -> dict[str, list[object]]:
    return {
        "eval": ["eval", run, "--episodes", 1],
        "record": ["record", run, "--out", workdir / "a.gif"],
        "resume": ["train", "--resume", run, "--timesteps", 1024, *QUIET],
    }


def test_env_wrapper_of_a_run_folder_is_not_imported(
    ppo_run: tuple[Path, Result], workdir: Path
) -> None:
    run = _tampered(ppo_run, workdir, env_wrapper="shaping_rf:Wrap")
    for name, argv in _commands(run, workdir).items():
        result = run_cli(*argv)
        assert (result.code, result.err) == (
            2,
            _refusal(run, "env_wrapper", "shaping_rf:Wrap", "shaping_rf"),
        ), name
    assert not (workdir / "shaping_rf.imported").exists()
    assert not (workdir / "a.gif").exists()
    assert json.loads((run / "status.json").read_text())["num_timesteps"] == 512


def test_allow_import_runs_eval_record_and_resume(
    ppo_run: tuple[Path, Result], workdir: Path
) -> None:
    run = _tampered(ppo_run, workdir, env_wrapper=["shaping_rf:Wrap"])
    note = f"note: importing module 'shaping_rf' for env_wrapper 'shaping_rf:Wrap' of {run}"
    for name, argv in _commands(run, workdir).items():
        result = run_cli(*argv, "--allow-import", "shaping_rf")
        assert result.code == 0, (name, result.err)
        assert note in result.err, name
    assert (workdir / "shaping_rf.imported").exists()
    assert (workdir / "a.gif").stat().st_size > 0
    assert json.loads((run / "status.json").read_text())["num_timesteps"] >= 1024


def test_env_id_with_a_module_is_not_imported(ppo_run: tuple[Path, Result], workdir: Path) -> None:
    run = _tampered(ppo_run, workdir, env_id="evil_rf:Foo-v0")
    for name, argv in _commands(run, workdir).items():
        result = run_cli(*argv)
        assert (result.code, result.err) == (
            2,
            _refusal(run, "env_id", "evil_rf:Foo-v0", "evil_rf"),
        ), name
    assert not (workdir / "evil_rf.imported").exists()
    # --env replaces the run's id: nothing of the run's id is imported then.
    result = run_cli("eval", run, "--env", "CartPole-v1", "--episodes", 1)
    assert result.code == 0, result.err
    assert not (workdir / "evil_rf.imported").exists()
    result = run_cli("eval", run, "--episodes", 1, "--allow-import", "evil_rf")
    assert result.code == 0, result.err
    assert "on evil_rf:Foo-v0" in result.out and (workdir / "evil_rf.imported").exists()


def test_a_callable_that_is_no_wrapper_class_is_refused_even_when_allowed(
    ppo_run: tuple[Path, Result], workdir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import os

    calls: list[object] = []
    monkeypatch.setattr(os, "system", lambda *a: calls.append(a) or 0)
    run = _tampered(ppo_run, workdir, env_wrapper=["builtins:str", "os:system"])
    both = "--allow-import builtins --allow-import os"
    result = run_cli("eval", run)
    assert result.err == _refusal(run, "env_wrapper", "builtins:str", "builtins", both)
    result = run_cli("eval", run, "--allow-import", "builtins")
    assert result.err == _refusal(run, "env_wrapper", "os:system", "os")
    result = run_cli("eval", run, "--allow-import", "builtins", "--allow-import", "os")
    assert result.code == 2
    assert result.err.endswith(
        "palaestra: error: env_wrapper 'builtins:str' is a class but no Wrapper, not a wrapper "
        "class (name a subclass of palaestra.Wrapper (gym.Wrapper, gym.RewardWrapper, ...))\n"
    )
    # A new run's own --set is the user's request, but still only a class is applied.
    result = run_cli("train", "ppo", "CartPole-v1", "--set", "env_wrapper=os:system",
                     "--out", workdir / "new", "--progress", "none")  # fmt: skip
    assert result.code == 2
    assert result.err.startswith("palaestra: error: env_wrapper 'os:system' is a ")
    assert "not a wrapper class" in result.err
    assert calls == [] and not (workdir / "new").exists()


def test_allow_import_without_a_settings_file_says_it_is_unused(workdir: Path) -> None:
    """A new run may pass --allow-import (for its --config file); with none, a note says so."""
    result = run_cli("train", "ppo", "CartPole-v1", "--allow-import", "shaping_rf",
                     "--timesteps", 64, "--set", "n_steps=8", "--n-envs", 1,
                     "--out", workdir / "new", *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    assert "note: --allow-import shaping_rf: no settings file to apply it to\n" in result.err
    assert not (workdir / "shaping_rf.imported").exists()


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"hook": "x"}, "holds unknown key(s) ['hook'] (a run's config.json holds only "),
        ({"n_envs": 10**9}, "n_envs must be an integer from 1 to 4096, got 1000000000"),
        ({"frame_stack": 2**62}, "frame_stack must be an integer from 1 to 256, got "),
        ({"device": "cuda; rm -rf"}, "device must be auto, cpu, mps or cuda[:N], got "),
        ({"seed": "0"}, "seed must be an integer from 0 to 18446744073709551615, got '0'"),
        ({"env_wrapper": {"a": 1}}, "env_wrapper must be 'module:Class' or a list of them"),
        ({"atari": {"screen_size": 10**6}}, "atari.screen_size must be a int from 1 to 1024"),
        ({"normalize": {"clip_obs": "x"}}, "normalize.clip_obs must be a float, got 'x'"),
        ({"hyperparams": {"tensorboard_log": "/tmp/x"}},
         "hyperparams names 'tensorboard_log', which is not a ppo hyperparameter"),
        ({"hyperparams": {"n_steps": 10**12}},
         "hyperparams n_steps=1000000000000 is refused: expected an integer from 1 to 1000000"),
        ({"hyperparams": {"policy_kwargs": {"net_arch": [10**9]}}},
         "hyperparams policy_kwargs.net_arch=[1000000000] is refused: expected null or a list "
         "of at most 64 layer widths from 1 to 65536"),
        ({"algo": "a3c"}, f"algo must be one of {', '.join(ALGOS)}, got 'a3c'"),
    ],
)  # fmt: skip
def test_bad_config_values_are_one_line(
    ppo_run: tuple[Path, Result], workdir: Path, changes: dict[str, Any], message: str
) -> None:
    run = _tampered(ppo_run, workdir, **changes)
    for name, argv in _commands(run, workdir).items():
        result = run_cli(*argv)
        assert result.code == 2, (name, result.err)
        assert result.err.startswith(f"palaestra: error: {run / 'config.json'}")
        assert message in result.err and result.err.count("\n") == 1, (name, result.err)


def test_model_file_limits_reach_the_cli(ppo_run: tuple[Path, Result], workdir: Path) -> None:
    from palaestra.algos.common.model_io import read_archive, write_archive

    run = _tampered(ppo_run, workdir)
    for path in run.rglob("model*.zip"):  # eval reads model.zip, --resume its checkpoint's
        meta, arrays = read_archive(path, "model")
        meta["hyperparameters"]["n_steps"] = 10**12
        write_archive(path, "model", meta, arrays)
    for name, argv in _commands(run, workdir).items():
        result = run_cli(*argv)
        assert result.code == 2 and result.err.count("\n") == 1, (name, result.err)
        assert (
            "hyperparameters n_steps=1000000000000 is refused: expected an integer from 1 to "
            "1000000" in result.err
        ), name
