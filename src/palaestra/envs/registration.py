"""``make()`` and ``make_vec()``: build an environment from its id, wrapped as Gymnasium wraps it.

``make()`` stacks, from the inside out: the environment, ``PassiveEnvChecker`` (unless disabled),
``OrderEnforcing`` (if the spec asks), ``TimeLimit`` (if there is a step limit), the spec's
additional wrappers, then ``HumanRendering`` / ``RenderCollection`` when the render mode needs
them, so that ``str(env)`` reads as in Gymnasium:
``<TimeLimit<OrderEnforcing<PassiveEnvChecker<MountainCarEnv<MountainCar-v0>>>>>``.

The registry itself lives in :mod:`palaestra.envs.lookup` and the spec dataclasses in
:mod:`palaestra.env_spec`; this module re-exports both so that it is the one import users
need, as ``gymnasium.envs.registration`` is.
"""

from __future__ import annotations

import copy
import functools
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from palaestra import error, logger
from palaestra.core import Env, Wrapper
from palaestra.env_spec import (
    EnvCreator,
    EnvSpec,
    VectorizeMode,
    WrapperSpec,
    get_env_id,
    install_maker,
    parse_env_id,
)
from palaestra.envs.lookup import (
    find_highest_version,
    foreign_registry,
    load_env_creator,
    namespace,
    pprint_registry,
    register,
    register_envs,
    registry,
    resolve_id,
    spec,
)

__all__ = [
    "EnvCreator",
    "EnvSpec",
    "VectorizeMode",
    "WrapperSpec",
    "find_highest_version",
    "get_env_id",
    "load_env_creator",
    "make",
    "make_vec",
    "namespace",
    "native_batch",
    "parse_env_id",
    "pprint_registry",
    "register",
    "register_envs",
    "registry",
    "spec",
]


def _render_modes_of(env_creator: Any) -> Iterable[str] | None:
    """The creator's declared render modes, if its class-level metadata says."""
    metadata = getattr(env_creator, "metadata", None)
    if metadata is None or isinstance(metadata, property):  # a Wrapper class: instance property
        return None
    if not isinstance(metadata, dict):
        raise error.InvalidMetadata(
            f"Expect the environment metadata to be dict, actual type: {type(metadata)}"
        )
    render_modes = metadata.get("render_modes")
    if render_modes is None:
        logger.warn(
            "The environment creator metadata doesn't include `render_modes`, "
            f"contains: {list(metadata.keys())}"
        )
    elif not isinstance(render_modes, Iterable):
        logger.warn(
            "Expects the environment metadata render_modes to be a Iterable, "
            f"actual type: {type(render_modes)}"
        )
        return None
    return render_modes


def _resolve_render_mode(env_creator: Any, env_kwargs: dict[str, Any]) -> str | None:
    """Adjust ``env_kwargs["render_mode"]``; return the rendering wrapper to add, if any."""
    render_mode = env_kwargs.get("render_mode")
    render_modes = _render_modes_of(env_creator)
    if render_mode is None or render_modes is None or render_mode in render_modes:
        return None
    displayable = {"rgb_array", "rgb_array_list"}.intersection(render_modes)
    if render_mode == "human" and displayable:
        logger.warn(
            "You are trying to use 'human' rendering for an environment that doesn't natively "
            "support it. The HumanRendering wrapper is being applied to your environment."
        )
        env_kwargs["render_mode"] = "rgb_array" if "rgb_array" in displayable else "rgb_array_list"
        return "HumanRendering"
    if render_mode.endswith("_list") and render_mode[: -len("_list")] in render_modes:
        env_kwargs["render_mode"] = render_mode[: -len("_list")]
        return "RenderCollection"
    logger.warn(
        f"The environment is being initialised with render_mode={render_mode!r} "
        f"that is not in the possible render_modes ({render_modes})."
    )
    return None


