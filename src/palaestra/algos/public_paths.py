"""The paths users import from, mapped to the modules that hold the code, and the import hook
that makes each one the same module object as its target (never a second copy).

``algos/`` is laid out as SB3's package is: shared code in ``common/``, one package per
algorithm. Users port SB3 code by a fixed substitution (``stable_baselines3.common.X`` and
``stable_baselines3.X`` -> ``palaestra.algos.X``), so ``palaestra.algos.callbacks`` and the
others stay importable for good: ``palaestra.algos.callbacks is palaestra.algos.common.callbacks``.
The hook imports a target only when its alias is first imported, as a plain import would.

``MOVED_CLASSES`` is the other half of the promise: model files name classes by
``module:qualname`` (``model_io.encode_classes``), and a file written before a class moved
keeps loading through it. Both tables only grow.

The tables are data, in ``public_paths.json`` beside this file, with every public SB3 module
(``SB3_MODULES``), the README's import table and the paths SPEC promises; the tests walk SB3's
public modules and names against it (``tests/algos/test_sb3_public_names.py``).
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import itertools
import json
import sys
import types
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "DATA_FILE",
    "MODULE_ALIASES",
    "MOVED_CLASSES",
    "MOVED_MODULES",
    "README_TABLE",
    "SB3_MODULES",
    "aliased",
    "install",
    "markdown_table",
    "public_ref",
    "resolve_moved",
    "sb3_path",
]

# One data file holds every public path (its "about" says what each table is); the README's
# import table is generated from it (``python -m tests.algos.public_names --write``).
DATA_FILE = Path(__file__).with_name("public_paths.json")
_DATA: dict[str, Any] = json.loads(DATA_FILE.read_text(encoding="utf-8"))

# SB3's module -> the palaestra module at its substituted path (``sb3_path``); None: not here yet.
SB3_MODULES: dict[str, str | None] = _DATA["sb3_modules"]
# "old.module:Qualname" a model file may name -> where that class lives now. Modules that
# moved whole map every class through MOVED_MODULES; classes that left a module are listed.
MOVED_MODULES: dict[str, str] = _DATA["moved_modules"]
MOVED_CLASSES: dict[str, str] = _DATA["moved_classes"]
# rows of the README's import table: Gymnasium/SB3 paths or statements ("theirs") -> palaestra's
# ("ours"), with the names a ``.*`` row promises and a note
README_TABLE: list[dict[str, Any]] = _DATA["readme_table"]


def sb3_path(module: str) -> str:
    """The palaestra path of SB3's module ``module``, by the one porting substitution.

    >>> sb3_path("stable_baselines3.common.vec_env.vec_normalize")
    'palaestra.algos.vec_env.vec_normalize'
    >>> sb3_path("stable_baselines3.dqn.policies"), sb3_path("stable_baselines3.common")
    ('palaestra.algos.dqn.policies', 'palaestra.algos.common')
    """
    parts = module.split(".")
    if parts[0] != "stable_baselines3":
        raise ValueError(f"not a stable_baselines3 module: {module!r}")
    if parts[1:2] == ["common"] and len(parts) > 2:
        parts = parts[1:]
    return ".".join(["palaestra", "algos", *parts[1:]])


def _module_aliases() -> dict[str, str]:
    """palaestra's own aliases first (``public_ref`` records a class by the first alias of its
    module), then each SB3 path that is another module and no alias above it already makes so."""
    aliases: dict[str, str] = dict(_DATA["aliases"])
    for theirs, real in SB3_MODULES.items():
        path = sb3_path(theirs)
        if real is not None and path != real and _resolve_alias(aliases, path) != real:
            aliases[path] = real
    return aliases


def _resolve_alias(aliases: dict[str, str], name: str) -> str | None:
    if name in aliases:
        return aliases[name]
    package = name.rpartition(".")[0]
    while package:
        target = aliases.get(package)
        if target is not None:
            return f"{target}.{name[len(package) + 1 :]}"
        package = package.rpartition(".")[0]
    return None


# public path -> the module it is (see _module_aliases)
MODULE_ALIASES: dict[str, str] = _module_aliases()


def aliased(name: str) -> str | None:
    """The module the public path ``name`` stands for, or None where it is no alias."""
    return _resolve_alias(MODULE_ALIASES, name)


def resolve_moved(ref: str) -> str:
    """The ``module:qualname`` where the class a model file names as ``ref`` lives now."""
    if ref in MOVED_CLASSES:
        return MOVED_CLASSES[ref]
    module, sep, qualname = ref.partition(":")
    module = MOVED_MODULES.get(module) or aliased(module) or module
    return f"{module}{sep}{qualname}"


def markdown_table() -> str:
    """The README's import table, generated from ``README_TABLE``."""
    lines = ["| Gymnasium / SB3 | palaestra |", "|---|---|"]
    for row in README_TABLE:
        theirs = ", ".join(f"`{path}`" for path in _shortened(row["theirs"]))
        if row.get("names"):
            theirs += " (" + ", ".join(f"`{name}`" for name in row["names"]) + ")"
        ours = ", ".join(f"`{path}`" for path in row["ours"])
        if row.get("note"):
            ours += f" ({row['note']})"
        lines.append(f"| {theirs} | {ours} |")
    return "\n".join(lines) + "\n"


