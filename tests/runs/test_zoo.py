"""RL Zoo hyperparameter files read as palaestra settings (``train --config ppo.yml``), tested
on the Zoo's own files as ``rl_zoo3`` installs them (``requirements/dev-no-deps.txt``): every
section of ppo/dqn/sac/td3/a2c parses or names the one key it cannot take, Python-literal
values are read without ``eval``, and CartPole, Pendulum, LunarLander and an Atari game train
from the files."""

from __future__ import annotations

import importlib.util
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from tests.cli.conftest import run_cli

import palaestra
from palaestra.runs import RunError, folder, known_names, resolve_spec, zoo
from palaestra.runs.literal import MAX_LENGTH, literal
from palaestra.runs.settings import load_config_file, resolve_settings, zoo_section_settings


def _zoo_files() -> Path | None:
    found = importlib.util.find_spec("rl_zoo3")  # finds the package without running it
    if found is None or not found.submodule_search_locations:
        return None
    return Path(next(iter(found.submodule_search_locations))) / "hyperparams"


ZOO = _zoo_files()
needs_zoo = pytest.mark.skipif(
    ZOO is None,
    reason="rl_zoo3 not installed: pip install --no-deps -r requirements/dev-no-deps.txt",
)
FILES = ("ppo", "dqn", "sac", "td3", "a2c")
QUIET = ("--progress", "none", "--eval-episodes", 0, "--checkpoint-every", 0)
GATE = "palaestra runs no code named by a settings file"
# What each section palaestra cannot take says: (file, section) -> the start of the error.
# A section not listed must parse; a new failure (or a fixed one) fails the test.
EXPECTED: dict[tuple[str, str], str] = {
    **{
        ("ppo", name): (
            f"section {name!r} names env_wrapper 'minigrid.wrappers.FlatObsWrapper', which would "
            f"import module 'minigrid.wrappers'; {GATE}"
        )
        for name in (
            "MiniGrid-Empty-Random-5x5-v0",
            "MiniGrid-FourRooms-v0",
            "MiniGrid-DoorKey-5x5-v0",
            "MiniGrid-MultiRoom-N4-S5-v0",
            "MiniGrid-Fetch-5x5-N2-v0",
            "MiniGrid-GoToDoor-5x5-v0",
            "MiniGrid-PutNear-6x6-N2-v0",
            "MiniGrid-RedBlueDoors-6x6-v0",
            "MiniGrid-LockedRoom-v0",
            "MiniGrid-KeyCorridorS3R1-v0",
            "MiniGrid-Unlock-v0",
            "MiniGrid-ObstructedMaze-2Dlh-v0",
        )
    },
    # GELU: palaestra's policies build ReLU, Tanh, ELU and LeakyReLU only (presets.ACTIVATIONS)
    ("ppo", "CarRacing-v3"): (
        "section 'CarRacing-v3': policy_kwargs: 'nn.GELU' in 'dict(log_std_init=-2, "
        "ortho_init=False, activation_fn=nn.GELU, net_arch=dict(pi=[256], vf=[256]), )' is "
        "refused: unknown name 'nn.GELU'"
    ),
    # SB3's TF-like RMSprop (sb3_common.sb2_compat) has no palaestra equivalent
    ("a2c", "atari"): (
        "section 'atari': policy_kwargs: 'RMSpropTFLike' in 'dict(optimizer_class=RMSpropTFLike, "
        "optimizer_kwargs=dict(eps=1e-5))' is refused: unknown name 'RMSpropTFLike'"
    ),
    # rl_zoo3's own wrappers (FrameSkip, HistoryWrapper) have no palaestra equivalent
    ("sac", "CarRacing-v3"): (
        "section 'CarRacing-v3' names env_wrapper 'rl_zoo3.wrappers.FrameSkip', which would "
        f"import module 'rl_zoo3.wrappers'; {GATE}"
    ),
    ("sac", "donkey-generated-track-v0"): (
        "section 'donkey-generated-track-v0' names env_wrapper 'rl_zoo3.wrappers.HistoryWrapper', "
        f"which would import module 'rl_zoo3.wrappers'; {GATE}"
    ),
    ("sac", "NeckEnvRelative-v2"): (
        "section 'NeckEnvRelative-v2' names env_wrapper 'rl_zoo3.wrappers.HistoryWrapper', "
        f"which would import module 'rl_zoo3.wrappers'; {GATE}"
    ),
}


