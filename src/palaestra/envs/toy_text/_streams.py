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


class Peek:
    """Draws read ahead for some rows (see :meth:`RowStreams.peek_bounded`)."""

    __slots__ = ("draws", "full", "offset", "places", "rows", "values")

    def __init__(self, rows: np.ndarray, full: np.ndarray, offset: np.ndarray, values: np.ndarray):
        self.rows = rows  # [R]
        self.full = full  # [R, 2W + 1] the kept half, then the low and high halves of W words
        self.offset = offset  # [R] where the row's sequence starts in `full` (0 or 1)
        self.values = values  # [R, window] the row's next 32-bit values, in order
        self.places: np.ndarray = values  # [R, count] index in `values` of each accepted draw
        self.draws: np.ndarray = values  # [R, count] the bounded draws

    def values_for(self, count: np.ndarray) -> np.ndarray:
        """How many 32-bit values the first ``count`` accepted draws of each row took."""
        last = self.places[np.arange(len(count)), np.maximum(count, 1) - 1]
        return np.where(count > 0, last + 1, 0)


class RowStreams:
    """Raw words drawn ahead for each of ``len(rngs)`` rows, plus each row's kept half-word.

    ``rngs`` is the batch's list of generators, shared: rows whose entry changes must be
    passed to :meth:`restart`. The generators themselves run ahead of what was consumed.
    """

    RUN_STATE = ("_words", "_pos", "_half", "_has_half", "_live", "_budget")
    # Row i's stream is column i of ``[per, N]`` words (False) or row i of ``[N, per]`` (True).
    row_major = False

    def __init__(self, rngs: list[np.random.Generator | None]) -> None:
        n = len(rngs)
        self._rngs = rngs
        self.per = min(max(_BUFFER_BYTES // (8 * n), _ROW_WORDS[0]), _ROW_WORDS[1])
        # Row i's stream is column i: rows that draw in step (a tabular env draws one word
        # per row per step, reset or not) read one contiguous line of this array. A layout
        # with each row's block contiguous scatters a step's N reads over the whole buffer:
        # measured 39 us against ~6 us for 1024 rows. (Rows that drift apart prefer the
        # other layout: HalfWordStreams.)
        shape = (n, self.per) if self.row_major else (self.per, n)
        self._words = np.zeros(shape, dtype=np.uint64)  # [per, N] (row-major: [N, per])
        # A view: word p of row i is flat[p * N + i] (row-major: flat[i * per + p]).
        self._flat = self._words.reshape(-1)
        self._cols = np.arange(n, dtype=np.int64)  # [N]
        self._pos = np.full(n, self.per, dtype=np.int64)  # [N] next unused word; per: empty
        self._half = np.zeros(n, dtype=np.uint64)  # [N] the kept high half-word
        self._has_half = np.zeros(n, dtype=bool)  # [N]
        self._live = np.zeros(n, dtype=bool)  # [N] has a generator
        self._budget = 0  # takes that cannot empty any live row

    def restart(self, rows: np.ndarray) -> None:
        """Rows got new generators: drop what the old ones drew (and their half-words)."""
        self._pos[rows] = self.per
        self._has_half[rows] = False
        self._live[rows] = True
        self._budget = 0

    def words(self, rows: np.ndarray | None) -> np.ndarray:
        """The next raw 64-bit word of each of ``rows`` (distinct, live; None: every row):
        uint64 ``[R]``."""
        if self._budget < 1:
            self._top_up()
        self._budget -= 1
        n = len(self._cols)
        if rows is None:
            out = self._flat.take(self._pos * n + self._cols)
            self._pos += 1
            return out
        pos = self._pos[rows]
        self._pos[rows] = pos + 1
        return self._flat.take(pos * n + rows)

    def doubles(self, rows: np.ndarray | None) -> np.ndarray:
        """``Generator.random()`` for each of ``rows`` (None: every row): float64 ``[R]``."""
        return (self.words(rows) >> _SHIFT11).astype(np.float64) * _TWO_M53

    def uint32(self, rows: np.ndarray) -> np.ndarray:
        """PCG64's ``next_uint32`` for each of ``rows`` (a kept half-word first): uint64 ``[R]``."""
        if self._budget < 1:
            self._top_up()
        self._budget -= 1
        kept = self._has_half[rows]  # [R]
        pos = self._pos[rows]
        word = self._flat.take(pos * len(self._cols) + rows)  # read even where unused
        half = self._half[rows]
        self._half[rows] = np.where(kept, half, word >> _SHIFT32)
        self._has_half[rows] = ~kept
        self._pos[rows] = pos + ~kept
        return np.where(kept, half, word & _LOW32)

    def bounded(self, rows: np.ndarray, n: int) -> np.ndarray:
        """``Generator.integers(0, n)`` (= ``choice`` of n items) for each row: int64 ``[R]``."""
        span = np.uint64(n)
        m = self.uint32(rows) * span  # < 2**64: a 32-bit word times n < 2**32
        threshold = np.uint64((2**32 - n) % n)
        if threshold:  # n a power of two never rejects
            redo = np.flatnonzero((m & _LOW32) < threshold)
            while len(redo):  # Lemire's rejection: about once in 2**32 / n draws
                m[redo] = self.uint32(rows[redo]) * span
                redo = redo[(m[redo] & _LOW32) < threshold]
        return (m >> _SHIFT32).astype(np.int64)

    def peek_bounded(self, rows: np.ndarray, n: int, count: int, slack: int = 2) -> Peek:
        """The next ``count`` draws of ``integers(0, n)`` of each row, not consumed yet.

        For a variable number of draws per row (a dealer draws until 17): read them all in
        one go, decide, then :meth:`consume` what each row used. ``slack`` more values are
        read for rejections (and for a caller that wants the values after the draws).
        """
        span = np.uint64(n)
        threshold = np.uint64((2**32 - n) % n)
        window = count + slack  # rejections: each about once in 2**32 / n draws
        peek = self._halves(rows, window)
        prod = peek.values * span  # [R, window]
        if threshold and ((prod & _LOW32) < threshold).any():
            # A rejected value in the window (rare): the c-th accepted draw's place in the
            # sequence, by a stable sort that puts the accepted places first, in order.
            accepted = (prod & _LOW32) >= threshold
            while (accepted.sum(axis=1) < count).any():
                window *= 2
                peek = self._halves(rows, window)
                prod = peek.values * span
                accepted = (prod & _LOW32) >= threshold
            order = np.argsort(~accepted, axis=1, kind="stable")[:, :count]
            peek.places = order
            prod = np.take_along_axis(prod, order, axis=1)
        else:
            peek.places = np.broadcast_to(np.arange(count), (len(rows), count))
            prod = prod[:, :count]
        peek.draws = (prod >> _SHIFT32).astype(np.int64)  # [R, count]
        return peek

    def consume(self, peek: Peek, used: np.ndarray) -> None:
        """Advance each row of ``peek`` past its first ``used`` 32-bit values (int ``[R]``,
        may be 0; :meth:`Peek.values_for` converts a number of accepted draws)."""
        end = peek.offset + used - 1  # [R] index in `full` of the last value used
        rows = peek.rows
        self._pos[rows] += (end + 1) // 2  # whole words read past
        keeps = (end % 2) == 1  # ended on a low half: its high half is kept (end -1: unchanged)
        self._has_half[rows] = keeps
        self._half[rows] = np.take_along_axis(peek.full, (end + 1)[:, None], axis=1)[:, 0]

    def _halves(self, rows: np.ndarray, window: int) -> Peek:
        """The next ``window`` 32-bit values of each row, without consuming them."""
        words = window // 2 + 1
        if self._budget < words:
            self._top_up()
        self._budget -= words
        n = len(self._cols)
        index = (self._pos[rows][:, None] + np.arange(words)) * n + rows[:, None]  # [R, W]
        w = self._flat.take(index)
        full = np.empty((len(rows), 2 * words + 1), dtype=np.uint64)
        full[:, 0] = self._half[rows]
        full[:, 1::2] = w & _LOW32
        full[:, 2::2] = w >> _SHIFT32
        offset = (~self._has_half[rows]).astype(np.int64)  # 0: start at the kept half
        values = np.take_along_axis(full, offset[:, None] + np.arange(window), axis=1)
        return Peek(rows, full, offset, values)

    def _top_up(self) -> None:
        """Refill every live row with half a block or less left; reset the budget.

        A row keeping a half-word keeps the word it came from too (``HalfWordStreams``
        reads it there).
        """
        per = self.per
        left = per - self._pos  # [N]
        for i in np.flatnonzero(self._live & (left <= per // 2)).tolist():
            rng = self._rngs[i]
            assert rng is not None
            back = int(self._has_half[i] and self._pos[i] > 0)
            k = int(left[i]) + back  # words kept: the unused ones (and the half-used one)
            column = self._words[i] if self.row_major else self._words[:, i]
            column[:k] = column[per - k :].copy()  # to the front (k <= per/2 + 1)
            column[k:] = rng.bit_generator.random_raw(per - k)
            self._pos[i] = back
            left[i] = per - back
        self._budget = int(np.min(left, where=self._live, initial=per))


class HalfWordStreams(RowStreams):
    """Streams for a batch that draws only 32-bit values (Blackjack's cards).

    Without ``random()`` draws in between, a kept half-word is always the high half of the
    word before ``_pos``, so a row's place is one number, ``q = 2 * pos - has_half`` in
    half-words, and reading the next values is a gather at ``q, q + 1, ...``: a few array
    operations instead of the general bookkeeping.

    Rows draw different numbers of values per step (a dealer draws to 17, a deal takes up to
    six), so their places drift apart: each row's block is contiguous (``[N, per]``), and
    reading a row's next few values touches one or two cache lines, not one per word with
    ``8 N`` bytes (two pages at 1024 rows) between them.
    """

    row_major = True

    def __init__(self, rngs: list[np.random.Generator | None]) -> None:
        super().__init__(rngs)
        self._starts = self._cols * self.per  # [N] where each row's block starts in _flat

    def words(self, rows: np.ndarray | None) -> np.ndarray:
        """Not available: 64-bit draws break the half-word model."""
        raise TypeError("HalfWordStreams draws 32-bit values only; use RowStreams")

    def doubles(self, rows: np.ndarray | None) -> np.ndarray:
        """Not available: a double between 32-bit draws breaks the half-word model."""
        raise TypeError("HalfWordStreams draws 32-bit values only; use RowStreams")

    def _place(self, rows: np.ndarray) -> np.ndarray:
        return 2 * self._pos[rows] - self._has_half[rows]  # [R] half-words consumed

    def _read(self, rows: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The 32-bit values at half-word places ``q`` (``[R]`` or ``[R, W]``) of ``rows``."""
        starts = self._starts[rows]
        w = self._flat.take((q >> 1) + (starts if q.ndim == 1 else starts[:, None]))
        return (w >> ((q & 1) << 5).astype(np.uint64)) & _LOW32

    def _advance(self, rows: np.ndarray, q: np.ndarray) -> None:
        self._pos[rows] = (q + 1) >> 1
        self._has_half[rows] = (q & 1).astype(bool)

    def uint32(self, rows: np.ndarray) -> np.ndarray:
        """The next 32-bit value of each of ``rows``: uint64 ``[R]``."""
        if self._budget < 1:
            self._top_up()
        self._budget -= 1
        q = self._place(rows)
        out = self._read(rows, q)
        self._advance(rows, q + 1)
        return out

    def _halves(self, rows: np.ndarray, window: int) -> Peek:
        words = window // 2 + 1
        if self._budget < words:
            self._top_up()
        self._budget -= words
        q = self._place(rows)
        values = self._read(rows, q[:, None] + np.arange(window))
        return Peek(rows, values, q, values)  # `offset` holds each row's place

    def consume(self, peek: Peek, used: np.ndarray) -> None:
        """Advance each row of ``peek`` past its first ``used`` 32-bit values."""
        self._advance(peek.rows, peek.offset + used)

    def window(self, width: int) -> tuple[np.ndarray, np.ndarray]:
        """Every row's place and next ``width`` 32-bit values, not consumed: ``(q [N],
        values [width, N] uint64)`` (value j of every row is one contiguous line);
        :meth:`advance_all` then moves each row to its new place. Every row must be live (a
        batch steps only once all rows were reset)."""
        words = width // 2 + 1
        if self._budget < words:
            self._top_up()
        self._budget -= words
        q = 2 * self._pos - self._has_half  # [N]
        places = q + np.arange(width)[:, None]  # [W, N]
        w = self._flat.take((places >> 1) + self._starts)
        return q, (w >> ((places & 1) << 5).astype(np.uint64)) & _LOW32

    def advance_all(self, q: np.ndarray) -> None:
        """Set every row's place (half-words consumed) to ``q`` (int ``[N]``)."""
        np.right_shift(q + 1, 1, out=self._pos)
        self._has_half[:] = q & 1
