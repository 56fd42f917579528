"""What PPO and A2C share: the actor-critic and its learner, rollout collection with the
values of a whole rollout in one batched forward, GAE, the bootstrap of truncated episodes,
the ``learn`` loop (collect, log, train) and the partial rollout kept for exact resume.

An on-policy algorithm adds its constructor, its optimizer default, ``train`` (its loss over
the rollout buffer) and what it saves; everything else is here, so both run the same steps
in the same order (PPO's golden hashes did not change when this was taken out of ``ppo.py``).
"""

from __future__ import annotations

import warnings
from typing import Any, ClassVar

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.base import BaseAlgorithm, round_up_steps
from palaestra.algos.common.policies import (
    ActorCritic,
    ActorCriticCnnPolicy,
    ActorCriticPolicy,
    MultiInputActorCriticPolicy,
    extractor_class,
)
from palaestra.algos.common.rollout_store import RolloutStore
from palaestra.algos.common.schedules import as_schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.learners import Group, Net

__all__ = ["OnPolicyAlgorithm"]


class OnPolicyAlgorithm(BaseAlgorithm):
    """Rollouts of ``n_steps`` per env into a ``RolloutStore``, then ``train()``.

    Subclasses take their own settings (``_take_settings``) and implement
    ``_optimizer_choice``, ``train`` and ``_check_rollout_size``."""

    supported_action_spaces = (
        spaces.Discrete,
        spaces.Box,
        spaces.MultiDiscrete,
        spaces.MultiBinary,
    )
    _policy_class_base = ActorCriticPolicy
    # SB3's table: the class each name stands for (``PPO(CnnPolicy, env)`` with the class)
    policy_aliases: ClassVar[dict[str, type[torch.nn.Module]]] = {
        "MlpPolicy": ActorCriticPolicy,
        "CnnPolicy": ActorCriticCnnPolicy,
        "MultiInputPolicy": MultiInputActorCriticPolicy,
    }
    # SB3's arguments for custom rollout buffers: refused, or without effect here.
    _not_saved = BaseAlgorithm._not_saved | {"rollout_buffer_class", "rollout_buffer_kwargs"}
    policy: ActorCritic
    n_steps: int
    gamma: float
    gae_lambda: float

    def _take_settings(self, settings: Settings) -> None:
        """SB3's ``OnPolicyAlgorithm`` arguments, once the algorithm has checked its own; the
        rollout's size is checked when the env is known."""
        self.learning_rate = settings["learning_rate"]
        self.lr_schedule = as_schedule(self.learning_rate)
        self.n_steps = settings["n_steps"]
        self.gamma, self.gae_lambda = settings["gamma"], settings["gae_lambda"]
        self.ent_coef, self.vf_coef = settings["ent_coef"], settings["vf_coef"]
        self.max_grad_norm = settings["max_grad_norm"]
        self.normalize_advantage = settings["normalize_advantage"]
        self.use_sde, self.sde_sample_freq = settings["use_sde"], settings["sde_sample_freq"]
        if not isinstance(self.use_sde, (bool, np.bool_)):
            raise TypeError(f"use_sde must be a bool, got {self.use_sde!r}")
        freq = self.sde_sample_freq
        if isinstance(freq, bool) or not isinstance(freq, (int, np.integer)):
            raise TypeError(f"sde_sample_freq must be an int (-1: once per rollout), got {freq!r}")
        settings.unused("rollout_buffer_kwargs")
        super()._take_settings(settings)
        if self.use_sde and not isinstance(
            getattr(self, "action_space", None), (spaces.Box, type(None))
        ):
            raise ValueError(
                "generalized State-Dependent Exploration (gSDE) can only be used with "
                "continuous actions."
            )
        if self.env is not None:
            # warnings point at the user's PPO(...): __init__, _configure, 2 _take_settings
            self._check_rollout_size(stacklevel=6)

    def _optimizer_choice(self, kwargs: dict[str, Any]) -> tuple[type, dict[str, Any]]:
        """The optimizer class and its kwargs, taking them out of ``kwargs`` (the policy's)."""
        raise NotImplementedError

    def _check_rollout_size(self, stacklevel: int = 3) -> None:
        """Refuse (or warn about, at ``stacklevel``) a rollout size that cannot train."""
        raise NotImplementedError

    def train(self) -> None:
        raise NotImplementedError

    def _setup_model(self) -> None:
        self.set_random_seed(self.seed)
        kwargs = dict(self.policy_kwargs)
        self._optimizer_choice(kwargs)  # takes its keys out of the policy's
        kwargs.pop("backend", None)
        if kwargs.pop("use_sde", self.use_sde) != self.use_sde:
            raise ValueError(
                f"policy_kwargs use_sde={self.policy_kwargs['use_sde']!r} contradicts "
                f"use_sde={self.use_sde!r}: give it once, as {type(self).__name__}(use_sde=...)"
            )
        policy: ActorCritic
        if isinstance(self.policy_name, type):  # an ActorCriticPolicy subclass (SB3's guide)
            # its own default extractor (ActorCriticCnnPolicy's is NatureCNN), as in SB3
            policy_class: Any = self.policy_name
            _warn_unused_overrides(policy_class)
            policy = policy_class(
                self.observation_space,
                self.action_space,
                self.lr_schedule,
                use_sde=self.use_sde,
                **kwargs,
            )
        else:
            kwargs.setdefault("features_extractor_class", extractor_class(self.policy_name))
            policy = ActorCritic(
                self.observation_space, self.action_space, use_sde=self.use_sde, **kwargs
            )
        self._use_policy(policy.to(self.device))
        self._make_rollout_buffer()

    def _policy_family(self) -> type[torch.nn.Module]:
        return ActorCritic

    def _use_policy(self, policy: Any) -> None:
        kwargs = dict(self.policy_kwargs)
        optimizer_class, optimizer_kwargs = self._optimizer_choice(kwargs)
        backend = kwargs.pop("backend", "auto")
        params = list(policy.parameters())
        optimizer = self._make_optimizer(params, optimizer_class, optimizer_kwargs)
        pi_modules, vf_modules, why = policy.mlp_modules()
        head = policy.action_head
        extras = {"log_std": head.log_std} if head.kind in ("gaussian", "sde") else {}
        if pi_modules is not None and vf_modules is not None:
            # The flat buffer's order (actor, critic, log-std) sets the order in which the
            # gradient norm is summed: kept from the numpy trainer it replaces.
            ordered = [p for m in pi_modules + vf_modules for p in m.parameters()]
            params = list(dict.fromkeys(ordered + list(extras.values()) + params))
        nets = {
            "pi": Net(policy.pi_out, pi_modules, group="policy", why=why),
            "vf": Net(policy.vf_out, vf_modules, group="policy", why=why),
        }
        joint = policy.pi_and_vf
        if head.kind == "sde":  # gSDE reads the latent: pi ends there, act is the mean's layer
            nets["pi"] = Net(policy.pi_latent, pi_modules and pi_modules[:-1], "policy", why=why)
            nets["act"] = Net(head.net, pi_modules and [head.net], group="policy", why=why)
            joint = policy.pi_latent_and_vf
        self._set_learner(
            policy,
            optimizer,
            backend,
            nets,
            {"policy": Group(optimizer, params, extras)},
            joint={("pi", "vf"): joint},
        )
        self._head = head

    def _make_rollout_buffer(self) -> None:
        self.rollout_buffer = RolloutStore(
            self.n_steps,
            self.observation_space,
            self.action_space,
            self.n_envs,
            self.gamma,
            self.gae_lambda,
        )

    def final_timesteps(self, total_timesteps: int) -> int:
        # Whole rollouts of n_steps per env, counted from where the one under way began.
        rollout = self.n_steps * self.n_envs
        start = self.num_timesteps - self.rollout_buffer.pos * self.n_envs
        return round_up_steps(start, self.num_timesteps, total_timesteps, rollout)

    def _on_n_envs_changed(self) -> None:
        self._check_rollout_size()
        self._make_rollout_buffer()

    def _sample(self, obs: Any, deterministic: bool) -> tuple[np.ndarray, np.ndarray]:
        """``(actions, log_probs)`` for a batch of raw observations."""
        head = self._head
        if head.kind == "sde":
            latent = self.learner.forward("pi", obs)
            mean = self.learner.forward("act", latent)
            sde_log_std = self.learner.extra("log_std")
            return head.sample(mean, sde_log_std, self._rng, deterministic, latent)
        log_std = self.learner.extra("log_std") if head.kind == "gaussian" else None
        return head.sample(self.learner.forward("pi", obs), log_std, self._rng, deterministic)

    def _reset_noise(self) -> None:
        """gSDE: new exploration matrices, one per env, from the model's generator."""
        self._head.reset_noise(self.learner.extra("log_std"), self.n_envs, self._rng)

    def _to_env_actions(self, actions: np.ndarray) -> np.ndarray:
        """Box actions clipped to the bounds, or, squashed (gSDE's ``squash_output``), mapped
        from ``[-1, 1]`` to them (SB3's ``unscale_action``)."""
        box = self.action_space
        assert isinstance(box, spaces.Box)
        if self._head.squash:
            return (box.low + 0.5 * (actions + 1.0) * (box.high - box.low)).astype(box.dtype)
        return np.clip(actions, box.low, box.high)

    def _values(self, obs: Any) -> np.ndarray:
        """``V(obs)`` ``[B]``, in chunks (a whole rollout of images may not fit at once)."""
        if isinstance(obs, dict):
            n = len(next(iter(obs.values())))
            chunks = [{k: v[i : i + 8192] for k, v in obs.items()} for i in range(0, n, 8192)]
        else:
            chunks = [obs[i : i + 8192] for i in range(0, len(obs), 8192)]
        with self.learner.session():  # a whole rollout: threads cost more than they save
            out = [self.learner.forward("vf", chunk)[:, 0] for chunk in chunks]
        return out[0] if len(out) == 1 else np.concatenate(out)

    def _predict(self, observation: Any, deterministic: bool) -> np.ndarray:
        actions = self._sample(observation, deterministic)[0]
        return self._to_env_actions(actions) if self._head.squash else actions

    # -- learning ----------------------------------------------------------------------------
    def _learn(
        self,
        total_timesteps: int,
        callback: Any,
        log_interval: int | None,
        tb_log_name: str,
        reset_num_timesteps: bool,
        progress_bar: bool,
    ) -> None:
        """Alternate ``n_steps``-per-env rollouts and ``train()``.

        A callback that stops training ends the rollout after its step is stored; the partial
        rollout stays in the buffer (and in a saved model), and the next ``learn`` completes it,
        so a stopped and resumed run updates at the same steps as one never stopped."""
        callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar
        )
        callback.on_training_start(self._callback_locals(), {})
        iteration = 0
        with self._learning_session():
            while self.num_timesteps < self._total_timesteps:
                if not self._collect_rollout(callback):
                    break
                iteration += 1
                self._update_progress()
                if log_interval is not None and iteration % log_interval == 0:
                    self.dump_logs(iteration)
                self.train()
                self.rollout_buffer.reset()
        callback.on_training_end()

    def dump_logs(self, iteration: int = 0) -> None:
        """Write the episode statistics, fps and what was recorded since the last dump
        (SB3's ``dump_logs``; ``iteration > 0`` also logs ``time/iterations``)."""
        if iteration > 0:
            self.logger.record("time/iterations", iteration, exclude="tensorboard")
        self._record_episode_stats()
        self.logger.dump(step=self.num_timesteps)

    def _on_env_reset(self, restart: bool) -> None:
        self.rollout_buffer.reset()  # a partial rollout only continues its own episodes

    def _collect_rollout(self, callback: Any) -> bool:
        """Fill the rest of the rollout buffer; False if a callback asked to stop."""
        env, buf = self.env, self.rollout_buffer
        box = self.action_space if isinstance(self.action_space, spaces.Box) else None
        callback.on_rollout_start()
        # The values of the whole rollout come from one batched forward at its end (the
        # parameters do not change during a rollout): per step, only the policy.
        bits = isinstance(self.action_space, spaces.MultiBinary)
        self._set_training_mode(False)
        sde, freq = self._head.kind == "sde", self.sde_sample_freq
        while not buf.full:
            # gSDE: new matrices when a rollout starts and every sde_sample_freq steps (SB3)
            if sde and (buf.pos == 0 or (freq > 0 and buf.pos % freq == 0)):
                self._reset_noise()
            actions, log_probs = self._sample(self._last_obs, False)
            if bits:
                actions = actions.astype(self.action_space.dtype)  # Bernoulli samples are floats
            env_actions = self._to_env_actions(actions) if box is not None else actions
            new_obs, rewards, dones, infos = env.step(env_actions)
            running = self._stepped(callback, actions, new_obs, rewards, dones, infos)
            rewards = np.asarray(rewards, dtype=np.float32)
            if np.count_nonzero(dones):  # dones.any() costs ~3x more per step
                rewards = self._bootstrap_truncated(rewards, dones, infos)
            buf.add(
                self._last_obs,
                actions,
                rewards,
                self._last_episode_starts,  # type: ignore[arg-type]
                None,
                log_probs,
            )
            self._last_obs, self._last_episode_starts = new_obs, dones
            if not running:
                return False
        buf.values[...] = self._values(buf.flat_observations()).reshape(buf.values.shape)
        # The last step's dones (also after a resume that found the buffer already full).
        assert self._last_episode_starts is not None
        buf.compute_returns_and_advantage(self._values(self._last_obs), self._last_episode_starts)
        callback.update_locals({"rollout_buffer": buf})
        callback.on_rollout_end()
        return True

    def _bootstrap_truncated(
        self, rewards: np.ndarray, dones: np.ndarray, infos: list[dict[str, Any]]
    ) -> np.ndarray:
        """Add ``gamma * V(terminal_obs)`` where an episode was cut by a time limit (SB3)."""
        idx = [
            i
            for i in np.flatnonzero(dones)
            if infos[i].get("TimeLimit.truncated", False)
            and infos[i].get("terminal_observation") is not None
        ]
        if not idx:
            return rewards
        terminal = [infos[i]["terminal_observation"] for i in idx]
        if isinstance(terminal[0], dict):
            batch: Any = {k: np.stack([t[k] for t in terminal]) for k in terminal[0]}
        else:
            batch = np.stack(terminal)
        rewards = rewards.copy()
        rewards[idx] += self.gamma * self._values(batch)
        return rewards

    # -- persistence ---------------------------------------------------------------------------
    def _loop_state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        meta, arrays = self.rollout_buffer.partial_state()
        # gSDE's matrices: a partial rollout continues with the ones it was drawn with
        arrays.update({f"sde/{k}": v for k, v in self._head.noise_state().items()})
        return meta, arrays

    def _sde_matrix_shape(self) -> tuple[int, ...] | None:
        noise = self._head.noise_state()
        return tuple(noise["exploration_mat"].shape) if noise else None

    def _load_loop_state(self, meta: Any, arrays: dict[str, np.ndarray]) -> None:
        noise = {k[4:]: arrays.pop(k) for k in list(arrays) if k.startswith("sde/")}
        if noise:
            self._head.load_noise_state(noise)
        self.rollout_buffer.load_partial_state(meta, arrays)


