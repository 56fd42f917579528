"""Blackjack-v1: draw cards (hit) or stop (stick) to beat the dealer without going over 21.

Gymnasium 1.x's ``BlackjackEnv`` (Sutton & Barto, Example 5.1): an infinite deck, the dealer
hits below 17, reward +1 / 0 / -1 (``natural=True``: 1.5 for a winning natural; ``sab=True``:
a natural wins outright unless the dealer has one too, and ``natural`` is ignored).

A hand is kept as ``(sum counting aces as 1, has an ace, cards)``; the rules below are written
once over :mod:`~palaestra.envs.classic_control._ops` (``where``) and run on ints for the
single env and on ``[N]`` arrays for the batch. Cards are ``deck[integers(13)]``: what
Gymnasium's ``choice(deck)`` draws.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_discrete_action
from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.toy_text._common import ToyTextBatch, ToyTextEnv
from palaestra.envs.toy_text._streams import HalfWordStreams
from palaestra.rendering.toy_text import render_blackjack
from palaestra.spaces import Discrete, Tuple

DECK = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 10, 10, 10)  # ace, 2-10, jack, queen, king
_DECK = np.array(DECK, dtype=np.int64)
_U3, _U4, _U13, _U30, _U32 = (np.uint64(k) for k in (3, 4, 13, 30, 32))
_LOW32 = np.uint64(0xFFFFFFFF)
# integers(13) rejects a 32-bit value x when (13 x) mod 2**32 < (2**32 - 13) mod 13 = 9.
_REJECT13 = np.uint64((2**32 - 13) % 13)
SUITS = ("C", "D", "H", "S")
FACES = ("J", "Q", "K")


def total(ops: Any, raw: Any, ace: Any) -> Any:
    """A hand's value: an ace counts 11 when that does not bust it."""
    return ops.where(ace & (raw + 10 <= 21), raw + 10, raw)


# The dealer's hand as one code, 2 * raw + ace (raw < 27: the dealer draws only below 17),
# and what a card does to it, as tables: the batch's dealer loop is then three gathers per
# card instead of a dozen array operations. A hand at 17 or more is absorbing: it draws no
# card, so rows that stopped (or never drew) can run through the loop unchanged.
_DEALER_CODES = 2 * 27
_DEALER_DRAWS = np.array(
    [total(SCALAR, h >> 1, bool(h & 1)) < 17 for h in range(_DEALER_CODES)], dtype=bool
)
_DEALER_NEXT = np.array(
    [
        [2 * ((h >> 1) + c) + ((h & 1) | (c == 1)) if _DEALER_DRAWS[h] else h for c in range(11)]
        for h in range(_DEALER_CODES)
    ],
    dtype=np.int64,
).reshape(-1)  # [codes * 11]: the code after card c (1-10) is at 11 * code + c
_DEALER_STOPPED = 2 * 26  # a code that draws nothing (for rows whose dealer does not play)


def usable_ace(raw: Any, ace: Any) -> Any:
    """Whether an ace counts 11 (the observation's third entry)."""
    return ace & (raw + 10 <= 21)


def is_natural(raw: Any, ace: Any, cards: Any) -> Any:
    """An ace and a ten-card as the first two cards."""
    return (cards == 2) & ace & (raw == 11)


def settle(
    ops: Any,
    player: tuple[Any, Any, Any],
    dealer: tuple[Any, Any, Any],
    natural: bool,
    sab: bool,
) -> Any:
    """The reward of a stick, once the dealer has drawn to 17 (hands: raw, ace, cards)."""
    p_total, d_total = total(ops, *player[:2]), total(ops, *dealer[:2])
    p_score = ops.where(p_total > 21, 0, p_total)
    d_score = ops.where(d_total > 21, 0, d_total)
    reward = (p_score > d_score) * 1.0 - (p_score < d_score) * 1.0
    p_natural = is_natural(*player)
    if sab:  # Sutton & Barto: a natural wins unless the dealer has one too
        # `>` on booleans: "player natural and dealer not", for Python bools and arrays alike.
        return ops.where(p_natural > is_natural(*dealer), 1.0, reward)
    if natural:  # casino rules: a winning natural pays 1.5
        return ops.where(p_natural & (reward == 1.0), 1.5, reward)
    return reward


def _space() -> Tuple:
    return Tuple((Discrete(32), Discrete(11), Discrete(2)))


