"""Training algorithms with Stable-Baselines3's API: ``from palaestra.algos import A2C, DQN, PPO``.

This subpackage needs torch (``pip install "palaestra[train]"``); ``import palaestra`` alone
never imports it.

Same names, defaults, log keys and learning rules as SB3 2.x. Where SB3 is unsafe or
surprising, palaestra differs on purpose:

- model and replay-buffer files are a zip of JSON and ``.npy`` arrays; loading never
  unpickles (SB3 model files are refused with an explanation); classes named in
  ``policy_kwargs`` resolve only in ``torch.nn``/``torch.optim``/``palaestra.algos`` unless
  passed through ``custom_objects``; callables (schedules) are stored exactly when they are
  ``ConstantSchedule``/``LinearSchedule``, as a 1001-point table otherwise;
- exact resume: a model file also holds its ``learn`` loop's state (current observations,
  a partial PPO/A2C rollout, DQN's open collection, episode statistics, generators), so
  ``save`` + ``load(path, env=the same env)`` + ``learn(T - t, reset_num_timesteps=False)``
  ends bit-identical to a run never stopped (with another env, new episodes start, as in
  SB3). Schedules use SB3's ``1 - num_timesteps / total``; a finished run given more steps
  trains as a run planned for the larger budget would, and ``learn`` warns when the learning
  rate is 0. The step on which a callback stops training is stored and counted before
  ``learn`` returns (SB3 drops it), which is what makes a stop resumable;
- DQN draws one epsilon coin per env (SB3: one for all envs);
- a function callback returning ``None`` keeps training (SB3 stops);
- ``progress_bar=True`` needs tqdm only; channel-last images need no ``VecTransposeImage``;
- two learners train the same networks, heads and losses (``palaestra.algos.learners``):
  small MLPs on the CPU with Adam train in numpy with hand-written gradients (several times
  faster than torch's overhead allows), everything else (CNNs, other optimizers, ``cuda``)
  with torch autograd; ``policy_kwargs={"backend": "numpy"|"torch"}`` forces one (numpy
  raises ``ValueError`` naming what it cannot run), ``verbose=1`` prints which runs and why.
  Acting samples from the model's numpy generator on either learner;
- SAC, TD3 and DDPG draw their exploration, target-smoothing and action noise from the model's
  seeded generator (SB3: torch's and numpy's global ones), so the same seed gives the same bits
  on either learner, and a model file stores its ``action_noise`` with its state (SB3 pickles
  it); SAC updates its temperature after the actor in each step, with that step's log-probs
  (the same update as SB3's, which runs it first: both losses use the coefficient from before);
- DQN's ``optimize_memory_usage=True`` keeps each frame of stacked observations once (SB3
  keeps it four times) and returns exact terminal observations, so it combines with
  ``handle_timeout_termination`` (SB3 refuses the pair);
- ``n_steps > 1`` (n-step returns of DQN, SAC, TD3, DDPG, as SB3 2.x's ``NStepReplayBuffer``)
  also works with Dict observations (SB3 asserts ``n_steps == 1`` there).

- gSDE (``use_sde`` in PPO, A2C and SAC) draws its exploration matrices from the model's
  generator (SB3: torch's), and a model file keeps those of an unfinished rollout.

Not supported yet: buffer classes other than ``HerReplayBuffer``, recurrent policies,
VecNormalize-aware replay (observations are stored as the env returns them).
"""

import importlib

from palaestra.error import dependency_not_installed

try:
    import torch  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised in a subprocess test
    raise dependency_not_installed("torch", "train", "palaestra.algos") from exc

# isort: skip_file
from palaestra.algos import public_paths  # first: puts the public-path hook in place
from palaestra.algos.common import callbacks, schedules
from palaestra.algos.a2c import A2C
from palaestra.algos.dqn import DQN
from palaestra.algos.sac import SAC
from palaestra.algos.td3 import TD3
from palaestra.algos.ddpg import DDPG
from palaestra.algos.common.action_noise import (
    NormalActionNoise,
    OrnsteinUhlenbeckActionNoise,
    VectorizedActionNoise,
)
from palaestra.algos.ppo import PPO
from palaestra.algos.qrdqn import QRDQN
from palaestra.algos.her import HerReplayBuffer
from palaestra.algos.common.evaluation import evaluate_policy
from palaestra.algos.common.model_io import ModelFileError
from palaestra.algos.common.schedules import ConstantSchedule, LinearSchedule
from palaestra.algos.common.utils import get_system_info

__all__ = [
    "A2C",
    "DDPG",
    "DQN",
    "PPO",
    "QRDQN",
    "SAC",
    "TD3",
    "ConstantSchedule",
    "HerReplayBuffer",
    "LinearSchedule",
    "ModelFileError",
    "NormalActionNoise",
    "OrnsteinUhlenbeckActionNoise",
    "VectorizedActionNoise",
    "callbacks",
    "evaluate_policy",
    "get_system_info",
    "schedules",
]


def __getattr__(name: str) -> object:
    """``palaestra.algos.buffers`` and the other public module paths as attributes, imported
    on first use as ``import palaestra.algos.buffers`` would."""
    if f"{__name__}.{name}" in public_paths.MODULE_ALIASES:
        return importlib.import_module(f"{__name__}.{name}")
    if name == "HER":  # SB3 1.x's class: SB3 2.x and palaestra raise this same ImportError
        raise ImportError(
            "HER is a replay buffer class, HerReplayBuffer, since Stable-Baselines3 2.1.0 (and "
            "in palaestra): pass replay_buffer_class=HerReplayBuffer to DQN, SAC, TD3 or DDPG. "
            "Please check the documentation for more information (palaestra's guide "
            "docs/guides/training.md; SB3's https://stable-baselines3.readthedocs.io/en/master/modules/her.html)"
        )
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
