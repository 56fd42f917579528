"""The environment API: ``Env`` and the wrapper base classes (Gymnasium 1.x semantics).

A wrapper forwards nothing implicitly: there is no ``__getattr__``. Attributes of inner layers
are reached with :meth:`Env.get_wrapper_attr` or through :attr:`Env.unwrapped`, as in
Gymnasium 1.x.
"""

from __future__ import annotations

from copy import deepcopy
from typing import TYPE_CHECKING, Any, Generic, Literal, SupportsFloat, TypeVar, overload

import numpy as np

from palaestra import logger
from palaestra.env_spec import EnvSpec, WrapperSpec
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.utils.seeding import ForwardedRandom, LazyRandom
from palaestra.utils.seeding import np_random as _make_rng

if TYPE_CHECKING:
    from typing_extensions import Self

    from palaestra.spaces import Space

ObsType = TypeVar("ObsType")
ActType = TypeVar("ActType")
WrapperObsType = TypeVar("WrapperObsType")
WrapperActType = TypeVar("WrapperActType")
T = TypeVar("T")

RenderFrame = Any  # np.ndarray frame, ANSI string, or a list of either


class Env(LazyRandom, Generic[ObsType, ActType]):
    """An environment: ``reset`` starts an episode, ``step`` advances it by one action.

    Subclasses set ``action_space``, ``observation_space`` and ``metadata``, and call
    ``super().reset(seed=seed)`` first in their ``reset`` so that ``np_random`` is reseeded.

    >>> class Coin(Env):
    ...     def __init__(self):
    ...         from palaestra.spaces import Discrete
    ...         self.observation_space = self.action_space = Discrete(2)
    ...     def reset(self, *, seed=None, options=None):
    ...         super().reset(seed=seed)
    ...         return int(self.np_random.integers(2)), {}
    ...     def step(self, action):
    ...         return int(self.np_random.integers(2)), 1.0, True, False, {}
    >>> env = Coin()
    >>> env.reset(seed=0)
    (1, {})
    >>> env.np_random_seed
    0
    >>> print(env)
    <Coin instance>
    """

    metadata: dict[str, Any] = {"render_modes": []}
    render_mode: str | None = None
    spec: EnvSpec | None = None

    action_space: Space[ActType]
    observation_space: Space[ObsType]

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Advance one step: ``(observation, reward, terminated, truncated, info)``."""
        raise NotImplementedError

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Start an episode; an integer ``seed`` reseeds ``np_random``, ``None`` keeps it."""
        if seed is not None:
            self._np_random, self._np_random_seed = _make_rng(seed)
        return None  # type: ignore[return-value]  # subclasses return (obs, info)

    def render(self) -> RenderFrame | None:
        """Render the current state as chosen by ``render_mode`` at construction."""
        raise NotImplementedError

    def close(self) -> None:
        """Release resources (windows, processes); calling it twice is harmless."""

    @property
    def unwrapped(self) -> Env[ObsType, ActType]:
        """The innermost environment, below every wrapper."""
        return self

    def has_wrapper_attr(self, name: str) -> bool:
        """Whether ``name`` exists on this environment."""
        return hasattr(self, name)

    def get_wrapper_attr(self, name: str) -> Any:
        """Return attribute ``name`` of this environment."""
        return getattr(self, name)

    def set_wrapper_attr(self, name: str, value: Any, *, force: bool = True) -> bool:
        """Set ``name`` to ``value`` if it exists here, or unconditionally when ``force``."""
        if force or hasattr(self, name):
            setattr(self, name, value)
            return True
        return False

    def __str__(self) -> str:
        if self.spec is None:
            return f"<{type(self).__name__} instance>"
        return f"<{type(self).__name__}<{self.spec.id}>>"

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *args: object) -> Literal[False]:
        self.close()
        return False


class OwnOrInner(Generic[T]):
    """A wrapper attribute that reads as the inner env's (``self.env``) until the wrapper
    assigns its own, which is kept in ``_<name>`` (``None``: not assigned).

    The wrapper bases (single and vector) declare their spaces and metadata with it.
    """

    def __init__(self, doc: str) -> None:
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name, self.own = name, "_" + name

    @overload
    def __get__(self, obj: None, objtype: type | None = None) -> Self: ...

    @overload
    def __get__(self, obj: object, objtype: type | None = None) -> T: ...

    def __get__(self, obj: object | None, objtype: type | None = None) -> T | Self:
        if obj is None:
            return self
        own = getattr(obj, self.own)
        return getattr(obj.env, self.name) if own is None else own  # type: ignore[attr-defined]

    def __set__(self, obj: object, value: T) -> None:
        setattr(obj, self.own, value)


