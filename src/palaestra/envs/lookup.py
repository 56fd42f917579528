"""The registry of environment ids, and the lookups that turn an id into an ``EnvSpec``.

Lookups and their errors follow Gymnasium 1.x word for word, so that a message a user searches
for reads the same: malformed ids, unknown namespaces and names (with "Did you mean"), missing and
deprecated versions, and unversioned ids that resolve to the latest version.
"""

from __future__ import annotations

import contextlib
import difflib
import importlib
import importlib.util
import re
from collections import defaultdict
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from palaestra import error, logger
from palaestra.env_spec import (
    EnvCreator,
    EnvSpec,
    WrapperSpec,
    get_env_id,
    parse_env_id,
)

registry: dict[str, EnvSpec] = {}


@dataclass(frozen=True)
class ForeignRegistry:
    """Another library's registry, reached by an id prefix (``"gymnasium:Taxi-v4"``).

    ``make``, ``make_vec`` and ``spec`` take the same arguments as palaestra's own and receive
    the id (or spec) with its prefix.
    """

    make: Callable[..., Any]
    make_vec: Callable[..., Any]
    spec: Callable[[str], EnvSpec]


# id prefix -> the registry that makes such ids. Filled by the package that talks to the
# other library (`palaestra.compat` adds "gymnasium:"), so the registry never imports it.
foreign_registries: dict[str, ForeignRegistry] = {}


def foreign_registry(id: Any) -> ForeignRegistry | None:
    """The registry of another library that ``id`` (an id or a spec) names by its prefix."""
    name = id.id if isinstance(id, EnvSpec) else id
    if isinstance(name, str):
        for prefix, found in foreign_registries.items():
            if name.startswith(prefix):
                return found
    return None


# Namespaces that an optional package provides: namespace -> (import name, pip name, extra).
# An unknown id in one of them gets "pip install palaestra[extra]" instead of "not found".
NAMESPACE_PACKAGES: dict[str, tuple[str, str, str]] = {"ALE": ("ale_py", "ale-py", "atari")}


def _package_installed(module_name: str) -> bool:
    return importlib.util.find_spec(module_name) is not None


def find_highest_version(ns: str | None, name: str) -> int | None:
    """The highest registered version of ``[ns/]name``, or ``None`` if it has no versions."""
    versions = [
        s.version
        for s in registry.values()
        if s.namespace == ns and s.name == name and s.version is not None
    ]
    return max(versions, default=None)


def _check_namespace_exists(ns: str | None) -> None:
    if ns is None:
        return
    namespaces = {s.namespace for s in registry.values() if s.namespace is not None}
    if ns in namespaces:
        return
    if ns in NAMESPACE_PACKAGES:
        module_name, pip_name, extra = NAMESPACE_PACKAGES[ns]
        if not _package_installed(module_name):
            raise error.dependency_not_installed(pip_name, extra, f"the {ns}/ environments")
    suggestion = difflib.get_close_matches(ns, namespaces, n=1)
    if suggestion:
        hint = f"Did you mean: `{suggestion[0]}`?"
    else:
        hint = f"Have you installed the proper package for {ns}?"
    raise error.NamespaceNotFound(f"Namespace {ns} not found. {hint}")


# Gymnasium 1.x's own envs that palaestra does not implement (name -> latest version): an id
# naming one of them gets the `gymnasium:` bridge in its error instead of a bare "not found".
# (Toy text and Box2D are native since issue 15, MuJoCo since issue 27: what is left are the
# Shimmy compatibility ids, which need `shimmy` beside Gymnasium.)
GYMNASIUM_ONLY: dict[str, int] = {"GymV21Environment": 0, "GymV26Environment": 0}


def _check_name_exists(ns: str | None, name: str) -> None:
    _check_namespace_exists(ns)
    names = {s.name for s in registry.values() if s.namespace == ns}
    if name in names:
        return
    suggestion = difflib.get_close_matches(name, names, n=1)
    namespace_msg = f" in namespace {ns}" if ns else ""
    suggestion_msg = f" Did you mean: `{suggestion[0]}`?" if suggestion else ""
    if ns is None and name in GYMNASIUM_ONLY:
        # Gymnasium's latest version: an older one is refused by Gymnasium as deprecated.
        env_id = get_env_id(None, name, GYMNASIUM_ONLY[name])
        suggestion_msg = (
            f" Gymnasium has it: make it through the bridge with "
            f'`make("gymnasium:{env_id}")` (with gymnasium and that env\'s own dependencies '
            "installed)."
        )
    raise error.NameNotFound(f"Environment `{name}` doesn't exist{namespace_msg}.{suggestion_msg}")


