"""The three wrappers ``make()`` applies: ``PassiveEnvChecker``, ``OrderEnforcing``, ``TimeLimit``.

They sit on every step of every ``make()``'d env, so their per-step cost is kept near zero:
once a wrapper has nothing left to do on ``step`` it stores the inner env's ``step`` on its
instance (``self.step = self.env.step``), and calls skip it. ``PassiveEnvChecker`` does so after
checking two steps; ``OrderEnforcing`` after the first step (past ``reset``) during which the
inner ``step`` did not rebind itself, so it never keeps a checking path alive. ``TimeLimit``
counts every step and stays: a made env costs one wrapper call per step (Gymnasium's: four).
Consequence: replacing ``env.unwrapped.step`` after the first steps is not seen by the stack.

Behaviour, messages and ``env.spec`` bookkeeping follow Gymnasium 1.x.
"""

from __future__ import annotations

from copy import deepcopy
from typing import TYPE_CHECKING, Any, SupportsFloat

from palaestra import logger
from palaestra.core import ActType, Env, ObsType, RenderFrame, Wrapper
from palaestra.error import ResetNeeded
from palaestra.utils.passive_env_checker import (
    check_action_space,
    check_observation_space,
    env_data_reuse_passive_checker,
    env_render_passive_checker,
    env_reset_passive_checker,
    env_step_passive_checker,
)
from palaestra.utils.record_constructor import RecordConstructorArgs

if TYPE_CHECKING:
    from palaestra.env_spec import EnvSpec

__all__ = ["OrderEnforcing", "PassiveEnvChecker", "TimeLimit"]

StepReturn = tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]


def _spec_with(wrapper: Wrapper[Any, Any, Any, Any], **fields: Any) -> EnvSpec | None:
    """The inner spec with ``fields`` set: these wrappers are spec fields, not extra wrappers."""
    if wrapper._cached_spec is not None:
        return wrapper._cached_spec
    env_spec = wrapper.env.spec
    if env_spec is not None:
        try:
            env_spec = deepcopy(env_spec)
        except Exception as e:  # a kwarg that cannot be copied: the spec is unknown, not wrong
            logger.warn(
                f"An exception occurred ({e}) while copying the environment spec={env_spec}"
            )
            return None
        for name, value in fields.items():
            setattr(env_spec, name, value)
    wrapper._cached_spec = env_spec
    return env_spec


