"""``EnvSpec`` and ``WrapperSpec``: what ``make()`` needs to rebuild an environment, and ids.

An id is ``[namespace/]Name[-vN]``; :func:`parse_env_id` splits it and :func:`get_env_id`
joins it again. Both specs are plain dataclasses so that a spec survives ``deepcopy``, pickling
and a JSON round trip (:meth:`EnvSpec.to_json` / :meth:`EnvSpec.from_json`).
"""

from __future__ import annotations

import dataclasses
import json
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Any, Protocol

from palaestra import error

if TYPE_CHECKING:
    from palaestra.core import Env

__all__ = [
    "ENV_ID_RE",
    "EnvCreator",
    "EnvSpec",
    "VectorizeMode",
    "WrapperSpec",
    "get_env_id",
    "install_maker",
    "parse_env_id",
]

# Gymnasium's id grammar, kept character for character so that every id valid there is valid
# here: the name is lazy so that a trailing "-vN" is read as the version, not part of the name.
ENV_ID_RE = re.compile(
    r"^(?:(?P<namespace>[\w:-]+)\/)?(?:(?P<name>[\w:.-]+?))(?:-v(?P<version>\d+))?$"
)


# The function `EnvSpec.make` calls: `palaestra.envs.registration.make`, installed by the
# registry when it is imported, so that the spec (used by `core`) never imports the registry.
_maker: Callable[..., Env[Any, Any]] | None = None


def install_maker(maker: Callable[..., Env[Any, Any]]) -> None:
    """Make ``maker`` the function :meth:`EnvSpec.make` calls (the registry's ``make``)."""
    global _maker
    _maker = maker


class EnvCreator(Protocol):
    """Anything that builds an environment from keyword arguments (usually the class)."""

    def __call__(self, **kwargs: Any) -> Env[Any, Any]: ...


class VectorizeMode(Enum):
    """How :func:`~palaestra.envs.registration.make_vec` vectorizes an environment."""

    ASYNC = "async"
    SYNC = "sync"
    VECTOR_ENTRY_POINT = "vector_entry_point"


def parse_env_id(env_id: str) -> tuple[str | None, str, int | None]:
    """Split ``[namespace/]Name[-vN]`` into ``(namespace, name, version)``.

    >>> parse_env_id("ALE/Breakout-v5")
    ('ALE', 'Breakout', 5)
    >>> parse_env_id("CartPole")
    (None, 'CartPole', None)
    """
    match = ENV_ID_RE.fullmatch(env_id)
    if not match:
        raise error.Error(
            f"Malformed environment ID: {env_id}. (Currently all IDs must be of the form "
            "[namespace/](env-name)-v(version). (namespace is optional))"
        )
    ns, name, version = match.group("namespace", "name", "version")
    return ns, name, None if version is None else int(version)


def get_env_id(ns: str | None, name: str, version: int | None) -> str:
    """Join a namespace, name and version into an id; the inverse of :func:`parse_env_id`.

    >>> get_env_id("ALE", "Pong", 5), get_env_id(None, "CartPole", None)
    ('ALE/Pong-v5', 'CartPole')
    """
    full_name = name if ns is None else f"{ns}/{name}"
    return full_name if version is None else f"{full_name}-v{version}"


@dataclass
class WrapperSpec:
    """One wrapper applied by ``make()``: its name, ``"module:Class"`` and constructor kwargs.

    ``kwargs`` is ``None`` when the wrapper does not record its arguments
    (no :class:`~palaestra.utils.record_constructor.RecordConstructorArgs`): it cannot be rebuilt.
    """

    name: str
    entry_point: str
    kwargs: dict[str, Any] | None


