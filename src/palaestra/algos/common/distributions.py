"""Action distributions at SB3's path (``stable_baselines3.common.distributions``): SB3's public
classes, and PPO's ``ActionHead`` that the algorithms run. Both compute through the one maths in
``learners.heads`` (log-probabilities, entropies, gSDE's std and noise); the SB3 classes run it
on torch tensors with autograd, keep a ``torch.distributions`` object in ``distribution`` (as
SB3's, for ``kl_divergence`` and for users who read it) and sample from torch's generator as
SB3 does, so the same torch seed gives SB3's samples.

Categorical (Discrete), one Categorical per dimension (MultiDiscrete), Bernoulli (MultiBinary)
and a diagonal Gaussian with a state-independent log-std (Box), as in SB3. Actions leave
``sample`` in the env's own terms (``start`` offsets added); ``index`` takes them back.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, TypeVar

import numpy as np
import torch
from torch import nn
from torch.distributions import Bernoulli, Categorical, Normal

from palaestra import spaces
from palaestra.algos.learners import heads
from palaestra.algos.learners.xp import numpy_ops, torch_ops
from palaestra.error import UnsupportedSpace

__all__ = [
    "ActionHead",
    "BernoulliDistribution",
    "CategoricalDistribution",
    "DiagGaussianDistribution",
    "Distribution",
    "MultiCategoricalDistribution",
    "SquashedDiagGaussianDistribution",
    "StateDependentNoiseDistribution",
    "TanhBijector",
    "kl_divergence",
    "make_proba_distribution",
    "sum_independent_dims",
]

SelfDistribution = TypeVar("SelfDistribution", bound="Distribution")


class Distribution(ABC):
    """SB3's base: ``proba_distribution(params)`` sets the distribution (and returns self),
    then ``log_prob``, ``entropy``, ``sample``, ``mode``, ``get_actions``."""

    distribution: Any

    def __init__(self) -> None:
        super().__init__()

    @abstractmethod
    def proba_distribution_net(self, *args: Any, **kwargs: Any) -> Any:
        """The layers (and parameter) that output the distribution's parameters."""

    @abstractmethod
    def proba_distribution(self: SelfDistribution, *args: Any, **kwargs: Any) -> SelfDistribution:
        """Set the distribution from its parameters; returns self."""

    @abstractmethod
    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        """Log-likelihood of ``actions`` ``[B]``."""

    @abstractmethod
    def entropy(self) -> torch.Tensor | None:
        """Entropy ``[B]``, or None where there is no closed form."""

    @abstractmethod
    def sample(self) -> torch.Tensor:
        """A sample (reparameterised where continuous)."""

    @abstractmethod
    def mode(self) -> torch.Tensor:
        """The most likely action."""

    def get_actions(self, deterministic: bool = False) -> torch.Tensor:
        """``mode()`` if ``deterministic`` else ``sample()``."""
        return self.mode() if deterministic else self.sample()

    @abstractmethod
    def actions_from_params(self, *args: Any, **kwargs: Any) -> torch.Tensor:
        """``proba_distribution(params)`` then ``get_actions``."""

    @abstractmethod
    def log_prob_from_params(self, *args: Any, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor]:
        """A sample and its log-probability from the parameters."""


def sum_independent_dims(tensor: torch.Tensor) -> torch.Tensor:
    """Sum over the action dimensions: ``[B, d] -> [B]``, ``[B] -> scalar`` (SB3's)."""
    return tensor.sum(dim=1) if tensor.dim() > 1 else tensor.sum()


