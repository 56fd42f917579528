"""Shared-memory details users meet (issue 26), side by side with gymnasium: the OneOf index
read back as ``np.int64``, a non-Space refused with ``TypeError``, and a scalar action for N
envs refused by ``AsyncVectorEnv(shared_memory=True)`` as by Sync and Async without it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import palaestra
from palaestra import spaces
from palaestra.error import CustomSpaceError
from palaestra.vector import AsyncVectorEnv, SyncVectorEnv
from palaestra.vector.utils import (
    create_shared_memory,
    read_from_shared_memory,
    write_to_shared_memory,
)

gymnasium = pytest.importorskip("gymnasium")
gym_utils = pytest.importorskip("gymnasium.vector.utils")
env_checker = pytest.importorskip("gymnasium.utils.env_checker")
to_gym = pytest.importorskip("palaestra.compat").to_gymnasium_space

ONEOF = spaces.OneOf([spaces.Discrete(3), spaces.Box(-1, 1, (2,))])


def test_oneof_read_back_is_data_equivalent_to_what_was_written() -> None:
    n = 4
    memory, theirs_memory = create_shared_memory(ONEOF, n=n), None
    theirs_space = to_gym(ONEOF)
    theirs_memory = gym_utils.create_shared_memory(theirs_space, n=n)
    ONEOF.seed(1)
    samples = [ONEOF.sample() for _ in range(n)]
    for i, sample in enumerate(samples):
        write_to_shared_memory(ONEOF, i, sample, memory)
        gym_utils.write_to_shared_memory(theirs_space, i, sample, theirs_memory)
    ours = read_from_shared_memory(ONEOF, memory, n=n)
    theirs = gym_utils.read_from_shared_memory(theirs_space, theirs_memory, n=n)
    for got, want, sample in zip(ours, theirs, samples):
        assert type(got[0]) is type(want[0]) is np.int64
        assert env_checker.data_equivalence(got, sample, exact=True)
        assert env_checker.data_equivalence(got, want, exact=True)


@pytest.mark.parametrize("value", [None, 3, "Box(0, 1)", gymnasium.spaces.Discrete(2)])
def test_a_value_that_is_no_space_is_a_type_error(value: Any) -> None:
    for theirs, ours in [
        (lambda: gym_utils.create_shared_memory(value, n=2), lambda: create_shared_memory(value)),
        (
            lambda: gym_utils.read_from_shared_memory(value, None, n=2),
            lambda: read_from_shared_memory(value, None, n=2),
        ),
        (
            lambda: gym_utils.write_to_shared_memory(value, 0, 1, None),
            lambda: write_to_shared_memory(value, 0, 1, None),
        ),
    ]:
        if not isinstance(value, gymnasium.spaces.Space):
            with pytest.raises(TypeError):
                theirs()
        with pytest.raises(TypeError, match=r"is not a palaestra Space, got ") as caught:
            ours()
        assert repr(value)[:20] in str(caught.value)
        assert not isinstance(caught.value, CustomSpaceError)


def test_a_custom_space_is_still_a_custom_space_error() -> None:
    class Custom(spaces.Space[Any]):
        pass

    with pytest.raises(CustomSpaceError):
        create_shared_memory(Custom())


def _cartpole() -> Any:
    return palaestra.make("CartPole-v1")


@pytest.mark.parametrize("shared_memory", [True, False])
def test_a_scalar_action_for_four_envs_is_a_type_error(shared_memory: bool) -> None:
    envs = AsyncVectorEnv([_cartpole] * 4, shared_memory=shared_memory, context="fork")
    try:
        envs.reset(seed=0)
        with pytest.raises(TypeError):
            envs.step(0)
        envs.reset(seed=0)  # still usable: nothing was sent
        assert envs.step(np.array([0, 1, 0, 1]))[0].shape == (4, 4)
    finally:
        envs.close()


def test_sync_and_gymnasium_raise_the_same_type_for_a_scalar_action() -> None:
    sync = SyncVectorEnv([_cartpole] * 4)
    sync.reset(seed=0)
    with pytest.raises(TypeError):
        sync.step(0)
    theirs = gymnasium.vector.AsyncVectorEnv(
        [lambda: gymnasium.make("CartPole-v1")] * 4, shared_memory=True, context="fork"
    )
    try:
        theirs.reset(seed=0)
        with pytest.raises(TypeError):
            theirs.step(0)
    finally:
        theirs.close()
