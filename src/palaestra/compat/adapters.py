"""The two Gymnasium adapters, each the other's inverse (so each unwraps the other).

``to_gymnasium(env)``: a palaestra environment seen as a real ``gymnasium.Env``. Libraries typed
against Gymnasium (Stable-Baselines3, Gymnasium's ``check_env`` and wrappers) get a
``gymnasium.Env`` subclass with Gymnasium spaces. Everything else is the palaestra env's: its
generator (seeding, ``np_random``), render mode and frames, metadata, ``close``. The adapter is
Gymnasium's innermost env (``unwrapped`` is itself, as Gymnasium's checker wants); the palaestra
stack below it stays reachable as ``adapter.palaestra_env``.

``from_gymnasium(env)``: any ``gymnasium.Env`` as a palaestra environment. The adapter is a
palaestra ``Env`` with palaestra spaces, so palaestra's algorithms, wrappers, vector envs and
checkers take it. Its generator, render mode, metadata and ``close`` are the Gymnasium env's;
the Gymnasium stack stays reachable as ``adapter.gymnasium_env``. Its spec is Gymnasium's with
the id prefixed ``"gymnasium:"``, so ``palaestra.make(adapter.spec)`` rebuilds it through
Gymnasium's ``make`` (wrappers Gymnasium's ``make`` did not apply are not part of a spec, there
as here).
"""

from __future__ import annotations

import functools
from typing import Any

from palaestra.compat._forwarding import Forwarding
from palaestra.compat._optional import GYMNASIUM_PREFIX, gymnasium_missing, shared_spec_fields
from palaestra.compat.spaces import (
    from_gymnasium_space,
    from_gymnasium_value,
    needs_value_conversion,
    to_gymnasium_space,
    to_gymnasium_value,
)
from palaestra.core import Env
from palaestra.env_spec import EnvSpec
from palaestra.envs.registration import bare_spec

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - exercised in a subprocess test
    raise gymnasium_missing() from exc

__all__ = ["GymnasiumEnvAdapter", "PalaestraEnvAdapter", "from_gymnasium", "to_gymnasium"]


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
    bare = bare_spec(spec, {}, spec.additional_wrappers)
    fields = shared_spec_fields(spec)
    fields["entry_point"] = functools.partial(_make_adapted, bare)
    return gymnasium.envs.registration.EnvSpec(id=spec.id, **fields)


def _make_adapted(bare: EnvSpec, **kwargs: Any) -> GymnasiumEnvAdapter:
    import palaestra

    return GymnasiumEnvAdapter(palaestra.make(bare, **kwargs))


class PalaestraEnvAdapter(Forwarding, Env[Any, Any]):  # type: ignore[override]
    """A palaestra ``Env`` that forwards to a ``gymnasium.Env``; build it with
    :func:`from_gymnasium`."""

    def __init__(self, env: Any) -> None:
        self.gymnasium_env = self._inner = env
        self.observation_space = from_gymnasium_space(env.observation_space)
        self.action_space = from_gymnasium_space(env.action_space)
        obs_space, act_space = self.observation_space, self.action_space
        # Graph values are the only ones whose type differs; skip the walk for everything else.
        self._act_in = (
            functools.partial(to_gymnasium_value, act_space)
            if needs_value_conversion(act_space)
            else None
        )
        self._obs_out = (
            functools.partial(from_gymnasium_value, obs_space)
            if needs_value_conversion(obs_space)
            else None
        )
        self.spec = _palaestra_spec(env.spec)


def from_gymnasium(env: Any) -> Env[Any, Any]:
    """Wrap ``gymnasium.Env`` ``env`` (with its wrappers) as a palaestra ``Env``.

    ``to_gymnasium``'s adapters are unwrapped instead of wrapped twice.

    >>> import gymnasium
    >>> env = from_gymnasium(gymnasium.make("Taxi-v4"))
    >>> env.observation_space, env.spec.id, env.reset(seed=0)[0]
    (Discrete(500), 'gymnasium:Taxi-v4', 314)
    """
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
    return EnvSpec(id=GYMNASIUM_PREFIX + spec.id, **shared_spec_fields(spec))
