"""``gymnasium.wrappers.vector`` at the path Gymnasium users write it.

``from palaestra.wrappers.vector import DictInfoToList`` works as the Gymnasium import does;
the wrappers themselves live in :mod:`palaestra.vector.wrappers` (one definition, two paths).
``ArrayConversion`` and ``NumpyToTorch`` are read on first use (they import torch).
"""

from typing import Any

from palaestra.vector import wrappers as _wrappers

__all__ = list(_wrappers.__all__)
globals().update(
    {name: getattr(_wrappers, name) for name in __all__ if name not in _wrappers.LAZY_NAMES}
)


def __getattr__(name: str) -> Any:  # PEP 562: a second path to the lazy ones
    if name in _wrappers.LAZY_NAMES:
        return getattr(_wrappers, name)
    raise AttributeError(f"module 'palaestra.wrappers.vector' has no attribute {name!r}")
