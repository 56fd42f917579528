"""The vector API: ``VectorEnv`` (N envs stepped as one) and the vector wrapper bases.

Semantics are Gymnasium 1.x's ``gymnasium.vector.VectorEnv``: ``reset`` returns a batch of
observations and one info dict, ``step`` a 5-tuple of batches; ``metadata["autoreset_mode"]``
says what happens after an episode ends (see :class:`AutoresetMode`).
"""

from __future__ import annotations

from enum import Enum
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np

from palaestra import logger
from palaestra.core import OwnOrInner
from palaestra.utils.seeding import ForwardedRandom, LazyRandom
from palaestra.utils.seeding import np_random as _make_rng

if TYPE_CHECKING:
    from typing_extensions import Self

    from palaestra.envs.registration import EnvSpec
    from palaestra.spaces import Space

__all__ = [
    "AutoresetMode",
    "VectorActionWrapper",
    "VectorEnv",
    "VectorObservationWrapper",
    "VectorRewardWrapper",
    "VectorWrapper",
]

ObsType = TypeVar("ObsType")
ActType = TypeVar("ActType")
ArrayType = TypeVar("ArrayType")
WrapperObsType = TypeVar("WrapperObsType")
WrapperActType = TypeVar("WrapperActType")

StepReturn = tuple[Any, Any, Any, Any, dict[str, Any]]


class AutoresetMode(Enum):
    """When a finished sub-env is reset (Gymnasium's values, so the two compare by value).

    NEXT_STEP: the step after the one that ended the episode resets it (reward 0, not done).
    SAME_STEP: it is reset at once; the last obs/info go to ``info["final_obs"/"final_info"]``.
    DISABLED: never; the caller resets it with ``reset(options={"reset_mask": mask})``.
    """

    NEXT_STEP = "NextStep"
    SAME_STEP = "SameStep"
    DISABLED = "Disabled"


class VectorEnv(LazyRandom, Generic[ObsType, ActType, ArrayType]):
    """Base of all vector environments: ``num_envs`` copies stepped with batched actions.

    Subclasses set ``num_envs``, the single and batched spaces and ``metadata`` (with an
    ``autoreset_mode``), and implement ``reset``/``step``.
    """

    metadata: dict[str, Any] = {}
    spec: EnvSpec | None = None
    render_mode: str | None = None
    closed: bool = False

    observation_space: Space[Any]
    action_space: Space[Any]
    single_observation_space: Space[Any]
    single_action_space: Space[Any]
    num_envs: int

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset every sub-env (or those in ``options["reset_mask"]``): ``(obs, infos)``."""
        if isinstance(seed, (int, np.integer)):
            self._np_random, self._np_random_seed = _make_rng(int(seed))
        return None  # type: ignore[return-value]  # subclasses return (obs, infos)

    def step(self, actions: ActType) -> StepReturn:
        """Step every sub-env: ``(obs, rewards, terminations, truncations, infos)``."""
        raise NotImplementedError(f"{self} step function is not implemented.")

    def render(self) -> tuple[Any, ...] | None:
        """The sub-envs' frames."""
        raise NotImplementedError(f"{self} render function is not implemented.")

    def close(self, **kwargs: Any) -> None:
        """Release the sub-envs (and worker processes); calling it twice is harmless."""
        if self.closed:
            return
        self.close_extras(**kwargs)
        self.closed = True

    def close_extras(self, **kwargs: Any) -> None:
        """What ``close`` releases; subclasses override it."""

    @property
    def unwrapped(self) -> Self:
        """The vector env below every vector wrapper."""
        return self

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *args: object) -> None:
        self.close()

    def __del__(self) -> None:
        # Worker processes and shared memory must not outlive a forgotten vector env.
        if not getattr(self, "closed", True):
            try:
                self.close()
            except Exception:  # interpreter shutdown: modules may already be gone
                pass

    def __repr__(self) -> str:
        num_envs = getattr(self, "num_envs", "?")
        if self.spec is None:
            return f"{type(self).__name__}(num_envs={num_envs})"
        return f"{type(self).__name__}({self.spec.id}, num_envs={num_envs})"


