"""Every space in the table behaves like its gymnasium twin: repr, seeding, draws, contains."""

from __future__ import annotations

import json
import pickle
import warnings

import numpy as np
import pytest

from .cases import SPACES, assert_same, build

NAMES = list(SPACES)


@pytest.fixture(autouse=True)
def _quiet() -> object:
    # Box.contains warns when it casts a list; that is the same in both libraries.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


@pytest.mark.parametrize("name", NAMES)
def test_repr_matches_gymnasium(name: str) -> None:
    ours, theirs = build(name)
    assert repr(ours) == repr(theirs)
    assert str(ours) == str(theirs)


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("box_mountaincar", "Box([-1.2  -0.07], [0.6  0.07], (2,), float32)"),
        ("box_atari", "Box(0, 255, (210, 160, 3), uint8)"),
        ("discrete", "Discrete(3)"),
        ("discrete_start", "Discrete(3, start=-1)"),
        ("discrete_int32", "Discrete(5, start=2, dtype=int32)"),
        ("multi_discrete", "MultiDiscrete([5 2 2])"),
        ("dict", "Dict('color': Discrete(3), 'position': Box(-1.0, 1.0, (2,), float32))"),
        ("dict_unsorted", "Dict('z': Discrete(2), 'a': Box(0.0, 1.0, (1,), float32))"),
    ],
)
def test_repr_literal(name: str, expected: str) -> None:
    # Pinned strings, so a change in gymnasium's reprs cannot silently move ours with it.
    assert repr(build(name)[0]) == expected


@pytest.mark.parametrize("name", NAMES)
def test_shape_dtype_and_flags_match(name: str) -> None:
    ours, theirs = build(name)
    assert ours.shape == theirs.shape
    assert ours.dtype == theirs.dtype
    assert ours.is_np_flattenable == theirs.is_np_flattenable


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("seed", [0, 42, 2**31 + 5])
def test_seeded_samples_match(name: str, seed: int) -> None:
    ours, theirs = build(name)
    assert ours.seed(seed) == theirs.seed(seed)
    for _ in range(5):
        assert_same(ours.sample(), theirs.sample())


@pytest.mark.parametrize("name", NAMES)
def test_seed_none_returns_same_structure(name: str) -> None:
    ours, theirs = build(name)
    ours_seeds, theirs_seeds = ours.seed(None), theirs.seed(None)
    assert type(ours_seeds) is type(theirs_seeds)
    if isinstance(theirs_seeds, (tuple, dict)):
        assert len(ours_seeds) == len(theirs_seeds)


@pytest.mark.parametrize("name", NAMES)
def test_contains_own_and_twin_samples(name: str) -> None:
    ours, theirs = build(name)
    ours.seed(1)
    theirs.seed(2)
    for _ in range(3):
        mine, twin = ours.sample(), theirs.sample()
        assert mine in ours
        assert ours.contains(twin) == theirs.contains(twin) is True


@pytest.mark.parametrize("name", NAMES)
def test_contains_rejects_like_gymnasium(name: str) -> None:
    ours, theirs = build(name)
    for junk in [None, "x", 1.5, -1, 7, (0, 0), [0.5, 0.5], np.zeros(3), {"a": 1}, np.int64(2)]:
        try:
            expected = theirs.contains(junk)
        except TypeError:
            expected = False  # gymnasium crashes on some junk; we answer "not a member"
        assert ours.contains(junk) == expected, junk


@pytest.mark.parametrize("name", NAMES)
def test_equality_matches_gymnasium(name: str) -> None:
    ours, theirs = build(name)
    assert ours == build(name)[0]
    for other in NAMES:
        ours_other, theirs_other = build(other)
        assert (ours == ours_other) == (theirs == theirs_other), other


@pytest.mark.parametrize("name", NAMES)
def test_pickle_round_trip_keeps_stream(name: str) -> None:
    ours, _ = build(name)
    ours.seed(11)
    ours.sample()
    copy = pickle.loads(pickle.dumps(ours))
    assert copy == ours
    assert repr(copy) == repr(ours)
    assert_same(copy.sample(), ours.sample())


@pytest.mark.parametrize("name", NAMES)
def test_jsonable_round_trip_matches_gymnasium(name: str) -> None:
    ours, theirs = build(name)
    ours.seed(5)
    theirs.seed(5)
    batch_ours = [ours.sample() for _ in range(3)]
    batch_theirs = [theirs.sample() for _ in range(3)]
    text = json.dumps(ours.to_jsonable(batch_ours))
    assert text == json.dumps(theirs.to_jsonable(batch_theirs))
    back = ours.from_jsonable(json.loads(text))
    assert_same(back, theirs.from_jsonable(json.loads(text)))
    assert all(sample in ours for sample in back)


def test_unseeded_spaces_differ() -> None:
    a, _ = build("box_scalar_bounds")
    b, _ = build("box_scalar_bounds")
    assert not np.array_equal(a.sample(), b.sample())


def test_generator_seed_is_used_directly() -> None:
    import palaestra.spaces as spaces

    rng = np.random.default_rng(9)
    space = spaces.Discrete(10, seed=rng)
    assert space.np_random is rng
