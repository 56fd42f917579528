"""Space conversion: every space type round-trips, matches the Gymnasium twin, and samples of
each side belong to the other."""

from __future__ import annotations

import warnings

import gymnasium
import numpy as np
import pytest
from tests.spaces.cases import SPACES, assert_same, build

from palaestra import spaces
from palaestra.compat import (
    from_gymnasium_space,
    from_gymnasium_value,
    to_gymnasium_space,
    to_gymnasium_value,
)

NAMES = list(SPACES)


@pytest.fixture(autouse=True)
def _quiet() -> object:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Box precision warnings of the recipes themselves
        yield


@pytest.mark.parametrize("name", NAMES)
def test_to_gymnasium_space_equals_the_gymnasium_twin(name: str) -> None:
    ours, theirs = build(name)
    converted = to_gymnasium_space(ours)
    assert type(converted) is type(theirs)
    assert converted == theirs
    assert repr(converted) == repr(theirs)


@pytest.mark.parametrize("name", NAMES)
def test_round_trip_is_identity(name: str) -> None:
    ours, theirs = build(name)
    back = from_gymnasium_space(to_gymnasium_space(ours))
    assert back == ours
    assert repr(back) == repr(ours)
    assert from_gymnasium_space(theirs) == ours
    assert to_gymnasium_space(from_gymnasium_space(theirs)) == theirs


@pytest.mark.parametrize("name", [n for n in NAMES if n.startswith("box")])
def test_box_bounds_and_flags_survive_exactly(name: str) -> None:
    ours, theirs = build(name)
    converted, back = to_gymnasium_space(ours), from_gymnasium_space(to_gymnasium_space(ours))
    for box in (converted, back):
        np.testing.assert_array_equal(box.low, ours.low)
        np.testing.assert_array_equal(box.high, ours.high)
        np.testing.assert_array_equal(box.bounded_below, ours.bounded_below)
        np.testing.assert_array_equal(box.bounded_above, ours.bounded_above)
    np.testing.assert_array_equal(converted.bounded_below, theirs.bounded_below)
    np.testing.assert_array_equal(converted.bounded_above, theirs.bounded_above)


def test_dict_key_order_and_text_charset_order_are_kept() -> None:
    d = spaces.Dict({"z": spaces.Discrete(2), "a": spaces.Text(3, charset="cab")}, sort_keys=False)
    converted = to_gymnasium_space(d)
    assert list(converted.spaces) == ["z", "a"]
    assert converted["a"].character_list == ("c", "a", "b")
    assert list(from_gymnasium_space(converted).spaces) == ["z", "a"]


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("seed", [0, 7])
def test_samples_belong_to_the_other_side(name: str, seed: int) -> None:
    ours, _ = build(name)
    theirs = to_gymnasium_space(ours)
    ours.seed(seed)
    theirs.seed(seed)
    for _ in range(5):
        assert to_gymnasium_value(ours, ours.sample()) in theirs
        assert from_gymnasium_value(ours, theirs.sample()) in ours


@pytest.mark.parametrize("name", NAMES)
def test_seeded_samples_are_the_same_values(name: str) -> None:
    # Same constructor, same seed: the converted space draws what the original draws.
    ours, _ = build(name)
    theirs = to_gymnasium_space(ours)
    ours.seed(3)
    theirs.seed(3)
    assert_same(to_gymnasium_value(ours, ours.sample()), theirs.sample())


def test_graph_values_change_type_both_ways() -> None:
    graph = spaces.Graph(spaces.Box(-1, 1, (2,)), spaces.Discrete(3))
    nested = spaces.Dict(g=graph, seq=spaces.Sequence(graph), pick=spaces.OneOf((graph,)))
    theirs = to_gymnasium_space(nested)
    nested.seed(1)
    sample = nested.sample()
    assert sample not in theirs  # palaestra's GraphInstance is not gymnasium's
    converted = to_gymnasium_value(nested, sample)
    assert converted in theirs
    assert type(converted["g"]) is gymnasium.spaces.GraphInstance
    assert all(type(g) is gymnasium.spaces.GraphInstance for g in converted["seq"])
    assert type(converted["pick"][1]) is gymnasium.spaces.GraphInstance
    back = from_gymnasium_value(nested, converted)
    assert type(back["g"]) is spaces.GraphInstance and back in nested
    np.testing.assert_array_equal(back["g"].nodes, sample["g"].nodes)


def test_values_of_plain_spaces_pass_through_untouched() -> None:
    box = spaces.Box(0, 1, (3,))
    x = box.sample()
    assert to_gymnasium_value(box, x) is x and from_gymnasium_value(box, x) is x


class Custom(spaces.Space[int]):
    def contains(self, x: object) -> bool:
        return x == 0


class GymCustom(gymnasium.spaces.Space[int]):
    def contains(self, x: object) -> bool:
        return x == 0


def test_unsupported_spaces_raise_naming_the_space_and_the_types() -> None:
    with pytest.raises(TypeError, match=r"to_gymnasium_space: .*Custom.* expected a palaestra"):
        to_gymnasium_space(Custom())
    with pytest.raises(TypeError, match=r"from_gymnasium_space: .*GymCustom.* Gymnasium space"):
        from_gymnasium_space(GymCustom())
    with pytest.raises(TypeError, match=r"Box, Discrete, MultiDiscrete, MultiBinary, Text"):
        to_gymnasium_space(spaces.Tuple((spaces.Discrete(2), Custom())))


def test_wrong_library_gets_a_clear_error() -> None:
    with pytest.raises(TypeError, match=r"to_gymnasium_space: Discrete\(3\) \(type gymnasium"):
        to_gymnasium_space(gymnasium.spaces.Discrete(3))
    with pytest.raises(TypeError, match=r"from_gymnasium_space: Discrete\(3\) \(type palaestra"):
        from_gymnasium_space(spaces.Discrete(3))
    with pytest.raises(TypeError, match=r"'not a space' \(type builtins.str\)"):
        to_gymnasium_space("not a space")