@dataclass
class EnvSpec:
    """Everything ``make()`` needs to create an environment; fields as in Gymnasium 1.x.

    >>> spec = EnvSpec("MyEnv-v2", entry_point="my_package:MyEnv", max_episode_steps=100)
    >>> spec.namespace, spec.name, spec.version
    (None, 'MyEnv', 2)
    >>> EnvSpec.from_json(spec.to_json()) == spec
    True
    """

    id: str
    entry_point: EnvCreator | str | None = field(default=None)
    reward_threshold: float | None = field(default=None)
    # True when the same seed and actions may still give different observations.
    nondeterministic: bool = field(default=False)
    max_episode_steps: int | None = field(default=None)
    order_enforce: bool = field(default=True)
    disable_env_checker: bool = field(default=False)
    kwargs: dict[str, Any] = field(default_factory=dict)
    # Derived from `id` in __post_init__.
    namespace: str | None = field(init=False)
    name: str = field(init=False)
    version: int | None = field(init=False)
    additional_wrappers: tuple[WrapperSpec, ...] = field(default_factory=tuple)
    vector_entry_point: Any = field(default=None)  # callable or "module:Class"

    def __post_init__(self) -> None:
        self.namespace, self.name, self.version = parse_env_id(self.id)

    def make(self, **kwargs: Any) -> Env[Any, Any]:
        """``make(self, **kwargs)``."""
        if _maker is None:
            raise error.Error(
                f"EnvSpec.make({self.id!r}) needs palaestra's registry, which installs make() "
                "when it is imported: import palaestra first"
            )
        return _maker(self, **kwargs)

    def to_json(self) -> str:
        """This spec as a JSON string; raises ``ValueError`` if a field holds a callable."""
        spec_dict = dataclasses.asdict(self)
        for derived in ("namespace", "name", "version"):  # rebuilt from `id` on load
            spec_dict.pop(derived)
        for key, value in spec_dict.items():
            if callable(value):
                raise ValueError(
                    f"Callable found in {self.id} for {key} attribute with value={value}. "
                    "Currently, palaestra does not support serialising callables."
                )
        return json.dumps(spec_dict)

    @staticmethod
    def from_json(json_env_spec: str) -> EnvSpec:
        """Rebuild a spec (wrappers included) from :meth:`to_json` output."""
        parsed = json.loads(json_env_spec)
        wrappers: list[WrapperSpec] = []
        for wrapper_json in parsed.pop("additional_wrappers"):
            try:
                wrappers.append(WrapperSpec(**wrapper_json))
            except Exception as e:
                raise ValueError(
                    f"An issue occurred when trying to make {wrapper_json} a WrapperSpec"
                ) from e
        try:
            env_spec = EnvSpec(**parsed)
        except Exception as e:
            raise ValueError(f"An issue occurred when trying to make {parsed} an EnvSpec") from e
        env_spec.additional_wrappers = tuple(wrappers)
        return env_spec

    def pprint(
        self,
        disable_print: bool = False,
        include_entry_points: bool = False,
        print_all: bool = False,
    ) -> str | None:
        """Print the fields that differ from their defaults (all with ``print_all``).

        >>> EnvSpec("Toy-v0", max_episode_steps=5).pprint()
        id=Toy-v0
        max_episode_steps=5
        """
        lines = [f"id={self.id}"]
        if print_all or include_entry_points:
            lines.append(f"entry_point={self.entry_point}")
        defaults = (
            ("reward_threshold", None),
            ("nondeterministic", False),
            ("max_episode_steps", None),
            ("order_enforce", True),
            ("disable_env_checker", False),
        )
        for name, default in defaults:
            value = getattr(self, name)
            if print_all or value is not default:
                lines.append(f"{name}={value}")
        if print_all or self.additional_wrappers:
            wrappers = [
                f"\n\tname={w.name}, entry_point={w.entry_point}, kwargs={w.kwargs}"
                if include_entry_points
                else f"\n\tname={w.name}, kwargs={w.kwargs}"
                for w in self.additional_wrappers
            ]
            lines.append(
                f"additional_wrappers=[{','.join(wrappers)}\n]"
                if wrappers
                else "additional_wrappers=[]"
            )
        output = "\n".join(lines)
        if disable_print:
            return output
        print(output)
        return None