class VectorWrapper(ForwardedRandom, VectorEnv[WrapperObsType, WrapperActType, ArrayType]):
    """Base of vector wrappers: every call goes to ``self.env`` unless overridden.

    Spaces and metadata fall through to the inner env until the wrapper assigns its own.
    """

    def __init__(self, env: VectorEnv[Any, Any, Any]) -> None:
        if not isinstance(env, VectorEnv):
            raise TypeError(
                f"Expected env to be a `palaestra.vector.VectorEnv` but got {type(env)}"
            )
        self.env = env
        self._observation_space: Space[Any] | None = None
        self._action_space: Space[Any] | None = None
        self._single_observation_space: Space[Any] | None = None
        self._single_action_space: Space[Any] | None = None
        self._metadata: dict[str, Any] | None = None

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[WrapperObsType, dict[str, Any]]:
        """Reset the inner vector env."""
        return self.env.reset(seed=seed, options=options)

    def step(self, actions: WrapperActType) -> StepReturn:
        """Step the inner vector env."""
        return self.env.step(actions)

    def render(self) -> tuple[Any, ...] | None:
        """Render the inner vector env."""
        return self.env.render()

    def close(self, **kwargs: Any) -> None:
        """Close the inner vector env."""
        self.env.close(**kwargs)

    def close_extras(self, **kwargs: Any) -> None:
        """Close the inner vector env's extras."""
        self.env.close_extras(**kwargs)

    def __del__(self) -> None:
        pass  # the inner env closes itself

    @property
    def unwrapped(self) -> VectorEnv[Any, Any, Any]:  # type: ignore[override]
        """The innermost vector env."""
        return self.env.unwrapped

    def __repr__(self) -> str:
        return f"<{type(self).__name__}, {self.env}>"

    observation_space: OwnOrInner[Space[Any]] = OwnOrInner(
        "The wrapper's batched observation space, or the inner one."
    )
    action_space: OwnOrInner[Space[Any]] = OwnOrInner(
        "The wrapper's batched action space, or the inner one."
    )
    single_observation_space: OwnOrInner[Space[Any]] = OwnOrInner(
        "The wrapper's per-env observation space, or the inner one."
    )
    single_action_space: OwnOrInner[Space[Any]] = OwnOrInner(
        "The wrapper's per-env action space, or the inner one."
    )

    @property
    def num_envs(self) -> int:  # type: ignore[override]
        """The inner env's number of sub-envs."""
        return self.env.num_envs

    metadata: OwnOrInner[dict[str, Any]] = OwnOrInner("The wrapper's metadata, or the inner one.")

    @property
    def spec(self) -> EnvSpec | None:  # type: ignore[override]
        """The inner env's spec."""
        return self.env.spec

    @property
    def render_mode(self) -> str | None:  # type: ignore[override]
        """The inner env's render mode."""
        return self.env.render_mode

    @property
    def closed(self) -> bool:
        """Whether the inner env is closed."""
        return self.env.closed

    @closed.setter
    def closed(self, value: bool) -> None:
        self.env.closed = value


class VectorObservationWrapper(VectorWrapper[WrapperObsType, ActType, ArrayType]):
    """Transforms batched observations: override :meth:`observations`.

    Only for NEXT_STEP/DISABLED envs: under SAME_STEP the final observations in the infos would
    escape the transform (Gymnasium refuses this too).
    """

    def __init__(self, env: VectorEnv[Any, Any, Any]) -> None:
        super().__init__(env)
        mode = env.metadata.get("autoreset_mode")
        if mode is None:
            logger.warn(f"Vector environment ({env}) is missing `autoreset_mode` metadata key.")
        elif mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.DISABLED):
            raise ValueError(f"Expected autoreset_mode to be NEXT_STEP or DISABLED, got {mode}")

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[WrapperObsType, dict[str, Any]]:
        """Reset and transform the first observations."""
        obs, infos = self.env.reset(seed=seed, options=options)
        return self.observations(obs), infos

    def step(self, actions: ActType) -> StepReturn:
        """Step and transform the observations."""
        obs, rewards, terminations, truncations, infos = self.env.step(actions)
        return self.observations(obs), rewards, terminations, truncations, infos

    def observations(self, observations: Any) -> WrapperObsType:
        """Return the transformed batch of observations."""
        raise NotImplementedError


class VectorActionWrapper(VectorWrapper[ObsType, WrapperActType, ArrayType]):
    """Transforms batched actions before they reach the env: override :meth:`actions`."""

    def step(self, actions: WrapperActType) -> StepReturn:
        """Transform the actions and step."""
        return self.env.step(self.actions(actions))

    def actions(self, actions: WrapperActType) -> Any:
        """Return the batch of actions for the inner env."""
        raise NotImplementedError


class VectorRewardWrapper(VectorWrapper[ObsType, ActType, ArrayType]):
    """Transforms batched rewards: override :meth:`rewards`."""

    def step(self, actions: ActType) -> StepReturn:
        """Step and transform the rewards."""
        obs, rewards, terminations, truncations, infos = self.env.step(actions)
        return obs, self.rewards(rewards), terminations, truncations, infos

    def rewards(self, rewards: Any) -> Any:
        """Return the transformed batch of rewards."""
        raise NotImplementedError