def _load_creator(env_spec: EnvSpec) -> Callable[..., Any]:
    if env_spec.entry_point is None:
        raise error.Error(f"{env_spec.id} registered but entry_point is not specified")
    entry = env_spec.entry_point
    return load_env_creator(entry) if isinstance(entry, str) else entry


def _instantiate(
    env_creator: Callable[..., Any], env_spec: EnvSpec, env_kwargs: dict[str, Any], human: bool
) -> Env[Any, Any]:
    """Call the creator and check that it built an ``Env``; errors name the id and kwargs."""
    try:
        env = env_creator(**env_kwargs)
    except TypeError as e:
        if human and "got an unexpected keyword argument 'render_mode'" in str(e):
            raise error.Error(
                f"You passed render_mode='human' although {env_spec.id} doesn't implement "
                "human-rendering natively. palaestra tried to apply the HumanRendering wrapper "
                "but it looks like your environment is using the old rendering API, which is not "
                "supported by the HumanRendering wrapper."
            ) from e
        raise type(e)(
            f"{e} was raised from the environment creator for {env_spec.id} "
            f"with kwargs ({env_kwargs})"
        ) from e
    if not isinstance(env, Env):
        raise TypeError(
            "The environment must inherit from the palaestra.Env class, actual class: "
            f"{type(env)}. See https://gymnasium.farama.org/introduction/create_custom_env/ "
            "for more info."
        )
    return env


def _check_prior_wrappers(env: Env[Any, Any], env_spec: EnvSpec) -> int:
    """How many of the spec's wrappers the entry point already applied (they must match)."""
    assert env.spec is not None
    prior = env.spec.additional_wrappers
    expected = env_spec.additional_wrappers[: len(prior)]
    if len(prior) <= len(env_spec.additional_wrappers) and expected != prior:
        for saved, recreated in zip(expected, prior):
            if saved != recreated:
                raise ValueError(
                    f"The environment's wrapper spec {recreated} is different from the saved "
                    f"`EnvSpec` additional wrapper {saved}"
                )
    return len(prior)


def make(
    id: str | EnvSpec,
    max_episode_steps: int | None = None,
    disable_env_checker: bool | None = None,
    **kwargs: Any,
) -> Env[Any, Any]:
    """Create the environment registered as ``id`` (or described by an ``EnvSpec``), wrapped.

    ``id`` may start with ``"module:"`` to import that module (which registers the id) first.
    ``"gymnasium:<id>"`` makes Gymnasium's ``<id>`` instead (see :mod:`palaestra.compat`).
    ``max_episode_steps`` overrides the spec's limit (``-1``: no ``TimeLimit``);
    ``disable_env_checker`` overrides the spec's; ``kwargs`` go to the environment constructor.

    >>> env = make("CartPole-v1")
    >>> env
    <TimeLimit<OrderEnforcing<PassiveEnvChecker<CartPoleEnv<CartPole-v1>>>>>
    >>> make("CartPole-v1", max_episode_steps=3, disable_env_checker=True).spec.max_episode_steps
    3
    """
    from palaestra.wrappers.common import (  # lazy: import-time — passive env checker
        OrderEnforcing,
        PassiveEnvChecker,
        TimeLimit,
    )

    foreign = foreign_registry(id)  # "gymnasium:<id>": Gymnasium's, through palaestra.compat
    if foreign is not None:
        return foreign.make(id, max_episode_steps, disable_env_checker, **kwargs)
    if isinstance(id, EnvSpec):
        env_spec = id
    elif isinstance(id, str):
        env_spec = resolve_id(id)
    else:
        raise TypeError(f"Expected id to be a string or EnvSpec, got {type(id)}")

    env_kwargs = copy.deepcopy(env_spec.kwargs)
    env_kwargs.update(kwargs)
    env_creator = _load_creator(env_spec)
    render_wrapper = _resolve_render_mode(env_creator, env_kwargs)
    env = _instantiate(env_creator, env_spec, env_kwargs, render_wrapper == "HumanRendering")

    # The innermost spec records only how the env itself was built; each wrapper below adds
    # its own part (TimeLimit its max_episode_steps, ...), so env.spec describes the stack.
    env.unwrapped.spec = bare_spec(env_spec, env_kwargs, ())
    num_prior = _check_prior_wrappers(env, env_spec)

    if disable_env_checker is False or (
        disable_env_checker is None and env_spec.disable_env_checker is False
    ):
        env = PassiveEnvChecker(env)
    if env_spec.order_enforce:
        env = OrderEnforcing(env)
    if max_episode_steps != -1:
        limit = env_spec.max_episode_steps if max_episode_steps is None else max_episode_steps
        if limit is not None:
            env = TimeLimit(env, limit)
    env = apply_wrapper_specs(env, env_spec.additional_wrappers[num_prior:])

    if render_wrapper is not None:
        # Written by the rendering owner; imported only when a render mode needs it.
        from palaestra.wrappers import rendering  # lazy: import-time — render wrappers

        env = getattr(rendering, render_wrapper)(env)
    return env