def _shortened(paths: list[str]) -> list[str]:
    """Each path after the first without the packages it shares with the one before
    (``…get_monitor_files`` after ``stable_baselines3.common.monitor.load_results``)."""
    out = paths[:1]
    for before, path in itertools.pairwise(paths):
        shared = 0
        if " " not in before + path:  # statements stay whole
            for a, b in zip(before.split(".")[:-1], path.split(".")[:-1]):
                if a != b:
                    break
                shared += 1
        out.append("…" + path.split(".", shared)[-1] if shared else path)
    return out


def public_ref(cls: type) -> str:
    """``module:qualname`` for ``cls`` at the path users import it from: a public alias of its
    module, else the nearest package above its module that exports it (``palaestra.algos.dqn``
    for ``palaestra.algos.dqn.policies.DQNPolicy``), else where it is defined."""
    module, qualname = cls.__module__, cls.__qualname__
    public: dict[str, str] = {}
    for alias, real in MODULE_ALIASES.items():  # the first alias is the documented one
        if real.startswith("palaestra.algos."):
            public.setdefault(real, alias)
    if module in public:
        return f"{public[module]}:{qualname}"
    if module.startswith("palaestra.algos.") and "." not in qualname:
        parts = module.split(".")
        for end in range(len(parts) - 1, 2, -1):
            package = sys.modules.get(".".join(parts[:end]))
            if package is not None and getattr(package, qualname, None) is cls:
                return f"{package.__name__}:{qualname}"
    return f"{module}:{qualname}"


class _AliasLoader(importlib.abc.Loader):
    """Hands the import system the already-imported target module as the alias's module."""

    def __init__(self, target: types.ModuleType) -> None:
        self.target = target
        self.target_spec = target.__spec__

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        return self.target

    def exec_module(self, module: types.ModuleType) -> None:
        # module_from_spec stamped the alias's spec on the module; it keeps its own
        module.__spec__ = self.target_spec


class _AliasFinder(importlib.abc.MetaPathFinder):
    def find_spec(
        self,
        fullname: str,
        path: Sequence[str] | None,
        target: types.ModuleType | None = None,
    ) -> importlib.machinery.ModuleSpec | None:
        real = aliased(fullname)
        if real is None:
            return None
        module = importlib.import_module(real)
        return importlib.machinery.ModuleSpec(fullname, _AliasLoader(module))


_FINDER = _AliasFinder()


def install() -> None:
    """Put the alias hook on ``sys.meta_path`` (once)."""
    if _FINDER not in sys.meta_path:
        sys.meta_path.insert(0, _FINDER)


install()
