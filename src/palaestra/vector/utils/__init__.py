"""Batching helpers, where Gymnasium keeps them (``gymnasium.vector.utils``)."""

from palaestra.spaces.batched_samples import concatenate, create_empty_array, iterate
from palaestra.spaces.batching import batch_differing_spaces, batch_space
from palaestra.vector.process_engine import clear_mpi_env_vars
from palaestra.vector.shared_memory import (
    create_shared_memory,
    read_from_shared_memory,
    write_to_shared_memory,
)
from palaestra.vector.worker import Payload as CloudpickleWrapper

__all__ = [
    "CloudpickleWrapper",
    "batch_differing_spaces",
    "batch_space",
    "clear_mpi_env_vars",
    "concatenate",
    "create_empty_array",
    "create_shared_memory",
    "iterate",
    "read_from_shared_memory",
    "write_to_shared_memory",
]
