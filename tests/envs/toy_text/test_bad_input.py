"""Bad maps, sizes, probabilities and actions: clear errors that name the value."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import error
from palaestra.envs.toy_text import (
    BlackjackEnv,
    CliffWalkingEnv,
    FrozenLakeBatch,
    FrozenLakeEnv,
    TaxiBatch,
    TaxiEnv,
    generate_random_map,
)


@pytest.mark.parametrize(
    "desc, match",
    [
        (["FFFF", "FHFH", "FFFH", "HFFG"], r"has no start tile 'S'"),
        (["SFFF", "FHFH", "FFFH", "HFFF"], r"has no goal tile 'G'"),
        (["SFFF", "FHF", "FFFH", "HFFG"], r"rows have different lengths \[4, 3, 4, 4\]"),
        (["SFFF", "FXFH", "FFFH", "HFFG"], r"Unknown letter 'X' at row 1, column 1"),
        (["SF F", "FFFG"], r"Unknown letter ' ' at row 0, column 2"),
        ([], r"is empty"),
        ([""], r"is empty"),
        ("SFFG", r"desc must be a list of rows"),
        (42, r"desc must be a list of rows .* got 42 \(int\)"),
    ],
)
def test_bad_maps(desc: Any, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FrozenLakeEnv(desc=desc)
    with pytest.raises(ValueError, match=match):
        FrozenLakeBatch(2, desc=desc)
    with pytest.raises(ValueError, match=match):
        palaestra.make("FrozenLake-v1", desc=desc)


def test_maps_given_as_bytes_or_char_lists_are_accepted() -> None:
    ref = FrozenLakeEnv(desc=["SF", "HG"])
    for desc in ([b"SF", b"HG"], [["S", "F"], ["H", "G"]], np.asarray(["SF", "HG"], dtype="c")):
        env = FrozenLakeEnv(desc=desc)  # type: ignore[arg-type]
        assert env.desc.tobytes() == ref.desc.tobytes() and env.P == ref.P


def test_unknown_map_name() -> None:
    with pytest.raises(
        ValueError, match=r"Unknown map_name '5x5': expected one of \['4x4', '8x8'\]"
    ):
        FrozenLakeEnv(map_name="5x5")


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        ({"size": 0}, ValueError, "size must be at least 2.*got 0"),
        ({"size": -3}, ValueError, "size must be at least 2.*got -3"),
        ({"size": 1}, ValueError, "size must be at least 2.*got 1"),
        ({"size": 4.0}, TypeError, r"size must be an int, got 4.0 \(float\)"),
        ({"p": 1.5}, ValueError, r"p must be a probability in \(0, 1\], got 1.5"),
        ({"p": -0.1}, ValueError, r"p must be a probability in \(0, 1\], got -0.1"),
        ({"p": 0.0}, ValueError, "got 0.0 .every tile would be a hole"),
        ({"p": float("nan")}, ValueError, r"got nan"),
        ({"p": "0.5"}, TypeError, r"p must be a number in \(0, 1\], got '0.5'"),
    ],
)
def test_bad_random_map_arguments(kwargs: dict[str, Any], exc: type, match: str) -> None:
    with pytest.raises(exc, match=match):
        generate_random_map(**kwargs)


def test_random_maps_equal_gymnasiums() -> None:
    gym_map = pytest.importorskip("gymnasium.envs.toy_text.frozen_lake").generate_random_map
    for seed in range(30):
        for size, p in ((2, 0.5), (4, 0.8), (8, 0.6), (13, 0.9)):
            assert generate_random_map(size, p, seed) == gym_map(size, p, seed)
    assert generate_random_map(5, 1, seed=0)[0] == "SFFFF"  # p=1: all frozen


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"success_rate": 1.2}, r"success_rate must be a probability in \[0, 1\], got 1.2"),
        ({"success_rate": -0.5}, r"success_rate must be a probability in \[0, 1\], got -0.5"),
        ({"reward_schedule": (1, 0)}, r"reward_schedule must be 3 numbers .* got \(1, 0\)"),
        ({"reward_schedule": (1, "a", 0)}, r"reward_schedule must be 3 numbers"),
    ],
)
def test_bad_frozen_lake_options(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FrozenLakeEnv(**kwargs)


@pytest.mark.parametrize("name", ["rainy_probability", "fickle_probability"])
def test_bad_taxi_probabilities(name: str) -> None:
    with pytest.raises(ValueError, match=rf"{name} must be a probability in \[0, 1\], got 2"):
        TaxiEnv(**{name: 2})
    with pytest.raises(ValueError, match=rf"{name} must be a probability"):
        TaxiBatch(3, **{name: -0.1})
    with pytest.raises(TypeError, match=rf"{name} must be a number"):
        TaxiEnv(**{name: None})


ENVS = [FrozenLakeEnv, CliffWalkingEnv, TaxiEnv, BlackjackEnv]


@pytest.mark.parametrize("cls", ENVS)
@pytest.mark.parametrize("action", [-1, 99, 1.0, "1", None, np.array([1]), np.float32(1.0)])
def test_bad_actions_name_the_action_and_space(cls: type, action: Any) -> None:
    env = cls()
    env.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=r"Invalid action .* for action space Discrete"):
        env.step(action)


@pytest.mark.parametrize("cls", ENVS)
def test_actions_the_space_contains_are_accepted(cls: type) -> None:
    for action in (np.int64(1), np.int32(1), True, np.array(1)):
        env = cls()
        env.reset(seed=0)
        env.step(action)


def test_bad_actions_through_make() -> None:
    env = palaestra.make("Taxi-v4")
    env.reset(seed=0)
    with pytest.raises(
        error.InvalidAction, match=r"Invalid action 6 \(int\) for action space Discrete\(6\)"
    ):
        env.step(6)
