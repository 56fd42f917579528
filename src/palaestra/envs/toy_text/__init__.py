"""The toy-text environments: FrozenLake, CliffWalking, Taxi, Blackjack; one engine, two faces.

FrozenLake, CliffWalking and Taxi are tabular: their transition table
(:class:`~.tabular.TransitionTable`, built from Gymnasium's ``P``) is the engine, read as
Python tuples by the single env and as arrays by the batch. Blackjack's rules are written once
over the classic-control ``ops`` namespace. Every batch (``*Batch``) draws row i's numbers from
its own generator, so row i equals a single env seeded ``seed + i``.

>>> from palaestra.envs.toy_text import FrozenLakeBatch, FrozenLakeEnv
>>> batch = FrozenLakeBatch(3)
>>> batch.reset(seed=42).tolist()
[0, 0, 0]
>>> obs, reward, terminated = batch.step([2, 2, 1])
>>> env = FrozenLakeEnv()
>>> _ = env.reset(seed=43)
>>> env.step(2)[0] == int(obs[1])  # row i behaves like a single env seeded 42 + i
True
"""

from palaestra.envs.toy_text.blackjack import BlackjackBatch, BlackjackEnv
from palaestra.envs.toy_text.cliffwalking import CliffWalkingBatch, CliffWalkingEnv
from palaestra.envs.toy_text.frozen_lake import FrozenLakeBatch, FrozenLakeEnv, generate_random_map
from palaestra.envs.toy_text.taxi import TaxiBatch, TaxiEnv

__all__ = [
    "BlackjackBatch",
    "BlackjackEnv",
    "CliffWalkingBatch",
    "CliffWalkingEnv",
    "FrozenLakeBatch",
    "FrozenLakeEnv",
    "TaxiBatch",
    "TaxiEnv",
    "generate_random_map",
]
