"""``to_gymnasium(env)``: a palaestra environment seen as a real ``gymnasium.Env``.

Libraries typed against Gymnasium (Stable-Baselines3, Gymnasium's ``check_env`` and wrappers)
get a ``gymnasium.Env`` subclass with Gymnasium spaces. Everything else is the palaestra env's:
its generator (seeding, ``np_random``), render mode and frames, metadata, ``close``. The
adapter is Gymnasium's innermost env (``unwrapped`` is itself, as Gymnasium's checker wants);
the palaestra stack below it stays reachable as ``adapter.palaestra_env``.
"""

from __future__ import annotations

import functools
from typing import Any

from palaestra.compat._forwarding import Forwarding
from palaestra.compat._optional import gymnasium_missing
from palaestra.compat.spaces import (
    from_gymnasium_value,
    needs_value_conversion,
    to_gymnasium_space,
    to_gymnasium_value,
)
from palaestra.core import Env
from palaestra.env_spec import EnvSpec

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - exercised in a subprocess test
    raise gymnasium_missing() from exc

__all__ = ["GymnasiumEnvAdapter", "to_gymnasium"]


class GymnasiumEnvAdapter(Forwarding, gymnasium.Env):  # type: ignore[override]
    """A ``gymnasium.Env`` that forwards to a palaestra env; build it with :func:`to_gymnasium`."""

    def __init__(self, env: Env[Any, Any]) -> None:
        self.palaestra_env = self._inner = env
        self.observation_space = to_gymnasium_space(env.observation_space)
        self.action_space = to_gymnasium_space(env.action_space)
        # Graph values are the only ones whose type differs; skip the walk for everything else.
        self._act_in = (
            functools.partial(from_gymnasium_value, env.action_space)
            if needs_value_conversion(env.action_space)
            else None
        )
        self._obs_out = (
            functools.partial(to_gymnasium_value, env.observation_space)
            if needs_value_conversion(env.observation_space)
            else None
        )
        self.spec = _gymnasium_spec(env.spec)


def to_gymnasium(env: Env[Any, Any]) -> Any:
    """Wrap palaestra ``env`` (with its wrappers) as a ``gymnasium.Env`` with Gymnasium spaces.

    ``from_gymnasium``'s adapters are unwrapped instead of wrapped twice.

    >>> import palaestra
    >>> env = to_gymnasium(palaestra.make("CartPole-v1"))
    >>> env.action_space, env.reset(seed=0)[0].shape, env.spec.max_episode_steps
    (Discrete(2), (4,), 500)
    """
    from palaestra.compat.from_gymnasium_env import PalaestraEnvAdapter

    if isinstance(env, PalaestraEnvAdapter):
        return env.gymnasium_env
    if not isinstance(env, Env):
        hint = (
            " (it already is a Gymnasium env: use it as it is)"
            if isinstance(env, gymnasium.Env)
            else ""
        )
        raise TypeError(
            f"to_gymnasium expects a palaestra.Env, got {env!r} of type "
            f"{type(env).__module__}.{type(env).__qualname__}{hint}"
        )
    return GymnasiumEnvAdapter(env)


def _gymnasium_spec(spec: EnvSpec | None) -> Any:
    """A Gymnasium spec whose ``make`` rebuilds the env: ``gymnasium.make(adapter.spec)``.

    The entry point builds the bare palaestra env (plus the spec's extra palaestra wrappers);
    Gymnasium then adds its own checker, order enforcing and ``TimeLimit`` from the copied
    fields, so the limit applies once and ``spec.max_episode_steps`` reads as the user expects.
    """
    if spec is None or spec.entry_point is None:
        return None
    bare = EnvSpec(
        id=spec.id,
        entry_point=spec.entry_point,
        reward_threshold=spec.reward_threshold,
        nondeterministic=spec.nondeterministic,
        max_episode_steps=None,
        order_enforce=False,
        disable_env_checker=True,
        kwargs={},
        additional_wrappers=spec.additional_wrappers,
        vector_entry_point=spec.vector_entry_point,
    )
    return gymnasium.envs.registration.EnvSpec(
        id=spec.id,
        entry_point=functools.partial(_make_adapted, bare),
        reward_threshold=spec.reward_threshold,
        nondeterministic=spec.nondeterministic,
        max_episode_steps=spec.max_episode_steps,
        order_enforce=spec.order_enforce,
        disable_env_checker=spec.disable_env_checker,
        kwargs=dict(spec.kwargs),
    )


def _make_adapted(bare: EnvSpec, **kwargs: Any) -> GymnasiumEnvAdapter:
    import palaestra

    return GymnasiumEnvAdapter(palaestra.make(bare, **kwargs))