def bare_spec(
    spec: EnvSpec, kwargs: dict[str, Any], additional_wrappers: tuple[WrapperSpec, ...]
) -> EnvSpec:
    """``spec`` without what ``make()`` puts around the env (checker, order enforcing, time
    limit): the spec of the env built with ``kwargs``, inside ``additional_wrappers``."""
    return EnvSpec(
        id=spec.id,
        entry_point=spec.entry_point,
        reward_threshold=spec.reward_threshold,
        nondeterministic=spec.nondeterministic,
        max_episode_steps=None,
        order_enforce=False,
        disable_env_checker=True,
        kwargs=kwargs,
        additional_wrappers=additional_wrappers,
        vector_entry_point=spec.vector_entry_point,
    )


def apply_wrapper_specs(env: Env[Any, Any], wrapper_specs: Sequence[WrapperSpec]) -> Env[Any, Any]:
    """``env`` inside the wrappers ``wrapper_specs`` describe (innermost first); a wrapper that
    did not record its arguments cannot be rebuilt: ``ValueError`` naming it."""
    for wrapper_spec in wrapper_specs:
        if wrapper_spec.kwargs is None:
            raise ValueError(
                f"{wrapper_spec.name} wrapper does not inherit from "
                "`palaestra.utils.RecordConstructorArgs`, therefore, the wrapper cannot be "
                "recreated."
            )
        env = load_env_creator(wrapper_spec.entry_point)(env=env, **wrapper_spec.kwargs)
    return env


install_maker(make)

# Vector options that palaestra's native batches (palaestra.vector.native) accept directly.
_NATIVE_VECTOR_KWARGS = {"copy", "autoreset_mode"}


def native_batch(spec: EnvSpec) -> tuple[Any, Any] | None:
    """``(batch class, env class)`` when ``spec``'s vector entry point names a native batch
    (a class with ``is_native_batch``: classic control's and toy text's ``*Batch``), else None.

    An entry point that does not load is not a native batch here: the error comes where the
    entry point is used, as for any other vector entry point.
    """
    entry = spec.vector_entry_point
    if entry is None:
        return None
    try:
        creator = load_env_creator(entry) if isinstance(entry, str) else entry
    except (ImportError, AttributeError):
        return None
    if not getattr(creator, "is_native_batch", False):
        return None
    return creator, _load_creator(spec)


