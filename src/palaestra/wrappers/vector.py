"""``gymnasium.wrappers.vector`` at the path Gymnasium users write it.

``from palaestra.wrappers.vector import DictInfoToList`` works as the Gymnasium import does;
the wrappers themselves live in :mod:`palaestra.vector.wrappers` (one definition, two paths).
"""

from palaestra.vector.wrappers import *  # noqa: F403 - this module is a second path to them
from palaestra.vector.wrappers import __all__ as __all__
