"""DDPG as SB3 defines it: TD3 with one critic, no target policy smoothing and no policy delay."""

from __future__ import annotations

from typing import Any

import torch

from palaestra.algos.common.schedules import Schedule
from palaestra.algos.td3.policies import TD3Policy
from palaestra.algos.td3.td3 import TD3

__all__ = ["DDPG"]


class DDPG(TD3):
    """DDPG as SB3 defines it: TD3 with one critic (``n_critics=1`` unless ``policy_kwargs``
    says otherwise), no target policy smoothing (``target_noise_clip=0``) and
    ``policy_delay=1``; SB3's constructor arguments and defaults."""

    _policy_defaults = {"n_critics": 1}  # SB3's DDPG, unless policy_kwargs says otherwise

    def __init__(
        self,
        policy: str | type[TD3Policy],
        env: Any,
        learning_rate: float | Schedule = 1e-3,
        buffer_size: int = 1_000_000,
        learning_starts: int = 100,
        batch_size: int = 256,
        tau: float = 0.005,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 1,
        gradient_steps: int = 1,
        action_noise: Any = None,
        replay_buffer_class: type | str | None = None,
        replay_buffer_kwargs: dict[str, Any] | None = None,
        optimize_memory_usage: bool = False,
        n_steps: int = 1,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: torch.device | str = "auto",
        num_threads: int | None = None,
        _init_setup_model: bool = True,
    ) -> None:
        # TD3 with these fixed (SB3's DDPG): not arguments, so a model file does not keep them
        self._configure(
            locals() | {"policy_delay": 1, "target_policy_noise": 0.1, "target_noise_clip": 0.0}
        )
