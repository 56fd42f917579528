"""Register toy ids in both palaestra's and gymnasium's registries, and remove them after."""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium
import pytest

import palaestra.envs.registration as registration

# Namespaced so that "Did you mean" candidates are the same in both registries.
TOY_IDS = (
    "PalTest/Toy-v0",
    "PalTest/Toy-v1",
    "PalTest/Toy-v3",
    "PalTest/Plain",
    "PalTest/Solo-v2",
    "Zyxwvut-v0",
    "Zyxwvut-v1",
)


@pytest.fixture
def toy_ids() -> Iterator[tuple[str, ...]]:
    """The ids above, registered in both libraries for the duration of one test.

    Entry points are strings so that the specs serialise to JSON.
    """
    for env_id in TOY_IDS:
        kwargs = {"max_episode_steps": 5} if env_id == "PalTest/Toy-v3" else {}
        registration.register(env_id, entry_point="tests.registry.toys:PalToy", **kwargs)
        gymnasium.register(env_id, entry_point="tests.registry.toys:GymToy", **kwargs)
    yield TOY_IDS
    for env_id in TOY_IDS:
        registration.registry.pop(env_id, None)
        gymnasium.registry.pop(env_id, None)


@pytest.fixture
def clean_registry() -> Iterator[None]:
    """Undo whatever a test registers in palaestra's registry."""
    before = dict(registration.registry)
    yield
    registration.registry.clear()
    registration.registry.update(before)
