"""SAC (Haarnoja et al. 2018) with Stable-Baselines3's parameters, defaults and update rules."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
import torch

from palaestra.algos.common.continuous_policies import ContinuousCritic, SquashedGaussianActor
from palaestra.algos.common.off_policy_actor_critic import ActorCriticOffPolicy
from palaestra.algos.common.policies import _numpy_input_problem
from palaestra.algos.common.schedules import Schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.learners import Group, Net
from palaestra.algos.learners.heads import sde_noise, squashed_gaussian_rsample
from palaestra.algos.learners.xp import numpy_ops
from palaestra.algos.sac.objective import (
    EntCoefObjective,
    SACActorObjective,
    SACCriticObjective,
    SDEDraw,
)
from palaestra.algos.sac.policies import CnnPolicy, MlpPolicy, MultiInputPolicy, SACPolicy

__all__ = ["SAC"]


def _ent_coef_init(ent_coef: Any) -> tuple[bool, float]:
    """``"auto"`` / ``"auto_0.1"`` (learned, from 1.0 / 0.1) or a fixed number > 0."""
    if isinstance(ent_coef, str):
        head, _, value = ent_coef.partition("_")
        try:
            init = float(value) if value else 1.0
        except ValueError:
            init = -1.0
        if head != "auto" or not init > 0 or not math.isfinite(init):
            raise ValueError(
                f'ent_coef must be "auto", "auto_<initial value > 0>" or a number > 0, '
                f"got {ent_coef!r}"
            )
        return True, init
    if isinstance(ent_coef, bool) or not isinstance(ent_coef, (int, float)) or not ent_coef > 0:
        raise ValueError(
            f'ent_coef must be "auto", "auto_<value>" or a number > 0, got {ent_coef!r}'
        )
    return False, float(ent_coef)


class SAC(ActorCriticOffPolicy):
    """Soft Actor-Critic: ``SAC(env, ...)``; arguments as SB3's ``SAC``.

    Kept from SB3: a tanh-squashed Gaussian actor (log-std in [-20, 2]), twin critics and
    their polyak-averaged targets (``tau``, every ``target_update_interval`` gradient steps),
    the entropy coefficient learned in log space towards ``target_entropy`` (``"auto"``:
    ``-dim(A)``) unless fixed, uniform actions before ``learning_starts``. Changed: noise is
    drawn from the model's generator (same seed, same run, on either learner), and the
    temperature is updated after the actor with the actor's log-probs of that step, which
    is the same update as SB3's (the coefficient used by both losses is the one before it).
    ``use_sde``: gSDE (SB3's), the exploration matrices drawn from the model's generator when
    each collection starts and every ``sde_sample_freq`` steps, and one noise matrix per
    gradient step for the losses.
    """

    policy_aliases: ClassVar[dict[str, type[torch.nn.Module]]] = {
        "MlpPolicy": MlpPolicy,
        "CnnPolicy": CnnPolicy,
        "MultiInputPolicy": MultiInputPolicy,
    }
    _policy_class_base = SACPolicy
    # target_entropy: the argument ("auto" or a number), not the number it resolves to
    _saved_from = ActorCriticOffPolicy._saved_from | {"target_entropy": "target_entropy_setting"}

    def __init__(
        self,
        policy: str | type[SACPolicy],
        env: Any,
        learning_rate: float | Schedule = 3e-4,
        buffer_size: int = 1_000_000,
        learning_starts: int = 100,
        batch_size: int = 256,
        tau: float = 0.005,
        gamma: float = 0.99,
        train_freq: int | tuple[int, str] = 1,
        gradient_steps: int = 1,
        action_noise: Any = None,
        replay_buffer_class: None = None,
        replay_buffer_kwargs: dict[str, Any] | None = None,
        optimize_memory_usage: bool = False,
        n_steps: int = 1,
        ent_coef: str | float = "auto",
        target_update_interval: int = 1,
        target_entropy: str | float = "auto",
        use_sde: bool = False,
        sde_sample_freq: int = -1,
        use_sde_at_warmup: bool = False,
        stats_window_size: int = 100,
        tensorboard_log: str | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        verbose: int = 0,
        seed: int | None = None,
        device: torch.device | str = "auto",
        num_threads: int | None = None,
        _init_setup_model: bool = True,
    ) -> None:
        self._configure(locals())

    def _take_settings(self, settings: Settings) -> None:
        self.use_sde, self.use_sde_at_warmup = settings["use_sde"], settings["use_sde_at_warmup"]
        self.sde_sample_freq = settings["sde_sample_freq"]
        for name in ("use_sde", "use_sde_at_warmup"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise TypeError(f"{name} must be a bool, got {getattr(self, name)!r}")
        freq = self.sde_sample_freq
        if isinstance(freq, bool) or not isinstance(freq, (int, np.integer)):
            raise TypeError(
                f"sde_sample_freq must be an int (-1: once per collection), got {freq!r}"
            )
        # SB3 hands use_sde to the policy (SACPolicy(use_sde=...)); only when on, so a custom
        # policy without the keyword still builds without gSDE.
        self._policy_defaults = {"use_sde": True} if self.use_sde else {}
        ent_coef, target_entropy = settings["ent_coef"], settings["target_entropy"]
        self._learn_ent_coef, self._ent_coef_init = _ent_coef_init(ent_coef)
        if isinstance(target_entropy, str) and target_entropy != "auto":
            raise ValueError(f'target_entropy must be "auto" or a number, got {target_entropy!r}')
        interval = settings["target_update_interval"]
        if isinstance(interval, bool) or not isinstance(interval, int) or interval < 1:
            raise ValueError(f"target_update_interval must be a positive int, got {interval!r}")
        self.ent_coef, self.target_entropy_setting = ent_coef, target_entropy
        self.target_update_interval = interval
        super()._take_settings(settings)

    def _setup_model(self) -> None:
        given = self.policy_kwargs.get("use_sde", self.use_sde)
        if given != self.use_sde:
            raise ValueError(
                f"policy_kwargs use_sde={given!r} contradicts use_sde={self.use_sde!r}: give it "
                "once, as SAC(use_sde=...)"
            )
        self._check_action_space()
        self.set_random_seed(self.seed)
        policy = self._make_policy(**self._policy_parts)
        self._use_policy(policy, math.log(self._ent_coef_init))
        self._make_replay_buffer()

    _policy_parts = dict(
        actor=SquashedGaussianActor, critic=ContinuousCritic, critic_target=ContinuousCritic
    )

    def _use_policy(self, policy: Any, log_ent_coef_init: float | None = None) -> None:
        """``log_ent_coef_init``: None keeps the current temperature (a policy assigned to
        ``model.policy``)."""
        self._check_parts(policy, self._policy_parts)
        if log_ent_coef_init is None:
            log_ent_coef_init = math.log(self._current_ent_coef())
        actor, critic, critic_target = policy.actor, policy.critic, policy.critic_target
        backend = self.policy_kwargs.get("backend", "auto")
        self.target_entropy = (
            float(-np.prod(self.action_space.shape).astype(np.float32))
            if self.target_entropy_setting == "auto"
            else float(self.target_entropy_setting)
        )
        log_ent_coef = torch.nn.Parameter(torch.full((1,), log_ent_coef_init))
        if self._learn_ent_coef:
            # Kept in the policy's state (``ent_coef.log_ent_coef``) so the model file has it.
            ent_coef = torch.nn.ParameterDict({"log_ent_coef": log_ent_coef}).to(self.device)
            policy.add_module("ent_coef", ent_coef)
        why = self._custom_policy(policy) or _numpy_input_problem(
            self.observation_space, actor.features_extractor, actor.normalize_images
        )
        nets = {
            "latent": Net(
                actor.latent,
                None if why else [actor.features_extractor, actor.latent_pi],
                group="actor",
                why=why,
            ),
            "mu": Net(actor.mu, [actor.mu], group="actor"),
            "log_std": Net(actor.log_std, [actor.log_std], group="actor"),
        }
        actor_extras: dict[str, torch.nn.Parameter] = {}
        self._sde: SDEDraw | None = None
        if getattr(actor, "use_sde", False):
            # gSDE: the mean's layer (its clip is the losses'), the weights' log-std an extra
            mean_layer = actor.mean_layer()
            nets["mu"] = Net(mean_layer, [mean_layer], group="actor")
            del nets["log_std"]
            assert isinstance(actor.log_std, torch.nn.Parameter)
            actor_extras = {"log_std": actor.log_std}
            self._sde = SDEDraw(actor.use_expln, actor.full_std, actor.clip_mean, self.action_dim)
            self._sde_dist = actor.action_dist
        critic_nets, critic_params = self._critic_nets(critic, critic_target, policy)
        nets.update(critic_nets)
        actor_params = list(actor.parameters())
        groups = {
            "actor": Group(
                self._make_optimizer_for(actor_params, policy), actor_params, actor_extras
            ),
            "critic": Group(self._make_optimizer_for(critic_params, policy), critic_params),
        }
        if self._learn_ent_coef:
            # SB3: plain Adam at the learning rate, whatever optimizer the networks use.
            ent_optimizer = self._make_optimizer([log_ent_coef], torch.optim.Adam, {})
            groups["ent_coef"] = Group(
                ent_optimizer, [log_ent_coef], {"log_ent_coef": log_ent_coef}
            )
        self._set_learner(policy, groups["actor"].optimizer, backend, nets, groups)
        self._groups = list(groups)

    @property
    def actor(self) -> SquashedGaussianActor:
        return self.policy.actor

    @property
    def critic(self) -> Any:
        return self.policy.critic

    @property
    def critic_target(self) -> Any:
        return self.policy.critic_target

    def _optimizers(self) -> dict[str, tuple[str, torch.optim.Optimizer]]:
        optimizers = super()._optimizers()
        groups = self.learner.groups
        if "ent_coef" in groups:
            optimizers["ent_coef_optimizer"] = ("ent_coef_optimizer", groups["ent_coef"].optimizer)
        return optimizers

    def _current_ent_coef(self) -> float:
        if not self._learn_ent_coef:
            return self._ent_coef_init
        return float(np.exp(self.learner.extra("log_ent_coef")[0]))

    # -- acting ------------------------------------------------------------------------------
    def _policy_actions(self, obs: Any, deterministic: bool) -> np.ndarray:
        latent = self.learner.forward("latent", obs)
        mean = self.learner.forward("mu", latent)
        if self._sde is not None:
            if self._sde.clip_mean > 0:
                mean = np.clip(mean, -self._sde.clip_mean, self._sde.clip_mean)
            if not deterministic:
                dist = self._sde_dist
                mat = dist.exploration_mat.detach().cpu().numpy()
                mats = dist.exploration_matrices.detach().cpu().numpy()
                mean = mean + sde_noise(numpy_ops, latent, mat, mats)
            return np.tanh(mean)
        if deterministic:
            return np.tanh(mean)
        log_std = self.learner.forward("log_std", latent)
        noise = self._rng.standard_normal(mean.shape, np.float32)
        return squashed_gaussian_rsample(numpy_ops, mean, log_std, noise)[0]

    def _reset_noise(self) -> None:
        """gSDE: new exploration matrices (one, and one per env) from the model's generator."""
        log_std = torch.as_tensor(self.learner.extra("log_std"))
        self._sde_dist.sample_weights(log_std, batch_size=self.n_envs, rng=self._rng)

    def _uniform_warmup(self) -> bool:
        return super()._uniform_warmup() and not (self.use_sde and self.use_sde_at_warmup)

    def _sample_actions(self) -> tuple[np.ndarray, np.ndarray]:
        if self._sde is not None:
            # SB3's collect_rollouts: new matrices as each collection starts and every
            # sde_sample_freq steps of it
            step, freq = self._collected_steps, self.sde_sample_freq
            if step == 0 or (freq > 0 and step % freq == 0):
                self._reset_noise()
        return super()._sample_actions()

    def _loop_state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        meta, arrays = super()._loop_state()
        if self._sde is not None:  # an open collection continues with its matrices
            dist = self._sde_dist
            arrays["sde/exploration_mat"] = dist.exploration_mat.detach().cpu().numpy()
            arrays["sde/exploration_matrices"] = dist.exploration_matrices.detach().cpu().numpy()
        return meta, arrays

    def _sde_matrix_shape(self) -> tuple[int, ...] | None:
        return None if self._sde is None else tuple(self._sde_dist.exploration_mat.shape)

    def _load_loop_state(self, meta: Any, arrays: dict[str, np.ndarray]) -> None:
        super()._load_loop_state(meta, arrays)
        if self._sde is not None and "sde/exploration_mat" in arrays:
            mat, mats = arrays["sde/exploration_mat"], arrays["sde/exploration_matrices"]
            shape = tuple(self._sde_dist.exploration_mat.shape)
            if mat.shape != shape or mats.shape[1:] != shape:
                raise ValueError(
                    f"gSDE exploration matrices of shape {mat.shape} and {mats.shape} do not "
                    f"fit the actor's {shape}"
                )
            self._sde_dist.exploration_mat = torch.as_tensor(mat)
            self._sde_dist.exploration_matrices = torch.as_tensor(mats)

    # -- learning ----------------------------------------------------------------------------
    def train(self, gradient_steps: int, batch_size: int = 64) -> None:
        """``gradient_steps`` updates of the critics, the actor and the temperature."""
        self._set_training_mode(True)
        for group in self._groups:
            self._update_learning_rate(group)
        logs: dict[str, list[float]] = {}
        with self.learner.session():
            for step in range(gradient_steps):
                batch = self._sample_batch(batch_size)
                if self._sde is not None:
                    # SB3 resamples the matrix every gradient step (the log-std moved): one
                    # for the batch, shared by the actor's and the target's actions
                    shape = tuple(self._sde_dist.exploration_mat.shape)
                    batch["sde_noise"] = self._rng.standard_normal(shape, np.float32)
                else:
                    shape = (batch_size, self.action_dim)
                    batch["noise"] = self._rng.standard_normal(shape, np.float32)
                    batch["next_noise"] = self._rng.standard_normal(shape, np.float32)
                ent_coef = self._current_ent_coef()
                logs.setdefault("ent_coef", []).append(ent_coef)
                critic = SACCriticObjective(self._n_critics, self.gamma, ent_coef, self._sde)
                metrics, _ = self.learner.update("critic", critic, batch)
                actor = SACActorObjective(self._n_critics, ent_coef, self.action_dim, self._sde)
                metrics.update(self.learner.update("actor", actor, batch)[0])
                if self._learn_ent_coef:
                    temperature = EntCoefObjective(self.target_entropy, actor.last_log_prob)
                    metrics.update(self.learner.update("ent_coef", temperature, {})[0])
                if step % self.target_update_interval == 0:
                    self._polyak_critics()
                for key, value in metrics.items():
                    logs.setdefault(key, []).append(value)
        self._n_updates += gradient_steps
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        for key in ("ent_coef", "actor_loss", "critic_loss", "ent_coef_loss"):
            if key in logs:
                self.logger.record(f"train/{key}", float(np.mean(logs[key])))