class BlackjackEnv(ToyTextEnv):
    """Single Blackjack. Actions: 0 stick, 1 hit. Observation: (player sum, dealer card, ace)."""

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 4}

    def __init__(self, render_mode: str | None = None, natural: bool = False, sab: bool = False):
        self.action_space = Discrete(2)
        self.observation_space = _space()
        self.natural = natural
        self.sab = sab
        self.player: list[int] = []
        self.dealer: list[int] = []
        self._init_render(render_mode)

    def _draw(self) -> int:
        return DECK[int(self.np_random.integers(13))]

    def _obs(self) -> tuple[int, int, int]:
        raw, ace = sum(self.player), 1 in self.player
        return total(SCALAR, raw, ace), self.dealer[0], int(usable_ace(raw, ace))

    @staticmethod
    def _hand(cards: list[int]) -> tuple[int, bool, int]:
        return sum(cards), 1 in cards, len(cards)

    def step(self, action: Any) -> tuple[tuple[int, int, int], float, bool, bool, dict[str, Any]]:
        """Hit (1) draws a card; stick (0) lets the dealer play and settles."""
        if type(action) is not int or not 0 <= action < 2:
            action = check_discrete_action(action, self.action_space, 2)
        if not self.player:
            raise error.ResetNeeded("Call reset before using step method.")
        if action:
            self.player.append(self._draw())
            terminated = total(SCALAR, sum(self.player), 1 in self.player) > 21
            reward = -1.0 if terminated else 0.0
        else:
            terminated = True
            while total(SCALAR, sum(self.dealer), 1 in self.dealer) < 17:
                self.dealer.append(self._draw())
            reward = float(
                settle(
                    SCALAR, self._hand(self.player), self._hand(self.dealer), self.natural, self.sab
                )
            )
        if self.render_mode == "human":
            self.render()
        return self._obs(), reward, terminated, False, {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[tuple[int, int, int], dict[str, Any]]:
        """Deal two cards to the dealer, then two to the player; pick the face-up card's look."""
        super().reset(seed=seed)
        self.dealer = [self._draw(), self._draw()]
        self.player = [self._draw(), self._draw()]
        # Only the picture uses these, but Gymnasium draws them: so must we, to stay in step.
        self.dealer_top_card_suit = SUITS[int(self.np_random.integers(4))]
        first = self.dealer[0]
        if first == 1:
            self.dealer_top_card_value_str = "A"
        elif first == 10:
            self.dealer_top_card_value_str = FACES[int(self.np_random.integers(3))]
        else:
            self.dealer_top_card_value_str = str(first)
        if self.render_mode == "human":
            self.render()
        return self._obs(), {}

    def _frame(self) -> np.ndarray:
        if not self.player:
            raise error.ResetNeeded("Call reset before render.")
        player_sum, dealer_value, ace = self._obs()
        card = self.dealer_top_card_value_str + self.dealer_top_card_suit
        return render_blackjack(player_sum, dealer_value, bool(ace), card)


class BlackjackBatch(ToyTextBatch):
    """N Blackjack tables as arrays; the dealer's draws loop over rounds, never over rows.

    A step with autoreset runs in one pass over every row (:meth:`_step_all`): each row's
    next ``WINDOW`` values are read once and every row's three possible moves (hit, stick
    with the dealer drawing to 17, a new deal) are computed on them as whole-array
    operations, then each row keeps its own and consumes what it used. Rows are never
    gathered into subsets, so a step costs a fixed ~60 array operations on ``[N]`` and
    ``[N, WINDOW]`` arrays.
    """

    streams_class = HalfWordStreams  # cards, suits and faces: 32-bit draws only
    # 32-bit values read per row and step: a deal takes up to 6 (4 cards, a suit, a ten's
    # face). A dealer needs more than 6 draws to reach 17 in 5.6e-7 of hands (exact, over
    # the infinite deck), a step then falls back about once in 3,500 at 1024 rows.
    WINDOW = 6
    max_dealer_draws = WINDOW  # draws the one-pass step allows a dealer (tests lower it)
    _streams: HalfWordStreams

    RUN_STATE = (
        *ToyTextBatch.RUN_STATE,
        "_p_raw",
        "_p_ace",
        "_p_cards",
        "_d_raw",
        "_d_ace",
        "_d_cards",
        "_first",
        "_suit",
        "_face",
    )

    def __init__(self, num_envs: int, natural: bool = False, sab: bool = False) -> None:
        super().__init__(num_envs)
        self.natural, self.sab = natural, sab
        self.single_observation_space = _space()
        self.single_action_space = Discrete(2)
        n = self.num_envs
        # Hands: raw sum (aces count 1), holds an ace, number of cards; [N] each.
        self._p_raw, self._d_raw = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
        self._p_ace, self._d_ace = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
        self._p_cards, self._d_cards = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
        self._first = np.zeros(n, dtype=np.int64)  # [N] the dealer's face-up card
        self._suit = np.zeros(n, dtype=np.int64)  # [N] index into SUITS (for pictures)
        self._face = np.zeros(n, dtype=np.int64)  # [N] index into FACES when the card is 10
        self._obs = tuple(np.zeros(n, dtype=np.int64) for _ in range(3))  # 3 x [N]
        self._reward = np.zeros(n)
        self._terminated = np.zeros(n, dtype=bool)

    def _reset_rows(self, rows: np.ndarray, mask: np.ndarray | None) -> Any:
        # Dealer, dealer, player, player, then the face-up card's suit (and its face when it
        # is a ten): Gymnasium's order, read in one go.
        streams = self._streams
        peek = streams.peek_bounded(rows, 13, 4)
        d1, d2, p1, p2 = _DECK.take(peek.draws).T
        tens = d1 == 10
        suit_at = peek.places[:, 3] + 1  # the values after the cards: suit, face
        window = peek.values.shape[1]
        if (suit_at + 1 < window).all():
            nxt = np.take_along_axis(peek.values, suit_at[:, None] + np.arange(2), axis=1)
            suit = (nxt[:, 0] * _U4) >> _U32
            face = nxt[:, 1] * _U3
            # integers(3) rejects a value whose product's low half is 0 (the value 0 itself).
            fits = not (tens & ((face & _LOW32) == 0)).any()
        else:
            fits = False
        if fits:
            streams.consume(peek, suit_at + 1 + tens)
            self._suit[rows] = suit.astype(np.int64)
            self._face[rows[tens]] = (face[tens] >> _U32).astype(np.int64)
        else:  # a rejected draw in the way (about once in 10**8 resets): one at a time
            streams.consume(peek, suit_at)
            self._suit[rows] = streams.bounded(rows, 4)
            if tens.any():
                self._face[rows[tens]] = streams.bounded(rows[tens], 3)
        self._d_raw[rows], self._d_ace[rows] = d1 + d2, (d1 == 1) | (d2 == 1)
        self._p_raw[rows], self._p_ace[rows] = p1 + p2, (p1 == 1) | (p2 == 1)
        self._d_cards[rows] = self._p_cards[rows] = 2
        self._first[rows] = d1
        self._observe(rows)
        return None

    def _step_all(
        self, actions: np.ndarray, resetting: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Hit, stick or deal anew (rows in ``resetting``) for every row in one pass.

        Returns None, with nothing changed, when a value in the window would be rejected by
        ``integers`` or a dealer needs more cards than the window holds: the two-part path
        (one draw at a time) then runs instead.
        """
        q, values = self._streams.window(self.WINDOW)  # [N], [W, N] uint64
        prod = values * _U13
        if ((prod & _LOW32) < _REJECT13).any():
            return None  # 9 values in 2**32 are: 1 step in ~80,000 at 1024 rows
        cards = _DECK.take(prod >> _U32)  # [W, N] each row's next cards
        hit = actions == 1  # [N]
        dealing = resetting is not None and bool(resetting.any())
        if resetting is not None and dealing:
            hit &= ~resetting
            stick = ~(hit | resetting)
            # integers(3) rejects only the value 0: a ten's face drawn from a 0 would be.
            if (resetting & (cards[0] == 10) & (values[5] == 0)).any():
                return None
        else:
            stick = ~hit
        # Stickers' dealers draw below 17: a loop over the window's cards, never over rows.
        code = np.where(stick, 2 * self._d_raw + self._d_ace, _DEALER_STOPPED)  # [N]
        taken = np.zeros_like(self._d_cards)  # [N] cards each dealer draws
        for card in cards[: self.max_dealer_draws]:
            drawing = _DEALER_DRAWS.take(code)
            if not drawing.any():
                break
            taken += drawing
            code = _DEALER_NEXT.take(11 * code + card)
        else:
            if _DEALER_DRAWS.take(code).any():
                return None  # a dealer still below 17 after max_dealer_draws cards
        # Nothing can fail from here on: commit. Hitters draw one card.
        card = cards[0]
        np.add(self._p_raw, card, out=self._p_raw, where=hit)
        self._p_ace |= hit & (card == 1)
        self._p_cards += hit
        bust = hit & (total(ARRAY, self._p_raw, self._p_ace) > 21)
        np.right_shift(code, 1, out=self._d_raw, where=stick)
        np.copyto(self._d_ace, code & 1, where=stick, casting="unsafe")
        self._d_cards += taken
        player = (self._p_raw, self._p_ace, self._p_cards)
        dealer = (self._d_raw, self._d_ace, self._d_cards)
        settled = settle(ARRAY, player, dealer, self.natural, self.sab)
        np.copyto(self._reward, np.where(stick, settled, np.where(bust, -1.0, 0.0)))
        np.logical_or(stick, bust, out=self._terminated)
        used = taken + hit  # [N] 32-bit values each row consumes
        if dealing:
            assert resetting is not None
            self._deal(resetting, cards, values)
            used += resetting * (5 + (cards[0] == 10))  # 4 cards, a suit, a ten's face
            self._terminated &= ~resetting
            self._reward[resetting] = 0.0
        self._streams.advance_all(q + used)
        self._observe_all()
        return self._reward, self._terminated

    def _deal(self, rows: np.ndarray, cards: np.ndarray, values: np.ndarray) -> None:
        """A new deal for the rows in the bool mask ``rows`` from their next cards and values
        (``[W, N]``): dealer, dealer, player, player, then the face-up card's suit and, when
        it is a ten, its face (Gymnasium's order)."""
        d1, d2, p1, p2 = cards[:4]
        np.copyto(self._d_raw, d1 + d2, where=rows)
        np.copyto(self._d_ace, (d1 == 1) | (d2 == 1), where=rows)
        np.copyto(self._p_raw, p1 + p2, where=rows)
        np.copyto(self._p_ace, (p1 == 1) | (p2 == 1), where=rows)
        np.copyto(self._d_cards, 2, where=rows)
        np.copyto(self._p_cards, 2, where=rows)
        np.copyto(self._first, d1, where=rows)
        # integers(4): the top two bits; integers(3): the top half of 3 x.
        np.copyto(self._suit, values[4] >> _U30, where=rows, casting="unsafe")
        np.copyto(self._face, (values[5] * _U3) >> _U32, where=rows & (d1 == 10), casting="unsafe")

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture, as the single env in that state draws it;
        ``action``: the row's last action (None since its reset)."""
        first = int(self._first[row])
        value = "A" if first == 1 else FACES[int(self._face[row])] if first == 10 else str(first)
        player_sum, dealer_value, ace = (int(part[row]) for part in self._obs)
        return render_blackjack(player_sum, dealer_value, bool(ace), value + SUITS[self._suit[row]])

    def _observe_all(self) -> None:
        raw, ace = self._p_raw, self._p_ace
        np.copyto(self._obs[0], total(ARRAY, raw, ace))
        np.copyto(self._obs[1], self._first)
        np.copyto(self._obs[2], usable_ace(raw, ace))

    def _observe(self, rows: np.ndarray) -> None:
        raw, ace = self._p_raw[rows], self._p_ace[rows]
        self._obs[0][rows] = total(ARRAY, raw, ace)
        self._obs[1][rows] = self._first[rows]
        self._obs[2][rows] = usable_ace(raw, ace)

    def _step_rows(self, rows: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        hit = actions == 1
        hitters, stickers = rows[hit], rows[~hit]
        if len(hitters):
            card = _DECK.take(self._streams.bounded(hitters, 13))
            raw = self._p_raw[hitters] + card
            ace = self._p_ace[hitters] | (card == 1)
            self._p_raw[hitters], self._p_ace[hitters] = raw, ace
            self._p_cards[hitters] += 1
            bust = total(ARRAY, raw, ace) > 21
            self._terminated[hitters] = bust
            self._reward[hitters] = np.where(bust, -1.0, 0.0)
        if len(stickers):
            dealer = self._dealer_plays(stickers)
            player = (self._p_raw[stickers], self._p_ace[stickers], self._p_cards[stickers])
            self._reward[stickers] = settle(ARRAY, player, dealer, self.natural, self.sab)
            self._terminated[stickers] = True
        self._observe(rows)
        return self._reward, self._terminated

    def _dealer_plays(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The dealer hits below 17; returns the final hands of ``rows``. Cards are read a
        few at a time for all rows, then each row keeps the ones it drew: a loop over rounds
        of cards, never over rows."""
        raw, ace, cards = self._d_raw[rows], self._d_ace[rows], self._d_cards[rows]
        pending = np.flatnonzero(total(ARRAY, raw, ace) < 17)  # positions in `rows`
        while len(pending):
            peek = self._streams.peek_bounded(rows[pending], 13, 4)
            drawn = _DECK.take(peek.draws)  # [P, 4]
            r, a = raw[pending], ace[pending]
            taken = np.zeros(len(pending), dtype=np.int64)
            for j in range(4):
                hits = total(ARRAY, r, a) < 17
                if not hits.any():
                    break
                card = np.where(hits, drawn[:, j], 0)
                r, a, taken = r + card, a | (card == 1), taken + hits
            self._streams.consume(peek, peek.values_for(taken))
            raw[pending], ace[pending] = r, a
            cards[pending] += taken
            pending = pending[total(ARRAY, r, a) < 17]
        self._d_raw[rows], self._d_ace[rows], self._d_cards[rows] = raw, ace, cards
        return raw, ace, cards