def _check_version_exists(ns: str | None, name: str, version: int | None) -> None:
    """Raise the most helpful error for an id that is not registered (nothing if it is)."""
    if get_env_id(ns, name, version) in registry:
        return
    _check_name_exists(ns, name)
    if version is None:
        return
    unversioned_id = get_env_id(ns, name, None)
    message = f"Environment version `v{version}` for environment `{unversioned_id}` doesn't exist."
    same_name = sorted(
        (s for s in registry.values() if s.namespace == ns and s.name == name),
        key=lambda s: -1 if s.version is None else s.version,
    )
    default_spec = [s for s in same_name if s.version is None]
    if default_spec:
        message += f" It provides the default version `{default_spec[0].id}`."
        if len(same_name) == 1:
            raise error.DeprecatedEnv(message)
    versioned = [s for s in same_name if s.version is not None]
    latest = max(versioned, key=lambda s: s.version or 0, default=None)
    if latest is not None and latest.version is not None and version > latest.version:
        listed = ", ".join(f"`v{s.version}`" for s in same_name)
        raise error.VersionNotFound(f"{message} It provides versioned environments: [ {listed} ].")
    if latest is not None and latest.version is not None and version < latest.version:
        raise error.DeprecatedEnv(
            f"Environment version v{version} for `{unversioned_id}` is deprecated. "
            f"Please use `{latest.id}` instead."
        )


def _check_spec_register(new: EnvSpec) -> None:
    """Refuse to mix versioned and unversioned ids of one name (lookups would be ambiguous)."""
    same_name = [
        s for s in registry.values() if s.namespace == new.namespace and s.name == new.name
    ]
    unversioned = next((s for s in same_name if s.version is None), None)
    latest = max(
        (s for s in same_name if s.version is not None), key=lambda s: s.version or 0, default=None
    )
    if unversioned is not None and new.version is not None:
        raise error.RegistrationError(
            f"Can't register the versioned environment `{new.id}` when the unversioned "
            f"environment `{unversioned.id}` of the same name already exists."
        )
    if latest is not None and new.version is None:
        raise error.RegistrationError(
            f"Can't register the unversioned environment `{new.id}` when the versioned "
            f"environment `{latest.id}` of the same name already exists. Note: the default "
            "behavior is that `gym.make` with the unversioned environment will return the latest "
            "versioned environment"
        )


# Set by `namespace(...)`: ids registered inside the block get this namespace (plugin loading).
current_namespace: str | None = None


@contextlib.contextmanager
def namespace(ns: str) -> Iterator[None]:
    """Register every id inside the ``with`` block under namespace ``ns``."""
    global current_namespace
    previous, current_namespace = current_namespace, ns
    try:
        yield
    finally:
        current_namespace = previous


def register(
    id: str,
    entry_point: EnvCreator | str | None = None,
    reward_threshold: float | None = None,
    nondeterministic: bool = False,
    max_episode_steps: int | None = None,
    order_enforce: bool = True,
    disable_env_checker: bool = False,
    additional_wrappers: tuple[WrapperSpec, ...] = (),
    vector_entry_point: Any = None,
    kwargs: dict[str, Any] | None = None,
) -> None:
    """Register ``id`` so that ``make(id)`` calls ``entry_point`` (callable or "module:Name")."""
    if entry_point is None and vector_entry_point is None:
        raise ValueError("Either `entry_point` or `vector_entry_point` (or both) must be provided")
    kwargs = {} if kwargs is None else kwargs
    if current_namespace is not None:
        if kwargs.get("namespace") not in (None, current_namespace):
            logger.warn(
                f"Custom namespace `{kwargs.get('namespace')}` is being overridden by namespace "
                f"`{current_namespace}`. If you are developing a plugin you shouldn't specify a "
                "namespace in `register` calls. The namespace is specified through the entry "
                "point package metadata."
            )
        _, name, version = parse_env_id(id)
        id = get_env_id(current_namespace, name, version)
    new_spec = EnvSpec(
        id=id,
        entry_point=entry_point,
        reward_threshold=reward_threshold,
        nondeterministic=nondeterministic,
        max_episode_steps=max_episode_steps,
        order_enforce=order_enforce,
        disable_env_checker=disable_env_checker,
        kwargs=kwargs,
        additional_wrappers=additional_wrappers,
        vector_entry_point=vector_entry_point,
    )
    _check_spec_register(new_spec)
    if new_spec.id in registry:
        logger.warn(f"Overriding environment {new_spec.id} already in registry.")
    registry[new_spec.id] = new_spec


def register_envs(env_module: ModuleType) -> None:
    """No-op: lets ``import ale_py; register_envs(ale_py)`` keep an import that only registers."""