def _action_size(env_id: str) -> int:
    """The env's action dimensions where palaestra registers it; 1 for the Zoo's other ids
    (Bullet, MuJoCo v4, donkey), whose size changes only the noise's length."""
    if env_id in palaestra.registry:
        return zoo.action_size(env_id, {})
    return 1


def _parse(algo: str, name: str, section: dict[str, Any]) -> dict[str, Any]:
    """One section as ``train --config`` reads it: settings, then the import gate."""
    source = f"config file '{algo}.yml' section {name!r}"
    settings = zoo_section_settings(algo, section, source, lambda: _action_size(name))
    folder.check_imports(settings, source, (), "settings file")
    return settings


def _sections() -> Iterator[tuple[str, str, dict[str, Any]]]:
    assert ZOO is not None
    for algo in FILES:
        data = load_config_file(str(ZOO / f"{algo}.yml"))
        assert zoo.is_zoo_file(data, {"policy", "n_envs", "atari", "hyperparams"}), algo
        for name, section in data.items():
            yield algo, name, section


@needs_zoo
def test_every_section_parses_or_names_what_it_cannot_take() -> None:
    seen: set[tuple[str, str]] = set()
    parsed = 0
    for algo, name, section in _sections():
        seen.add((algo, name))
        expected = EXPECTED.get((algo, name))
        if expected is None:
            try:
                _parse(algo, name, section)
            except RunError as exc:
                pytest.fail(f"{algo}.yml section {name!r}: {exc.line()}")
            parsed += 1
            continue
        with pytest.raises(RunError) as caught:
            _parse(algo, name, section)
        assert caught.value.what.startswith(f"config file '{algo}.yml' {expected}"), (
            algo,
            name,
            caught.value.what,
        )
    assert set(EXPECTED) <= seen, sorted(set(EXPECTED) - seen)  # no stale expectation
    assert parsed == len(seen) - len(EXPECTED) and parsed >= 100, parsed


@needs_zoo
def test_a_her_section_names_palaestras_her_buffer() -> None:
    assert ZOO is not None
    sac = load_config_file(str(ZOO / "sac.yml"))
    hyper = _parse("sac", "FetchReach-v1", sac["FetchReach-v1"])["hyperparams"]
    assert hyper["replay_buffer_class"] == "HerReplayBuffer"
    assert hyper["replay_buffer_kwargs"] == {
        "goal_selection_strategy": "future",
        "n_sampled_goal": 4,
    }


@needs_zoo
def test_sections_read_as_the_zoo_reads_them() -> None:
    assert ZOO is not None
    ppo = load_config_file(str(ZOO / "ppo.yml"))
    cartpole = _parse("ppo", "CartPole-v1", ppo["CartPole-v1"])
    assert cartpole == {
        "n_envs": 8,
        "n_timesteps": 100_000,  # !!float 1e5
        "policy": "MlpPolicy",
        "hyperparams": {
            "n_steps": 32,
            "batch_size": 256,
            "gae_lambda": 0.8,
            "gamma": 0.98,
            "n_epochs": 20,
            "ent_coef": 0.0,
            "learning_rate": "lin_0.001",  # the presets' schedule form
            "clip_range": "lin_0.2",
        },
    }
    # A merge key: AntBulletEnv-v0 is HalfCheetahBulletEnv-v0's section with its own lines.
    ant = _parse("ppo", "AntBulletEnv-v0", ppo["AntBulletEnv-v0"])
    cheetah = _parse("ppo", "HalfCheetahBulletEnv-v0", ppo["HalfCheetahBulletEnv-v0"])
    assert ant["hyperparams"]["policy_kwargs"] == {
        "log_std_init": -1,
        "ortho_init": False,
        "activation_fn": "relu",
        "net_arch": {"pi": [256, 256], "vf": [256, 256]},
    }
    assert cheetah["hyperparams"]["policy_kwargs"]["log_std_init"] == -2
    assert {k: v for k, v in ant.items() if k != "hyperparams"} == {
        "normalize": True, "n_envs": 16, "n_timesteps": 2_000_000, "policy": "MlpPolicy"
    }  # fmt: skip
    assert ant["hyperparams"]["n_epochs"] == 20
    atari = _parse("ppo", "atari", ppo["atari"])
    assert (atari["atari"], atari["frame_stack"], atari["policy"]) == (True, 4, "CnnPolicy")
    assert "env_wrapper" not in atari
    sac = load_config_file(str(ZOO / "sac.yml"))
    humanoid = _parse("sac", "HumanoidBulletEnv-v0", sac["HumanoidBulletEnv-v0"])
    assert humanoid["normalize"] == {"norm_obs": True, "norm_reward": False}
    donkey = sac["donkey-generated-track-v0"]
    assert zoo.section_settings("sac", donkey, "s", {"log_std_init", "net_arch", "use_expln"},
                                lambda: 2)["train_freq"] == [1, "episode"]  # fmt: skip
    td3 = load_config_file(str(ZOO / "td3.yml"))
    for name, kind, sigma in (
        ("Pendulum-v1", "NormalActionNoise", [0.1]),
        ("MountainCarContinuous-v0", "OrnsteinUhlenbeckActionNoise", [0.5]),
        ("BipedalWalker-v3", "NormalActionNoise", [0.1] * 4),
    ):
        noise = _parse("td3", name, td3[name])["hyperparams"]["action_noise"]
        assert noise == {"type": kind, "mean": [0.0] * len(sigma), "sigma": sigma}


