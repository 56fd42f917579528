"""A user's own env from the command line (issue 24 #2): ``palaestra train ppo
mygrid_ue:GridWorldUE-v0`` imports ``mygrid_ue.py`` from the current folder, records the
module's sha256 in the run folder; ``eval``, ``record`` and ``--resume`` of that run import it
only with ``--allow-import mygrid_ue``, say where it is missing and warn when it changed.
With no preset the policy follows the observation space; ``--env-kwargs`` reaches the env."""

from __future__ import annotations

import hashlib
import json
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from .conftest import Result, run_cli

NAME = "mygrid_ue"
ENV = f"{NAME}:GridWorldUE-v0"
# The user's module: a tiny grid, Dict observations on request; each import adds a line to
# imports.log beside it (proof that its code ran).
MODULE = """
from pathlib import Path

import numpy as np

import palaestra as gym
from palaestra import spaces

with open(Path(__file__).with_name("imports.log"), "a") as log:
    log.write("imported\\n")


class GridWorld(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, size=4, dict_obs=False, render_mode=None):
        self.size, self.dict_obs, self.render_mode = size, dict_obs, render_mode
        box = spaces.Box(0.0, float(size), shape=(2,), dtype=np.float32)
        self.observation_space = spaces.Dict({"pos": box}) if dict_obs else box
        self.action_space = spaces.Discrete(4)
        self.pos = [0, 0]

    def _obs(self):
        obs = np.array(self.pos, dtype=np.float32)
        return {"pos": obs} if self.dict_obs else obs

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.pos = [0, 0]
        return self._obs(), {}

    def step(self, action):
        dx, dy = [(1, 0), (-1, 0), (0, 1), (0, -1)][int(action)]
        self.pos = [min(max(self.pos[0] + dx, 0), self.size - 1),
                    min(max(self.pos[1] + dy, 0), self.size - 1)]
        done = self.pos == [self.size - 1, self.size - 1]
        return self._obs(), float(done), done, False, {}

    def render(self):
        return np.zeros((8, 8, 3), dtype=np.uint8)


gym.register("GridWorldUE-v0", entry_point=GridWorld, max_episode_steps=12)
"""
TINY = ("--timesteps", 64, "--set", "n_steps=32", "--set", "batch_size=32")
QUIET = ("--progress", "none", "--eval-episodes", 0)


def _forget() -> None:
    """As in a new process: the module not imported, its id not registered."""
    from palaestra.envs.registration import registry

    sys.modules.pop(NAME, None)
    registry.pop("GridWorldUE-v0", None)


def _imports(folder: Path) -> int:
    log = folder / "imports.log"
    return len(log.read_text().splitlines()) if log.exists() else 0


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The user's project folder, holding ``mygrid_ue.py``, as the current folder."""
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / f"{NAME}.py").write_text(MODULE, encoding="utf-8")
    monkeypatch.chdir(folder)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", ".")])
    _forget()
    yield folder
    _forget()


def _cli(*argv: object) -> Result:
    _forget()
    return run_cli(*argv)


@pytest.fixture
def trained(project: Path) -> Path:
    """A tiny PPO run on the user's env, trained from the project folder."""
    result = _cli("train", "ppo", ENV, *TINY, "--seed", 0, "--out", project / "run", *QUIET)
    assert result.code == 0, result.err
    assert _imports(project) == 1
    return project / "run"


def _commands(run: Path, where: Path) -> dict[str, list[object]]:
    return {
        "eval": ["eval", run, "--episodes", 1],
        "record": ["record", run, "--out", where / "a.gif"],
        "resume": ["train", "--resume", run, "--timesteps", 128, *QUIET],
    }


def test_train_on_a_user_module_env_records_it(trained: Path, project: Path) -> None:
    config = json.loads((trained / "config.json").read_text())
    assert config["env_id"] == ENV and config["policy"] == "MlpPolicy"
    digest = hashlib.sha256((project / f"{NAME}.py").read_bytes()).hexdigest()
    assert config["module_sha256"] == {NAME: digest}
    assert (trained / "model.zip").is_file()


def test_no_preset_prints_the_policy_chosen_for_box_observations(project: Path) -> None:
    result = _cli("train", "ppo", ENV, *TINY, "--out", project / "run", *QUIET)
    assert result.code == 0, result.err
    assert (
        f"note: no preset for ppo on {ENV}: using the PPO defaults (SB3's) with MlpPolicy, "
        "chosen for its Box observations\n"
    ) in result.err


