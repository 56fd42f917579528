"""The toy-text ids, the kwargs variants the parity tests cover, and their action rules.

Random play never delivers a Taxi passenger nor reaches CliffWalking's goal, so the tabular
rules are epsilon-greedy on the optimal Q of the env's own ``P`` (value iteration): episodes
then end in every way (goal, hole, cliff, delivery, time limit), and the fickle passenger's
destination change happens.
"""

from __future__ import annotations

from typing import Any

import numpy as np

TOY_TEXT_IDS = [
    "Blackjack-v1",
    "CliffWalking-v1",
    "CliffWalkingSlippery-v1",
    "FrozenLake-v1",
    "FrozenLake8x8-v1",
    "Taxi-v4",
]

RANDOM_MAP = [
    "SHFFFFFF",
    "FHFFFHHH",
    "FFFFFFHF",
    "FHFHHFHF",
    "FFFFHFFF",
    "FHFFHFFF",
    "FHFHFHFH",
    "FFHFFFFG",
]

# (id, kwargs): every kwargs variant that Gymnasium 1.4 has.
VARIANTS: list[tuple[str, dict[str, Any]]] = [
    ("FrozenLake-v1", {}),
    ("FrozenLake-v1", {"is_slippery": False}),
    ("FrozenLake-v1", {"success_rate": 0.75, "reward_schedule": (5, -2, -0.1)}),
    ("FrozenLake-v1", {"desc": ["SFFH", "FSHF", "FFFG"], "success_rate": 0.0}),
    # generate_random_map(8, 0.7, seed=5), the same from both libraries (test_frozen_lake.py)
    ("FrozenLake-v1", {"desc": RANDOM_MAP}),
    ("FrozenLake8x8-v1", {}),
    ("CliffWalking-v1", {}),
    ("CliffWalkingSlippery-v1", {}),
    ("Taxi-v4", {}),
    ("Taxi-v4", {"is_rainy": True}),
    ("Taxi-v4", {"fickle_passenger": True, "fickle_probability": 0.9}),
    ("Taxi-v4", {"is_rainy": True, "rainy_probability": 0.6, "fickle_passenger": True}),
    ("Blackjack-v1", {}),
    ("Blackjack-v1", {"sab": False}),
    ("Blackjack-v1", {"sab": False, "natural": True}),
]


def variant_id(case: tuple[str, dict[str, Any]]) -> str:
    env_id, kwargs = case
    return env_id + "".join(f"-{k}={v}" for k, v in kwargs.items())


def optimal_q(P: dict[int, dict[int, list[tuple[float, int, Any, bool]]]]) -> np.ndarray:
    """Q* of a tabular env's ``P`` (gamma 0.95, 200 sweeps of value iteration): ``[S, A]``."""
    n_s, n_a = len(P), len(P[0])
    k = max(len(P[s][a]) for s in P for a in P[s])
    prob, nxt, rew, term = (np.zeros((n_s, n_a, k)) for _ in range(4))
    for s in P:
        for a in P[s]:
            for j, (p, ns, r, t) in enumerate(P[s][a]):
                prob[s, a, j], nxt[s, a, j], rew[s, a, j], term[s, a, j] = p, ns, r, t
    nxt_i = nxt.astype(np.int64)
    v = np.zeros(n_s)
    for _ in range(200):
        q = (prob * (rew + 0.95 * (1 - term) * v[nxt_i])).sum(axis=2)
        v = q.max(axis=1)
    return q


_GREEDY: dict[str, np.ndarray] = {}


def _greedy(P: Any) -> np.ndarray:
    """argmax Q*, cached by the table's text (many envs of one variant share it)."""
    key = str(P)
    if key not in _GREEDY:
        _GREEDY[key] = optimal_q(P).argmax(axis=1)
    return _GREEDY[key]


class Policy:
    """Epsilon-greedy on Q* for tabular envs, a threshold rule with noise for Blackjack."""

    def __init__(self, env: Any, seed: int, epsilon: float = 0.3) -> None:
        self.rng = np.random.default_rng(seed)
        self.epsilon = epsilon
        self.n = int(env.action_space.n)
        P = getattr(env.unwrapped, "P", None)
        self.greedy = None if P is None else _greedy(P)

    def __call__(self, obs: Any) -> int:
        if self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.n))
        if self.greedy is None:  # Blackjack: hit below 17
            return int(obs[0] < 17)
        return int(self.greedy[int(obs)])
