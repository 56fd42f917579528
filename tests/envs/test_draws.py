"""Reset uniforms drawn ahead come out, row by row, in the order each generator drew them."""

from __future__ import annotations

import numpy as np
import pytest

from palaestra.envs.classic_control._draws import PreDrawn


@pytest.mark.parametrize("num_rows", [3, 20_000])  # big blocks (8 KiB a row) and small (1 KiB)
def test_rows_draw_their_generators_stream_in_order(num_rows: int) -> None:
    rngs: list[np.random.Generator | None] = [None] * num_rows
    draws = PreDrawn(rngs, 4)
    watched = np.array([0, 1, num_rows - 1])  # rows compared with a reference generator
    refs = {}
    for i in watched.tolist():
        rngs[i], refs[i] = np.random.default_rng(i), np.random.default_rng(i)
    draws.restart(watched)
    pick = np.random.default_rng(0)
    for k in range(6 * draws.per):  # rows used at different rates: partial blocks move
        if k == 3 * draws.per:  # a new generator for row 1 drops its buffered draws
            rngs[1], refs[1] = np.random.default_rng(99), np.random.default_rng(99)
            draws.restart(np.array([1]))
        rows = watched[pick.random(3) < (0.9, 0.5, 0.2)]
        got = draws.take(rows)
        assert got.shape == (len(rows), 4)
        for row, values in zip(rows.tolist(), got):
            assert values.tobytes() == refs[row].random(4).tobytes(), (k, row)


def test_unseeded_rows_do_not_block_top_ups() -> None:
    rngs: list[np.random.Generator | None] = [None, np.random.default_rng(5)]
    draws = PreDrawn(rngs, 1)
    draws.restart(np.array([1]))
    ref = np.random.default_rng(5)
    for _ in range(3 * draws.per):
        assert draws.take(np.array([1]))[0, 0] == ref.random()