def test_dict_observations_choose_multi_input_policy_and_env_kwargs_reach_the_env(
    project: Path,
) -> None:
    from palaestra.algos import PPO

    out = project / "run"
    result = _cli("train", "ppo", ENV, *TINY, "--env-kwargs", "dict_obs:True", "size:3",
                  "--out", out, *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    assert (
        f"note: no preset for ppo on {ENV}: using the PPO defaults (SB3's) with "
        "MultiInputPolicy, chosen for its Dict observations\n"
    ) in result.err
    config = json.loads((out / "config.json").read_text())
    assert config["policy"] == "MultiInputPolicy"
    assert config["env_kwargs"] == {"dict_obs": True, "size": 3}
    model = PPO.load(out / "model.zip")
    assert float(model.observation_space["pos"].high.max()) == 3.0  # size 3 reached the env


def test_a_policy_given_is_kept(project: Path) -> None:
    out = project / "run"
    result = _cli("train", "ppo", ENV, *TINY, "--env-kwargs", "dict_obs:True",
                  "--set", "policy=MultiInputPolicy", "--out", out, *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    assert "with the policy given, MultiInputPolicy\n" in result.err


def test_env_kwargs_override_the_config_file(project: Path) -> None:
    (project / "s.json").write_text(json.dumps({"env_kwargs": {"size": 6, "dict_obs": False}}))
    out = project / "run"
    result = _cli("train", "ppo", ENV, *TINY, "--config", "s.json", "--env-kwargs", "size:3",
                  "--out", out, *QUIET)  # fmt: skip
    assert result.code == 0, result.err
    config = json.loads((out / "config.json").read_text())
    assert config["env_kwargs"] == {"size": 3, "dict_obs": False}


@pytest.mark.parametrize(
    ("item", "message"),
    [
        ("size=3", "palaestra: error: --env-kwargs 'size=3' is not KEY:VALUE (e.g. "
                   "--env-kwargs size:5)\n"),
        ("size:{1, 2}", "palaestra: error: --env-kwargs 'size:{1, 2}': {1, 2} is not plain "
                        "data (use numbers, true/false, text, lists or dicts)\n"),
    ],
)  # fmt: skip
def test_bad_env_kwargs_are_one_line(project: Path, item: str, message: str) -> None:
    result = _cli("train", "ppo", ENV, "--env-kwargs", item, "--out", project / "run")
    assert (result.code, result.err) == (2, message)
    assert not (project / "run").exists()


def test_an_env_kwarg_the_env_refuses_is_one_line(project: Path) -> None:
    result = _cli("train", "ppo", ENV, "--env-kwargs", "colour:1", "--out", project / "run")
    assert result.code == 2 and result.err.count("\n") == 1, result.err
    assert result.err.startswith(
        f"palaestra: error: cannot make {ENV} with env_kwargs {{'colour': 1}}: "
    )


def test_resume_refuses_env_kwargs(trained: Path) -> None:
    result = _cli("train", "--resume", trained, "--env-kwargs", "size:3")
    assert (result.code, result.err) == (
        2,
        "palaestra: error: --resume continues a run with its saved settings; --env-kwargs "
        "cannot change them (drop them, or start a new run)\n",
    )


def test_a_missing_module_on_the_command_line_is_one_line(project: Path) -> None:
    result = _cli("train", "ppo", "nosuchgrid_ue:Grid-v0", "--out", project / "run")
    assert result.code == 2 and result.err.count("\n") == 1, result.err
    assert result.err.startswith(
        "palaestra: error: cannot import module 'nosuchgrid_ue' of env id "
        "'nosuchgrid_ue:Grid-v0': No module named 'nosuchgrid_ue' (run from the folder that "
        "holds it, or fix the name)"
    )


def test_eval_record_resume_refuse_the_run_s_module_without_the_flag(
    trained: Path, project: Path
) -> None:
    for name, argv in _commands(trained, project).items():
        result = _cli(*argv)
        assert (result.code, result.err) == (
            2,
            f"palaestra: error: {trained / 'config.json'} names env_id {ENV!r}, which would "
            f"import module {NAME!r}; palaestra runs no code named by a run folder (pass "
            f"--allow-import {NAME} to allow it)\n",
        ), name
    assert _imports(project) == 1  # train's import only
    assert not (project / "a.gif").exists()


def test_eval_record_resume_import_it_with_the_flag(trained: Path, project: Path) -> None:
    note = (
        f"note: importing module {NAME!r} for env_id {ENV!r} of {trained / 'config.json'} "
        "(allowed)\n"
    )
    for name, argv in _commands(trained, project).items():
        result = _cli(*argv, "--allow-import", NAME)
        assert result.code == 0, (name, result.err)
        assert note in result.err and "warning" not in result.err, (name, result.err)
    assert (project / "a.gif").stat().st_size > 0
    assert json.loads((trained / "status.json").read_text())["num_timesteps"] >= 128


def test_an_env_named_on_the_eval_command_line_needs_no_flag(trained: Path, project: Path) -> None:
    result = _cli("eval", trained, "--env", ENV, "--episodes", 1)
    assert result.code == 0, result.err
    assert f"on {ENV}: 1 episode" in result.out and "importing module" not in result.err
    assert _imports(project) == 2  # train's, then eval's own --env


def test_eval_where_the_module_is_missing_names_it_and_the_flag(
    trained: Path, project: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    elsewhere = project.parent / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    result = _cli("eval", trained)
    assert (result.code, result.err) == (
        2,
        f"palaestra: error: {trained / 'config.json'} names env_id {ENV!r}, which would "
        f"import module {NAME!r}; palaestra runs no code named by a run folder (run from the "
        f"folder that holds module {NAME!r}, and pass --allow-import {NAME} to allow it)\n",
    )
    result = _cli("eval", trained, "--allow-import", NAME)
    assert (result.code, result.err) == (
        2,
        f"palaestra: error: {trained / 'config.json'} names env_id {ENV!r}, but module "
        f"{NAME!r} is not found from {elsewhere} (run from the folder that holds it, with "
        f"--allow-import {NAME})\n",
    )


def test_a_changed_module_file_gets_a_warning(trained: Path, project: Path) -> None:
    recorded = json.loads((trained / "config.json").read_text())["module_sha256"][NAME]
    with open(project / f"{NAME}.py", "a") as file:
        file.write("# edited after training\n")
    now = hashlib.sha256((project / f"{NAME}.py").read_bytes()).hexdigest()
    result = _cli("eval", trained, "--episodes", 1, "--allow-import", NAME)
    assert result.code == 0, result.err
    assert (
        f"palaestra: warning: module {NAME!r} ({project / (NAME + '.py')}) is not the file "
        f"{trained / 'config.json'} recorded (sha256 {recorded[:12]}..., now {now[:12]}...): "
        "results may differ from the run's\n"
    ) in result.err


def test_a_tampered_module_hash_is_refused(trained: Path, project: Path) -> None:
    copy = project / "copy"
    shutil.copytree(trained, copy)
    config = json.loads((copy / "config.json").read_text())
    config["module_sha256"] = {NAME: "not a digest"}
    (copy / "config.json").write_text(json.dumps(config))
    result = _cli("eval", copy, "--allow-import", NAME)
    assert result.code == 2 and result.err.count("\n") == 1
    assert "module_sha256 must be a mapping of module names to sha256 digests" in result.err


class _ImageEnv:
    """A stand-in env of 8x8 RGB frames (``CnnPolicy``) or a float box (``MlpPolicy``)."""

    def __new__(cls, image: bool = True):  # type: ignore[no-untyped-def]
        import numpy as np

        import palaestra as gym
        from palaestra import spaces

        class Env(gym.Env):  # type: ignore[type-arg]
            observation_space = (
                spaces.Box(0, 255, shape=(8, 8, 3), dtype=np.uint8)
                if image
                else spaces.Box(0.0, 255.0, shape=(8, 8, 3), dtype=np.float32)
            )
            action_space = spaces.Discrete(2)

        return Env()


def test_image_observations_choose_cnn_policy() -> None:
    import palaestra
    from palaestra.envs.registration import registry
    from palaestra.runs.recipe import choose_policy

    palaestra.register("ImageUE-v0", entry_point=_ImageEnv)
    try:
        assert choose_policy({}, "ImageUE-v0") == ("CnnPolicy", "image observations (8, 8, 3)")
        # a float box of the same shape is no image to SB3
        assert choose_policy({"env_kwargs": {"image": False}}, "ImageUE-v0") == (
            "MlpPolicy",
            "Box observations",
        )
    finally:
        registry.pop("ImageUE-v0", None)
