"""Random number generators seeded the way Gymnasium seeds them (PCG64 on a SeedSequence)."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import error

RNG = RandomNumberGenerator = np.random.Generator


def np_random(seed: int | None = None) -> tuple[np.random.Generator, int]:
    """Return a generator and the seed it came from; ``seed=None`` draws fresh entropy.

    The same integer seed gives the same stream as ``gymnasium.utils.seeding.np_random``.

    >>> rng, seed = np_random(42)
    >>> seed, int(rng.integers(100))
    (42, 8)
    """
    # bool is an int subclass, but seeding with True is almost always a bug; Gymnasium accepts
    # it, and so do we, to draw the same streams.
    if seed is not None and not (isinstance(seed, int) and seed >= 0):
        if not isinstance(seed, int):
            raise error.Error(f"Seed must be a python integer, actual type: {type(seed)}")
        raise error.Error(f"Seed must be greater or equal to zero, actual value: {seed}")
    seed_seq = np.random.SeedSequence(seed)
    return np.random.Generator(np.random.PCG64(seed_seq)), int(seed_seq.entropy)  # type: ignore[arg-type]


# Gymnasium's message for a list of seeds of the wrong length
_WRONG_LENGTH = (
    "If seeds are passed as a list the length must match num_envs={num_envs} but got "
    "length={length}."
)


def row_seeds(seed: Any, num_envs: int, wrong_length: str = _WRONG_LENGTH) -> list[int | None]:
    """One seed per row: None, an int ``s`` (row i gets ``s + i``), or a list of N seeds.

    A list of another length raises ``ValueError(wrong_length)``, formatted with ``num_envs``
    and ``length``.
    """
    if seed is None:
        return [None] * num_envs
    if isinstance(seed, (int, np.integer)):
        return [int(seed) + i for i in range(num_envs)]
    seeds = list(seed)
    if len(seeds) != num_envs:
        raise ValueError(wrong_length.format(num_envs=num_envs, length=len(seeds)))
    return seeds


class LazyRandom:
    """``np_random`` / ``np_random_seed`` created from fresh entropy on first use.

    Shared by :class:`palaestra.Env` and :class:`palaestra.vector.VectorEnv`; ``reset(seed=...)``
    assigns ``_np_random`` and ``_np_random_seed`` directly.
    """

    _np_random: np.random.Generator | None = None
    _np_random_seed: int | None = None

    @property
    def np_random(self) -> np.random.Generator:
        """The generator, created from fresh entropy on first use."""
        if self._np_random is None:
            self._np_random, self._np_random_seed = np_random()
        return self._np_random

    @np_random.setter
    def np_random(self, value: np.random.Generator) -> None:
        self._np_random = value
        # A generator does not reveal its seed; -1 says "unknown" (Gymnasium's convention).
        self._np_random_seed = -1

    @property
    def np_random_seed(self) -> int:
        """The seed behind ``np_random`` (-1 if a generator was assigned directly)."""
        if self._np_random_seed is None:
            self._np_random, self._np_random_seed = np_random()
        return self._np_random_seed


class ForwardedRandom:
    """``np_random`` / ``np_random_seed`` of the env this one wraps (the attribute named by
    ``_wrapped_attr``).

    Shared by the wrapper bases and the compat adapters: a stack has one generator, the
    innermost env's, so code that reads or replaces it at any layer sees the stream the env
    actually draws from.
    """

    _wrapped_attr: str = "env"

    @property
    def np_random(self) -> np.random.Generator:
        """The wrapped env's generator."""
        return getattr(self, self._wrapped_attr).np_random

    @np_random.setter
    def np_random(self, value: np.random.Generator) -> None:
        getattr(self, self._wrapped_attr).np_random = value

    @property
    def np_random_seed(self) -> int:
        """The wrapped env's seed."""
        return getattr(self, self._wrapped_attr).np_random_seed