# -- choosing the section ----------------------------------------------------------------------
def _write(folder_: Path, name: str, text: str) -> str:
    (folder_ / name).write_text(text, encoding="utf-8")
    return str(folder_ / name)


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return tmp_path


SECTIONS = """
default: &base
  n_timesteps: !!float 2e3
  policy: MlpPolicy
  gamma: 0.9
atari:
  policy: CnnPolicy
  env_wrapper:
    - stable_baselines3.common.atari_wrappers.AtariWrapper:
        terminal_on_life_loss: false
  frame_stack: 4
CartPole-v1:
  <<: *base
  n_envs: 2
  learning_rate: lin_3e-4
"""


def test_the_env_s_section_then_atari_then_default(workdir: Path) -> None:
    path = _write(workdir, "ppo.yml", SECTIONS)
    settings, used, notes = resolve_settings("ppo", "CartPole-v1", config=path)
    assert used is None  # the section replaces the CartPole preset
    assert (settings["n_envs"], settings["n_timesteps"]) == (2, 2000)
    assert settings["hyperparams"] == {"gamma": 0.9, "learning_rate": "lin_3e-4"}
    assert notes == [
        f"settings from section 'CartPole-v1' of the RL Zoo file {path!r} over the PPO defaults "
        "(SB3's), not a preset"
    ]
    settings, _, _ = resolve_settings("ppo", "Acrobot-v1", config=path)
    assert (settings["n_envs"], settings["hyperparams"]) == (1, {"gamma": 0.9})
    pytest.importorskip("ale_py")
    settings, _, _ = resolve_settings("ppo", "ALE/Pong-v5", config=path)
    assert settings["atari"] == {"terminal_on_life_loss": False}
    assert (settings["frame_stack"], settings["env_kwargs"]) == (4, {"frameskip": 1})
    assert "env_wrapper" not in settings


def test_a_preset_asked_for_goes_beneath_the_section(workdir: Path) -> None:
    path = _write(workdir, "ppo.yml", SECTIONS)
    settings, used, _ = resolve_settings("ppo", "CartPole-v1", "default", config=path)
    assert used == "default" and settings["n_envs"] == 2
    assert settings["hyperparams"]["n_steps"] == 32  # the preset's, under the section


def test_no_section_for_the_env_lists_the_sections(workdir: Path) -> None:
    path = _write(workdir, "ppo.yml", "Pendulum-v1: {n_envs: 4}\nAcrobot-v1: {n_envs: 2}\n")
    with pytest.raises(RunError) as caught:
        resolve_spec("ppo", "CartPole-v1", config=path)
    assert caught.value.line() == (
        f"config file {path!r} (an RL Zoo hyperparameter file) has no section 'CartPole-v1' or "
        "'default'; its sections: 'Pendulum-v1', 'Acrobot-v1' (add a section named "
        "CartPole-v1, or train an env it has)"
    )