class Wrapper(
    ForwardedRandom,
    Env[WrapperObsType, WrapperActType],
    Generic[WrapperObsType, WrapperActType, ObsType, ActType],
):
    """Base of all wrappers: by default every call goes straight to ``self.env``.

    Spaces and metadata fall through to the inner env until the wrapper assigns its own.
    """

    def __init__(self, env: Env[ObsType, ActType]) -> None:
        if not isinstance(env, Env):
            raise TypeError(f"Expected env to be a `palaestra.Env` but got {type(env)}")
        self.env = env
        self._action_space: Space[Any] | None = None
        self._observation_space: Space[Any] | None = None
        self._metadata: dict[str, Any] | None = None
        self._cached_spec: EnvSpec | None = None

    def step(
        self, action: WrapperActType
    ) -> tuple[WrapperObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner environment."""
        return self.env.step(action)  # type: ignore[arg-type,return-value]

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[WrapperObsType, dict[str, Any]]:
        """Reset the inner environment."""
        return self.env.reset(seed=seed, options=options)  # type: ignore[return-value]

    def render(self) -> RenderFrame | None:
        """Render the inner environment."""
        return self.env.render()

    def close(self) -> None:
        """Close the inner environment."""
        return self.env.close()

    @property
    def unwrapped(self) -> Env[Any, Any]:
        """The innermost environment."""
        return self.env.unwrapped

    action_space: OwnOrInner[Space[Any]] = OwnOrInner(
        "The wrapper's action space, or the inner one if the wrapper set none."
    )
    observation_space: OwnOrInner[Space[Any]] = OwnOrInner(
        "The wrapper's observation space, or the inner one if the wrapper set none."
    )
    metadata: OwnOrInner[dict[str, Any]] = OwnOrInner(
        "The wrapper's metadata, or the inner one if the wrapper set none."
    )

    @property
    def render_mode(self) -> str | None:  # type: ignore[override]
        """The inner environment's render mode."""
        return self.env.render_mode

    @property
    def _np_random(self) -> np.random.Generator:  # type: ignore[override]
        raise AttributeError(
            "Can't access `_np_random` of a wrapper, use `.unwrapped._np_random` or `.np_random`."
        )

    @property
    def spec(self) -> EnvSpec | None:  # type: ignore[override]
        """The inner spec plus this wrapper, so that ``make(env.spec)`` rebuilds the stack."""
        if self._cached_spec is not None:
            return self._cached_spec
        env_spec = self.env.spec
        if env_spec is not None:
            if isinstance(self, RecordConstructorArgs):
                kwargs: dict[str, Any] | None = {
                    k: v for k, v in self._saved_kwargs.items() if k != "env"
                }
            else:
                kwargs = None  # make() will refuse to rebuild it, saying why
            try:
                env_spec = deepcopy(env_spec)
                env_spec.additional_wrappers += (self.wrapper_spec_with(kwargs),)
            except Exception as e:  # a kwarg that cannot be copied: spec is unknown, not wrong
                logger.warn(
                    f"An exception occurred ({e}) while copying the environment spec={env_spec}"
                )
                return None
        self._cached_spec = env_spec
        return env_spec

    @classmethod
    def wrapper_spec(cls, **kwargs: Any) -> WrapperSpec:
        """The ``WrapperSpec`` describing this wrapper class with ``kwargs``."""
        return cls.wrapper_spec_with(kwargs)

    @classmethod
    def wrapper_spec_with(cls, kwargs: dict[str, Any] | None) -> WrapperSpec:
        """Like :meth:`wrapper_spec`, with ``None`` meaning "arguments unknown"."""
        return WrapperSpec(
            name=cls.class_name(), entry_point=f"{cls.__module__}:{cls.__name__}", kwargs=kwargs
        )

    @classmethod
    def class_name(cls) -> str:
        """The wrapper's class name."""
        return cls.__name__

    def has_wrapper_attr(self, name: str) -> bool:
        """Whether ``name`` exists on this wrapper or any inner layer."""
        return hasattr(self, name) or self.env.has_wrapper_attr(name)

    def get_wrapper_attr(self, name: str) -> Any:
        """Return ``name`` from the outermost layer that has it."""
        if hasattr(self, name):
            return getattr(self, name)
        try:
            return self.env.get_wrapper_attr(name)
        except AttributeError as e:
            raise AttributeError(f"wrapper {self.class_name()} has no attribute {name!r}") from e

    def set_wrapper_attr(self, name: str, value: Any, *, force: bool = True) -> bool:
        """Set ``name`` on the outermost layer that has it; with ``force``, here if none does."""
        if hasattr(self, name):
            setattr(self, name, value)
            return True
        if self.env.set_wrapper_attr(name, value, force=False):
            return True
        if force:
            setattr(self, name, value)
            return True
        return False

    def __str__(self) -> str:
        return f"<{type(self).__name__}{self.env}>"

    def __repr__(self) -> str:
        return str(self)


class ObservationWrapper(Wrapper[WrapperObsType, ActType, ObsType, ActType]):
    """A wrapper that changes observations: override :meth:`observation`.

    >>> from palaestra.spaces import Discrete
    >>> class Doubled(ObservationWrapper):
    ...     def observation(self, observation):
    ...         return 2 * observation
    """

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[WrapperObsType, dict[str, Any]]:
        """Reset the inner env and transform its first observation."""
        obs, info = self.env.reset(seed=seed, options=options)
        return self.observation(obs), info

    def step(
        self, action: ActType
    ) -> tuple[WrapperObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and transform the observation."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        return self.observation(obs), reward, terminated, truncated, info

    def observation(self, observation: ObsType) -> WrapperObsType:
        """Return the transformed observation."""
        raise NotImplementedError


class RewardWrapper(Wrapper[ObsType, ActType, ObsType, ActType]):
    """A wrapper that changes rewards: override :meth:`reward`."""

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the inner env and transform the reward."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, self.reward(reward), terminated, truncated, info

    def reward(self, reward: SupportsFloat) -> SupportsFloat:
        """Return the transformed reward."""
        raise NotImplementedError


class ActionWrapper(Wrapper[ObsType, WrapperActType, ObsType, ActType]):
    """A wrapper that changes actions before they reach the env: override :meth:`action`."""

    def step(
        self, action: WrapperActType
    ) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Transform the action and step the inner env."""
        return self.env.step(self.action(action))

    def action(self, action: WrapperActType) -> ActType:
        """Return the action to pass to the inner env."""
        raise NotImplementedError
