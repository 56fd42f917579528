"""``envs``, ``bench``, every command's ``--help``, and the one-line errors for bad input."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import pytest

from palaestra.cli import COMMANDS, build_parser
from palaestra.runs.settings import ALGOS

from .conftest import run_cli


def test_envs_lists_spaces_and_marks_atari() -> None:
    result = run_cli("envs")
    assert result.code == 0, result.err
    lines = result.out.splitlines()
    assert lines[0].split() == ["id", "action", "space", "threshold", "max", "steps",
                                "presets", "observation", "space"]  # fmt: skip
    cartpole = next(line for line in lines if line.startswith("CartPole-v1 "))
    assert cartpole.split()[1:5] == ["Discrete(2)", "475", "500", "a2c,dqn,ppo,qrdqn"]
    assert cartpole.endswith(
        "Box([-4.8               -inf -0.41887903        -inf], "
        "[4.8               inf 0.41887903        inf], (4,), float32)"
    )
    pong = next(line for line in lines if line.startswith("ALE/Pong-v5 *"))
    assert "Box(0, 255, (210, 160, 3), uint8)" in pong
    assert re.search(r"^\* \d+ Atari ids: need ale-py", result.out, re.M)
    assert result.out.strip().endswith("env ids")


def test_envs_filter() -> None:
    result = run_cli("envs", "--filter", "mountaincar")
    ids = [line.split()[0] for line in result.out.splitlines()[2:] if line and "ids" not in line]
    assert ids == ["MountainCar-v0", "MountainCarContinuous-v0"]
    assert run_cli("envs", "--filter", "zzz").out == "no registered env id contains 'zzz'\n"


def test_envs_without_ale_py_loads_no_rom() -> None:
    """Atari rows are listed without importing ale-py, and with it missing."""
    code = (
        "import sys; sys.modules['ale_py'] = None\n"
        "from palaestra.cli import main\n"
        "code = main(['envs', '--filter', 'Breakout'])\n"
        "assert 'torch' not in sys.modules, 'envs imported torch'\n"
        "sys.exit(code)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "ALE/Breakout-v5 *" in out.stdout
    assert 'need ale-py (not installed: pip install "palaestra[atari]")' in out.stdout


def test_bench_quick_table() -> None:
    result = run_cli("bench", "--quick", "--seconds", 0.02, "--num-envs", 16,
                     "--envs", "CartPole-v1", "Pendulum-v1")  # fmt: skip
    assert result.code == 0, result.err
    header, *rows, note = result.out.strip().splitlines()
    assert header.split()[:7] == ["env", "palaestra", "1", "env", "gymnasium", "1", "env"]
    assert [r.split()[0] for r in rows] == ["CartPole-v1", "Pendulum-v1"]
    for row in rows:
        cells = row.split()
        assert float(cells[1].replace(",", "")) > 0 and cells[3].endswith("x")
    assert "(native)" in rows[0] and "(sync)" in rows[1]  # Gymnasium's Pendulum has no batch
    assert note.startswith("env steps per second, median of 1 repeat(s) of 0.02 s;")
    plain = run_cli("bench", "--quick", "--seconds", 0.01, "--num-envs", 4,
                    "--envs", "MountainCar-v0", "--no-gymnasium")  # fmt: skip
    assert plain.out.splitlines()[0].split() == ["env", "palaestra", "1", "env", "palaestra",
                                                 "4", "envs"]  # fmt: skip


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


@pytest.mark.parametrize("command", COMMANDS)
def test_help_documents_every_option(command: str) -> None:
    sub = _subparsers()[command]
    result = run_cli(command, "--help")
    assert result.code == 0 and result.out.startswith(f"usage: palaestra {command}")
    for action in sub._actions:
        assert action.help, f"{command}: {action.option_strings or action.dest} has no help"
        for option in action.option_strings:
            assert option in result.out, f"{command} --help does not mention {option}"
        if not action.option_strings:
            assert (action.metavar or action.dest) in result.out


def test_top_level_help_lists_commands() -> None:
    result = run_cli("--help")
    assert result.code == 0
    for command in COMMANDS:
        assert re.search(rf"^\s+{command}\s+\S", result.out, re.M), command


def _bad(tmp_path: Path) -> dict[str, tuple[list[object], int, str | re.Pattern[str]]]:
    """argv -> (exit code, the exact stderr line or a pattern for it)."""
    (tmp_path / "bad.yaml").write_text("hyperparams: [unclosed\n")
    (tmp_path / "bad.json").write_text('{"gamma": }')
    (tmp_path / "list.json").write_text("[1, 2]")
    e = "palaestra: error: "
    return {
        "unknown algo": (["train", "a3c", "CartPole-v1"], 2,
                         e + f"unknown algorithm 'a3c' (choose one of: {', '.join(ALGOS)})"),
        "unknown env": (["train", "ppo", "CartPol-v1"], 2,
                        e + "Environment `CartPol` doesn't exist. Did you mean: `CartPole`? "
                        "(run `palaestra envs` to list the ids)"),
        # the preset list grows as presets are tuned: match its shape only
        "unknown preset": (["train", "ppo", "CartPole-v1", "--preset", "fast"], 2, re.compile(
            re.escape(e + "no ppo preset named 'fast' for CartPole-v1; choose from [")
            + ".*'default'.*" + re.escape("] (pick another --preset, or drop it)"))),
        # (Taxi is registered since the toy-text envs: an unknown version of it.)
        "no preset for env": (["train", "ppo", "Taxi-v9", "--preset", "default"], 2,
                              e + "Environment version `v9` for environment `Taxi` doesn't exist. "
                              "It provides versioned environments: [ `v4` ]. "
                              "(run `palaestra envs` to list the ids)"),
        "no preset for algo/env": (["train", "dqn", "Pendulum-v1", "--preset", "x"], 2,
            re.compile(re.escape(e + "no dqn preset for env 'Pendulum-v1'; dqn presets exist for [")
                       + ".*" + re.escape("] (pick another --preset, or drop it)"))),
        "malformed yaml": (["train", "ppo", "CartPole-v1", "--config", tmp_path / "bad.yaml"], 2,
                           e + f"malformed YAML in '{tmp_path / 'bad.yaml'}' at line 2, column 1:"
                           " expected ',' or ']', but got '<stream end>' (fix the file)"),
        "malformed json": (["train", "ppo", "CartPole-v1", "--config", tmp_path / "bad.json"], 2,
                           e + f"malformed JSON in '{tmp_path / 'bad.json'}': Expecting value: "
                           "line 1 column 11 (char 10) (fix the file)"),
        "config not a mapping": (["train", "ppo", "CartPole-v1", "--config",
                                  tmp_path / "list.json"], 2,
                                 e + f"config file '{tmp_path / 'list.json'}' holds a list, not "
                                 "a mapping (write keys such as hyperparams, n_envs, n_timesteps "
                                 "at the top level)"),
        "missing config": (["train", "ppo", "CartPole-v1", "--config", tmp_path / "no.json"], 2,
                           e + f"no config file at '{tmp_path / 'no.json'}' (check the path)"),
        "bad --set": (["train", "ppo", "CartPole-v1", "--set", "gamma"], 2,
                      e + "--set 'gamma' is not key=value (e.g. --set learning_rate=0.001)"),
        "bad value": (["train", "ppo", "CartPole-v1", "--set", "batch_size=1"], 2,
                      e + "invalid ppo settings: `batch_size` must be greater than 1 when "
                      "normalize_advantage=True (see "
                      "https://github.com/DLR-RM/stable-baselines3/issues/440) "
                      "(check --set/--config values)"),
        "algo cannot act": (["train", "dqn", "Pendulum-v1", "--progress", "none"], 2,
                            e + "cannot train dqn on Pendulum-v1: DQN does not support "
                            "Box(-2.0, 2.0, (1,), float32) action spaces; supported: Discrete "
                            "(use ppo)"),
        "bad schedule": (["train", "ppo", "CartPole-v1", "--set", "learning_rate=lin_fast"], 2,
                         e + "learning_rate='lin_fast' is not a linear schedule; write "
                         "'lin_<start>', e.g. 'lin_0.001' (fix the setting)"),
        "bad int": (["train", "ppo", "CartPole-v1", "--timesteps", "lots"], 2,
                    e + "argument --timesteps: invalid int value: 'lots' "
                    "(see palaestra train --help)"),
        "zero steps": (["train", "ppo", "CartPole-v1", "--timesteps", "0"], 2,
                       e + "n_timesteps must be a positive integer, got 0 (fix n_timesteps)"),
        "no algo": (["train"], 2,
                    e + "train needs ALGO and ENV (e.g. palaestra train ppo CartPole-v1)"),
        "resume nothing": (["train", "--resume", tmp_path / "none"], 2,
                           e + f"no run config at '{tmp_path / 'none' / 'config.json'}' "
                           "(check the path)"),
        "missing model": (["eval", tmp_path / "m.zip"], 2,
                          e + f"no model file at '{tmp_path / 'm.zip'}' "
                          "(pass a model.zip or a run folder written by train)"),
        "record missing model": (["record", tmp_path / "m.zip", "--out", tmp_path / "a.gif"], 2,
                                 e + f"no model file at '{tmp_path / 'm.zip'}' "
                                 "(pass a model.zip or a run folder written by train)"),
        # argparse quotes the choices from Python 3.12 on
        "unknown command": (["fly"], 2, re.compile(
            re.escape(e + "argument COMMAND: invalid choice: 'fly' (choose from ")
            + ".*envs.*bench.*" + re.escape(") (see palaestra --help)"))),
        "no command": ([], 2, e + "no command given (choose one of envs, train, eval, record, "
                       "compare, sweep, bench)"),
        "bench unknown env": (["bench", "--envs", "Qwxz-v0"], 2,
                              e + "Environment `Qwxz` doesn't exist. "
                              "(run `palaestra envs` to list the ids)"),
        "bench zero seconds": (["bench", "--seconds", "0"], 2,
                               e + "--seconds must be a positive number, got 0.0 (e.g. 0.5)"),
        "bench endless": (["bench", "--seconds", "inf"], 2,
                          e + "--seconds must be a positive number, got inf (e.g. 0.5)"),
        "bench no envs": (["bench", "--num-envs", "0"], 2,
                          e + "--num-envs must be at least 1, got 0 (e.g. 1024)"),
    }  # fmt: skip


def test_bad_input_gives_one_line_and_exit_code(tmp_path: Path) -> None:
    for name, (argv, code, line) in _bad(tmp_path).items():
        result = run_cli(*argv)
        if isinstance(line, str):
            assert (result.code, result.err) == (code, line + "\n"), name
        else:
            assert result.code == code and line.fullmatch(result.err.rstrip("\n")), name
        assert result.out == "" and len(result.err.splitlines()) == 1, name


def test_unknown_set_key_lists_the_valid_keys() -> None:
    result = run_cli("train", "dqn", "CartPole-v1", "--set", "learning_rate_typo=1")
    assert result.code == 2 and len(result.err.splitlines()) == 1
    assert result.err.startswith(
        "palaestra: error: unknown --set key 'learning_rate_typo' for dqn (valid keys: "
    )
    for key in ("batch_size", "exploration_fraction", "learning_rate", "n_envs", "n_timesteps",
                "policy_kwargs", "target_update_interval"):  # fmt: skip
        assert key in result.err
    config = run_cli("train", "dqn", "CartPole-v1", "--config", _write(
        "c.json", '{"hyperparams": {"clip_range": 0.2}}'))  # fmt: skip
    assert config.code == 2
    assert config.err.startswith("palaestra: error: config file 'c.json': unknown dqn setting "
                                 "'clip_range' (valid keys: ")  # fmt: skip


def _write(name: str, text: str) -> str:
    Path(name).write_text(text)
    return name


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)


def test_yaml_config_without_pyyaml(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "c.yaml").write_text("gamma: 0.9\n")
    monkeypatch.setitem(sys.modules, "yaml", None)  # `import yaml` now fails
    result = run_cli("train", "ppo", "CartPole-v1", "--config", tmp_path / "c.yaml")
    assert result.code == 1
    assert result.err == (
        'palaestra: error: PyYAML is not installed, run `pip install "palaestra[sweep]"` '
        f"(needed for reading the YAML config '{tmp_path / 'c.yaml'}'; or write it as JSON)\n"
    )


def test_console_script_and_module_errors_have_no_traceback() -> None:
    for argv in (
        [sys.executable, "-m", "palaestra", "train", "trpo", "Pendulum-v1"],
        [str(Path(sys.executable).with_name("palaestra")), "eval", "missing.zip"],
    ):
        if not Path(argv[0]).exists():
            continue  # the console script exists once the package is installed
        out = subprocess.run(argv, capture_output=True, text=True)
        assert out.returncode == 2, out.stderr
        assert len(out.stderr.splitlines()) == 1 and "Traceback" not in out.stderr
        assert out.stderr.startswith("palaestra: error: ")
