"""RowStreams draws what each row's ``Generator`` would: ``random()``, ``integers(0, n)`` and
``choice`` of n items, in any interleaving, rejections included."""

from __future__ import annotations

import numpy as np
import pytest

from palaestra.envs.toy_text._streams import RowStreams


def _streams(seeds: list[int]) -> RowStreams:
    rngs: list[np.random.Generator | None] = [np.random.default_rng(s) for s in seeds]
    streams = RowStreams(rngs)
    streams.restart(np.arange(len(seeds)))
    return streams


def test_interleaved_draws_equal_each_rows_generator() -> None:
    n = 5
    streams = _streams(list(range(100, 100 + n)))
    refs = [np.random.default_rng(100 + i) for i in range(n)]
    plan = np.random.default_rng(0)
    for _ in range(3000):  # several top-ups (a row holds at most 8192 words)
        rows = np.flatnonzero(plan.random(n) < 0.7)
        kind = int(plan.integers(4))
        if kind == 0:
            got = streams.doubles(rows)
            want = [refs[i].random() for i in rows]
        else:
            span = (13, 3, 4)[kind - 1]
            got = streams.bounded(rows, span)
            want = [refs[i].choice(span) for i in rows]
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("span", [2, 3, 6, 13, 1000, 2**31 + 11])
def test_bounded_equals_integers_for_any_span(span: int) -> None:
    streams = _streams([7, 8])
    refs = [np.random.default_rng(7), np.random.default_rng(8)]
    rows = np.arange(2)
    for _ in range(200):
        got = streams.bounded(rows, span)
        assert got.tolist() == [int(r.integers(span)) for r in refs]


def test_rejected_draw_takes_the_next_word_as_numpy_does() -> None:
    # span 2**31 + 11 rejects about half of the 32-bit words: both paths are exercised a lot.
    streams = _streams([1])
    ref = np.random.default_rng(1)
    span = 2**31 + 11
    for _ in range(500):
        assert int(streams.bounded(np.array([0]), span)[0]) == int(ref.integers(span))
        assert float(streams.doubles(np.array([0]))[0]) == ref.random()


def test_restart_drops_the_old_draws_and_the_kept_half_word() -> None:
    rngs: list[np.random.Generator | None] = [np.random.default_rng(1)]
    streams = RowStreams(rngs)
    streams.restart(np.array([0]))
    streams.bounded(np.array([0]), 13)  # leaves a half-word kept
    rngs[0] = np.random.default_rng(2)
    streams.restart(np.array([0]))
    ref = np.random.default_rng(2)
    assert int(streams.bounded(np.array([0]), 13)[0]) == int(ref.integers(13))


@pytest.mark.parametrize("span", [13, 2**31 + 11])
def test_peek_then_consume_a_different_number_per_row(span: int) -> None:
    n = 6
    streams = _streams(list(range(n)))
    refs = [np.random.default_rng(i) for i in range(n)]
    plan = np.random.default_rng(1)
    rows = np.arange(n)
    for _ in range(300):
        if plan.random() < 0.3:  # interleave doubles and single draws, as Taxi's fickle does
            np.testing.assert_array_equal(streams.doubles(rows), [r.random() for r in refs])
            np.testing.assert_array_equal(streams.bounded(rows, 3), [r.choice(3) for r in refs])
        peek = streams.peek_bounded(rows, span, 4)
        taken = plan.integers(0, 5, n)  # each row uses its first `taken` draws
        for i, r in enumerate(refs):
            assert peek.draws[i, : taken[i]].tolist() == [
                int(r.integers(span)) for _ in range(taken[i])
            ]
        streams.consume(peek, peek.values_for(taken))


@pytest.mark.parametrize("half_words_only", [False, True])
def test_tiny_blocks_refill_often_and_stay_exact(
    half_words_only: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    from palaestra.envs.toy_text import _streams

    monkeypatch.setattr(_streams, "_ROW_WORDS", (16, 16))  # a top-up every few draws
    n = 4
    cls = _streams.HalfWordStreams if half_words_only else RowStreams
    rngs: list[np.random.Generator | None] = [np.random.default_rng(30 + i) for i in range(n)]
    streams = cls(rngs)
    assert streams.per == 16
    streams.restart(np.arange(n))
    refs = [np.random.default_rng(30 + i) for i in range(n)]
    plan = np.random.default_rng(5)
    for _ in range(2000):
        rows = np.flatnonzero(plan.random(n) < 0.8)
        kind = int(plan.integers(3 if half_words_only else 4))
        if kind == 0:
            np.testing.assert_array_equal(
                streams.bounded(rows, 13), [refs[i].integers(13) for i in rows]
            )
        elif kind == 1:
            peek = streams.peek_bounded(rows, 13, 4)
            taken = plan.integers(0, 5, len(rows))
            for j, i in enumerate(rows):
                got = peek.draws[j, : taken[j]].tolist()
                assert got == [int(refs[i].integers(13)) for _ in range(taken[j])]
            streams.consume(peek, peek.values_for(taken))
        elif kind == 2:
            np.testing.assert_array_equal(
                streams.bounded(rows, 3), [refs[i].choice(3) for i in rows]
            )
        else:
            np.testing.assert_array_equal(streams.doubles(rows), [refs[i].random() for i in rows])


def test_half_word_streams_refuse_doubles() -> None:
    from palaestra.envs.toy_text._streams import HalfWordStreams

    streams = HalfWordStreams([np.random.default_rng(0)])
    with pytest.raises(TypeError, match="32-bit values only"):
        streams.doubles(None)
    with pytest.raises(TypeError, match="32-bit values only"):
        streams.words(None)
