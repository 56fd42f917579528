"""Reset uniforms drawn ahead, per row, so that resetting R rows of a batch is one gather.

Every reset of a classic-control env consumes a fixed number of uniform doubles, and numpy's
``uniform(low, high)`` is ``low + (high - low) * random()``. So each row's own generator fills a
block of future resets ahead of time, and a reset of any rows takes each row's next record.
A row's records are used in the order its generator drew them (a top-up moves the unused ones
to the front before drawing more), so row i draws exactly what a single env would.

The per-row Python loop runs only in top-ups, and a top-up runs only when some row could run
out: each ``take`` uses a row at most once, so after a top-up no row empties for as many takes
as the fewest records any row has left (at least half a block).
"""

from __future__ import annotations

from typing import Any

import numpy as np

# Bigger blocks mean fewer generator calls (~1 us each plus the loop around them): 16 MiB in
# all, 1 KiB to 8 KiB a row (1024 CartPoles: 256 resets a block).
_BUFFER_BYTES = 16 << 20
_ROW_BYTES = (1 << 10, 8 << 10)


class PreDrawn:
    """Blocks of ``per`` resets of ``draws`` uniforms for each of ``len(rngs)`` rows.

    ``rngs`` is the batch's list of generators, shared: rows whose entry changes must be passed
    to :meth:`restart`.
    """

    # What exact resume saves (utils.run_state); the generators belong to the batch.
    RUN_STATE = ("_uniforms", "_pos", "_live", "_budget")

    def __init__(self, rngs: list[np.random.Generator | None], draws: int) -> None:
        n = len(rngs)
        row_bytes = min(max(_BUFFER_BYTES // n, _ROW_BYTES[0]), _ROW_BYTES[1])
        self.per = max(1, row_bytes // (8 * draws))  # resets a block holds
        self.draws = draws
        self._rngs = rngs
        self._uniforms = np.empty((n * self.per, draws))  # row i: records [i*per, (i+1)*per)
        self._make_views()
        self._end = np.arange(1, n + 1) * self.per  # [N] one past each row's block
        self._pos = self._end.copy()  # [N] each row's next unused record; end means empty
        self._live = np.zeros(n, dtype=bool)  # [N] has a generator
        self._budget = 0  # takes that cannot empty any live row

    def _make_views(self) -> None:
        # One record per reset: gathering R of them is 1-D fancy indexing, several times
        # cheaper than indexing the 2-D array (numpy's multi-dimensional indexing costs more).
        self._records = self._uniforms.view(np.dtype((np.void, 8 * self.draws)))[:, 0]

    # pickle and deepcopy copy each array on its own: a copied view would not see the copied
    # buffer's top-ups, so it is left out and made again.
    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state.pop("_records", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._make_views()

    def restart(self, rows: np.ndarray) -> None:
        """Rows got new generators: drop what the old ones drew."""
        self._pos[rows] = self._end[rows]
        self._live[rows] = True
        self._budget = 0

    def take(self, rows: np.ndarray) -> np.ndarray:
        """The next reset's uniforms ``[R, draws]`` of each of ``rows`` (distinct, live)."""
        if self._budget < 1:
            self._top_up()
        self._budget -= 1
        pos = self._pos[rows]
        self._pos[rows] = pos + 1
        return self._records[pos].view(np.float64).reshape(len(rows), self.draws)

    def _top_up(self) -> None:
        """Refill every live row with half a block or less left; reset the budget."""
        per = self.per
        left = self._end - self._pos  # [N]
        for i in np.flatnonzero(self._live & (left <= per // 2)).tolist():
            rng = self._rngs[i]
            assert rng is not None
            k = int(left[i])
            block = self._uniforms[self._end[i] - per : self._end[i]]
            block[:k] = block[per - k :]  # the unused draws first (k <= per/2: no overlap)
            rng.random(out=block[k:])  # then what rng.random((per - k, draws)) would give
            self._pos[i] = self._end[i] - per
            left[i] = per
        self._budget = int(np.min(left, where=self._live, initial=per))
