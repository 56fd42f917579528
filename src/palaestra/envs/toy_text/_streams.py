"""Per-row random streams for a toy-text batch: the draws of N generators as array ops.

A toy-text env draws on every step (which slippery move, which card), so row i of a batch
must take its numbers from its own generator, in the order a single env would. Each row's
generator fills a block of raw 64-bit outputs ahead (``bit_generator.random_raw``, the very
words ``random()`` and ``integers()`` consume), and a draw for R rows is then one gather.

What numpy does with those words, reproduced here (tests/envs/toy_text/test_streams.py
compares with ``Generator`` on many seeds):

- ``random()``: one word ``w``, ``(w >> 11) * 2**-53``.
- ``integers(0, n)`` / ``choice(seq)`` (n < 2**32): Lemire's bounded draw on 32-bit words.
  PCG64 serves a 32-bit word from the low half of a new 64-bit word and keeps the high half
  for the next 32-bit request (``has_uint32``), so a row carries that half-word too.
  ``x * n >> 32`` is the result unless ``(x * n) mod 2**32 < (2**32 - n) mod n``, a
  one-in-a-few-billion rejection that draws again.

The per-row Python loop runs only in top-ups: every take uses a row at most once, so after a
top-up no row runs dry for as many takes as the fewest words any row has left.
"""

from __future__ import annotations

import numpy as np

_BUFFER_BYTES = 16 << 20  # all rows together
_ROW_WORDS = (256, 8192)  # words a row holds: 2 KiB to 64 KiB
_LOW32 = np.uint64(0xFFFFFFFF)
_SHIFT11, _SHIFT32 = np.uint64(11), np.uint64(32)
_TWO_M53 = 2.0**-53


class RowStreams:
    """Raw words drawn ahead for each of ``len(rngs)`` rows, plus each row's kept half-word.

    ``rngs`` is the batch's list of generators, shared: rows whose entry changes must be
    passed to :meth:`restart`. The generators themselves run ahead of what was consumed.
    """

    RUN_STATE = ("_words", "_pos", "_half", "_has_half", "_live", "_budget")

    def __init__(self, rngs: list[np.random.Generator | None]) -> None:
        n = len(rngs)
        self._rngs = rngs
        self.per = min(max(_BUFFER_BYTES // (8 * n), _ROW_WORDS[0]), _ROW_WORDS[1])
        self._words = np.zeros(n * self.per, dtype=np.uint64)  # row i: [i*per, (i+1)*per)
        self._end = (np.arange(n, dtype=np.int64) + 1) * self.per  # [N] one past each block
        self._pos = self._end.copy()  # [N] next unused word; end means empty
        self._half = np.zeros(n, dtype=np.uint64)  # [N] the kept high half-word
        self._has_half = np.zeros(n, dtype=bool)  # [N]
        self._live = np.zeros(n, dtype=bool)  # [N] has a generator
        self._budget = 0  # takes that cannot empty any live row

    def restart(self, rows: np.ndarray) -> None:
        """Rows got new generators: drop what the old ones drew (and their half-words)."""
        self._pos[rows] = self._end[rows]
        self._has_half[rows] = False
        self._live[rows] = True
        self._budget = 0

    def words(self, rows: np.ndarray) -> np.ndarray:
        """The next raw 64-bit word of each of ``rows`` (distinct, live): uint64 ``[R]``."""
        if self._budget < 1:
            self._top_up()
        self._budget -= 1
        pos = self._pos[rows]
        self._pos[rows] = pos + 1
        return self._words[pos]

    def doubles(self, rows: np.ndarray) -> np.ndarray:
        """``Generator.random()`` for each of ``rows``: float64 ``[R]`` in [0, 1)."""
        return (self.words(rows) >> _SHIFT11).astype(np.float64) * _TWO_M53

    def uint32(self, rows: np.ndarray) -> np.ndarray:
        """PCG64's ``next_uint32`` for each of ``rows`` (a kept half-word first): uint64 ``[R]``."""
        out = np.empty(len(rows), dtype=np.uint64)
        kept = self._has_half[rows]  # [R]
        if kept.any():
            out[kept] = self._half[rows[kept]]
            self._has_half[rows[kept]] = False
            fresh = rows[~kept]
            need = ~kept
        else:
            fresh, need = rows, slice(None)
        if len(fresh):
            w = self.words(fresh)
            self._half[fresh] = w >> _SHIFT32
            self._has_half[fresh] = True
            out[need] = w & _LOW32
        return out

    def bounded(self, rows: np.ndarray, n: int) -> np.ndarray:
        """``Generator.integers(0, n)`` (= ``choice`` of n items) for each row: int64 ``[R]``."""
        span = np.uint64(n)
        m = self.uint32(rows) * span  # < 2**64: a 32-bit word times n < 2**32
        threshold = np.uint64((2**32 - n) % n)
        redo = np.flatnonzero((m & _LOW32) < threshold)
        while len(redo):  # Lemire's rejection: about once in 2**32 / n draws
            m[redo] = self.uint32(rows[redo]) * span
            redo = redo[(m[redo] & _LOW32) < threshold]
        return (m >> _SHIFT32).astype(np.int64)

    def _top_up(self) -> None:
        """Refill every live row with half a block or less left; reset the budget."""
        per = self.per
        left = self._end - self._pos  # [N]
        for i in np.flatnonzero(self._live & (left <= per // 2)).tolist():
            rng = self._rngs[i]
            assert rng is not None
            k = int(left[i])
            start = int(self._end[i]) - per
            block = self._words[start : start + per]
            block[:k] = block[per - k :]  # the unused words first (k <= per/2: no overlap)
            block[k:] = rng.bit_generator.random_raw(per - k)
            self._pos[i] = start
            left[i] = per
        self._budget = int(np.min(left, where=self._live, initial=per))
