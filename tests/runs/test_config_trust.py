"""A settings file is data, as a run folder is (issue 24 #3, #8): the modules it names are
imported only with ``--allow-import``, except names that are palaestra's own (under
``palaestra``, or mapped by :mod:`palaestra.runs.known_names`); ``!!python`` tags are refused;
command-line values override the file's; its values are held to a run folder's limits; a
sweep writes nowhere a symbolic link in its folder points."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from tests.cli.conftest import run_cli

from palaestra.runs import RunError, known_names, resolve_spec
from palaestra.runs.folder import check_inside
from palaestra.runs.settings import load_config_file

# A wrapper module that leaves a marker file when imported: proof that code ran.
MODULE = """
from pathlib import Path
import palaestra as gym

Path(__file__).with_name("wrap_ct.imported").write_text("imported")

class Wrap(gym.Wrapper):
    pass
"""
QUIET = ("--progress", "none", "--eval-episodes", 0)
TINY = ("--timesteps", 64, "--n-envs", 1, "--set", "n_steps=32", "--set", "batch_size=32")
DOCS = Path(__file__).resolve().parents[2] / "docs" / "known_names.md"


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    (tmp_path / "wrap_ct.py").write_text(MODULE, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.delitem(sys.modules, "wrap_ct", raising=False)
    yield tmp_path
    sys.modules.pop("wrap_ct", None)


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


# -- the gate ----------------------------------------------------------------------------------
def test_an_unmapped_wrapper_in_a_config_file_is_refused(workdir: Path) -> None:
    _write(workdir, "best.yaml", "env_wrapper: wrap_ct:Wrap\n")
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "best.yaml", *TINY,
                     "--out", workdir / "run", *QUIET)  # fmt: skip
    assert (result.code, result.err) == (
        2,
        "palaestra: error: config file 'best.yaml' names env_wrapper 'wrap_ct:Wrap', which "
        "would import module 'wrap_ct'; palaestra runs no code named by a settings file (pass "
        "--allow-import wrap_ct to allow it; wrapper names in palaestra.runs.known_names "
        "(docs/known_names.md) need no flag)\n",
    )
    assert not (workdir / "wrap_ct.imported").exists() and not (workdir / "run").exists()
    with pytest.raises(RunError, match="palaestra runs no code named by a settings file"):
        resolve_spec("ppo", "CartPole-v1", config=workdir / "best.yaml")  # the Python API too
    assert not (workdir / "wrap_ct.imported").exists()


def test_an_unmapped_wrapper_runs_with_the_flag(workdir: Path) -> None:
    _write(workdir, "best.yaml", "env_wrapper: wrap_ct:Wrap\n")
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "best.yaml", *TINY,
                     "--allow-import", "wrap_ct", "--out", workdir / "run", *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    assert (
        "note: importing module 'wrap_ct' for env_wrapper 'wrap_ct:Wrap' of config file "
        "'best.yaml' (allowed)\n"
    ) in result.err
    assert (workdir / "wrap_ct.imported").exists()
    config = json.loads((workdir / "run" / "config.json").read_text())
    assert config["env_wrapper"] == "wrap_ct:Wrap"
    assert len(config["module_sha256"]["wrap_ct"]) == 64
    spec = resolve_spec("ppo", "CartPole-v1", config="best.yaml", allow_import=["wrap_ct"])
    assert spec[0].env_wrapper == "wrap_ct:Wrap"


@pytest.mark.parametrize(
    "name",
    ["gymnasium.wrappers.FlattenObservation", "gymnasium.wrappers:FlattenObservation",
     "palaestra.wrappers:FlattenObservation", "palaestra.wrappers.FlattenObservation"],
)  # fmt: skip
def test_palaestra_s_own_wrapper_names_need_no_flag(workdir: Path, name: str) -> None:
    from palaestra.wrappers import FlattenObservation

    _write(workdir, "best.json", json.dumps({"env_wrapper": [name]}))
    run = workdir / "run"
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "best.json", *TINY,
                     "--out", run, *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    assert "importing module" not in result.err
    config = json.loads((run / "config.json").read_text())
    assert config["env_wrapper"] == [name] and "module_sha256" not in config
    # The run folder naming it needs no flag either, and its env is palaestra's class.
    result = run_cli("eval", run, "--episodes", 1)
    assert result.code == 0, result.err
    from palaestra.runs.recipe import env_wrapper

    wrap = env_wrapper(config)
    assert wrap is not None
    import palaestra

    assert isinstance(wrap(palaestra.make("CartPole-v1")), FlattenObservation)


def test_python_yaml_tags_are_refused_by_name(workdir: Path) -> None:
    path = _write(
        workdir,
        "evil.yaml",
        "n_envs: 1\nhyperparams: !!python/object/apply:os.system ['touch pwned']\n",
    )
    message = (
        f"config file {str(path)!r} uses the YAML tag '!!python/object/apply:os.system' at "
        "line 2, column 14; palaestra reads settings files as plain data and builds no Python "
        "object"
    )
    with pytest.raises(RunError) as caught:
        load_config_file(str(path))
    assert (caught.value.what, caught.value.fix) == (
        message,
        "remove the tag: write the value as plain YAML",
    )
    result = run_cli("train", "ppo", "CartPole-v1", "--config", path, "--out", workdir / "run")
    assert result.code == 2 and result.err.startswith(f"palaestra: error: {message} (")
    assert not (workdir / "pwned").exists()
    _write(workdir, "name.yaml", "policy: !!python/name:os.system\n")
    with pytest.raises(RunError, match=r"the YAML tag '!!python/name:os.system' at line 1"):
        load_config_file("name.yaml")


# -- precedence and limits ---------------------------------------------------------------------
def test_command_line_values_override_the_file(workdir: Path) -> None:
    _write(workdir, "best.yaml",
           "n_envs: 2\nn_timesteps: 5000\nseed: 3\ngamma: 0.9\nlearning_rate: 0.01\n"
           "env_kwargs: {sutton_barto_reward: true}\n")  # fmt: skip
    spec, _ = resolve_spec(
        "ppo",
        "CartPole-v1",
        config="best.yaml",
        assignments=["gamma=0.95"],
        overrides={"env_kwargs": {"sutton_barto_reward": False}},
        n_envs=1,
        seed=7,
    )
    assert (spec.n_envs, spec.seed, spec.n_timesteps) == (1, 7, 5000)
    assert spec.hyperparams["gamma"] == 0.95 and spec.hyperparams["learning_rate"] == 0.01
    assert spec.env_kwargs == {"sutton_barto_reward": False}
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "best.yaml", "--seed", 5,
                     "--set", "gamma=0.97", "--env-kwargs", "sutton_barto_reward:False",
                     "--timesteps", 64, "--set", "n_steps=32", "--set", "batch_size=32",
                     "--out", workdir / "run", *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    config = json.loads((workdir / "run" / "config.json").read_text())
    assert (config["seed"], config["n_envs"], config["n_timesteps"]) == (5, 2, 64)
    assert config["hyperparams"]["gamma"] == 0.97
    assert config["env_kwargs"] == {"sutton_barto_reward": False}


@pytest.mark.parametrize(
    ("algo", "text", "message"),
    [
        ("ppo", "n_envs: 1000000000\n",
         "n_envs must be an integer from 1 to 4096, got 1000000000"),
        ("dqn", "buffer_size: 1000000000000\n",
         "hyperparams buffer_size=1000000000000 is refused: expected an integer from 1 to "),
        ("ppo", "frame_stack: 1000000\n",
         "frame_stack must be an integer from 1 to 256, got 1000000"),
        ("ppo", "hyperparams: {tensorboard_log: /tmp/x}\n", "unknown ppo setting"),
        ("ppo", "policy_kwargs: {net_arch: [1000000000]}\n",
         "hyperparams policy_kwargs.net_arch=[1000000000] is refused"),
        ("ppo", "module_sha256: {x: 1}\nn_envs: 0\n",
         "n_envs must be an integer from 1 to 4096, got 0"),
    ],
)  # fmt: skip
def test_config_values_are_held_to_run_folder_limits(
    workdir: Path, algo: str, text: str, message: str
) -> None:
    _write(workdir, "big.yaml", text)
    result = run_cli("train", algo, "CartPole-v1", "--config", "big.yaml", "--out", workdir / "r")
    assert result.code == 2 and result.err.count("\n") == 1, result.err
    assert result.err.startswith("palaestra: error: config file 'big.yaml'"), result.err
    assert message in result.err, result.err
    assert not (workdir / "r").exists()


def test_command_line_sizes_are_held_to_the_same_limits(workdir: Path) -> None:
    result = run_cli("train", "ppo", "CartPole-v1", "--n-envs", 100_000, "--out", workdir / "r")
    assert (result.code, result.err) == (
        2,
        "palaestra: error: settings: n_envs must be an integer from 1 to 4096, got 100000 "
        "(check --set, --n-envs, --timesteps and the config file)\n",
    )
    result = run_cli("train", "dqn", "CartPole-v1", "--set", "buffer_size=10**12")
    assert result.code == 2 and result.err.count("\n") == 1, result.err


# -- the table ---------------------------------------------------------------------------------
def test_rl_zoo_activation_names_map_to_preset_names() -> None:
    for name in ("nn.ReLU", "th.nn.ReLU", "torch.nn.ReLU"):
        spec, _ = resolve_spec("ppo", "CartPole-v1",
                               assignments=[f"policy_kwargs.activation_fn={name}"])  # fmt: skip
        assert spec.hyperparams["policy_kwargs"]["activation_fn"] == "relu"
    spec, _ = resolve_spec(
        "ppo", "CartPole-v1", config={"policy_kwargs": {"activation_fn": "nn.Tanh"}}
    )
    assert spec.hyperparams["policy_kwargs"]["activation_fn"] == "tanh"


def test_every_mapped_name_is_palaestra_s_and_exists() -> None:
    import importlib

    from palaestra import presets
    from palaestra.algos.callbacks import BaseCallback
    from palaestra.core import Wrapper

    for kind, table in known_names.KINDS.items():
        for name, ours in table.items():
            assert known_names.palaestra_name(kind, name) == ours
            if kind == "activation_fn":
                assert ours in presets.ACTIVATIONS, name
                continue
            module, _, attr = ours.partition(":")
            assert known_names.is_palaestra(module), ours
            target = getattr(importlib.import_module(module), attr)
            assert issubclass(target, Wrapper if kind == "env_wrapper" else BaseCallback), ours
    assert known_names.palaestra_name("env_wrapper", "rl_zoo3.wrappers.FrameSkip") is None
    assert known_names.palaestra_name("env_wrapper", "palaestra_evil:Wrap") is None


def test_the_gymnasium_and_sb3_names_exist_where_installed() -> None:
    """Each mapped Gymnasium 1.x / SB3 name is a real class there (installed in the dev venv)."""
    import importlib

    gymnasium = pytest.importorskip("gymnasium")
    if not gymnasium.__version__.startswith("1."):
        pytest.skip(f"Gymnasium {gymnasium.__version__}")
    old = ("time_limit", "resize_observation", "gray_scale_observation", "GrayScaleObservation")
    checked = 0
    for name in [*known_names.ENV_WRAPPERS, *known_names.CALLBACKS]:
        if any(part in name for part in old):  # Gymnasium 0.29's paths, gone in 1.x
            continue
        if (
            name.startswith("stable_baselines3")
            and importlib.util.find_spec("stable_baselines3") is None
        ):
            continue
        module, _, attr = name.rpartition(".")
        assert isinstance(getattr(importlib.import_module(module), attr), type), name
        checked += 1
    assert checked >= 25


def test_the_docs_page_shows_the_table() -> None:
    text = DOCS.read_text(encoding="utf-8")
    assert text.endswith(known_names.markdown_table())
    assert text.count("\n| `") == sum(len(t) for t in known_names.KINDS.values())


# -- a sweep folder ----------------------------------------------------------------------------
def test_check_inside_refuses_links_out_of_the_folder(tmp_path: Path) -> None:
    root, outside = tmp_path / "sweep", tmp_path / "outside"
    root.mkdir()
    outside.mkdir()
    check_inside(root / "trials", root, "trials")  # absent: fine
    (root / "trials").mkdir()
    (root / "trials" / "0").mkdir()
    check_inside(root / "trials", root, "trials")
    (root / "trials" / "7").symlink_to(outside)
    with pytest.raises(RunError) as caught:
        check_inside(root / "trials", root, "the sweep's trials folder")
    assert caught.value.line() == (
        f"the sweep's trials folder {str(root / 'trials' / '7')!r} links to "
        f"{str(outside.resolve())!r}, outside {str(root)!r} (remove the link: palaestra writes "
        "only inside the folder)"
    )


def test_a_sweep_with_a_symlinked_trials_folder_writes_nothing(tmp_path: Path) -> None:
    pytest.importorskip("optuna")
    from palaestra.runs.space import space_from_mapping
    from palaestra.runs.sweep import run_sweep

    folder, outside = tmp_path / "sweep", tmp_path / "outside"
    folder.mkdir()
    outside.mkdir()
    (folder / "trials").symlink_to(outside)
    space = space_from_mapping({"gamma": [0.9, 0.99]}, "ppo")
    with pytest.raises(RunError, match=r"trials' links to '.*/outside', outside"):
        run_sweep(space, "ppo", "CartPole-v1", 1, out=folder, n_timesteps=64)
    assert list(outside.iterdir()) == []
    assert sorted(p.name for p in folder.iterdir()) == ["trials"]


# -- wrapper arguments (RL Zoo's form) ---------------------------------------------------------
def test_a_mapped_wrapper_takes_rl_zoo_style_arguments(workdir: Path) -> None:
    _write(workdir, "zoo.yaml",
           "env_wrapper:\n  - gymnasium.wrappers.TimeLimit:\n      max_episode_steps: 7\n"
           "  - gymnasium.wrappers.FlattenObservation\n")  # fmt: skip
    run = workdir / "run"
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "zoo.yaml", *TINY,
                     "--out", run, *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    config = json.loads((run / "config.json").read_text())
    assert config["env_wrapper"] == [
        {"gymnasium.wrappers.TimeLimit": {"max_episode_steps": 7}},
        "gymnasium.wrappers.FlattenObservation",
    ]
    import palaestra
    from palaestra.runs.recipe import env_wrapper
    from palaestra.wrappers import FlattenObservation, TimeLimit

    wrap = env_wrapper(config)
    assert wrap is not None
    env = wrap(palaestra.make("CartPole-v1"))
    assert isinstance(env, FlattenObservation) and isinstance(env.env, TimeLimit)
    env.reset(seed=0)
    steps = [env.step(0) for _ in range(7)]  # pushing left: the pole stands 7 steps
    assert [s[3] for s in steps] == [False] * 6 + [True]  # truncated at the 7th


@pytest.mark.parametrize(
    ("wrapper", "message"),
    [
        ({"gymnasium.wrappers.TimeLimit": {"max_steps": 7}},
         "palaestra: error: env_wrapper 'gymnasium.wrappers.TimeLimit' does not take "
         "{'max_steps': 7}: missing a required argument: 'max_episode_steps' (fix its "
         "arguments)\n"),
        ({"gymnasium.wrappers.TimeLimit": 7},
         "palaestra: error: config file 'bad.json': env_wrapper must be 'module:Class' or a "
         "list of them (each may be {'module:Class': {kwargs}}), got "
         "[{'gymnasium.wrappers.TimeLimit': 7}] (fix the file)\n"),
        ({"a:W": {}, "b:V": {}}, "env_wrapper must be 'module:Class' or a list of them"),
    ],
)  # fmt: skip
def test_bad_wrapper_arguments_are_one_line(
    workdir: Path, wrapper: dict[str, object], message: str
) -> None:
    _write(workdir, "bad.json", json.dumps({"env_wrapper": [wrapper]}))
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "bad.json", "--out", workdir / "r")
    assert result.code == 2 and result.err.count("\n") == 1, result.err
    assert message in result.err, result.err
    assert not (workdir / "r").exists()


def test_wrappers_that_write_files_need_the_flag_even_under_palaestra(workdir: Path) -> None:
    target = workdir / "elsewhere"
    _write(workdir, "video.json",
           json.dumps({"env_wrapper": [{"palaestra.wrappers:RecordVideo":
                                        {"video_folder": str(target)}}]}))  # fmt: skip
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "video.json", *TINY,
                     "--out", workdir / "r", *QUIET)  # fmt: skip
    assert result.code == 2, result.err
    assert (
        "names env_wrapper 'palaestra.wrappers:RecordVideo', which would import module "
        "'palaestra.wrappers'; palaestra runs no code named by a settings file (pass "
        "--allow-import palaestra.wrappers to allow it"
    ) in result.err
    assert not target.exists() and not (workdir / "r").exists()
    for name in ("palaestra.wrappers.monitor:Monitor", "palaestra.wrappers.HumanRendering"):
        assert known_names.palaestra_name("env_wrapper", name) is None


def test_wrapper_arguments_need_keyword_names(workdir: Path) -> None:
    _write(workdir, "keys.yaml", "env_wrapper:\n  - gymnasium.wrappers.TimeLimit:\n      5: 7\n")
    result = run_cli("train", "ppo", "CartPole-v1", "--config", "keys.yaml", "--out", workdir / "r")
    assert result.code == 2 and result.err.count("\n") == 1, result.err
    assert "config file 'keys.yaml': env_wrapper must be 'module:Class' or a list" in result.err
