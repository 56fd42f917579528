"""``palaestra.algos.vec_env.patch_gym`` (SB3's ``patch_gym``): palaestra envs and spaces come
back as they are, Gymnasium ones are adapted, anything else is a ValueError naming its type;
the module imports no Gymnasium."""

from __future__ import annotations

import subprocess
import sys

import gymnasium
import numpy as np
import pytest

import palaestra
from palaestra import spaces
from palaestra.compat import PalaestraEnvAdapter
from palaestra.vec_env.patch_gym import _convert_space, _patch_env


def test_palaestra_envs_and_spaces_are_returned_as_they_are() -> None:
    env = palaestra.make("CartPole-v1")
    assert _patch_env(env) is env
    space = spaces.Box(-1, 1, (2,))
    assert _convert_space(space) is space


def test_a_gymnasium_env_is_adapted_and_steps_as_gymnasiums() -> None:
    theirs = gymnasium.make("CartPole-v1")
    ours = _patch_env(gymnasium.make("CartPole-v1"))
    assert isinstance(ours, PalaestraEnvAdapter) and isinstance(ours, palaestra.Env)
    assert repr(ours.observation_space) == repr(theirs.observation_space)
    np.testing.assert_array_equal(ours.reset(seed=3)[0], theirs.reset(seed=3)[0])
    np.testing.assert_array_equal(ours.step(1)[0], theirs.step(1)[0])


def test_a_gymnasium_space_is_converted() -> None:
    theirs = gymnasium.spaces.Dict({"a": gymnasium.spaces.MultiDiscrete([2, 3])})
    ours = _convert_space(theirs)
    assert isinstance(ours, spaces.Dict) and isinstance(ours["a"], spaces.MultiDiscrete)
    assert repr(ours) == repr(theirs)


def test_anything_else_is_refused_naming_its_type() -> None:
    with pytest.raises(ValueError, match=r"The environment is of type <class 'str'>, not a "):
        _patch_env("CartPole-v1")
    with pytest.raises(ValueError, match=r"The space is of type <class 'tuple'>, not a .*shimmy"):
        _convert_space((2,))


def test_the_module_imports_no_gymnasium() -> None:
    code = (
        "import sys, palaestra.algos.vec_env.patch_gym as p, palaestra;"
        "assert 'gymnasium' not in sys.modules;"
        "assert p._patch_env(palaestra.make('CartPole-v1')) is not None;"
        "assert 'gymnasium' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