class DiagGaussianDistribution(Distribution):
    """Diagonal Gaussian for Box actions, with a state-independent log-std parameter."""

    distribution: Normal

    def __init__(self, action_dim: int) -> None:
        super().__init__()
        self.action_dim = action_dim
        self.mean_actions: torch.Tensor | None = None
        self.log_std: torch.Tensor | None = None

    def proba_distribution_net(
        self, latent_dim: int, log_std_init: float = 0.0
    ) -> tuple[nn.Module, nn.Parameter]:
        """``(Linear(latent_dim, action_dim), log_std parameter [action_dim])``."""
        mean_actions = nn.Linear(latent_dim, self.action_dim)
        log_std = nn.Parameter(torch.ones(self.action_dim) * log_std_init, requires_grad=True)
        return mean_actions, log_std

    def proba_distribution(
        self: SelfDistribution, mean_actions: torch.Tensor, log_std: torch.Tensor
    ) -> SelfDistribution:
        self.mean_actions, self.log_std = mean_actions, log_std  # type: ignore[attr-defined]
        self.distribution = Normal(mean_actions, torch.ones_like(mean_actions) * log_std.exp())
        return self

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        assert self.mean_actions is not None and self.log_std is not None
        return heads.gaussian_evaluate(torch_ops, self.mean_actions, self.log_std, actions)[0]

    def entropy(self) -> torch.Tensor | None:
        assert self.mean_actions is not None and self.log_std is not None
        mean, log_std = self.mean_actions, self.log_std
        entropy = heads.gaussian_evaluate(torch_ops, mean, log_std, mean)[1]
        return entropy.expand(mean.shape[0]) if entropy.dim() == 0 else entropy

    def sample(self) -> torch.Tensor:
        return self.distribution.rsample()

    def mode(self) -> torch.Tensor:
        return self.distribution.mean

    def actions_from_params(
        self, mean_actions: torch.Tensor, log_std: torch.Tensor, deterministic: bool = False
    ) -> torch.Tensor:
        self.proba_distribution(mean_actions, log_std)
        return self.get_actions(deterministic=deterministic)

    def log_prob_from_params(
        self, mean_actions: torch.Tensor, log_std: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        actions = self.actions_from_params(mean_actions, log_std)
        return actions, self.log_prob(actions)


class SquashedDiagGaussianDistribution(DiagGaussianDistribution):
    """A diagonal Gaussian followed by tanh (actions in ``(-1, 1)``), as SAC's."""

    def __init__(self, action_dim: int, epsilon: float = 1e-6) -> None:
        super().__init__(action_dim)
        if epsilon != heads.SQUASH_EPS:
            raise ValueError(f"epsilon must be {heads.SQUASH_EPS} (SB3's), got {epsilon!r}")
        self.epsilon = epsilon
        self.gaussian_actions: torch.Tensor | None = None

    def log_prob(
        self, actions: torch.Tensor, gaussian_actions: torch.Tensor | None = None
    ) -> torch.Tensor:
        if gaussian_actions is None:
            gaussian_actions = heads.tanh_inverse(torch_ops, actions)
        log_prob = super().log_prob(gaussian_actions)
        return log_prob - heads.squash_correction(torch_ops, actions)

    def entropy(self) -> torch.Tensor | None:
        return None  # no closed form: estimated as -log_prob.mean() by the losses

    def sample(self) -> torch.Tensor:
        self.gaussian_actions = super().sample()
        return torch.tanh(self.gaussian_actions)

    def mode(self) -> torch.Tensor:
        self.gaussian_actions = super().mode()
        return torch.tanh(self.gaussian_actions)

    def log_prob_from_params(
        self, mean_actions: torch.Tensor, log_std: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        action = self.actions_from_params(mean_actions, log_std)
        return action, self.log_prob(action, self.gaussian_actions)


class _LogitsDistribution(Distribution):
    """The discrete distributions' common part: their one parameter is the logits."""

    def actions_from_params(
        self, action_logits: torch.Tensor, deterministic: bool = False
    ) -> torch.Tensor:
        self.proba_distribution(action_logits)
        return self.get_actions(deterministic=deterministic)

    def log_prob_from_params(
        self, action_logits: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        actions = self.actions_from_params(action_logits)
        return actions, self.log_prob(actions)


class CategoricalDistribution(_LogitsDistribution):
    """Categorical over ``action_dim`` choices (Discrete)."""

    distribution: Categorical

    def __init__(self, action_dim: int) -> None:
        super().__init__()
        self.action_dim = action_dim

    def proba_distribution_net(self, latent_dim: int) -> nn.Module:
        """``Linear(latent_dim, action_dim)``: the logits."""
        return nn.Linear(latent_dim, self.action_dim)

    def proba_distribution(self: SelfDistribution, action_logits: torch.Tensor) -> SelfDistribution:
        self.distribution = Categorical(logits=action_logits)
        return self

    def _logits(self) -> torch.Tensor:
        return self.distribution.logits.reshape(-1, self.distribution.logits.shape[-1])

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        return heads.categorical_evaluate(torch_ops, self._logits(), actions.reshape(-1))[0]

    def entropy(self) -> torch.Tensor:
        logits = self._logits()
        idx = torch.zeros(logits.shape[0], dtype=torch.long, device=logits.device)
        return heads.categorical_evaluate(torch_ops, logits, idx)[1]

    def sample(self) -> torch.Tensor:
        return self.distribution.sample()

    def mode(self) -> torch.Tensor:
        return torch.argmax(self.distribution.probs, dim=1)


class MultiCategoricalDistribution(_LogitsDistribution):
    """One categorical per dimension (MultiDiscrete); ``distribution`` is their list."""

    distribution: list[Categorical]

    def __init__(self, action_dims: list[int]) -> None:
        super().__init__()
        self.action_dims = action_dims
        self.action_logits: torch.Tensor | None = None

    def proba_distribution_net(self, latent_dim: int) -> nn.Module:
        """``Linear(latent_dim, sum(action_dims))``: the logits side by side."""
        return nn.Linear(latent_dim, int(sum(self.action_dims)))

    def proba_distribution(self: SelfDistribution, action_logits: torch.Tensor) -> SelfDistribution:
        sizes = [int(n) for n in self.action_dims]  # type: ignore[attr-defined]
        self.action_logits = action_logits  # type: ignore[attr-defined]
        self.distribution = [
            Categorical(logits=part) for part in torch.split(action_logits, sizes, dim=1)
        ]
        return self

    def _evaluate(self, actions: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        assert self.action_logits is not None
        sizes = [int(n) for n in self.action_dims]
        lp, ent, _ = heads.multi_categorical_evaluate(
            torch_ops, self.action_logits, actions.reshape(-1, len(sizes)), sizes
        )
        return lp, ent

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        return self._evaluate(actions)[0]

    def entropy(self) -> torch.Tensor:
        assert self.action_logits is not None
        n = self.action_logits.shape[0]
        zeros = torch.zeros(n, len(self.action_dims), dtype=torch.long)
        return self._evaluate(zeros.to(self.action_logits.device))[1]

    def sample(self) -> torch.Tensor:
        return torch.stack([dist.sample() for dist in self.distribution], dim=1)

    def mode(self) -> torch.Tensor:
        return torch.stack([torch.argmax(dist.probs, dim=1) for dist in self.distribution], dim=1)


class BernoulliDistribution(_LogitsDistribution):
    """Independent bits (MultiBinary)."""

    distribution: Bernoulli

    def __init__(self, action_dims: int) -> None:
        super().__init__()
        self.action_dims = action_dims

    def proba_distribution_net(self, latent_dim: int) -> nn.Module:
        """``Linear(latent_dim, action_dims)``: one logit per bit."""
        return nn.Linear(latent_dim, self.action_dims)

    def proba_distribution(self: SelfDistribution, action_logits: torch.Tensor) -> SelfDistribution:
        self.distribution = Bernoulli(logits=action_logits)
        return self

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        logits = self.distribution.logits
        return heads.bernoulli_evaluate(torch_ops, logits, actions.to(logits.dtype))[0]

    def entropy(self) -> torch.Tensor:
        logits = self.distribution.logits
        return heads.bernoulli_evaluate(torch_ops, logits, torch.zeros_like(logits))[1]

    def sample(self) -> torch.Tensor:
        return self.distribution.sample()

    def mode(self) -> torch.Tensor:
        return torch.round(self.distribution.probs)


class StateDependentNoiseDistribution(Distribution):
    """gSDE (Raffin et al. 2022): the action noise is ``latent_sde @ W`` for a weight matrix
    ``W ~ N(0, std^2)`` drawn by ``sample_weights`` (``exploration_mat``, and one per env in
    ``exploration_matrices``), so the action is Gaussian with variance
    ``latent_sde^2 @ std^2`` (+``epsilon``). ``full_std``: a std per (feature, action), else
    per feature; ``use_expln``: SB3's slowly growing ``expln`` instead of ``exp``;
    ``squash_output``: tanh on top; ``learn_features``: gradients reach ``latent_sde``."""

    distribution: Normal
    exploration_mat: torch.Tensor
    exploration_matrices: torch.Tensor

    def __init__(
        self,
        action_dim: int,
        full_std: bool = True,
        use_expln: bool = False,
        squash_output: bool = False,
        learn_features: bool = False,
        epsilon: float = 1e-6,
    ) -> None:
        super().__init__()
        if epsilon != heads.SDE_EPS:
            raise ValueError(f"epsilon must be {heads.SDE_EPS} (SB3's), got {epsilon!r}")
        self.action_dim = action_dim
        self.latent_sde_dim: int | None = None
        self.use_expln, self.full_std, self.epsilon = use_expln, full_std, epsilon
        self.learn_features = learn_features
        self.bijector = TanhBijector(epsilon) if squash_output else None
        self.mean_actions: torch.Tensor | None = None
        self._latent_sde: torch.Tensor | None = None
        self._std: torch.Tensor | None = None

    def get_std(self, log_std: torch.Tensor) -> torch.Tensor:
        """The weights' std ``[latent_sde_dim, action_dim]`` from ``log_std``."""
        if not self.full_std and self.latent_sde_dim is None:
            raise ValueError("get_std without full_std needs proba_distribution_net first")
        return heads.sde_std(torch_ops, log_std, self.use_expln, self.full_std, self.action_dim)[0]

    def sample_weights(
        self, log_std: torch.Tensor, batch_size: int = 1, rng: np.random.Generator | None = None
    ) -> None:
        """Draw ``exploration_mat`` and ``batch_size`` ``exploration_matrices`` (from torch's
        generator as SB3, reparameterised; or, given ``rng``, from that numpy generator)."""
        std = self.get_std(log_std)
        if rng is None:
            self.weights_dist = Normal(torch.zeros_like(std), std)
            self.exploration_mat = self.weights_dist.rsample()
            self.exploration_matrices = self.weights_dist.rsample((batch_size,))
            return
        with torch.no_grad():
            shape = (batch_size + 1, *std.shape)
            noise = torch.as_tensor(rng.standard_normal(shape, np.float32), device=std.device)
            weights = std * noise
        self.exploration_mat, self.exploration_matrices = weights[0], weights[1:]

    def proba_distribution_net(
        self, latent_dim: int, log_std_init: float = -2.0, latent_sde_dim: int | None = None
    ) -> tuple[nn.Module, nn.Parameter]:
        """``(Linear(latent_dim, action_dim), log_std [latent_sde_dim, action_dim or 1])``,
        and a first exploration matrix."""
        mean_actions_net = nn.Linear(latent_dim, self.action_dim)
        self.latent_sde_dim = latent_dim if latent_sde_dim is None else latent_sde_dim
        cols = self.action_dim if self.full_std else 1
        log_std = nn.Parameter(torch.ones(self.latent_sde_dim, cols) * log_std_init)
        self.sample_weights(log_std)
        return mean_actions_net, log_std

    def proba_distribution(
        self: SelfDistribution,
        mean_actions: torch.Tensor,
        log_std: torch.Tensor,
        latent_sde: torch.Tensor,
    ) -> SelfDistribution:
        this: Any = self
        this._latent_sde = latent_sde if this.learn_features else latent_sde.detach()
        this._std = this.get_std(log_std)
        this.mean_actions = mean_actions
        variance = (this._latent_sde**2) @ (this._std**2)
        this.distribution = Normal(mean_actions, torch.sqrt(variance + this.epsilon))
        return self

    def log_prob(self, actions: torch.Tensor) -> torch.Tensor:
        assert self.mean_actions is not None and self._std is not None
        squash = self.bijector is not None
        gaussian = heads.tanh_inverse(torch_ops, actions) if squash else actions
        return heads.sde_log_prob(
            torch_ops, self.mean_actions, self._std, self._latent_sde, gaussian, squash
        )[0]

    def entropy(self) -> torch.Tensor | None:
        if self.bijector is not None:
            return None  # no closed form: estimated as -log_prob.mean() by the losses
        assert self.mean_actions is not None and self._std is not None
        mean = self.mean_actions
        return heads.sde_log_prob(torch_ops, mean, self._std, self._latent_sde, mean, False)[1]

    def sample(self) -> torch.Tensor:
        assert self._latent_sde is not None
        actions = self.distribution.mean + self.get_noise(self._latent_sde)
        return actions if self.bijector is None else self.bijector.forward(actions)

    def mode(self) -> torch.Tensor:
        actions = self.distribution.mean
        return actions if self.bijector is None else self.bijector.forward(actions)

    def get_noise(self, latent_sde: torch.Tensor) -> torch.Tensor:
        """``latent_sde @ W``: one matrix, or one per row when there are as many (envs)."""
        latent_sde = latent_sde if self.learn_features else latent_sde.detach()
        return heads.sde_noise(
            torch_ops, latent_sde, self.exploration_mat, self.exploration_matrices
        )

    def actions_from_params(
        self,
        mean_actions: torch.Tensor,
        log_std: torch.Tensor,
        latent_sde: torch.Tensor,
        deterministic: bool = False,
    ) -> torch.Tensor:
        self.proba_distribution(mean_actions, log_std, latent_sde)
        return self.get_actions(deterministic=deterministic)

    def log_prob_from_params(
        self, mean_actions: torch.Tensor, log_std: torch.Tensor, latent_sde: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        actions = self.actions_from_params(mean_actions, log_std, latent_sde)
        return actions, self.log_prob(actions)


class TanhBijector:
    """tanh and its inverse, and the log-density correction of a tanh-squashed variable."""

    def __init__(self, epsilon: float = 1e-6) -> None:
        super().__init__()
        self.epsilon = epsilon

    @staticmethod
    def forward(x: torch.Tensor) -> torch.Tensor:
        return torch.tanh(x)

    @staticmethod
    def atanh(x: torch.Tensor) -> torch.Tensor:
        """``0.5 * log((1 + x) / (1 - x))`` written with ``log1p``."""
        return 0.5 * (x.log1p() - (-x).log1p())

    @staticmethod
    def inverse(y: torch.Tensor) -> torch.Tensor:
        """``atanh`` of ``y`` clipped one float32 epsilon inside ``(-1, 1)``."""
        return heads.tanh_inverse(torch_ops, y)

    def log_prob_correction(self, x: torch.Tensor) -> torch.Tensor:
        """``log(1 - tanh(x)^2 + epsilon)`` per entry."""
        return torch.log(1.0 - torch.tanh(x) ** 2 + self.epsilon)


def make_proba_distribution(
    action_space: spaces.Space[Any],
    use_sde: bool = False,
    dist_kwargs: dict[str, Any] | None = None,
) -> Distribution:
    """The distribution class for ``action_space`` (Box: ``StateDependentNoiseDistribution``
    with ``use_sde``, else ``DiagGaussianDistribution``), built with ``dist_kwargs``."""
    dist_kwargs = dist_kwargs or {}
    if isinstance(action_space, spaces.Box):
        cls: Any = StateDependentNoiseDistribution if use_sde else DiagGaussianDistribution
        return cls(int(np.prod(action_space.shape)), **dist_kwargs)
    if isinstance(action_space, spaces.Discrete):
        return CategoricalDistribution(int(action_space.n), **dist_kwargs)
    if isinstance(action_space, spaces.MultiDiscrete):
        return MultiCategoricalDistribution(list(action_space.nvec), **dist_kwargs)
    if isinstance(action_space, spaces.MultiBinary):
        if not isinstance(action_space.n, (int, np.integer)):
            raise ValueError(
                f"Multi-dimensional MultiBinary({action_space.n}) action space is not "
                "supported. You can flatten it instead."
            )
        return BernoulliDistribution(int(action_space.n), **dist_kwargs)
    raise NotImplementedError(
        "Error: probability distribution, not implemented for action space"
        f"of type {type(action_space)}."
        " Must be of type Gym Spaces: Box, Discrete, MultiDiscrete or MultiBinary."
    )


def kl_divergence(dist_true: Distribution, dist_pred: Distribution) -> torch.Tensor:
    """``KL(dist_true || dist_pred)`` ``[B]`` of two distributions of the same class."""
    if dist_true.__class__ != dist_pred.__class__:
        raise TypeError(
            "Error: input distributions should be the same type, "
            f"{dist_true.__class__} != {dist_pred.__class__}"
        )
    if isinstance(dist_pred, MultiCategoricalDistribution):
        assert isinstance(dist_true, MultiCategoricalDistribution)
        if not np.allclose(dist_pred.action_dims, dist_true.action_dims):
            raise ValueError(
                "Error: distributions must have the same input space: "
                f"{dist_pred.action_dims} != {dist_true.action_dims}"
            )
        return torch.stack(
            [
                torch.distributions.kl_divergence(p, q)
                for p, q in zip(dist_true.distribution, dist_pred.distribution, strict=True)
            ],
            dim=1,
        ).sum(dim=1)
    return torch.distributions.kl_divergence(dist_true.distribution, dist_pred.distribution)


class ActionHead(nn.Module):
    """``latent -> distribution parameters`` for one action space, and ``dist``: the SB3
    distribution object of the same kind (the policy's ``action_dist``).

    With ``use_sde`` a Box is gSDE's ``StateDependentNoiseDistribution`` (features not
    learned, as SB3's on-policy algorithms): ``log_std`` is ``[latent_dim, d or 1]``, and the
    exploration matrices live in ``dist`` (torch, as SB3) with a numpy copy for acting."""

    def __init__(
        self,
        action_space: spaces.Space[Any],
        latent_dim: int,
        log_std_init: float = 0.0,
        use_sde: bool = False,
        full_std: bool = True,
        use_expln: bool = False,
        squash_output: bool = False,
    ):
        super().__init__()
        self.offset: np.ndarray | None = None
        self.squash = False
        self._noise: tuple[np.ndarray, np.ndarray] | None = None  # gSDE: (matrix, per env)
        if use_sde and not isinstance(action_space, spaces.Box):
            raise ValueError(
                f"use_sde (gSDE) needs a Box action space, got {type(action_space).__name__}"
            )
        if squash_output and not use_sde:
            raise ValueError("squash_output=True is only available when using gSDE (use_sde=True)")
        self.dist: Distribution
        if isinstance(action_space, spaces.Discrete):
            self.kind, self.sizes, out = "categorical", [int(action_space.n)], int(action_space.n)
            self.offset = np.asarray(int(action_space.start)) if int(action_space.start) else None
            self.dist = CategoricalDistribution(out)
        elif isinstance(action_space, spaces.MultiDiscrete):
            if action_space.nvec.ndim != 1:
                raise ValueError(
                    f"only 1-D MultiDiscrete action spaces are supported, got {action_space}"
                )
            self.kind, self.sizes = "multi_categorical", [int(n) for n in action_space.nvec]
            out = sum(self.sizes)
            start = np.asarray(action_space.start, dtype=np.int64)
            self.offset = start if start.any() else None
            self.dist = MultiCategoricalDistribution(self.sizes)
        elif isinstance(action_space, spaces.MultiBinary):
            self.kind, self.sizes = "bernoulli", [int(np.prod(action_space.shape))]
            out = self.sizes[0]
            self.dist = BernoulliDistribution(out)
        elif isinstance(action_space, spaces.Box) and use_sde:
            self.kind, self.sizes = "sde", [int(np.prod(action_space.shape))]
            self.squash, self.full_std, self.use_expln = squash_output, full_std, use_expln
            self.dist = StateDependentNoiseDistribution(
                self.sizes[0], full_std, use_expln, squash_output, learn_features=False
            )
            # SB3's order: the mean's layer, the log-std, a first exploration matrix.
            self.net, self.log_std = self.dist.proba_distribution_net(latent_dim, log_std_init)
            self._noise_from_dist()
        elif isinstance(action_space, spaces.Box):
            self.kind, self.sizes = "gaussian", [int(np.prod(action_space.shape))]
            out = self.sizes[0]
            self.log_std = nn.Parameter(torch.full((out,), float(log_std_init)))
            self.dist = DiagGaussianDistribution(out)
        else:
            raise UnsupportedSpace(
                f"PPO does not support {type(action_space).__name__} action spaces"
            )
        self.action_shape: tuple[int, ...] = tuple(action_space.shape or ())
        if self.kind != "sde":
            self.net = nn.Linear(latent_dim, out)

    # -- gSDE's exploration matrices ------------------------------------------------------------
    def _noise_from_dist(self) -> None:
        dist = self.dist
        assert isinstance(dist, StateDependentNoiseDistribution)
        self._noise = (
            dist.exploration_mat.detach().cpu().numpy(),
            dist.exploration_matrices.detach().cpu().numpy(),
        )

    def reset_noise(
        self, log_std: Any, n_envs: int, rng: np.random.Generator | None = None
    ) -> None:
        """Draw new exploration matrices (one, and one per env) for the std of ``log_std``
        (a tensor, or the learner's numpy array), from ``rng`` or torch's generator."""
        dist = self.dist
        if not isinstance(dist, StateDependentNoiseDistribution):
            raise ValueError("reset_noise() is only available when using gSDE")
        log_std = torch.as_tensor(log_std, device=self.log_std.device)
        dist.sample_weights(log_std, batch_size=n_envs, rng=rng)
        self._noise_from_dist()

    def noise_state(self) -> dict[str, np.ndarray]:
        """The exploration matrices, for a model file (empty without gSDE)."""
        if self._noise is None:
            return {}
        return {"exploration_mat": self._noise[0], "exploration_matrices": self._noise[1]}

    def load_noise_state(self, arrays: dict[str, np.ndarray]) -> None:
        """Restore ``noise_state`` output."""
        dist = self.dist
        if not isinstance(dist, StateDependentNoiseDistribution):
            return
        mat, mats = arrays["exploration_mat"], arrays["exploration_matrices"]
        assert self._noise is not None
        if mat.shape != self._noise[0].shape or mats.shape[1:] != self._noise[0].shape:
            raise ValueError(
                f"gSDE exploration matrices of shape {mat.shape} and {mats.shape} do not fit "
                f"the policy's {self._noise[0].shape}"
            )
        device = self.log_std.device
        dist.exploration_mat = torch.as_tensor(mat, device=device)
        dist.exploration_matrices = torch.as_tensor(mats, device=device)
        self._noise_from_dist()

    # -- the networks' outputs -----------------------------------------------------------------
    def run(self, run: Any, obs: Any) -> tuple[Any, Any]:
        """``(head outputs, latent or None)`` through the learner's ``run``: gSDE's variance
        needs the policy latent, so its nets are ``pi`` (to the latent) and ``act`` (the
        mean's layer); other heads run ``pi`` whole."""
        if self.kind == "sde":
            latent = run("pi", obs)
            return run("act", latent), latent
        return run("pi", obs), None

    def backprop(self, backprop: Any, g_params: np.ndarray) -> None:
        """Send d(loss)/d(head outputs) back through the nets ``run`` ran."""
        if self.kind == "sde":
            g_latent = backprop("act", g_params, input_grad=True)
            backprop("pi", g_latent)
        else:
            backprop("pi", g_params)

    def sample(
        self,
        params: np.ndarray,
        log_std: np.ndarray | None,
        rng: np.random.Generator,
        deterministic: bool,
        latent: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Actions ``[B, *shape]`` (or their modes) from head outputs ``params``, drawn from
        ``rng`` (gSDE: the exploration matrices and the ``latent``), and their
        log-probabilities ``[B]`` float32."""
        n = params.shape[0]
        if self.kind == "categorical":
            actions, log_prob = heads.categorical_sample(params, rng, deterministic)
        elif self.kind == "multi_categorical":
            actions, log_prob = heads.multi_categorical_sample(
                params, self.sizes, rng, deterministic
            )
        elif self.kind == "bernoulli":
            actions, log_prob = heads.bernoulli_sample(params, rng, deterministic)
        elif self.kind == "sde":
            assert log_std is not None and latent is not None and self._noise is not None
            std = heads.sde_std(numpy_ops, log_std, self.use_expln, self.full_std, self.sizes[0])[0]
            gaussian = params
            if not deterministic:
                gaussian = params + heads.sde_noise(numpy_ops, latent, *self._noise)
            log_prob = heads.sde_log_prob(numpy_ops, params, std, latent, gaussian, self.squash)[0]
            actions = np.tanh(gaussian) if self.squash else gaussian
            log_prob = log_prob.astype(np.float32, copy=False)
        else:
            assert log_std is not None
            actions, log_prob = heads.gaussian_sample(params, log_std, rng, deterministic)
        if self.offset is not None:
            actions = actions + self.offset
        return actions.reshape(n, *self.action_shape), log_prob

    def index(self, actions: np.ndarray) -> np.ndarray:
        """Env actions (a batch) as the head's operand: 0-based int64 indices, or the float32
        bits or values ``[B, d]``."""
        n = actions.shape[0]
        if self.kind == "categorical":
            idx = actions.reshape(n).astype(np.int64, copy=False)
        elif self.kind == "multi_categorical":
            idx = actions.reshape(n, -1).astype(np.int64, copy=False)
        else:
            return actions.reshape(n, -1).astype(np.float32, copy=False)
        return idx if self.offset is None else idx - self.offset

    def evaluate(
        self, xp: Any, params: Any, log_std: Any, actions: Any, latent: Any = None
    ) -> tuple[Any, Any, Any]:
        """``(log_prob [B], entropy, tape)`` of ``index``-ed actions (see ``learners.heads``);
        gSDE also takes the policy ``latent`` (not differentiated through the variance)."""
        if self.kind == "categorical":
            return heads.categorical_evaluate(xp, params, actions)
        if self.kind == "multi_categorical":
            return heads.multi_categorical_evaluate(xp, params, actions, self.sizes)
        if self.kind == "bernoulli":
            return heads.bernoulli_evaluate(xp, params, actions)
        if self.kind == "sde":
            d = self.sizes[0]
            std, std_tape = heads.sde_std(xp, log_std, self.use_expln, self.full_std, d)
            gaussian = heads.tanh_inverse(xp, actions) if self.squash else actions
            log_prob, entropy, tape = heads.sde_log_prob(
                xp, params, std, xp.stop_gradient(latent), gaussian, self.squash
            )
            return log_prob, entropy, (std_tape, tape)
        return heads.gaussian_evaluate(xp, params, log_std, actions)

    def evaluate_vjp(
        self, tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """``(d/d params, d/d log_std or None)``."""
        if self.kind == "categorical":
            return heads.categorical_evaluate_vjp(tape, g_log_prob, g_mean_entropy), None
        if self.kind == "multi_categorical":
            return heads.multi_categorical_evaluate_vjp(tape, g_log_prob, g_mean_entropy), None
        if self.kind == "bernoulli":
            return heads.bernoulli_evaluate_vjp(tape, g_log_prob, g_mean_entropy), None
        if self.kind == "sde":
            std_tape, lp_tape = tape
            g_mean, g_std, _, _ = heads.sde_log_prob_vjp(lp_tape, g_log_prob, g_mean_entropy, False)
            return g_mean, heads.sde_std_vjp(std_tape, g_std)
        return heads.gaussian_evaluate_vjp(tape, g_log_prob, g_mean_entropy)

    def distribution(self, params: Any, log_std: Any, latent: Any = None) -> Distribution:
        """``dist`` set to these torch parameters (SB3's ``_get_action_dist_from_latent``)."""
        if self.kind == "sde":
            return self.dist.proba_distribution(params, log_std, latent)
        if self.kind == "gaussian":
            return self.dist.proba_distribution(params, log_std)
        return self.dist.proba_distribution(params)
