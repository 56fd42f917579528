"""Vector environments with Stable-Baselines3's API (``stable_baselines3.common.vec_env``).

``DummyVecEnv``, ``SubprocVecEnv`` and the native ``BatchedVecEnv`` are thin faces over the
engines of :mod:`palaestra.vector`; ``make_vec_env`` picks the native batch for built-in ids.
"""

from palaestra.vec_env.atari_vec_env import AtariVecEnv
from palaestra.vec_env.base import CloudpickleWrapper, VecEnv, VecEnvWrapper
from palaestra.vec_env.check_nan import VecCheckNan
from palaestra.vec_env.engine_vec_env import BatchedVecEnv, DummyVecEnv, SubprocVecEnv
from palaestra.vec_env.env_util import make_atari_env, make_vec_env
from palaestra.vec_env.extract_dict_obs import VecExtractDictObs
from palaestra.vec_env.image import VecFrameStack, VecTransposeImage
from palaestra.vec_env.monitor import VecMonitor
from palaestra.vec_env.normalize import VecNormalize
from palaestra.vec_env.stacked_observations import StackedObservations
from palaestra.vec_env.util import (
    is_vecenv_wrapped,
    sync_envs_normalization,
    unwrap_vec_normalize,
    unwrap_vec_wrapper,
)
from palaestra.vec_env.video_recorder import VecVideoRecorder

__all__ = [
    "AtariVecEnv",
    "BatchedVecEnv",
    "CloudpickleWrapper",
    "DummyVecEnv",
    "StackedObservations",
    "SubprocVecEnv",
    "VecCheckNan",
    "VecEnv",
    "VecEnvWrapper",
    "VecExtractDictObs",
    "VecFrameStack",
    "VecMonitor",
    "VecNormalize",
    "VecTransposeImage",
    "VecVideoRecorder",
    "is_vecenv_wrapped",
    "make_atari_env",
    "make_vec_env",
    "sync_envs_normalization",
    "unwrap_vec_normalize",
    "unwrap_vec_wrapper",
]
