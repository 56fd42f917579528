"""Constructor errors and per-type behaviour of the non-Box spaces."""

from __future__ import annotations

import pickle
import re
import warnings
from collections import OrderedDict
from typing import Any

import gymnasium.spaces
import numpy as np
import pytest

import palaestra.spaces
from palaestra.spaces import Dict, Discrete, MultiDiscrete, Text, Tuple

BAD: list[tuple[Any, type[Exception], str]] = [
    (lambda S: S.Discrete(0), ValueError, "n (counts) have to be positive, actual value: 0"),
    (lambda S: S.Discrete(-2), ValueError, "have to be positive"),
    (lambda S: S.Discrete(2.0), TypeError, "Expects `n` to be an integer"),
    (lambda S: S.Discrete(2, start=0.5), TypeError, "Expects `start` to be an integer"),
    (lambda S: S.Discrete(2, dtype=np.float32), TypeError, "must be an integer dtype"),
    (lambda S: S.Discrete(2, dtype=None), TypeError, "cannot be None"),
    (lambda S: S.MultiDiscrete([2, 0]), ValueError, "nvec (counts) have to be positive"),
    (lambda S: S.MultiDiscrete([2, 3], start=[0]), ValueError, "should have the same shape"),
    (lambda S: S.MultiDiscrete([2], dtype=np.float64), ValueError, "must be an integer dtype"),
    (lambda S: S.MultiDiscrete([2], dtype=None), ValueError, "cannot be None"),
    (lambda S: S.MultiBinary(0), ValueError, "n (counts) have to be positive"),
    (lambda S: S.MultiBinary([2, -1]), ValueError, "have to be positive"),
    (lambda S: S.MultiBinary(2.5), ValueError, "Expected n to be an int or a sequence"),
    (lambda S: S.Text(3, min_length=-1), ValueError, "must be non-negative"),
    (lambda S: S.Text(3, min_length=4), ValueError, "less than or equal to the max_length"),
    (lambda S: S.Text(3.0), TypeError, "max_length to be an integer"),
    (lambda S: S.Text(3, min_length=1.0), TypeError, "min_length to be an integer"),
    (lambda S: S.Text(3, charset=["ab", "c"]), ValueError, "single character"),
    (lambda S: S.Tuple((S.Discrete(2), 3)), TypeError, "does not inherit from"),
    (lambda S: S.Dict({"a": 3}), TypeError, "not an instance of Space: key='a'"),
    (lambda S: S.Dict(5), TypeError, "expecting dict, OrderedDict or Sequence"),
    (
        lambda S: S.Dict({"a": S.Discrete(2)}, a=S.Discrete(3)),
        ValueError,
        "keyword 'a' already exists",
    ),
    (lambda S: S.OneOf([]), ValueError, "Empty `OneOf` spaces are not supported"),
    (lambda S: S.OneOf(5), TypeError, "is not an iterable"),
    (lambda S: S.OneOf([S.Discrete(2), "x"]), TypeError, "does not inherit from"),
    (lambda S: S.Sequence(5), TypeError, "feature space to be instance of a"),
]


