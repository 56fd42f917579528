"""Standard wrappers, imported on first use so that ``import palaestra`` stays fast.

Each public name maps to the submodule that defines it; ``palaestra.wrappers.TimeLimit`` imports
``palaestra.wrappers.common`` the first time it is read.
"""

from __future__ import annotations

import importlib
from typing import Any

# name -> submodule of palaestra.wrappers that defines it
_LAZY: dict[str, str] = {
    # applied by make()
    "TimeLimit": "common",
    "OrderEnforcing": "common",
    "PassiveEnvChecker": "common",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:  # PEP 562 module attribute, not wrapper forwarding
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'palaestra.wrappers' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"palaestra.wrappers.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