class TimeLimit(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Set ``truncated=True`` on the step that reaches ``max_episode_steps`` since ``reset``.

    >>> from palaestra.spaces import Discrete
    >>> class Counter(Env):
    ...     observation_space = action_space = Discrete(2)
    ...     def reset(self, *, seed=None, options=None):
    ...         return 0, {}
    ...     def step(self, action):
    ...         return 0, 1.0, False, False, {}
    >>> env = TimeLimit(Counter(), max_episode_steps=2)
    >>> _ = env.reset()
    >>> [env.step(0)[3] for _ in range(2)]
    [False, True]
    """

    def __init__(self, env: Env[ObsType, ActType], max_episode_steps: int) -> None:
        """Wrap ``env``; ``max_episode_steps`` must be a positive ``int``."""
        if not isinstance(max_episode_steps, int):
            raise TypeError(
                "Expect the `max_episode_steps` to be an integer, actually: "
                f"{type(max_episode_steps)}"
            )
        if max_episode_steps <= 0:
            raise ValueError(
                f"Expect the `max_episode_steps` to be positive, actually: {max_episode_steps}"
            )
        RecordConstructorArgs.__init__(self, max_episode_steps=max_episode_steps)
        Wrapper.__init__(self, env)
        self._max_episode_steps = max_episode_steps
        self._elapsed_steps: int | None = None  # None until reset, like Gymnasium

    def step(self, action: ActType) -> StepReturn:
        """Step the inner env; truncate once ``max_episode_steps`` steps have elapsed."""
        result = self.env.step(action)
        self._elapsed_steps += 1  # type: ignore[operator]  # TypeError before reset, as Gymnasium
        if self._elapsed_steps >= self._max_episode_steps:
            obs, reward, terminated, _, info = result
            return obs, reward, terminated, True, info
        return result  # the inner tuple as is: no unpacking on the common path

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env and the step count."""
        self._elapsed_steps = 0
        return self.env.reset(seed=seed, options=options)

    @property
    def spec(self) -> EnvSpec | None:  # type: ignore[override]
        """The inner spec with ``max_episode_steps`` set to this wrapper's limit."""
        return _spec_with(self, max_episode_steps=self._max_episode_steps)


class OrderEnforcing(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Raise ``ResetNeeded`` on ``step`` (and ``render``) before the first ``reset``.

    After the first few steps this wrapper costs nothing per step: ``step`` is rebound to the
    inner env's ``step``.
    """

    def __init__(
        self, env: Env[ObsType, ActType], disable_render_order_enforcing: bool = False
    ) -> None:
        """Wrap ``env``; ``disable_render_order_enforcing`` allows ``render`` before ``reset``."""
        RecordConstructorArgs.__init__(
            self, disable_render_order_enforcing=disable_render_order_enforcing
        )
        Wrapper.__init__(self, env)
        self._has_reset = False
        self._disable_render_order_enforcing = disable_render_order_enforcing

    def step(self, action: ActType) -> StepReturn:
        """Step the inner env; before any ``reset`` this raises ``ResetNeeded``."""
        if not self._has_reset:
            raise ResetNeeded("Cannot call env.step() before calling env.reset()")
        inner_step = self.env.step
        result = inner_step(action)
        # Skip this layer from now on, but only once the inner step has stopped rebinding
        # itself (PassiveEnvChecker does during its first steps): a stale binding would keep
        # its checking path in the loop.
        if self.env.step == inner_step:
            self.step = inner_step  # type: ignore[method-assign]
        return result

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env; ``step`` is allowed from now on."""
        result = self.env.reset(seed=seed, options=options)
        self._has_reset = True
        return result

    def render(self) -> RenderFrame | None:
        """Render the inner env; before any ``reset`` this raises ``ResetNeeded``."""
        if not self._disable_render_order_enforcing and not self._has_reset:
            raise ResetNeeded(
                "Cannot call `env.render()` before calling `env.reset()`, if this is an intended "
                "action, set `disable_render_order_enforcing=True` on the OrderEnforcer wrapper."
            )
        return self.env.render()

    @property
    def has_reset(self) -> bool:
        """Whether ``reset`` has been called."""
        return self._has_reset

    @property
    def spec(self) -> EnvSpec | None:  # type: ignore[override]
        """The inner spec with ``order_enforce=True``."""
        return _spec_with(self, order_enforce=True)


class PassiveEnvChecker(Wrapper[ObsType, ActType, ObsType, ActType], RecordConstructorArgs):
    """Check the env against the API on construction and on its first reset, steps and render.

    Checks warn (or raise when the env cannot work) and never change the data. Once the first
    two steps are checked, ``step`` is rebound to the inner env's, so checking costs nothing
    afterwards.
    """

    def __init__(self, env: Env[ObsType, ActType]) -> None:
        """Wrap ``env`` and check its action and observation spaces now."""
        RecordConstructorArgs.__init__(self)
        Wrapper.__init__(self, env)
        if not hasattr(env, "action_space"):
            raise AttributeError(
                "The environment must specify an action space. "
                "https://gymnasium.farama.org/introduction/create_custom_env/"
            )
        check_action_space(env.action_space)
        if not hasattr(env, "observation_space"):
            raise AttributeError(
                "The environment must specify an observation space. "
                "https://gymnasium.farama.org/introduction/create_custom_env/"
            )
        check_observation_space(env.observation_space)
        self.checked_reset = False
        self.checked_step = False
        self.checked_render = False
        self.close_called = False
        # Data reuse is checked between reset and step 1, then step 1 and step 2.
        self.checked_data_reuse = False
        self._previous_data: tuple[Any, dict[str, Any]] | None = None

    def step(self, action: ActType) -> StepReturn:
        """Step the inner env, checking the first two steps."""
        if self.checked_data_reuse:  # reached only through a reference taken before the rebind
            return self.env.step(action)
        if self.checked_step:
            return self._check_second_step(action)
        self.checked_step = True
        result = env_step_passive_checker(self.env, action)
        if len(result) == 5:  # a 4-tuple (old API) was already reported by the step check
            env_data_reuse_passive_checker(
                self._previous_data, (result[0], result[4]), "reset", "step"
            )
            self._previous_data = (result[0], result[4])
        # Rebinding now tells the outer OrderEnforcing that this layer is not settled yet.
        self.step = self._check_second_step  # type: ignore[method-assign]
        return result

    def _check_second_step(self, action: ActType) -> StepReturn:
        result: StepReturn = self.env.step(action)
        self.checked_data_reuse = True
        self.step = self.env.step  # type: ignore[method-assign]  # checks done: bypass this layer
        if len(result) == 5 and self._previous_data is not None:
            env_data_reuse_passive_checker(
                self._previous_data, (result[0], result[4]), "step", "step"
            )
        self._previous_data = None
        return result

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Reset the inner env, checking the first reset."""
        if self.checked_reset:
            return self.env.reset(seed=seed, options=options)
        self.checked_reset = True
        result = env_reset_passive_checker(self.env, seed=seed, options=options)
        if isinstance(result, tuple) and len(result) == 2:
            self._previous_data = result
        return result

    def render(self) -> RenderFrame | None:
        """Render the inner env, checking the first render."""
        if self.checked_render:
            return self.env.render()
        self.checked_render = True
        return env_render_passive_checker(self.env)

    def close(self) -> None:
        """Close the inner env; a second ``close`` must be harmless, and is reported if not."""
        if not self.close_called:
            self.close_called = True
            return self.env.close()
        try:
            return self.env.close()
        except Exception:
            logger.warn(
                "Calling `env.close()` on the closed environment should be allowed, but it raised "
                "the following exception."
            )
            raise

    @property
    def spec(self) -> EnvSpec | None:  # type: ignore[override]
        """The inner spec with ``disable_env_checker=False``."""
        return _spec_with(self, disable_env_checker=False)
