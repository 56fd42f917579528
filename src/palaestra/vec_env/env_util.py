"""``make_vec_env`` and ``make_atari_env``: SB3's helpers, with the native batch as the default
for built-in envs."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import asdict, replace
from typing import Any

import numpy as np

from palaestra import error, logger
from palaestra.core import Env
from palaestra.envs.atari.ale_engine import vector_interface_available
from palaestra.envs.registration import make, native_batch, resolve_id
from palaestra.vec_env.atari_vec_env import AtariGameMonitor, AtariVecEnv, atari_wrapper_settings
from palaestra.vec_env.base import VecEnv
from palaestra.vec_env.engine_vec_env import BatchedVecEnv, DummyVecEnv, SubprocVecEnv
from palaestra.vec_env.monitor import VecMonitor
from palaestra.vector.engine import is_wrapped as is_wrapped  # SB3 env_util names
from palaestra.vector.engine import unwrap_wrapper as unwrap_wrapper
from palaestra.vector.native import BatchedVectorEnv, batched_vector_env
from palaestra.wrappers.atari import AtariWrapper
from palaestra.wrappers.monitor import Monitor

# make()'s keywords that wrap a single env (SB3 passes them in env_kwargs): real envs for them.
_MAKE_ONLY = frozenset({"disable_env_checker", "autoreset", "apply_api_compatibility"})


def _native_batch(env_id: Any, env_kwargs: dict[str, Any], n_envs: int) -> BatchedVecEnv | None:
    """The native batch for a built-in id, or None when the id has none (or ``env_kwargs``
    ask for what only real envs do: a render mode other than ``rgb_array``, ``make``'s own
    options other than ``max_episode_steps``)."""
    if not isinstance(env_id, str):
        return None
    spec = resolve_id(env_id)
    classes = native_batch(spec)
    if classes is None or spec.additional_wrappers:
        return None
    kwargs = {**spec.kwargs, **env_kwargs}
    # SB3 asks for rgb_array frames unless told otherwise; batches that draw rows give them.
    render_mode = kwargs.pop("render_mode", "rgb_array")
    if render_mode == "rgb_array" and not hasattr(classes[0], "frame"):
        render_mode = None
    if render_mode not in (None, "rgb_array") or set(kwargs) & _MAKE_ONLY:
        return None
    # make()'s time limit, which gym.make takes among the env's keywords (SB3 passes them on)
    limit = kwargs.pop("max_episode_steps", spec.max_episode_steps)
    limit = None if limit == -1 else limit  # make(max_episode_steps=-1): no TimeLimit
    native = batched_vector_env(*classes, num_envs=n_envs, max_episode_steps=limit, **kwargs)
    assert isinstance(native, BatchedVectorEnv)  # no render_mode: the batch itself
    venv = BatchedVecEnv(native.batch, limit, native.metadata, render_mode)
    venv.spec = spec if limit == spec.max_episode_steps else replace(spec, max_episode_steps=limit)
    return venv


def make_vec_env(
    env_id: str | Callable[..., Env[Any, Any]],
    n_envs: int = 1,
    seed: int | None = None,
    start_index: int = 0,
    monitor_dir: str | None = None,
    wrapper_class: Callable[..., Env[Any, Any]] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    vec_env_cls: type[VecEnv] | None = None,
    vec_env_kwargs: dict[str, Any] | None = None,
    monitor_kwargs: dict[str, Any] | None = None,
    wrapper_kwargs: dict[str, Any] | None = None,
) -> VecEnv:
    """``n_envs`` monitored envs as one ``VecEnv`` (SB3's signature and behaviour).

    A built-in id with no ``wrapper_class`` or ``vec_env_cls`` gets its native batch
    (``BatchedVecEnv``) under a ``VecMonitor``: the same observations, rewards, dones and
    ``infos[i]["episode"]`` as SB3's ``DummyVecEnv`` of ``Monitor``-wrapped envs, without a
    Python loop per step. Env ``i`` is seeded ``seed + start_index + i`` at the first reset.
    As SB3's, the envs have ``render_mode="rgb_array"`` unless ``env_kwargs`` say otherwise
    (the batch draws each row), so ``VecVideoRecorder(make_vec_env(id), ...)`` records; and
    ``env_kwargs`` may hold ``make``'s ``max_episode_steps``.

    >>> vec_env = make_vec_env("MountainCar-v0", n_envs=4, seed=0)
    >>> vec_env.reset().shape
    (4, 2)
    """
    if isinstance(n_envs, bool) or not isinstance(n_envs, (int, np.integer)) or n_envs < 1:
        raise error.InvalidNumEnvs(f"make_vec_env: n_envs must be an int >= 1, got {n_envs!r}")
    env_kwargs = env_kwargs or {}
    vec_env_kwargs = vec_env_kwargs or {}
    monitor_kwargs = monitor_kwargs or {}
    wrapper_kwargs = wrapper_kwargs or {}

    # The native batch stands in for SB3's DummyVecEnv of Monitors only where it behaves the
    # same: not for vec_env_kwargs (DummyVecEnv takes none: SB3 raises TypeError, and so does
    # the loop below) nor for Monitor settings other than override_existing.
    native_ok = not vec_env_kwargs and set(monitor_kwargs) <= {"override_existing"}
    if vec_env_cls is None and wrapper_class is None and native_ok:
        native = _native_batch(env_id, env_kwargs, n_envs)
        if native is not None:
            monitor = VecMonitor(native)
            if monitor_dir is not None:
                os.makedirs(monitor_dir, exist_ok=True)
                names = [os.path.join(monitor_dir, str(start_index + i)) for i in range(n_envs)]
                monitor.log_per_env(names, **monitor_kwargs)
            vec_env: VecEnv = monitor
            if seed is not None:
                native.action_space.seed(seed + start_index)
            vec_env.seed(seed)  # SB3: env i gets seed + i (start_index only shifts ranks)
            return vec_env

    def make_env(rank: int) -> Callable[[], Env[Any, Any]]:
        def init() -> Env[Any, Any]:
            if isinstance(env_id, str):
                # SB3 asks for rgb_array frames unless told otherwise.
                try:
                    env = make(env_id, **{"render_mode": "rgb_array", **env_kwargs})
                except TypeError:
                    env = make(env_id, **env_kwargs)
            else:
                env = env_id(**env_kwargs)
            if seed is not None:
                env.action_space.seed(seed + rank)
            path = None
            if monitor_dir is not None:
                os.makedirs(monitor_dir, exist_ok=True)
                path = os.path.join(monitor_dir, str(rank))
            env = Monitor(env, filename=path, **monitor_kwargs)
            if wrapper_class is not None:
                env = wrapper_class(env, **wrapper_kwargs)
            return env

        return init

    cls: Any = DummyVecEnv if vec_env_cls is None else vec_env_cls
    vec_env = cls([make_env(i + start_index) for i in range(n_envs)], **vec_env_kwargs)
    vec_env.seed(seed)
    return vec_env


def _atari_engine(
    env_id: Any,
    n_envs: int,
    wrapper_kwargs: dict[str, Any],
    env_kwargs: dict[str, Any],
    vec_env_cls: type[VecEnv] | None,
    seed: int | None = None,
    recipe_only: tuple[str, ...] = (),
) -> VecEnv | None:
    """The one place that decides whether ``make_atari_env`` uses the native vector Atari
    instead of ``n_envs`` wrapped single envs; None means "build single envs".

    Only when the caller asks for it with ``vec_env_cls=AtariVecEnv``: its preprocessing means
    what SB3's recipe means but is not frame for frame the same (see
    :func:`~palaestra.vec_env.atari_vec_env.atari_wrapper_settings`), so the default stays the
    recipe itself. When a setting does not map (or ``recipe_only`` names arguments that only
    single envs take, such as ``monitor_dir``), a warning says which and None is returned.
    """
    if vec_env_cls is not AtariVecEnv:
        return None
    if recipe_only:
        mapped: tuple[str, Any] | str = f"{list(recipe_only)} need single envs"
    elif not vector_interface_available():
        mapped = "the installed ale-py has no ALEVectorInterface"
    else:
        mapped = atari_wrapper_settings(env_id, wrapper_kwargs, env_kwargs)
    if isinstance(mapped, str):
        logger.warn(f"make_atari_env: {mapped}; running SB3's recipe in SubprocVecEnv workers")
        return None
    game, settings = mapped
    venv = AtariVecEnv(game, n_envs, frames_last=True, **asdict(settings))
    venv.spec = resolve_id(env_id)
    monitor = AtariGameMonitor(venv)
    monitor.seed(seed)  # SB3: env i gets seed + i
    return monitor


def make_atari_env(
    env_id: str | Callable[..., Env[Any, Any]],
    n_envs: int = 1,
    seed: int | None = None,
    start_index: int = 0,
    monitor_dir: str | None = None,
    wrapper_kwargs: dict[str, Any] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    vec_env_cls: type[VecEnv] | None = None,
    vec_env_kwargs: dict[str, Any] | None = None,
    monitor_kwargs: dict[str, Any] | None = None,
) -> VecEnv:
    """``n_envs`` Atari envs, each ``Monitor`` then ``AtariWrapper`` (SB3's ``make_atari_env``).

    ``wrapper_kwargs`` go to :class:`palaestra.wrappers.AtariWrapper`. As in SB3, the default
    ``terminal_on_life_loss=True`` makes ``reset()`` after a lost life a no-op step rather than
    a new game; pass ``wrapper_kwargs=dict(terminal_on_life_loss=False)`` to avoid it. Use an id
    without frame skip of its own, e.g. ``"BreakoutNoFrameskip-v4"``.

    ``vec_env_cls=AtariVecEnv`` runs the games on ale-py's C++ threads instead, with the same
    settings in meaning (not frame for frame; see ``atari_wrapper_settings``); settings that do
    not map fall back to ``SubprocVecEnv`` workers with a warning.

    >>> vec_env = make_atari_env("BreakoutNoFrameskip-v4", n_envs=2, seed=0)  # doctest: +SKIP
    >>> vec_env.reset().shape  # doctest: +SKIP
    (2, 84, 84, 1)
    """
    given = (monitor_dir, vec_env_kwargs, monitor_kwargs)
    names = ("monitor_dir", "vec_env_kwargs", "monitor_kwargs")
    recipe_only = tuple(name for name, value in zip(names, given) if value)
    engine = _atari_engine(
        env_id, n_envs, wrapper_kwargs or {}, env_kwargs or {}, vec_env_cls, seed, recipe_only
    )
    if engine is not None:
        return engine
    if vec_env_cls is AtariVecEnv:
        vec_env_cls = SubprocVecEnv  # _atari_engine has said why
    return make_vec_env(
        env_id,
        n_envs=n_envs,
        seed=seed,
        start_index=start_index,
        monitor_dir=monitor_dir,
        wrapper_class=AtariWrapper,
        env_kwargs=env_kwargs,
        vec_env_cls=vec_env_cls,
        vec_env_kwargs=vec_env_kwargs,
        monitor_kwargs=monitor_kwargs,
        wrapper_kwargs=wrapper_kwargs,
    )
