"""SB3's ``patch_gym`` (``stable_baselines3.common.vec_env.patch_gym``): ``_patch_env`` and
``_convert_space`` turn what a user hands over into the library's own env and space types.

In SB3 they turn OpenAI Gym objects into Gymnasium ones (through shimmy). Here the library's
own types are palaestra's: a palaestra env or space comes back as it is, a Gymnasium one is
adapted (``palaestra.compat.from_gymnasium`` / ``from_gymnasium_space``), and anything else,
OpenAI Gym objects included, is a ``ValueError`` naming its type and the way through Gymnasium.
Gymnasium is never imported here: an object can only be a Gymnasium one if its user imported
Gymnasium already.
"""

from __future__ import annotations

import sys
from typing import Any

from palaestra import spaces
from palaestra.core import Env

__all__: list[str] = []  # SB3's names here are private; its users import them by name

_GYM_HINT = (
    "an OpenAI Gym object can be converted to Gymnasium first with shimmy "
    "(`pip install 'shimmy>=2.0'`, `shimmy.GymV26CompatibilityV0(env=env)`)"
)


def _gymnasium() -> Any:
    """The Gymnasium module if something imported it, else None."""
    return sys.modules.get("gymnasium")


def _patch_env(env: Any) -> Env[Any, Any]:
    """``env`` as a palaestra env: itself, or a Gymnasium env adapted by ``from_gymnasium``."""
    if isinstance(env, Env):
        return env
    gymnasium = _gymnasium()
    if gymnasium is not None and isinstance(env, gymnasium.Env):
        from palaestra.compat import from_gymnasium  # lazy: optional-dep — gymnasium

        return from_gymnasium(env)
    raise ValueError(
        f"The environment is of type {type(env)}, not a palaestra or Gymnasium environment; "
        f"{_GYM_HINT}"
    )


def _convert_space(space: Any) -> spaces.Space[Any]:
    """``space`` as a palaestra space: itself, or a Gymnasium space converted."""
    if isinstance(space, spaces.Space):
        return space
    gymnasium = _gymnasium()
    if gymnasium is not None and isinstance(space, gymnasium.spaces.Space):
        from palaestra.compat import from_gymnasium_space  # lazy: optional-dep — gymnasium

        return from_gymnasium_space(space)
    raise ValueError(
        f"The space is of type {type(space)}, not a palaestra or Gymnasium space; {_GYM_HINT}"
    )