def test_palaestra_settings_files_are_not_sections(workdir: Path) -> None:
    assert not zoo.is_zoo_file({"hyperparams": {"gamma": 0.9}}, {"hyperparams"})
    assert not zoo.is_zoo_file({"atari": {"noop_max": 10}}, {"atari"})
    assert not zoo.is_zoo_file({"n_envs": 2, "default": {}}, {"n_envs"})
    assert zoo.is_zoo_file({"atari": {"policy": "CnnPolicy"}}, {"atari", "policy"})


# -- what a section cannot hold ----------------------------------------------------------------
@pytest.mark.parametrize("key", sorted(zoo.REFUSED))
def test_keys_palaestra_cannot_take_are_refused_with_why(key: str) -> None:
    with pytest.raises(RunError) as caught:
        zoo.section_settings("sac", {key: "x.Y"}, "zoo", set(), lambda: 1)
    assert caught.value.what == f"zoo: {key} 'x.Y' is refused: {zoo.REFUSED[key]}"


@pytest.mark.parametrize(
    ("section", "message"),
    [
        ({"n_timesteps": 1.5e3 + 0.5}, "zoo: n_timesteps must be a whole number, got 1500.5"),
        ({"n_timesteps": True}, "zoo: n_timesteps must be a whole number, got True"),
        ({"policy": "my.policies.Custom"},
         "zoo: policy 'my.policies.Custom' names a class; palaestra's settings name a policy "
         "of the algorithm"),
        ({"policy_kwargs": "dict(use_expln=True)"},
         "zoo: policy_kwargs use_expln=True is refused: palaestra's DQN policy takes no "
         "'use_expln'"),
        ({"policy_kwargs": "[64, 64]"}, "zoo: policy_kwargs must be dict(...), got [64, 64]"),
        ({"normalize": "[1]"},
         "zoo: normalize must give VecNormalize kwargs as {...}, got [1]"),
        ({"noise_std": 0.1}, "zoo: noise_std 0.1 without noise_type"),
        ({"replay_buffer_class": "DictReplayBuffer"},
         "zoo: replay_buffer_class 'DictReplayBuffer' is refused: palaestra's algorithms take "
         "HerReplayBuffer or none"),
        ({"noise_type": "adaptive-param", "noise_std": 0.1},
         "zoo: noise_type 'adaptive-param' is refused: expected one of ['normal', "
         "'ornstein-uhlenbeck']"),
        ({"noise_type": "normal", "noise_std": -1},
         "zoo: noise_std must be a number >= 0 (or 2 of them), got -1"),
        ({"env_wrapper": ["stable_baselines3.common.atari_wrappers.AtariWrapper",
                          "gymnasium.wrappers.FlattenObservation"]},
         "zoo: env_wrapper ['stable_baselines3.common.atari_wrappers.AtariWrapper', "
         "'gymnasium.wrappers.FlattenObservation'] is refused: palaestra's Atari recipe"),
        ({"env_wrapper": 7}, "zoo: env_wrapper must be 'module:Class', got 7"),
    ],
)  # fmt: skip
def test_bad_section_values_name_the_value(section: dict[str, Any], message: str) -> None:
    with pytest.raises(RunError) as caught:
        zoo.section_settings("dqn", section, "zoo", {"net_arch", "activation_fn"}, lambda: 2)
    assert caught.value.what.startswith(message), caught.value.what


def test_noise_on_discrete_actions_is_refused(workdir: Path) -> None:
    path = _write(workdir, "dqn.yml", "CartPole-v1: {noise_type: normal, noise_std: 0.1}\n")
    with pytest.raises(RunError, match=r"noise_type adds noise to continuous actions; "
                       r"CartPole-v1 has Discrete\(2\)"):  # fmt: skip
        resolve_spec("dqn", "CartPole-v1", config=path)


