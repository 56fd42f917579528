"""The native engine's time limit: an elapsed counter per row, kept as one step count."""

from __future__ import annotations

import numpy as np
import pytest

from palaestra.envs.classic_control import CartPoleBatch
from palaestra.vector.native_engine import NativeEngine


@pytest.mark.parametrize("limit", [1, 3, 9])
def test_truncation_follows_each_rows_elapsed_steps(limit: int) -> None:
    """Rows reset at scattered times (by the step or by reset) truncate exactly at the limit,
    including the steps where the engine skips the comparison because no row can be due."""
    n = 12
    engine = NativeEngine(CartPoleBatch(n), limit)
    engine.reset(None, [7] * n, None)
    elapsed = np.zeros(n, dtype=np.int64)
    rng = np.random.default_rng(0)
    for t in range(300):
        mask = rng.random(n) < 0.15
        if t % 37 == 5:  # a reset outside a step
            engine.reset(mask, [None] * n, None)
            elapsed[mask] = 0
            continue
        engine.step_send(rng.integers(0, 2, n), mask if mask.any() else None)
        _, _, truncated, _ = engine.step_recv()
        elapsed += 1
        # Rows reset by this step report on the step that was replaced (the autoresetter
        # overwrites them); the others must say exactly elapsed >= limit.
        np.testing.assert_array_equal(truncated[~mask], (elapsed >= limit)[~mask], str(t))
        elapsed[mask] = 0


def test_no_time_limit_never_truncates() -> None:
    engine = NativeEngine(CartPoleBatch(3), None)
    engine.reset(None, [0, 1, 2], None)
    for _ in range(50):
        engine.step_send(np.ones(3, dtype=np.int64), None)
        assert not engine.step_recv()[2].any()