def make_vec(
    id: str | EnvSpec,
    num_envs: int = 1,
    vectorization_mode: VectorizeMode | str | None = None,
    vector_kwargs: dict[str, Any] | None = None,
    wrappers: Sequence[Callable[[Env[Any, Any]], Wrapper[Any, Any, Any, Any]]] | None = None,
    **kwargs: Any,
) -> Any:
    """Create ``num_envs`` copies of ``id`` as one vector environment.

    ``vectorization_mode`` is ``"sync"``, ``"async"`` or ``"vector_entry_point"`` (default: the
    spec's vector entry point if it has one, else sync); ``vector_kwargs`` go to the vector
    env, ``wrappers`` wrap each copy (sync/async only), ``kwargs`` go to each env.
    """
    foreign = foreign_registry(id)  # "gymnasium:<id>": Gymnasium's, through palaestra.compat
    if foreign is not None:
        return foreign.make_vec(id, num_envs, vectorization_mode, vector_kwargs, wrappers, **kwargs)
    if isinstance(id, EnvSpec):
        env_spec = id
    elif isinstance(id, str):
        env_spec = resolve_id(id)
    else:
        raise error.Error(f"Invalid id type: {type(id)}. Expected `str` or `EnvSpec`")
    env_spec = copy.deepcopy(env_spec)
    # A spec saved from a vector env keeps the make_vec arguments in its kwargs: take them out.
    env_kwargs = env_spec.kwargs
    env_spec.kwargs = {}
    num_envs = env_kwargs.pop("num_envs", num_envs)
    vectorization_mode = env_kwargs.pop("vectorization_mode", vectorization_mode)
    vector_kwargs = env_kwargs.pop("vector_kwargs", vector_kwargs) or {}
    wrappers = env_kwargs.pop("wrappers", wrappers) or []
    env_kwargs.update(kwargs)

    if vectorization_mode is None:
        # palaestra gives ids a native vector entry point where Gymnasium has none (MountainCar,
        # Pendulum, ...). Code written for Gymnasium passes per-env `wrappers` or `vector_kwargs`
        # to such ids, which only a SyncVectorEnv takes: keep that code working.
        entry = env_spec.vector_entry_point
        sync_args = bool(wrappers) or not set(vector_kwargs) <= _NATIVE_VECTOR_KWARGS
        if entry is None or (sync_args and native_batch(env_spec) is not None):
            mode = VectorizeMode.SYNC
        else:
            mode = VectorizeMode.VECTOR_ENTRY_POINT
    else:
        try:
            mode = VectorizeMode(vectorization_mode)
        except ValueError as e:
            raise ValueError(
                f"Invalid vectorization mode: {vectorization_mode!r}, "
                f"valid modes: {[m.value for m in VectorizeMode]}"
            ) from e

    if mode is VectorizeMode.VECTOR_ENTRY_POINT:
        env = _make_with_vector_entry_point(
            id, env_spec, num_envs, vector_kwargs, wrappers, env_kwargs
        )
    else:
        if env_spec.entry_point is None:
            raise error.Error(
                f"Cannot create vectorized environment for {env_spec.id} because it doesn't have "
                "an entry point defined."
            )
        from palaestra import vector  # lazy: import-time — multiprocessing, ~30 ms

        def create_single_env() -> Env[Any, Any]:
            single_env = make(env_spec, **env_kwargs.copy())
            for wrapper in wrappers:
                single_env = wrapper(single_env)
            return single_env

        vector_cls = vector.SyncVectorEnv if mode is VectorizeMode.SYNC else vector.AsyncVectorEnv
        env = vector_cls([create_single_env for _ in range(num_envs)], **vector_kwargs)

    # Record how the vector env was made, so that make_vec(env.spec) makes it again.
    saved = copy.deepcopy(env_spec)
    saved.kwargs = env_kwargs.copy()
    if num_envs != 1:
        saved.kwargs["num_envs"] = num_envs
    saved.kwargs["vectorization_mode"] = mode.value
    if vector_kwargs:
        saved.kwargs["vector_kwargs"] = vector_kwargs
    if wrappers:
        saved.kwargs["wrappers"] = wrappers
    env.unwrapped.spec = saved
    _check_autoreset_metadata(env)
    return env