def test_python_kwargs_strings_are_read_in_any_settings(workdir: Path) -> None:
    text = 'policy_kwargs: "dict(net_arch=[64, 64], activation_fn=nn.ReLU)"\n'
    path = _write(workdir, "flat.yaml", text)
    for spec, _ in (
        resolve_spec("ppo", "CartPole-v1", config=path),
        resolve_spec("ppo", "CartPole-v1", assignments=["policy_kwargs=dict(net_arch=[64, 64], "
                                                        "activation_fn=nn.ReLU)"]),
    ):  # fmt: skip
        assert spec.hyperparams["policy_kwargs"] == {"net_arch": [64, 64], "activation_fn": "relu"}
    with pytest.raises(RunError) as caught:
        resolve_spec("dqn", "CartPole-v1", assignments=["policy_kwargs=__import__('os')"])
    assert caught.value.what.startswith(
        "--set: policy_kwargs: \"__import__('os')\" in \"__import__('os')\" is refused: the only "
        "call allowed is dict(key=value, ...)"
    )


# -- the literal reader ------------------------------------------------------------------------
NAMES = {"nn.ReLU": "relu", "th.nn.Tanh": "tanh"}


def test_literals_dicts_and_table_names_are_read() -> None:
    text = """dict(
        log_std_init=-2.5, ortho_init=False, activation_fn=th.nn.Tanh, x=None, t=(1, +2),
        net_arch=dict(pi=[256, 256], vf=[64]), k={'a': 'b'}, e=1e-5,
    )"""
    assert literal(text, "policy_kwargs", NAMES) == {
        "log_std_init": -2.5,
        "ortho_init": False,
        "activation_fn": "tanh",
        "x": None,
        "t": [1, 2],
        "net_arch": {"pi": [256, 256], "vf": [64]},
        "k": {"a": "b"},
        "e": 1e-5,
    }


@pytest.mark.parametrize(
    ("text", "piece", "why"),
    [
        ("dict(activation_fn=nn.GELU)", "nn.GELU", "unknown name 'nn.GELU'"),
        ("dict(a=os)", "os", "unknown name 'os'"),
        ("nn.ReLU.__class__", "nn.ReLU.__class__", "unknown name 'nn.ReLU.__class__'"),
        ("__import__('os')", "__import__('os')", "the only call allowed is dict(key=value, ...)"),
        ("__import__('os').system('touch pwned')", "__import__('os').system('touch pwned')",
         "the only call allowed is dict(key=value, ...)"),
        ("().__class__.__bases__", "().__class__.__bases__",
         "an attribute of a value is not data"),
        ("dict(a=''.join)", "''.join", "an attribute of a value is not data"),
        ("getattr(nn, 'ReLU')", "getattr(nn, 'ReLU')",
         "the only call allowed is dict(key=value, ...)"),
        ("nn.ReLU()", "nn.ReLU()", "the only call allowed is dict(key=value, ...)"),
        ("dict([('a', 1)])", "dict([('a', 1)])", "dict(...) takes keyword arguments only"),
        ("dict(**{'a': 1})", "dict(**{'a': 1})", "** unpacking is not data"),
        ("{**x}", "{**x}", "** unpacking is not data"),
        ("{1: 2}", "1", "a key must be a string"),
        ("dict(n=10**100000)", "10**100000", "BinOp is not data"),
        ("[x for x in ()]", "[x for x in ()]", "ListComp is not data"),
        ("lambda: 0", "lambda: 0", "Lambda is not data"),
        ("dict(a=b'x')", "b'x'", "Constant is not data"),
        ("dict(a=-'x')", "-'x'", "a sign applies to a number only"),
        ("{1, 2}", "{1, 2}", "Set is not data"),
        ("nn.ReLU[0]", "nn.ReLU[0]", "Subscript is not data"),
        ("f'{nn}'", "f'{nn}'", "JoinedStr is not data"),
    ],
)  # fmt: skip
def test_anything_but_data_is_refused_by_name(text: str, piece: str, why: str) -> None:
    with pytest.raises(RunError) as caught:
        literal(text, "policy_kwargs", NAMES)
    assert caught.value.what == f"policy_kwargs: {piece!r} in {text!r} is refused: {why}" + (
        ", which palaestra.runs.known_names (docs/known_names.md) does not map"
        if why.startswith("unknown name")
        else ""
    )
    assert caught.value.fix == (
        "write literals, lists, {...} or dict(key=value) only, and names among: nn.ReLU, th.nn.Tanh"
    )


