"""Interop with Gymnasium and Stable-Baselines3, the one place palaestra talks to them.

Gymnasium (needs ``pip install gymnasium``; imported on first use):

- ``to_gymnasium(env)``: a palaestra env as a real ``gymnasium.Env`` (e.g. for SB3);
- ``from_gymnasium(env)``: any ``gymnasium.Env`` as a palaestra env (e.g. for palaestra's DQN);
- ``to_gymnasium_space`` / ``from_gymnasium_space``: every standard space type, both ways;
- ``palaestra.make("gymnasium:Taxi-v4")`` / ``make_vec("gymnasium:...")``: Gymnasium's registry.

Stable-Baselines3 (needs neither SB3 nor Gymnasium, only torch):

- ``from_sb3(path, env=None)``: a DQN or PPO ``MlpPolicy`` model file saved by SB3, as a palaestra
  ``DQN``/``PPO`` with the same weights. Nothing in the file is unpickled: ``policy.pth`` is
  read by :func:`read_torch_state_dict`, which interprets the pickle opcodes of a tensor
  ``state_dict`` as data and refuses every other callable (``UnsafeFileError``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from palaestra.compat.adapters import (
        GymnasiumEnvAdapter,
        PalaestraEnvAdapter,
        from_gymnasium,
        to_gymnasium,
    )
    from palaestra.compat.sb3 import from_sb3
    from palaestra.compat.spaces import (
        from_gymnasium_space,
        from_gymnasium_value,
        to_gymnasium_space,
        to_gymnasium_value,
    )
    from palaestra.compat.torch_file import UnsafeFileError, read_torch_state_dict

# Each name lives in a module that imports its optional dependency (gymnasium, torch) at the top:
# importing palaestra.compat itself stays free, and the first use says what is missing.
_WHERE = {
    "to_gymnasium": "adapters",
    "GymnasiumEnvAdapter": "adapters",
    "from_gymnasium": "adapters",
    "PalaestraEnvAdapter": "adapters",
    "to_gymnasium_space": "spaces",
    "from_gymnasium_space": "spaces",
    "to_gymnasium_value": "spaces",
    "from_gymnasium_value": "spaces",
    "from_sb3": "sb3",
    "read_torch_state_dict": "torch_file",
    "UnsafeFileError": "torch_file",
}

__all__ = [
    "GymnasiumEnvAdapter",
    "PalaestraEnvAdapter",
    "UnsafeFileError",
    "from_gymnasium",
    "from_gymnasium_space",
    "from_gymnasium_value",
    "from_sb3",
    "read_torch_state_dict",
    "to_gymnasium",
    "to_gymnasium_space",
    "to_gymnasium_value",
]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(f"palaestra.compat.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'palaestra.compat' has no attribute {name!r}")