def default_adam(kwargs: dict[str, Any]) -> tuple[type, dict[str, Any]]:
    """SB3's ``ActorCriticPolicy`` optimizer: ``optimizer_class`` (Adam) with ``eps=1e-5``
    for Adam unless given, taken out of the policy ``kwargs``."""
    optimizer_class = kwargs.pop("optimizer_class", torch.optim.Adam)
    optimizer_kwargs = dict(kwargs.pop("optimizer_kwargs", None) or {})
    if optimizer_class is torch.optim.Adam:
        optimizer_kwargs.setdefault("eps", 1e-5)
    return optimizer_class, optimizer_kwargs


# What SB3's on-policy loop calls on its policy; palaestra's learner runs the policy's modules
# (extractor, mlp_extractor, heads) instead, so an override of these changes nothing here.
_LOOP_METHODS = ("forward", "evaluate_actions", "predict_values", "get_distribution")


def _warn_unused_overrides(policy_class: type) -> None:
    """Warn when an ``ActorCriticPolicy`` subclass overrides a method SB3's rollout or train
    step calls but palaestra's learner does not: its result would silently differ from SB3's."""
    overridden = [
        name
        for name in _LOOP_METHODS
        if getattr(policy_class, name, None) is not getattr(ActorCriticPolicy, name, None)
    ]
    if overridden:
        warnings.warn(
            f"{policy_class.__name__} overrides {', '.join(overridden)}: palaestra's PPO/A2C "
            "run the policy's modules (features extractor, mlp_extractor, action and value "
            "heads), not these methods, when collecting rollouts and training; customise "
            "those modules (_build_mlp_extractor, features_extractor_class) instead",
            UserWarning,
            stacklevel=4,
        )
