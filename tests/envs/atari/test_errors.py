"""Every bad Atari input gets an exception naming the value and what was expected."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error
from palaestra.envs.atari.env import AtariEnv


def test_missing_ale_py_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ale_py", None)  # `import ale_py` raises ImportError
    with pytest.raises(error.DependencyNotInstalled) as excinfo:
        palaestra.make("ALE/Breakout-v5")
    assert str(excinfo.value) == (
        'ale-py is not installed, run `pip install "palaestra[atari]"` '
        "(needed for the Atari environments)"
    )
    with pytest.raises(error.DependencyNotInstalled, match=r"palaestra\[atari\]"):
        palaestra.make("BreakoutNoFrameskip-v4")


@pytest.mark.parametrize(
    "env_id, exc, message",
    [
        ("ALE/Breakot-v5", error.NameNotFound, "Did you mean: `Breakout`?"),
        ("ALE/breakout-v5", error.NameNotFound, "Did you mean: `Breakout`?"),
        ("ALE/Space_Invaders-v5", error.NameNotFound, "Did you mean: `SpaceInvaders`?"),
        ("ALE/Foo-v5", error.NameNotFound, "Environment `Foo` doesn't exist in namespace ALE."),
        ("ALE/Breakout-v6", error.VersionNotFound, "It provides versioned environments: [ `v5` ]"),
        ("ALE/Breakout-v4", error.DeprecatedEnv, "Please use `ALE/Breakout-v5` instead."),
    ],
)
@pytest.mark.filterwarnings("ignore:.*is out of date")
def test_unknown_ids(env_id: str, exc: type, message: str) -> None:
    with pytest.raises(exc) as excinfo:
        palaestra.make(env_id)
    assert message in str(excinfo.value)


def test_unknown_game_suggests_close_rom_ids() -> None:
    with pytest.raises(error.Error) as excinfo:
        AtariEnv("breakot")
    assert "Unknown Atari game 'breakot'" in str(excinfo.value)
    assert "Did you mean: 'breakout'?" in str(excinfo.value)
    with pytest.raises(error.Error, match="Did you mean: 'space_invaders'"):
        AtariEnv("SpaceInvaders")  # the id's spelling, not the ROM id's


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"mode": 3}, "Invalid mode 3 for breakout: expected one of [0, 4, 8, 12, 16, 20, 24, "),
        ({"difficulty": 5}, "Invalid difficulty 5 for breakout: expected one of [0, 1]"),
        ({"obs_type": "rgbx"}, "Invalid observation type: 'rgbx'. Expecting: rgb, grayscale, ram"),
        ({"frameskip": 0}, "Invalid frameskip 0: expected a positive int"),
        ({"frameskip": 2.5}, "Invalid frameskip 2.5: expected a positive int"),
        ({"frameskip": True}, "Invalid frameskip True"),
        ({"frameskip": (4, 2)}, "Invalid frameskip (4, 2): expected a positive int (frames "),
        ({"frameskip": (0, 2)}, "with 1 <= low < high"),
        ({"frameskip": (1, 2, 3)}, "Invalid frameskip (1, 2, 3)"),
        ({"repeat_action_probability": 1.5}, "Invalid repeat_action_probability 1.5: expected"),
        ({"repeat_action_probability": -0.1}, "a probability in [0, 1]"),
        ({"repeat_action_probability": "0.2"}, "Invalid repeat_action_probability '0.2'"),
    ],
)
def test_bad_arguments_name_the_valid_choices(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(error.Error) as excinfo:
        palaestra.make("ALE/Breakout-v5", **kwargs)
    assert message in str(excinfo.value)


def test_bad_render_mode() -> None:
    with pytest.raises(error.UnsupportedMode, match=r"render_mode='ansi' is not one of \["):
        AtariEnv("breakout", render_mode="ansi")


@pytest.mark.parametrize("action", [4, -1, 1.5, "a", None, np.array([1, 2])])
def test_invalid_discrete_action(action: Any) -> None:
    env = AtariEnv("breakout")
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction) as excinfo:
        env.step(action)
    assert "Discrete(4)" in str(excinfo.value) and "Invalid action" in str(excinfo.value)


def test_accepted_discrete_actions() -> None:
    env = AtariEnv("breakout")
    env.reset(seed=0)
    for action in [0, np.int64(1), np.int32(2), np.array(3), np.uint8(0)]:
        env.step(action)


@pytest.mark.parametrize(
    "action", [np.zeros(3), np.zeros(2, np.float32), np.array([0.5, np.nan, 1.0], np.float32)]
)
def test_invalid_continuous_action(action: Any) -> None:
    env = AtariEnv("breakout", continuous=True)
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match="expected 3 finite float32 values"):
        env.step(action)


def test_keys_to_action_is_undefined_for_continuous_actions() -> None:
    with pytest.raises(AttributeError, match="continuous=True"):
        AtariEnv("pong", continuous=True).get_keys_to_action()


def test_a_rom_the_installed_ale_py_lacks(monkeypatch: pytest.MonkeyPatch) -> None:
    roms = pytest.importorskip("ale_py.roms")
    monkeypatch.setattr(roms, "get_rom_path", lambda name: None)  # what an older ale-py returns
    with pytest.raises(error.Error, match=r"does not ship the ROM of 'pong'; upgrade it"):
        AtariEnv("pong")
