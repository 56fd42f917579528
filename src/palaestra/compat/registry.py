"""Gymnasium's registry from palaestra: ``palaestra.make("gymnasium:Taxi-v4", **kwargs)``.

The id after the prefix goes to ``gymnasium.make`` unchanged (so ``"gymnasium:ale_py:ALE/Pong-v5"``
imports ``ale_py`` first, as Gymnasium does), and the result comes back through
:func:`~palaestra.compat.from_gymnasium`. Gymnasium's ``make`` already applied its checker,
order enforcing and ``TimeLimit``, so palaestra adds none of its own on top.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from palaestra import error
from palaestra.compat._optional import GYMNASIUM_PREFIX, gymnasium_missing, shared_spec_fields
from palaestra.core import Env
from palaestra.env_spec import EnvSpec, VectorizeMode
from palaestra.envs.lookup import ForeignRegistry, foreign_registries
from palaestra.envs.registration import apply_wrapper_specs

__all__ = ["GYMNASIUM_PREFIX", "gymnasium_spec", "make_gymnasium", "make_vec_gymnasium"]


def make_gymnasium(
    id: str | EnvSpec,
    max_episode_steps: int | None = None,
    disable_env_checker: bool | None = None,
    **kwargs: Any,
) -> Env[Any, Any]:
    """``gymnasium.make`` on the id after ``"gymnasium:"``, as a palaestra env.

    Arguments mean what they mean for ``palaestra.make``. A spec (from an adapter's
    ``env.spec``) is rebuilt with its palaestra wrappers.
    """
    try:
        import gymnasium
    except ImportError as exc:
        raise gymnasium_missing(f"making {id if isinstance(id, str) else id.id!r}") from exc
    from palaestra.compat.adapters import from_gymnasium  # lazy: optional-dep — gymnasium

    spec = id if isinstance(id, EnvSpec) else None
    gym_id = (spec.id if spec is not None else str(id))[len(GYMNASIUM_PREFIX) :]
    if not gym_id:
        raise error.Error(
            f"Expected an environment id after {GYMNASIUM_PREFIX!r}, e.g. 'gymnasium:Taxi-v4'"
        )
    target: Any = gym_id if spec is None else _gymnasium_spec(gymnasium, spec, gym_id)
    with _registry_errors(gymnasium, gym_id):
        gym_env = gymnasium.make(
            target,
            max_episode_steps=max_episode_steps,
            disable_env_checker=disable_env_checker,
            **kwargs,
        )
    env = from_gymnasium(gym_env)
    if spec is not None:
        # the palaestra wrappers recorded in the spec (Wrapper.spec adds one per layer)
        env = apply_wrapper_specs(env, spec.additional_wrappers)
    return env


@contextlib.contextmanager
def _registry_errors(gymnasium: Any, gym_id: str) -> Iterator[None]:
    """Gymnasium's registry errors as palaestra's classes of the same name."""
    try:
        yield
    except gymnasium.error.UnregisteredEnv as exc:
        cls = getattr(error, type(exc).__name__, error.UnregisteredEnv)
        raise cls(f"{gym_id!r} is not in Gymnasium's registry: {exc}") from exc
    except gymnasium.error.DeprecatedEnv as exc:
        raise error.DeprecatedEnv(
            f"{gym_id!r} is deprecated in Gymnasium's registry: {exc}"
        ) from exc
    except gymnasium.error.DependencyNotInstalled as exc:
        raise error.DependencyNotInstalled(f"Gymnasium's {gym_id!r}: {exc}") from exc


def gymnasium_spec(id: str) -> EnvSpec:
    """The spec of ``"gymnasium:<id>"`` from Gymnasium's registry (entry point, reward
    threshold, time limit), as ``palaestra.spec`` gives it for palaestra's own ids."""
    try:
        import gymnasium
    except ImportError as exc:
        raise gymnasium_missing(f"looking up {id!r}") from exc
    from palaestra.compat.adapters import _palaestra_spec  # lazy: optional-dep — gymnasium

    gym_id = id[len(GYMNASIUM_PREFIX) :]
    with _registry_errors(gymnasium, gym_id):
        found = gymnasium.spec(gym_id)
    spec = _palaestra_spec(found)
    assert spec is not None
    return spec


def _gymnasium_spec(gymnasium: Any, spec: EnvSpec, gym_id: str) -> Any:
    if spec.entry_point is None:
        return gym_id  # look it up in Gymnasium's registry
    return gymnasium.envs.registration.EnvSpec(id=gym_id, **shared_spec_fields(spec))


def _make_one(
    id: str | EnvSpec, wrappers: Sequence[Callable[[Env[Any, Any]], Env[Any, Any]]], kwargs: Any
) -> Env[Any, Any]:
    env = make_gymnasium(id, **kwargs)
    for wrapper in wrappers:
        env = wrapper(env)
    return env


def make_vec_gymnasium(
    id: str | EnvSpec,
    num_envs: int = 1,
    vectorization_mode: VectorizeMode | str | None = None,
    vector_kwargs: dict[str, Any] | None = None,
    wrappers: Sequence[Callable[[Env[Any, Any]], Env[Any, Any]]] | None = None,
    **kwargs: Any,
) -> Any:
    """``num_envs`` Gymnasium envs in a palaestra ``SyncVectorEnv`` (default) or
    ``AsyncVectorEnv``; arguments as for ``palaestra.make_vec``."""
    from palaestra import vector  # lazy: import-time — multiprocessing

    mode = VectorizeMode(vectorization_mode or VectorizeMode.SYNC)
    if mode is VectorizeMode.VECTOR_ENTRY_POINT:
        raise error.Error(
            f"{id if isinstance(id, str) else id.id!r}: Gymnasium's vector entry points build "
            "Gymnasium vector envs; use vectorization_mode='sync' or 'async'"
        )
    make_one = functools.partial(_make_one, id, list(wrappers or []), kwargs)
    cls = vector.SyncVectorEnv if mode is VectorizeMode.SYNC else vector.AsyncVectorEnv
    return cls([make_one] * num_envs, **(vector_kwargs or {}))


foreign_registries[GYMNASIUM_PREFIX] = ForeignRegistry(
    make=make_gymnasium, make_vec=make_vec_gymnasium, spec=gymnasium_spec
)
