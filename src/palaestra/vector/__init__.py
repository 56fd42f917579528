"""Vector environments (``gymnasium.vector``'s API): N envs stepped as one.

``SyncVectorEnv`` loops over env objects, ``AsyncVectorEnv`` runs each in a worker process, and
``BatchedVectorEnv`` steps a built-in env's native batch with array ops (what ``make_vec``
returns for the classic-control ids). All three are views on one engine layer
(:mod:`palaestra.vector.engine`), so autoreset, seeding and info handling are written once.
"""

from palaestra.vector import utils
from palaestra.vector.async_vector_env import AsyncVectorEnv
from palaestra.vector.native import BatchedVectorEnv
from palaestra.vector.process_engine import MissingMainGuardError, WorkerDiedError
from palaestra.vector.sync_vector_env import SyncVectorEnv
from palaestra.vector.vector_env import (
    AutoresetMode,
    VectorActionWrapper,
    VectorEnv,
    VectorObservationWrapper,
    VectorRewardWrapper,
    VectorWrapper,
)

__all__ = [
    "AsyncVectorEnv",
    "AutoresetMode",
    "BatchedVectorEnv",
    "MissingMainGuardError",
    "SyncVectorEnv",
    "VectorActionWrapper",
    "VectorEnv",
    "VectorObservationWrapper",
    "VectorRewardWrapper",
    "VectorWrapper",
    "WorkerDiedError",
    "utils",
]
