"""Moved to :mod:`palaestra.env_spec` (the spec stands alone at the package root, so that
``palaestra.core`` can use it without importing the registry); this path re-exports it."""

from palaestra.env_spec import *  # noqa: F403
from palaestra.env_spec import __all__ as __all__
