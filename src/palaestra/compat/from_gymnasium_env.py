"""``from_gymnasium(env)``: any ``gymnasium.Env`` as a palaestra environment.

The adapter is a palaestra ``Env`` with palaestra spaces, so palaestra's algorithms, wrappers,
vector envs and checkers take it. Its generator, render mode, metadata and ``close`` are the
Gymnasium env's; the Gymnasium stack stays reachable as ``adapter.gymnasium_env``. Its spec
is Gymnasium's with the id prefixed ``"gymnasium:"``, so ``palaestra.make(adapter.spec)``
rebuilds it through Gymnasium's ``make`` (wrappers Gymnasium's ``make`` did not apply are not
part of a spec, there as here).
"""

from __future__ import annotations

from typing import Any, SupportsFloat

import numpy as np

from palaestra.compat._optional import gymnasium_missing
from palaestra.compat.registry import GYMNASIUM_PREFIX
from palaestra.compat.spaces import (
    from_gymnasium_space,
    from_gymnasium_value,
    needs_value_conversion,
    to_gymnasium_value,
)
from palaestra.core import Env
from palaestra.envs.env_spec import EnvSpec

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - exercised in a subprocess test
    raise gymnasium_missing() from exc

__all__ = ["PalaestraEnvAdapter", "from_gymnasium"]


class PalaestraEnvAdapter(Env[Any, Any]):
    """A palaestra ``Env`` that forwards to a ``gymnasium.Env``; build it with
    :func:`from_gymnasium`."""

    def __init__(self, env: Any) -> None:
        self.gymnasium_env = env
        self.observation_space = from_gymnasium_space(env.observation_space)
        self.action_space = from_gymnasium_space(env.action_space)
        self._convert_obs = needs_value_conversion(self.observation_space)
        self._convert_act = needs_value_conversion(self.action_space)
        self.spec = _palaestra_spec(env.spec)

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the Gymnasium env with ``action`` (a palaestra-space element)."""
        if self._convert_act:
            action = to_gymnasium_value(self.action_space, action)
        obs, reward, terminated, truncated, info = self.gymnasium_env.step(action)
        if self._convert_obs:
            obs = from_gymnasium_value(self.observation_space, obs)
        return obs, reward, terminated, truncated, info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset the Gymnasium env (which seeds its own generator)."""
        obs, info = self.gymnasium_env.reset(seed=seed, options=options)
        if self._convert_obs:
            obs = from_gymnasium_value(self.observation_space, obs)
        return obs, info

    def render(self) -> Any:
        """The Gymnasium env's frame for its ``render_mode``."""
        return self.gymnasium_env.render()

    def close(self) -> None:
        """Close the Gymnasium env."""
        self.gymnasium_env.close()

    @property
    def render_mode(self) -> str | None:  # type: ignore[override]
        """The Gymnasium env's render mode."""
        return self.gymnasium_env.render_mode

    @property
    def metadata(self) -> dict[str, Any]:  # type: ignore[override]
        """The Gymnasium env's metadata."""
        return self.gymnasium_env.metadata

    # One generator, the Gymnasium env's (see to_gymnasium_env for the other direction).
    @property
    def np_random(self) -> np.random.Generator:
        """The Gymnasium env's generator."""
        return self.gymnasium_env.np_random

    @np_random.setter
    def np_random(self, value: np.random.Generator) -> None:
        self.gymnasium_env.np_random = value

    @property
    def np_random_seed(self) -> int:
        """The Gymnasium env's seed."""
        return self.gymnasium_env.np_random_seed

    @property
    def _np_random(self) -> np.random.Generator | None:  # type: ignore[override]
        return self.gymnasium_env.unwrapped._np_random

    def __str__(self) -> str:
        return f"<{type(self).__name__}{self.gymnasium_env}>"

    def __repr__(self) -> str:
        return str(self)


def from_gymnasium(env: Any) -> Env[Any, Any]:
    """Wrap ``gymnasium.Env`` ``env`` (with its wrappers) as a palaestra ``Env``.

    ``to_gymnasium``'s adapters are unwrapped instead of wrapped twice.

    >>> import gymnasium
    >>> env = from_gymnasium(gymnasium.make("Taxi-v4"))
    >>> env.observation_space, env.spec.id, env.reset(seed=0)[0]
    (Discrete(500), 'gymnasium:Taxi-v4', 314)
    """
    from palaestra.compat.to_gymnasium_env import GymnasiumEnvAdapter

    if isinstance(env, GymnasiumEnvAdapter):
        return env.palaestra_env
    if not isinstance(env, gymnasium.Env):
        if isinstance(env, Env):
            hint = " (it already is a palaestra env: use it as it is)"
        elif isinstance(env, gymnasium.vector.VectorEnv):
            hint = " (a vector env: adapt each sub-env, e.g. make_vec('gymnasium:<id>'))"
        else:
            hint = ""
        raise TypeError(
            f"from_gymnasium expects a gymnasium.Env, got {env!r} of type "
            f"{type(env).__module__}.{type(env).__qualname__}{hint}"
        )
    return PalaestraEnvAdapter(env)


def _palaestra_spec(spec: Any) -> EnvSpec | None:
    if spec is None:
        return None
    return EnvSpec(
        id=GYMNASIUM_PREFIX + spec.id,
        entry_point=spec.entry_point,
        reward_threshold=spec.reward_threshold,
        nondeterministic=spec.nondeterministic,
        max_episode_steps=spec.max_episode_steps,
        order_enforce=spec.order_enforce,
        disable_env_checker=spec.disable_env_checker,
        kwargs=dict(spec.kwargs),
    )
