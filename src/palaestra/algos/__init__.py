"""Training algorithms with Stable-Baselines3's API: ``from palaestra.algos import DQN, PPO``.

This subpackage needs torch (``pip install "palaestra[train]"``); ``import palaestra`` alone
never imports it.
"""

from palaestra.error import dependency_not_installed

try:
    import torch  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised in a subprocess test
    raise dependency_not_installed("torch", "train", "palaestra.algos") from exc

# isort: skip_file
from palaestra.algos import callbacks, schedules
from palaestra.algos.dqn import DQN
from palaestra.algos.ppo import PPO
from palaestra.algos.evaluation import evaluate_policy
from palaestra.algos.model_io import ModelFileError
from palaestra.algos.schedules import ConstantSchedule, LinearSchedule

__all__ = [
    "DQN",
    "PPO",
    "ConstantSchedule",
    "LinearSchedule",
    "ModelFileError",
    "callbacks",
    "evaluate_policy",
    "schedules",
]
