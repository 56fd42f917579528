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
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
from collections.abc import Sequence

__all__ = [
    "MODULE_ALIASES",
    "MOVED_CLASSES",
    "MOVED_MODULES",
    "aliased",
    "install",
    "public_ref",
    "resolve_moved",
]

# public path -> the module it is. Documented (README's import table, SPEC) or SB3's rule.
MODULE_ALIASES: dict[str, str] = {
    "palaestra.algos.action_noise": "palaestra.algos.common.action_noise",
    "palaestra.algos.buffers": "palaestra.algos.common.buffers",
    "palaestra.algos.callbacks": "palaestra.algos.common.callbacks",
    "palaestra.algos.distributions": "palaestra.algos.common.distributions",
    "palaestra.algos.env_checker": "palaestra.algos.common.env_checker",
    "palaestra.algos.evaluation": "palaestra.algos.common.evaluation",
    "palaestra.algos.logger": "palaestra.algos.common.logger",
    "palaestra.algos.networks": "palaestra.algos.common.networks",
    "palaestra.algos.policies": "palaestra.algos.common.policies",
    "palaestra.algos.preprocessing": "palaestra.algos.common.preprocessing",
    "palaestra.algos.results_plotter": "palaestra.algos.common.results_plotter",
    "palaestra.algos.schedules": "palaestra.algos.common.schedules",
    "palaestra.algos.utils": "palaestra.algos.common.utils",
    # SB3's module names where palaestra's differ, so the substitution has no exceptions
    "palaestra.algos.base_class": "palaestra.algos.common.base",
    "palaestra.algos.noise": "palaestra.algos.common.action_noise",
    "palaestra.algos.off_policy_algorithm": "palaestra.algos.common.off_policy",
    "palaestra.algos.on_policy_algorithm": "palaestra.algos.common.on_policy",
    "palaestra.algos.torch_layers": "palaestra.algos.common.networks",
    # SB3's env-side common modules, which live with the envs here (a package's submodules
    # come with it: palaestra.algos.vec_env.normalize is palaestra.vec_env.normalize)
    "palaestra.algos.env_util": "palaestra.vec_env.env_util",
    "palaestra.algos.monitor": "palaestra.wrappers.monitor",
    "palaestra.algos.running_mean_std": "palaestra.wrappers.running_mean_std",
    "palaestra.algos.vec_env": "palaestra.vec_env",
    # never documented; palaestra.compat.sb3 imports it by this path (move it to
    # palaestra.algos.common.model_io there, then this line may go)
    "palaestra.algos.model_io": "palaestra.algos.common.model_io",
}

# "old.module:Qualname" a model file may name -> where that class lives now. Modules that
# moved whole map every class through MOVED_MODULES; classes that left a module are listed.
MOVED_MODULES: dict[str, str] = {
    "palaestra.algos.continuous_policies": "palaestra.algos.common.continuous_policies",
}
MOVED_CLASSES: dict[str, str] = {
    "palaestra.algos.off_policy_policies:DQNPolicy": "palaestra.algos.dqn:DQNPolicy",
    "palaestra.algos.off_policy_policies:SACPolicy": "palaestra.algos.sac:SACPolicy",
    "palaestra.algos.off_policy_policies:TD3Policy": "palaestra.algos.td3:TD3Policy",
    "palaestra.algos.policies:QNetwork": "palaestra.algos.dqn:QNetwork",
}


def aliased(name: str) -> str | None:
    """The module the public path ``name`` stands for, or None where it is no alias."""
    if name in MODULE_ALIASES:
        return MODULE_ALIASES[name]
    package = name.rpartition(".")[0]
    while package:
        target = MODULE_ALIASES.get(package)
        if target is not None:
            return f"{target}.{name[len(package) + 1 :]}"
        package = package.rpartition(".")[0]
    return None


def resolve_moved(ref: str) -> str:
    """The ``module:qualname`` where the class a model file names as ``ref`` lives now."""
    if ref in MOVED_CLASSES:
        return MOVED_CLASSES[ref]
    module, sep, qualname = ref.partition(":")
    module = MOVED_MODULES.get(module) or aliased(module) or module
    return f"{module}{sep}{qualname}"


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
