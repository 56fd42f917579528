"""What ``to_gymnasium`` and ``from_gymnasium`` adapters share: forwarding to the env they wrap.

Each adapter is an env of one library around an env of the other. Stepping, resetting,
rendering and closing go to the wrapped env, converting values only for the spaces whose
element types differ between the libraries (``Graph``). There is one generator, the wrapped
env's: code that reads or replaces ``np_random`` (or ``unwrapped._np_random``, as Gymnasium's
``check_env`` does) sees the stream the env actually draws from.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, SupportsFloat

import numpy as np

from palaestra.utils.seeding import ForwardedRandom

Convert = Callable[[Any], Any] | None  # None: the value passes as it is


class Forwarding(ForwardedRandom):
    """Mixin for the adapters: ``_inner`` is the wrapped env, ``_act_in`` converts an action
    for it and ``_obs_out`` converts its observations back (each ``None`` when not needed)."""

    _inner: Any
    _wrapped_attr = "_inner"
    _act_in: Convert
    _obs_out: Convert

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        """Step the wrapped env with ``action`` (an element of this adapter's action space)."""
        if self._act_in is not None:
            action = self._act_in(action)
        obs, reward, terminated, truncated, info = self._inner.step(action)
        if self._obs_out is not None:
            obs = self._obs_out(obs)
        return obs, reward, terminated, truncated, info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset the wrapped env; ``seed`` seeds its generator (both libraries seed alike)."""
        obs, info = self._inner.reset(seed=seed, options=options)
        if self._obs_out is not None:
            obs = self._obs_out(obs)
        return obs, info

    def render(self) -> Any:
        """The wrapped env's frame for its ``render_mode``."""
        return self._inner.render()

    def close(self) -> None:
        """Close the wrapped env."""
        self._inner.close()

    @property
    def render_mode(self) -> str | None:
        """The wrapped env's render mode."""
        return self._inner.render_mode

    @property
    def metadata(self) -> dict[str, Any]:
        """The wrapped env's metadata (``render_modes``, ``render_fps``)."""
        return self._inner.metadata

    @property
    def _np_random(self) -> np.random.Generator | None:
        return self._inner.unwrapped._np_random

    def __str__(self) -> str:
        return f"<{type(self).__name__}{self._inner}>"

    def __repr__(self) -> str:
        return str(self)