def spec(env_id: str) -> EnvSpec:
    """The registered :class:`EnvSpec` of ``env_id``; helpful errors if there is none.
    ``"gymnasium:<id>"``: the spec in Gymnasium's registry (what ``make`` would build)."""
    foreign = foreign_registry(env_id)
    if foreign is not None:
        return foreign.spec(env_id)
    env_spec = registry.get(env_id)
    if env_spec is None:
        ns, name, version = parse_env_id(env_id)
        _check_version_exists(ns, name, version)
        raise error.Error(f"No registered env with id: {env_id}")
    return env_spec


def resolve_id(env_id: str) -> EnvSpec:
    """Resolve ``[module:]id``: import ``module`` first, then fall back to the latest version."""
    module, _, env_name = env_id.rpartition(":")
    if ":" in env_id and (not module or ":" in module):
        raise error.InvalidEnvId(
            f"{env_id!r} is not an environment id: expected 'Name-vN' or 'module:Name-vN' "
            "(one ':' after the name of a module to import, which registers the id)"
        )
    if module:
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as e:
            raise ModuleNotFoundError(
                f"{e}. Environment registration via importing a module failed. "
                f"Check whether '{module}' contains env registration and can be imported."
            ) from e
    env_spec = registry.get(env_name)
    ns, name, version = parse_env_id(env_name)
    latest = find_highest_version(ns, name)
    if version is not None and latest is not None and latest > version:
        logger.deprecation(
            f"The environment {env_name} is out of date. You should consider "
            f"upgrading to version `v{latest}`."
        )
    if version is None and latest is not None:
        version = latest
        latest_id = get_env_id(ns, name, version)
        env_spec = registry.get(latest_id)
        logger.warn(
            f"Using the latest versioned environment `{latest_id}` "
            f"instead of the unversioned environment `{env_name}`."
        )
    if env_spec is None:
        _check_version_exists(ns, name, version)
        raise error.Error(
            f"No registered env with id: {env_name}. Did you register it, or import the package "
            "that registers it? Use `palaestra.pprint_registry()` to see all of the registered "
            "environments."
        )
    return env_spec


def load_env_creator(name: str) -> Callable[..., Any]:
    """Import ``"package.module:Attr"`` and return ``Attr`` (usually an env class)."""
    mod_name, attr_name = name.split(":")
    creator: Callable[..., Any] = getattr(importlib.import_module(mod_name), attr_name)
    return creator


def _display_namespace(env_spec: EnvSpec) -> str | None:
    """The heading an id is listed under: its namespace, else guessed from the entry point.

    An id with neither (a callable entry point) is listed under ``None``, as in Gymnasium.
    """
    if env_spec.namespace is not None or not isinstance(env_spec.entry_point, str):
        return env_spec.namespace
    # "palaestra.envs.classic_control.cartpole:CartPoleEnv" -> "classic_control" (Gymnasium's rule)
    parts = re.sub(r":\w+", "", env_spec.entry_point).split(".")
    if len(parts) >= 3:
        return parts[2]
    return parts[1] if len(parts) > 1 else env_spec.name


def pprint_registry(
    print_registry: dict[str, EnvSpec] = registry,
    *,
    num_cols: int = 3,
    exclude_namespaces: list[str] | None = None,
    disable_print: bool = False,
) -> str | None:
    """Print the registered ids grouped by namespace, ``num_cols`` to a row.

    >>> toys = {i: EnvSpec(i, "toys.grid:Env") for i in ("A-v0", "B-v0", "Cee-v1")}
    >>> pprint_registry(toys, num_cols=2)
    ===== grid =====
    A-v0 B-v0
    Cee-v1
    """
    by_namespace: dict[str | None, list[str]] = defaultdict(list)
    width = 0
    for env_spec in print_registry.values():
        by_namespace[_display_namespace(env_spec)].append(env_spec.id)
        # Gymnasium pads to the longest *name*, not id, so long ids touch; kept for parity.
        width = max(width, len(env_spec.name))
    blocks: list[str] = []
    for ns, env_ids in by_namespace.items():
        if exclude_namespaces is not None and ns in exclude_namespaces:
            continue
        block = f"{'=' * 5} {ns} {'=' * 5}\n"
        for count, env_id in enumerate(sorted(env_ids), 1):
            block += env_id.ljust(width) + " "
            if count % num_cols == 0:
                block = block.rstrip(" ")
                if count != len(env_ids):
                    block += "\n"
        blocks.append(block.rstrip(" "))
    output = "\n".join(blocks)
    if disable_print:
        return output
    print(output)
    return None
