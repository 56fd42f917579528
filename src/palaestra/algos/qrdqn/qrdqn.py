"""QR-DQN (Dabney et al. 2018) with sb3-contrib's parameters, defaults and update rules: DQN
with a distribution of returns per action, ``n_quantiles`` quantiles, instead of one value."""

from __future__ import annotations

from typing import Any, ClassVar, cast

import numpy as np
import torch

from palaestra.algos.common.schedules import Schedule
from palaestra.algos.dqn.dqn import DQN
from palaestra.algos.qrdqn.objective import QRDQNObjective, quantile_midpoints
from palaestra.algos.qrdqn.policies import (
    CnnPolicy,
    MlpPolicy,
    MultiInputPolicy,
    QRDQNPolicy,
    QuantileNetwork,
)

__all__ = ["QRDQN"]


class QRDQN(DQN):
    """Quantile regression DQN: ``QRDQN(env, ...)``; arguments as sb3-contrib's ``QRDQN``
    (``n_quantiles`` goes in ``policy_kwargs``, default 200).

    Everything but the network and the loss is DQN's (exploration, target updates, replay,
    saving, both learners, and DQN's differences from SB3, such as one epsilon coin per env).
    The loss is the quantile Huber loss (kappa 1) against the target net's quantiles of the
    action with the largest mean; ``max_grad_norm=None`` (the default) does not clip. As in
    sb3-contrib, without an ``optimizer_class`` in ``policy_kwargs`` the optimizer is Adam with
    ``eps=0.01 / batch_size`` (the paper's, for batch 32); changed: ``optimizer_kwargs`` given
    without ``optimizer_class`` are added to that (sb3-contrib replaces them).
    """

    policy_aliases: ClassVar[dict[str, type[torch.nn.Module]]] = {
        "MlpPolicy": MlpPolicy,
        "CnnPolicy": CnnPolicy,
        "MultiInputPolicy": MultiInputPolicy,
    }
    _policy_class_base = QRDQNPolicy  # type: ignore[assignment]  # DQN's, narrowed

    def __init__(
        self,
        policy: str | type[QRDQNPolicy],
        env: Any,
        learning_rate: float | Schedule = 5e-5,
        buffer_size: int = 1000000,
        learning_starts: int = 100,
        batch_size: int = 32,
        tau: float = 1.0,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 4,
        gradient_steps: int = 1,
        replay_buffer_class: type | str | None = None,
        replay_buffer_kwargs: dict[str, Any] | None = None,
        optimize_memory_usage: bool = False,
        n_steps: int = 1,
        target_update_interval: int = 10000,
        exploration_fraction: float = 0.005,
        exploration_initial_eps: float = 1.0,
        exploration_final_eps: float = 0.01,
        max_grad_norm: float | None = None,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: torch.device | str = "auto",
        _init_setup_model: bool = True,
    ) -> None:
        super().__init__(**{k: v for k, v in locals().items() if k not in ("self", "__class__")})

    # sb3-contrib's attributes; reading the nets hands the parameters to torch, as ``policy``.
    @property
    def quantile_net(self) -> QuantileNetwork:
        return self.policy.quantile_net

    @property
    def quantile_net_target(self) -> QuantileNetwork:
        return self.policy.quantile_net_target

    @property
    def n_quantiles(self) -> int:
        return cast(QRDQNPolicy, self._policy).n_quantiles

    def _build_policy(self, policy_kwargs: dict[str, Any]) -> Any:
        if "optimizer_class" not in policy_kwargs:
            # The QR-DQN paper's Adam epsilon, 0.01 / 32 for its batch of 32 (sb3-contrib).
            optimizer_kwargs = {"eps": 0.01 / self.batch_size}
            optimizer_kwargs |= policy_kwargs.get("optimizer_kwargs") or {}
            policy_kwargs = policy_kwargs | {"optimizer_kwargs": optimizer_kwargs}
        return super()._build_policy(policy_kwargs)

    # -- acting ------------------------------------------------------------------------------
    def _greedy(self, obs: Any) -> np.ndarray:
        quantiles = self.learner.forward("q", obs)  # [B, N * n_actions] or [B, N, n_actions]
        values = quantiles.reshape(quantiles.shape[0], self.n_quantiles, -1).mean(axis=1)
        return values.argmax(axis=1) + int(self.action_space.start)

    # -- learning ------------------------------------------------------------------------------
    def _objective(self) -> Any:
        return QRDQNObjective(self.gamma)

    def _fixed_batch(self, batch_size: int) -> dict[str, np.ndarray]:
        # The objective indexes and weighs with these (arrays, so they reach torch's device).
        return {"rows": np.arange(batch_size), "cum_prob": quantile_midpoints(self.n_quantiles)}
