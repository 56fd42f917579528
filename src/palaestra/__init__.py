"""palaestra: Gymnasium's environment API, classic-control and Atari envs, and SB3-style agents.

``import palaestra as gym`` is a drop-in for ``import gymnasium as gym``. Importing it loads numpy
only: torch, ale-py and the rendering libraries are imported where they are used.
"""

# isort: skip_file
from palaestra.core import ActionWrapper, Env, ObservationWrapper, RewardWrapper, Wrapper
from palaestra.spaces import Space
from palaestra.envs.registration import (
    VectorizeMode,
    make,
    make_vec,
    pprint_registry,
    register,
    register_envs,
    registry,
    spec,
)
from palaestra import error, logger, spaces, utils, wrappers
from palaestra import envs  # registers the built-in environments
import palaestra.compat.registry  # noqa: F401 -- fills the "gymnasium:" id prefix

__version__ = "0.1.0"


def __getattr__(name: str) -> object:
    # `gym.vector` is imported on first use: its worker machinery (multiprocessing, shared
    # memory) would otherwise cost every `import palaestra` ~30 ms.
    if name in ("vector", "vec_env"):
        import importlib

        return importlib.import_module(f"palaestra.{name}")
    raise AttributeError(f"module 'palaestra' has no attribute {name!r}")


__all__ = [
    "ActionWrapper",
    "Env",
    "ObservationWrapper",
    "RewardWrapper",
    "Space",
    "VectorizeMode",
    "Wrapper",
    "envs",
    "error",
    "logger",
    "make",
    "make_vec",
    "pprint_registry",
    "register",
    "register_envs",
    "registry",
    "spaces",
    "spec",
    "utils",
    "vector",
    "wrappers",
]
