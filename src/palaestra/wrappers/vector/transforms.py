"""Vector transform wrappers: batch functions (``Transform*``) and single-env wrappers applied
per sub-env (``VectorizeTransform*``), plus ``ClipReward``."""

from __future__ import annotations

from collections.abc import Callable
from copy import deepcopy
from typing import Any

import numpy as np

from palaestra import logger
from palaestra.core import Env
from palaestra.spaces import Space
from palaestra.spaces.batched_samples import concatenate, create_empty_array, iterate
from palaestra.spaces.batching import batch_space
from palaestra.vector.vector_env import (
    VectorActionWrapper,
    VectorEnv,
    VectorObservationWrapper,
    VectorRewardWrapper,
)
from palaestra.wrappers.transform_reward import ClipReward as SingleClip


def _warn_if_unbatched(env: Any, kind: str, space: Space[Any], single: Space[Any]) -> None:
    """Gymnasium's warning when a ``Transform*`` wrapper's batched space is not its single
    space batched (the two given disagree, or only one was given and the other is the env's)."""
    batched = batch_space(single, env.num_envs)
    if space != batched:
        logger.warn(
            f"For {env}, the {kind} space and the batched single {kind} space don't match as "
            f"expected, {kind}_space={space}, batched single_{kind}_space={batched}"
        )


class TransformObservation(VectorObservationWrapper[Any, Any, np.ndarray]):
    """``func(batch_of_observations)``; give the new batched and/or single observation space."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        func: Callable[[Any], Any],
        observation_space: Space[Any] | None = None,
        single_observation_space: Space[Any] | None = None,
    ) -> None:
        super().__init__(env)
        if single_observation_space is not None:
            self.single_observation_space = single_observation_space
        if observation_space is not None:
            self.observation_space = observation_space
        elif single_observation_space is not None:
            self.observation_space = batch_space(single_observation_space, self.num_envs)
        _warn_if_unbatched(
            env, "observation", self.observation_space, self.single_observation_space
        )
        self.func = func

    def observations(self, observations: Any) -> Any:
        """``func(observations)``."""
        return self.func(observations)


class _SpaceEnv(Env[Any, Any]):
    """A stand-in env that only has spaces, to build a single-env wrapper on."""

    def __init__(self, observation_space: Space[Any] | None, action_space: Space[Any] | None):
        if observation_space is not None:
            self.observation_space = observation_space
        if action_space is not None:
            self.action_space = action_space


class VectorizeTransformObservation(VectorObservationWrapper[Any, Any, np.ndarray]):
    """Apply a single-env observation wrapper (``wrapper(env, **kwargs)``) to each sub-env's obs."""

    def __init__(self, env: VectorEnv[Any, Any, Any], wrapper: type, **kwargs: Any) -> None:
        super().__init__(env)
        self.wrapper = wrapper(_SpaceEnv(env.single_observation_space, None), **kwargs)
        self.single_observation_space = self.wrapper.observation_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.same_out = self.observation_space == env.observation_space
        self.out = create_empty_array(self.single_observation_space, self.num_envs)

    def observations(self, observations: Any) -> Any:
        """Each sub-env's observation through the single-env wrapper."""
        items = tuple(
            self.wrapper.observation(obs)
            for obs in iterate(self.env.observation_space, observations)
        )
        if self.same_out:
            return concatenate(self.single_observation_space, items, observations)
        return deepcopy(concatenate(self.single_observation_space, items, self.out))


class TransformAction(VectorActionWrapper[Any, Any, np.ndarray]):
    """``func(batch_of_actions)`` before the inner env sees it."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        func: Callable[[Any], Any],
        action_space: Space[Any] | None = None,
        single_action_space: Space[Any] | None = None,
    ) -> None:
        super().__init__(env)
        if single_action_space is not None:
            self.single_action_space = single_action_space
        if action_space is not None:
            self.action_space = action_space
        elif single_action_space is not None:
            self.action_space = batch_space(single_action_space, self.num_envs)
        _warn_if_unbatched(env, "action", self.action_space, self.single_action_space)
        self.func = func

    def actions(self, actions: Any) -> Any:
        """``func(actions)``."""
        return self.func(actions)


class VectorizeTransformAction(VectorActionWrapper[Any, Any, np.ndarray]):
    """Apply a single-env action wrapper (``wrapper(env, **kwargs)``) to each sub-env's action."""

    def __init__(self, env: VectorEnv[Any, Any, Any], wrapper: type, **kwargs: Any) -> None:
        super().__init__(env)
        self.wrapper = wrapper(_SpaceEnv(None, env.single_action_space), **kwargs)
        self.single_action_space = self.wrapper.action_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.same_out = self.action_space == env.action_space
        self.out = create_empty_array(env.single_action_space, self.num_envs)

    def actions(self, actions: Any) -> Any:
        """Each sub-env's action through the single-env wrapper."""
        items = tuple(self.wrapper.action(a) for a in iterate(self.action_space, actions))
        return deepcopy(concatenate(self.env.single_action_space, items, self.out))


class TransformReward(VectorRewardWrapper[Any, Any, np.ndarray]):
    """``func(batch_of_rewards)``."""

    def __init__(self, env: VectorEnv[Any, Any, Any], func: Callable[[Any], Any]) -> None:
        super().__init__(env)
        self.func = func

    def rewards(self, rewards: Any) -> Any:
        """``func(rewards)``."""
        return self.func(rewards)


class VectorizeTransformReward(VectorRewardWrapper[Any, Any, np.ndarray]):
    """Apply a single-env reward wrapper's function to each sub-env's reward."""

    def __init__(self, env: VectorEnv[Any, Any, Any], wrapper: type, **kwargs: Any) -> None:
        super().__init__(env)
        self.wrapper = wrapper(Env(), **kwargs)

    def rewards(self, rewards: Any) -> Any:
        """Each reward through the single-env wrapper's ``func``."""
        for i, r in enumerate(rewards):
            rewards[i] = self.wrapper.func(r)
        return rewards


class ClipReward(VectorRewardWrapper[Any, Any, np.ndarray]):
    """Clip rewards into ``[min_reward, max_reward]`` (one array op; either bound may be None)."""

    def __init__(
        self,
        env: VectorEnv[Any, Any, Any],
        min_reward: float | np.ndarray | None = None,
        max_reward: float | np.ndarray | None = None,
    ) -> None:
        super().__init__(env)
        SingleClip(Env(), min_reward=min_reward, max_reward=max_reward)  # same bound checks
        self.min_reward, self.max_reward = min_reward, max_reward

    def rewards(self, rewards: Any) -> Any:
        """Clipped rewards."""
        return np.clip(rewards, self.min_reward, self.max_reward)