@pytest.mark.parametrize(("recipe", "exc", "match"), BAD)
def test_invalid_spaces_raise_like_gymnasium(recipe: Any, exc: type, match: str) -> None:
    with pytest.raises(exc, match=re.escape(match)):
        recipe(gymnasium.spaces)
    with pytest.raises(exc, match=re.escape(match)):
        recipe(palaestra.spaces)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: palaestra.spaces.Discrete(100, start=100, dtype=np.int8), "199 does not fit"),
        (lambda: palaestra.spaces.MultiDiscrete([3, 100], start=[0, 100], dtype=np.int8), "int8"),
        (lambda: palaestra.spaces.MultiDiscrete([2.5, 3]), "nvec must be whole numbers"),
        (lambda: palaestra.spaces.MultiDiscrete([2, 3], start=[0.5, 0]), "start must be whole"),
        (lambda: palaestra.spaces.Text(3, charset=""), "at least one character"),
    ],
)
def test_spaces_gymnasium_accepts_but_cannot_sample_are_rejected(call: Any, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call()


def test_whole_float_counts_are_accepted() -> None:
    assert palaestra.spaces.MultiDiscrete(np.array([2.0, 3.0])) == MultiDiscrete([2, 3])
    assert 127 in palaestra.spaces.Discrete(100, start=28, dtype=np.int8)


def test_graph_rejects_non_space_subspaces_clearly() -> None:
    with pytest.raises(TypeError, match="`node_space` to be a palaestra Space"):
        palaestra.spaces.Graph(5, None)  # type: ignore[arg-type]


DISCRETE_MEMBERS: list[Any] = [
    0,
    2,
    3,
    -1,
    True,
    2**70,
    -(2**70),
    1.0,
    "1",
    None,
    np.int8(1),
    np.uint64(1),
    np.int64(3),
    np.float32(1),
    np.bool_(True),
    np.array(1),
    np.array([1]),
    np.array(1.0),
    np.array(1, dtype=np.uint64),
]


@pytest.mark.parametrize(
    "recipe",
    [
        lambda S: S.Discrete(3),
        lambda S: S.Discrete(3, start=-1),
        lambda S: S.Discrete(3, dtype=np.int32),
        lambda S: S.Discrete(100, start=28, dtype=np.int8),  # range ends at the dtype max
        lambda S: S.Discrete(5, dtype=np.uint8),
    ],
)
def test_discrete_contains_matches_gymnasium(recipe: Any) -> None:
    ours, theirs = recipe(palaestra.spaces), recipe(gymnasium.spaces)
    for x in [*DISCRETE_MEMBERS, 127, 128, 150]:
        assert ours.contains(x) == theirs.contains(x), x
        assert (x in ours) == (x in theirs)


def test_discrete_pickle_and_legacy_state() -> None:
    space = Discrete(4, start=2)
    restored = pickle.loads(pickle.dumps(space))
    assert restored == space and 5 in restored and 6 not in restored
    legacy = {"n": np.int64(3), "_shape": (), "dtype": np.dtype(np.int64), "_np_random": None}
    old = Discrete.__new__(Discrete)
    old.__setstate__(legacy)
    assert old == Discrete(3) and 0 in old and 3 not in old


def test_multi_discrete_indexing_and_len() -> None:
    space = MultiDiscrete([[2, 3], [4, 5]], start=[[0, 1], [2, 3]], seed=5)
    twin = gymnasium.spaces.MultiDiscrete([[2, 3], [4, 5]], start=[[0, 1], [2, 3]], seed=5)
    assert repr(space[0]) == repr(twin[0]) == "MultiDiscrete([2 3], start=[0 1])"
    assert repr(space[1, 1]) == repr(twin[1, 1]) == "Discrete(5, start=3)"
    # The sub-space continues the parent's stream, as in gymnasium.
    assert space[1, 0].sample() == twin[1, 0].sample()
    with pytest.warns(UserWarning, match="multi-dimensional"):
        assert len(space) == 2
    assert len(MultiDiscrete([2, 3, 4])) == 3


def test_multi_discrete_legacy_state_without_start() -> None:
    space = MultiDiscrete([2, 3])
    state = {k: v for k, v in space.__dict__.items() if k != "start"}
    old = MultiDiscrete.__new__(MultiDiscrete)
    old.__setstate__(state)
    assert old == space


def test_multi_binary_accepts_numpy_int() -> None:
    assert repr(palaestra.spaces.MultiBinary(np.int64(3))) == "MultiBinary(3)"


def test_dict_key_order_and_mapping_protocol() -> None:
    a, b = Discrete(2), Discrete(3)
    assert list(Dict({"b": b, "a": a})) == ["a", "b"]
    assert list(Dict({"b": b, "a": a}, sort_keys=False)) == ["b", "a"]
    assert list(Dict(OrderedDict([("b", b), ("a", a)]))) == ["b", "a"]
    assert list(Dict([("b", b), ("a", a)])) == ["b", "a"]
    assert list(Dict({1: a, "x": b})) == [1, "x"]  # incomparable keys keep insertion order
    space = Dict(b=b, a=a)
    assert space["a"] is a and len(space) == 2 and list(space.keys()) == ["b", "a"]
    assert dict(space.items()) == {"b": b, "a": a}
    space["c"] = Discrete(4)
    assert "c" in space.spaces
    with pytest.raises(TypeError, match="not a palaestra space"):
        space["d"] = 5  # type: ignore[assignment]
    assert Dict(a=a, b=b) == Dict(b=b, a=a)  # like gymnasium: plain dict equality


def test_tuple_sequence_protocol() -> None:
    space = Tuple([Discrete(2), Discrete(3)])
    assert len(space) == 2 and space[1] == Discrete(3) and list(space) == [Discrete(2), Discrete(3)]
    assert space[:1] == (Discrete(2),)
    assert (np.int64(1), np.int64(2)) in space and [1, 2] in space and np.array([1, 2]) in space
    assert (1,) not in space and (1, 2, 0) not in space


def test_text_charset_order_and_accessors() -> None:
    space = Text(4, charset="cabca")
    assert space.character_list == ("c", "a", "b")
    assert space.characters == "abc" and space.character_index("b") == 2
    assert space.character_set == frozenset("abc")
    assert "abca" in space and "abcd" not in space and "" not in space and 5 not in space
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert Text(4, charset=frozenset("zyx")).character_list == ("x", "y", "z")


def test_oneof_contains() -> None:
    space = palaestra.spaces.OneOf([Discrete(2), Discrete(3)])
    assert (1, 2) in space and (np.int64(0), 1) in space
    assert (0, 2) not in space and (2, 0) not in space and [0, 1] not in space


def test_graph_contains_checks_links() -> None:
    from palaestra.spaces import Box, Graph, GraphInstance

    space = Graph(Box(0, 1, (2,)), Discrete(3))
    nodes = np.zeros((3, 2), np.float32)
    good = GraphInstance(nodes, np.array([0, 2]), np.array([[0, 1], [2, 2]]))
    assert good in space
    assert GraphInstance(nodes, np.array([0, 2]), np.array([[0, 1], [2, 3]])) not in space
    assert GraphInstance(nodes, np.array([0, 2]), np.array([[0.0, 1.0], [2, 2]])) not in space
    assert GraphInstance(nodes, np.array([0, 5]), np.array([[0, 1], [2, 2]])) not in space
    assert GraphInstance(nodes, None, None) in space
    assert GraphInstance(nodes, np.array([0]), None) not in space
    assert GraphInstance(nodes + 2, None, None) not in space
    assert (nodes, None, None) not in space


def test_scalar_nvec_is_shape_empty_as_in_gymnasium_and_its_samples_are_members() -> None:
    space, twin = MultiDiscrete(3, seed=1), gymnasium.spaces.MultiDiscrete(3, seed=1)
    assert (repr(space), space.shape) == (repr(twin), twin.shape) == ("MultiDiscrete(3)", ())
    draws = [space.sample() for _ in range(30)]
    assert all(d.shape == () and d.dtype == np.int64 and d in space for d in draws)
    assert {int(d) for d in draws} == {0, 1, 2}
    assert 2 in space and np.int8(1) in space and 3 not in space and "1" not in space
    assert not twin.contains(twin.sample())  # Gymnasium's own sample is not in its space
    assert space.sample(mask=np.array([0, 0, 1], np.int8)) == 2
    with pytest.raises(TypeError, match=r"MultiDiscrete\(3\) has shape \(\): it has no length"):
        len(space)


@pytest.mark.parametrize(
    ("nvec", "exc", "match"),
    [
        ("4", TypeError, "MultiDiscrete nvec must be integers, got '4' (str of <U1)"),
        (None, TypeError, "MultiDiscrete nvec must be integers, got None (NoneType of object)"),
        (True, TypeError, "MultiDiscrete nvec must be integers, got True (bool of bool)"),
        ([2 + 1j], TypeError, "MultiDiscrete nvec must be integers, got [(2+1j)] (list of"),
        ([[2, 3], [4]], ValueError, "must be a rectangular array of integers, got [[2, 3], [4]]"),
        ([np.inf], ValueError, "MultiDiscrete nvec must be whole numbers, actual values: [inf]"),
        ([np.nan], ValueError, "MultiDiscrete nvec must be whole numbers, actual values: [nan]"),
        (2**70, ValueError, "MultiDiscrete nvec 1180591620717411303424 do not fit dtype int64"),
        ([2**63], ValueError, "MultiDiscrete nvec [9223372036854775808] do not fit dtype int64"),
    ],
)
def test_nvec_of_a_wrong_type_names_the_value(nvec: Any, exc: type, match: str) -> None:
    # Gymnasium parses "4", truncates inf, casts complex values and True, or fails in numpy.
    with pytest.raises(exc, match=re.escape(match)):
        MultiDiscrete(nvec)


# Found by tests/fuzz/test_spaces.py: wrong-type crashes and messages that named nothing.
@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (lambda: Discrete(2**64), ValueError, "start + n - 1 = 18446744073709551615 does not fit"),
        (lambda: Discrete(2**63 + 5, start=-10), ValueError, "n=9223372036854775813 does not fit"),
        (lambda: Discrete(2, start=-(2**64)), ValueError, "does not fit dtype int64"),
        (lambda: MultiDiscrete(0), ValueError, "have to be positive, actual values: 0"),
        (lambda: palaestra.spaces.MultiBinary("0;"), ValueError, "actual type: <class 'str'>"),
        (lambda: palaestra.spaces.MultiBinary(["0;"]), ValueError, "actual: ['0;']"),
        (lambda: palaestra.spaces.MultiBinary([2.5]), ValueError, "actual: [2.5]"),
        (lambda: palaestra.spaces.MultiBinary([[1], 2]), ValueError, "actual: [[1], 2]"),
        (lambda: palaestra.spaces.MultiBinary(np.array("")), ValueError, "actual type"),
        (lambda: palaestra.spaces.MultiBinary(2**64), ValueError, "n=18446744073709551616 has"),
        (lambda: Dict("00"), TypeError, "actual type: <class 'str'>"),
        (lambda: Dict(b"\x00"), TypeError, "actual type: <class 'bytes'>"),
        (lambda: Dict(["00"]), TypeError, "sequence of (key, space) pairs, actual value: ['00']"),
        (lambda: Dict([("a",)]), TypeError, "actual value: [('a',)]"),
        (lambda: Text(2**64), ValueError, "max_length must fit int64, actual value: 1844674407"),
        (
            lambda: palaestra.spaces.Box(np.array([3.0]), -254.0, dtype=np.int8),
            ValueError,
            "Box high is out of bounds of the dtype range, high=-254.0, int8 holds [-128, 127]",
        ),
        (
            lambda: palaestra.spaces.Box(np.array([300.0]), 400, dtype=np.uint8),
            ValueError,
            "Box low is out of bounds of the dtype range, low=[300.], uint8 holds [0, 255]",
        ),
        (
            lambda: palaestra.spaces.Box(0, 1, shape=(2**64,)),
            ValueError,
            "Box shape=(18446744073709551616,) has more elements than an array can hold",
        ),
    ],
)
def test_bad_arguments_found_by_the_fuzz(call: Any, exc: type, match: str) -> None:
    with pytest.raises(exc, match=re.escape(match)):
        call()


def test_contains_answers_false_for_what_cannot_be_an_element() -> None:
    S = palaestra.spaces
    assert [1, [2]] not in S.MultiBinary(2)  # ragged: numpy raised ValueError
    assert (None, []) not in MultiDiscrete([2, 2])
    assert np.array(False) not in Tuple([])  # 0-d array: "iteration over a 0-d array"
    assert None not in S.Sequence(Text(3), stack=True)  # CustomSpaceError from iterate
    graph = S.Graph(S.Box(-1, 1, (2,)), Discrete(3))
    assert S.GraphInstance(np.array(1), None, None) not in graph  # Gymnasium: TypeError
    assert S.GraphInstance("ab", 3, 4) not in graph


def test_box_with_high_minus_zero_samples() -> None:
    # numpy's uniform refused high=-0.0 over low=0.0 ("high - low < 0"); Gymnasium's too.
    box = palaestra.spaces.Box(0.0, -0.0, shape=(2,), seed=0)
    assert box.sample().tolist() == [0.0, 0.0] and box.sample() in box