def test_text_that_is_no_python_or_too_long_is_refused() -> None:
    with pytest.raises(RunError) as caught:
        literal("dict(a=", "normalize", {})
    assert caught.value.what == "normalize: 'dict(a=' is not a Python literal: '(' was never closed"
    with pytest.raises(RunError, match=f"of {MAX_LENGTH + 1:,} characters is refused"):
        literal("[" + " " * (MAX_LENGTH - 1) + "]", "normalize", {})
    with pytest.raises(RunError, match=r"nests too deeply|is not a Python literal"):
        literal("[" * 5000 + "]" * 5000, "normalize", {})


def test_a_zoo_file_runs_no_code(workdir: Path) -> None:
    text = "CartPole-v1:\n  policy_kwargs: \"__import__('os').system('touch pwned')\"\n"
    path = _write(workdir, "ppo.yml", text)
    result = run_cli("train", "ppo", "CartPole-v1", "--config", path, "--out", workdir / "r")
    assert (result.code, result.err) == (
        2,
        f"palaestra: error: config file {path!r} section 'CartPole-v1': policy_kwargs: "
        "\"__import__('os').system('touch pwned')\" in \"__import__('os').system('touch "
        "pwned')\" is refused: the only call allowed is dict(key=value, ...) (write literals, "
        "lists, {...} or dict(key=value) only, and names among: "
        + ", ".join(sorted(known_names.ACTIVATIONS))
        + ")\n",
    )
    assert not (workdir / "pwned").exists() and not (workdir / "r").exists()


# -- training from the Zoo's files -------------------------------------------------------------
def _train(workdir: Path, algo: str, env_id: str, *args: object) -> dict[str, Any]:
    assert ZOO is not None
    out = workdir / "run"
    result = run_cli("train", algo, env_id, "--config", ZOO / f"{algo}.yml", "--seed", 0,
                     "--out", out, *args, *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    assert "note: settings from section " in result.err
    config = json.loads((out / "config.json").read_text())
    assert config["preset"] is None
    return config


@needs_zoo
def test_ppo_trains_cartpole_from_the_zoo_file(workdir: Path) -> None:
    config = _train(workdir, "ppo", "CartPole-v1", "--timesteps", 256)
    assert (config["n_envs"], config["n_timesteps"], config["policy"]) == (8, 256, "MlpPolicy")
    assert config["hyperparams"]["learning_rate"] == "lin_0.001"
    status = json.loads((workdir / "run" / "status.json").read_text())
    assert status["num_timesteps"] == 256


@needs_zoo
def test_td3_trains_pendulum_with_the_zoo_s_noise(workdir: Path) -> None:
    config = _train(workdir, "td3", "Pendulum-v1", "--timesteps", 200,
                    "--set", "learning_starts=100")  # fmt: skip
    assert config["hyperparams"]["action_noise"] == {
        "type": "NormalActionNoise", "mean": [0.0], "sigma": [0.1]
    }  # fmt: skip
    assert config["hyperparams"]["policy_kwargs"] == {"net_arch": [400, 300]}
    from palaestra.algos import TD3
    from palaestra.algos.common.action_noise import NormalActionNoise

    model = TD3.load(workdir / "run" / "model.zip")
    assert isinstance(model.action_noise, NormalActionNoise)
    assert model.policy_kwargs["net_arch"] == [400, 300]


@needs_zoo
def test_dqn_trains_lunar_lander_from_the_zoo_file(workdir: Path) -> None:
    pytest.importorskip("Box2D")
    config = _train(workdir, "dqn", "LunarLander-v3", "--timesteps", 256)
    assert config["hyperparams"]["policy_kwargs"] == {"net_arch": [256, 256]}
    assert config["hyperparams"]["gradient_steps"] == -1


@needs_zoo
def test_ppo_trains_an_atari_game_from_the_zoo_s_atari_section(workdir: Path) -> None:
    pytest.importorskip("ale_py")
    config = _train(workdir, "ppo", "ALE/Pong-v5", "--timesteps", 64, "--n-envs", 2,
                    "--set", "n_steps=32", "--set", "batch_size=32")  # fmt: skip
    assert (config["atari"], config["frame_stack"], config["policy"]) == (True, 4, "CnnPolicy")
    assert config["env_kwargs"] == {"frameskip": 1} and "env_wrapper" not in config
    assert config["hyperparams"]["clip_range"] == "lin_0.1"