def _make_with_vector_entry_point(
    id: str | EnvSpec,
    env_spec: EnvSpec,
    num_envs: int,
    vector_kwargs: dict[str, Any],
    wrappers: Sequence[Any],
    env_kwargs: dict[str, Any],
) -> Any:
    native = native_batch(env_spec)
    if native is not None and set(vector_kwargs) <= _NATIVE_VECTOR_KWARGS:
        env_kwargs = {**env_kwargs, **vector_kwargs}
        vector_kwargs = {}
    if vector_kwargs:
        raise error.Error(
            "Custom vector environment can be passed arguments only through kwargs and "
            f"`vector_kwargs` is not empty ({vector_kwargs})"
        )
    if wrappers:
        raise error.Error(
            f"Cannot use `vector_entry_point` vectorization mode with the wrappers argument "
            f"({wrappers})."
        )
    if env_spec.additional_wrappers:
        raise error.Error(
            "Cannot use `vector_entry_point` vectorization mode with the additional_wrappers "
            f"parameter in spec being not empty ({env_spec.additional_wrappers})."
        )
    entry = env_spec.vector_entry_point
    if entry is None:
        raise error.Error(
            f"Cannot create vectorized environment for {id} because it doesn't have a vector "
            "entry point defined."
        )
    if native is not None and env_kwargs.get("render_mode") is not None:
        env_creator: Callable[..., Any] = functools.partial(_rendering_envs, native[1])
    elif native is not None:
        from palaestra.vector.native import (  # lazy: import-time — multiprocessing
            batched_vector_env,
        )

        env_creator = functools.partial(batched_vector_env, *native)
    else:
        env_creator = load_env_creator(entry) if isinstance(entry, str) else entry
    if env_spec.max_episode_steps is not None and "max_episode_steps" not in env_kwargs:
        env_kwargs["max_episode_steps"] = env_spec.max_episode_steps
    return env_creator(num_envs=num_envs, **env_kwargs)


def _rendering_envs(
    env_cls: Any,
    num_envs: int = 1,
    max_episode_steps: int | None = None,
    render_mode: str | None = None,
    copy: bool = True,
    autoreset_mode: Any = None,  # None: the vector env's default (AutoresetMode.NEXT_STEP)
    **env_kwargs: Any,
) -> Any:
    """What ``make_vec`` builds, with a ``render_mode``, for an id whose vector entry point is a
    native batch: batches do not draw, so the envs run as real envs (with the wrappers
    ``make()`` adds) in a ``SyncVectorEnv``."""
    from palaestra import vector  # lazy: import-time — multiprocessing, ~30 ms
    from palaestra.wrappers.common import (  # lazy: import-time — passive env checker
        OrderEnforcing,
        PassiveEnvChecker,
        TimeLimit,
    )

    def one() -> Env[Any, Any]:
        env = OrderEnforcing(PassiveEnvChecker(env_cls(render_mode=render_mode, **env_kwargs)))
        return env if max_episode_steps is None else TimeLimit(env, max_episode_steps)

    autoreset_mode = autoreset_mode or vector.AutoresetMode.NEXT_STEP
    return vector.SyncVectorEnv([one] * num_envs, copy=copy, autoreset_mode=autoreset_mode)


def _check_autoreset_metadata(env: Any) -> None:
    """Warn, as Gymnasium does, when a vector env does not declare its autoreset mode."""
    from palaestra.vector import AutoresetMode  # lazy: import-time — multiprocessing

    if "autoreset_mode" not in env.metadata:
        logger.warn(
            f"The VectorEnv ({env}) is missing AutoresetMode metadata, metadata={env.metadata}"
        )
    elif not isinstance(env.metadata["autoreset_mode"], AutoresetMode):
        logger.warn(
            f"The VectorEnv ({env}) metadata['autoreset_mode'] is not an instance of "
            f"AutoresetMode, {type(env.metadata['autoreset_mode'])}."
        )
