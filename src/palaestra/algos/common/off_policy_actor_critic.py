"""What SAC, TD3 and DDPG share on top of the replay loop: Box actions kept in ``[-1, 1]``
inside the networks and the buffer (scaled to the env's bounds when sent), uniform actions
before ``learning_starts``, optional exploration noise, twin (or single) critics with target
copies, and one optimizer per part (SB3's ``actor.optimizer``/``critic.optimizer``)."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.action_noise import (
    ActionNoise,
    VectorizedActionNoise,
    noise_from_json,
    noise_to_json,
)
from palaestra.algos.common.continuous_policies import ContinuousCritic
from palaestra.algos.common.off_policy import OffPolicyAlgorithm
from palaestra.algos.common.policies import _numpy_input_problem
from palaestra.algos.common.settings import Settings
from palaestra.algos.learners import Net

__all__ = ["ActorCriticOffPolicy"]


class ActorCriticOffPolicy(OffPolicyAlgorithm):
    """The continuous-action part of SAC, TD3 and DDPG (see the module docstring)."""

    supported_action_spaces = (spaces.Box,)
    action_noise: ActionNoise | None

    def _take_settings(self, settings: Settings) -> None:
        """Checks SB3 leaves to a crash later: ``tau`` in [0, 1], an ``ActionNoise``; then the
        replay loop's settings and the common ones."""
        tau, action_noise = settings["tau"], settings["action_noise"]
        if isinstance(tau, bool) or not isinstance(tau, (int, float)) or not 0.0 <= tau <= 1.0:
            raise ValueError(f"tau must be a number in [0, 1], got {tau!r}")
        if isinstance(action_noise, dict):  # from a model file
            action_noise = noise_from_json(action_noise)
        if action_noise is not None and not isinstance(action_noise, ActionNoise):
            raise TypeError(
                f"action_noise must be a palaestra.algos.action_noise.ActionNoise, got "
                f"{type(action_noise).__name__}"
            )
        self.action_noise = action_noise
        super()._take_settings(settings)

    def _check_action_space(self) -> None:
        box = self.action_space
        if not isinstance(box, spaces.Box):
            raise TypeError(f"{type(self).__name__} only supports Box action spaces, got {box}")
        if not (np.all(np.isfinite(box.low)) and np.all(np.isfinite(box.high))):
            raise ValueError(
                f"{type(self).__name__} needs a bounded Box action space (actions are squashed "
                f"to its bounds), got {box}"
            )
        self._low = box.low.astype(np.float64)
        self._span = box.high.astype(np.float64) - self._low
        self.action_dim = int(np.prod(box.shape))
        noise = self.action_noise
        if noise is not None:
            want = tuple(box.shape)
            got = tuple(noise.shape)
            # SB3 adds the noise with numpy broadcasting: NormalActionNoise(np.zeros(1), ...)
            # on a Box((10,)) adds one draw to every dimension, as SB3's HER tests do.
            one = got[1:] if isinstance(noise, VectorizedActionNoise) else got
            if not _broadcasts(one, want):
                raise ValueError(
                    f"action_noise of shape {got} does not fit the action space {box} "
                    f"(expected {want} or a shape that broadcasts to it, or (n_envs, *{want}) "
                    "for VectorizedActionNoise)"
                )

    # -- acting --------------------------------------------------------------------------------
    def _unscale(self, scaled: np.ndarray) -> np.ndarray:
        """``[-1, 1]`` -> the env's bounds."""
        shape = (-1, *self.action_space.shape)
        out = self._low + 0.5 * (scaled.reshape(shape) + 1.0) * self._span
        return out.astype(self.action_space.dtype)

    def _policy_actions(self, obs: Any, deterministic: bool) -> np.ndarray:
        """Actions in ``[-1, 1]`` ``[B, action_dim]`` (subclasses)."""
        raise NotImplementedError

    def _predict(self, observation: Any, deterministic: bool) -> np.ndarray:
        return self._unscale(self._policy_actions(observation, deterministic))

    def _uniform_warmup(self) -> bool:
        """Whether this step's actions are uniform (before ``learning_starts``; SAC's
        ``use_sde_at_warmup`` acts with gSDE instead)."""
        return self.num_timesteps < self.learning_starts

    def _sample_actions(self) -> tuple[np.ndarray, np.ndarray]:
        n = self.n_envs
        if self._uniform_warmup():
            scaled = 2.0 * self._rng.random((n, self.action_dim)) - 1.0  # uniform in the bounds
        else:
            scaled = self._policy_actions(self._last_obs, deterministic=False)
        if self.action_noise is not None:
            if n > 1 and not isinstance(self.action_noise, VectorizedActionNoise):
                self.action_noise = VectorizedActionNoise(self.action_noise, n)  # as SB3
            noise = self.action_noise(self._rng)
            noise = np.broadcast_to(noise, (n, *self.action_space.shape)).reshape(n, -1)
            scaled = np.clip(scaled + noise, -1.0, 1.0)
        scaled = scaled.astype(np.float32)
        return self._unscale(scaled), scaled.reshape(-1, *self.action_space.shape)

    def _on_episode_end(self, index: int) -> None:
        noise = self.action_noise
        if isinstance(noise, VectorizedActionNoise):
            noise.reset([index])
        elif noise is not None:
            noise.reset()

    # -- networks ------------------------------------------------------------------------------
    # Keys DDPG adds to policy_kwargs when they are absent (SB3's DDPG: n_critics=1).
    _policy_defaults: dict[str, Any] = {}

    def _make_policy(self, **parts: type[torch.nn.Module]) -> Any:
        """The policy (``SACPolicy``/``TD3Policy`` or a subclass), checked to hold ``parts``
        (attribute name -> the class it must be an instance of) for the learner to run."""
        policy = self._build_policy({**self._policy_defaults, **self.policy_kwargs})
        self._check_parts(policy, parts)
        return policy

    def _check_parts(self, policy: Any, parts: dict[str, type[torch.nn.Module]]) -> None:
        for name, cls in parts.items():
            part = getattr(policy, name, None)
            if not isinstance(part, cls):
                raise TypeError(
                    f"{type(policy).__name__}.{name} must be a {cls.__module__}.{cls.__name__} "
                    f"(or a subclass; see make_actor/make_critic), got {type(part).__name__}"
                )

    def _critic_nets(
        self, critic: ContinuousCritic, target: ContinuousCritic, policy: torch.nn.Module
    ) -> tuple[dict[str, Net], list[torch.nn.Parameter]]:
        """``qf{i}`` and ``qf{i}_target`` nets, and the critic optimizer's parameters (without
        a features extractor shared with the actor, which SB3 trains with the actor only)."""
        why = self._custom_policy(policy) or _numpy_input_problem(
            self.observation_space, critic.features_extractor, critic.normalize_images
        )
        nets: dict[str, Net] = {}
        for i in range(len(critic.q_networks)):
            own: torch.nn.Module = critic.q_networks[i]
            frozen: torch.nn.Module = target.q_networks[i]
            if i == 0:
                # The extractor moves with qf0, shared or not: SB3 polyak-averages all of
                # critic.parameters() (with a shared one, the actor's) into the target's.
                own = torch.nn.ModuleList([critic.features_extractor, own])
                frozen = torch.nn.ModuleList([target.features_extractor, frozen])
            nets[f"qf{i}"] = Net(
                functools.partial(critic.q, i),
                None if why else [critic.q_networks[i]],
                group="critic",
                why=why,
                module=own,
            )
            nets[f"qf{i}_target"] = Net(
                functools.partial(target.q, i),
                None if why else [target.q_networks[i]],
                target_of=f"qf{i}",
                why=why,
                module=frozen,
            )
        self._n_critics = len(critic.q_networks)
        shared = {id(p) for p in critic.features_extractor.parameters()}
        params = [
            p
            for p in critic.parameters()
            if not (critic.share_features_extractor and id(p) in shared)
        ]
        return nets, params

    def _make_optimizer_for(
        self, params: list[torch.nn.Parameter], policy: Any
    ) -> torch.optim.Optimizer:
        """An optimizer of the policy's ``optimizer_class``/``optimizer_kwargs``."""
        optimizer_class = getattr(policy, "optimizer_class", torch.optim.Adam)
        optimizer_kwargs = getattr(policy, "optimizer_kwargs", None) or {}
        return self._make_optimizer(params, optimizer_class, optimizer_kwargs)

    def _polyak_critics(self) -> None:
        for i in range(self._n_critics):
            self.learner.polyak(f"qf{i}_target", self.tau)

    def _optimizers(self) -> dict[str, tuple[str, torch.optim.Optimizer]]:
        """SB3's ``actor.optimizer`` and ``critic.optimizer`` (SAC adds its temperature's)."""
        self.learner.to_torch()
        groups = self.learner.groups
        return {
            "actor_optimizer": ("actor.optimizer", groups["actor"].optimizer),
            "critic_optimizer": ("critic.optimizer", groups["critic"].optimizer),
        }

    def _saved_value(self, name: str) -> Any:
        if name == "action_noise":  # the exploration noise with its state
            return noise_to_json(self.action_noise)
        return super()._saved_value(name)

    def _sample_batch(self, batch_size: int) -> dict[str, Any]:
        batch = super()._sample_batch(batch_size)
        batch["actions"] = batch["actions"].reshape(batch_size, -1)
        return batch


def _broadcasts(shape: tuple[int, ...], target: tuple[int, ...]) -> bool:
    """Whether numpy broadcasts an array of ``shape`` to exactly ``target``."""
    try:
        return np.broadcast_shapes(shape, target) == target
    except ValueError:
        return False
