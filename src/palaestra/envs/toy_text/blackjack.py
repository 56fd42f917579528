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
from palaestra.envs.classic_control._common import check_discrete_action
from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.toy_text._common import ToyTextBatch, ToyTextEnv
from palaestra.envs.toy_text._streams import HalfWordStreams
from palaestra.spaces import Discrete, Tuple

DECK = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 10, 10, 10)  # ace, 2-10, jack, queen, king
_DECK = np.array(DECK, dtype=np.int64)
_U3, _U4, _U32 = np.uint64(3), np.uint64(4), np.uint64(32)
_LOW32 = np.uint64(0xFFFFFFFF)
SUITS = ("C", "D", "H", "S")
FACES = ("J", "Q", "K")


def total(ops: Any, raw: Any, ace: Any) -> Any:
    """A hand's value: an ace counts 11 when that does not bust it."""
    return ops.where(ace & (raw + 10 <= 21), raw + 10, raw)


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
        from palaestra.rendering.toy_text import render_blackjack

        if not self.player:
            raise error.ResetNeeded("Call reset before render.")
        player_sum, dealer_value, ace = self._obs()
        card = self.dealer_top_card_value_str + self.dealer_top_card_suit
        return render_blackjack(player_sum, dealer_value, bool(ace), card)


class BlackjackBatch(ToyTextBatch):
    """N Blackjack tables as arrays; the dealer's draws loop over rounds, never over rows."""

    streams_class = HalfWordStreams  # cards, suits and faces: 32-bit draws only

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
