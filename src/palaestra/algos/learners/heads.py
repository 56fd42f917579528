"""Action distributions written once over an array namespace ``xp`` (numpy or torch), each with
its vector-Jacobian product beside it, and numpy samplers for acting.

``*_evaluate(xp, ...)`` returns ``(log_prob [B], entropy, tape)``: entropy is ``[B]``, or a
scalar where it does not depend on the row (a state-independent Gaussian); ``tape`` holds what
the VJP needs (numpy). The VJPs take d(loss)/d(log_prob) per row and d(loss)/d(mean entropy)
as one number: the losses use the entropy only through its mean, and keeping it one number
keeps the numpy gradients exactly those of the trainers before this module.

Heads: Categorical (Discrete), MultiCategorical (MultiDiscrete), Bernoulli (MultiBinary),
diagonal Gaussian with a state-independent log-std (PPO's Box), the tanh-squashed Gaussian
(SAC, with SB3's log-std bounds and 1e-6 in the squashing correction), the deterministic
tanh (TD3, DDPG), and gSDE's state-dependent noise (Raffin et al. 2022: the action noise is
``latent @ W`` for a Gaussian weight matrix ``W`` drawn now and then, so the action's
variance is ``latent^2 @ std^2``), squashed by tanh or not. Sampling draws from the model's
numpy generator whatever learner runs the networks, so the two learners act alike.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from palaestra.algos.learners.xp import row_indices

__all__ = [
    "LOG_STD_MAX",
    "LOG_STD_MIN",
    "bernoulli_evaluate",
    "bernoulli_evaluate_vjp",
    "bernoulli_sample",
    "categorical_evaluate",
    "categorical_evaluate_vjp",
    "categorical_sample",
    "gaussian_evaluate",
    "gaussian_evaluate_vjp",
    "gaussian_sample",
    "multi_categorical_evaluate",
    "multi_categorical_evaluate_vjp",
    "multi_categorical_sample",
    "sde_log_prob",
    "sde_log_prob_vjp",
    "sde_noise",
    "sde_rsample",
    "sde_rsample_vjp",
    "sde_std",
    "sde_std_vjp",
    "squash_correction",
    "squashed_gaussian_rsample",
    "squashed_gaussian_rsample_vjp",
    "tanh_action",
    "tanh_action_vjp",
    "tanh_inverse",
]

LOG_SQRT_2PI = 0.5 * math.log(2 * math.pi)
LOG_STD_MIN, LOG_STD_MAX = -20.0, 2.0  # SB3's SAC actor bounds
SQUASH_EPS = 1e-6  # SB3's TanhBijector epsilon
SDE_EPS = 1e-6  # SB3's StateDependentNoiseDistribution epsilon (variance floor, expln)
F32_EPS = float(np.finfo(np.float32).eps)  # the inverse tanh's clip, as SB3's for float32


# -- Categorical ------------------------------------------------------------------------------
def categorical_sample(
    logits: np.ndarray, rng: np.random.Generator, deterministic: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise draws (inverse CDF) or the argmax of logits ``[B, n]``, and the
    log-probability of each pick: ``(indices [B], log_probs [B])``.

    Called every env step with B of 1-16, where each numpy call costs about a microsecond
    whatever its size: the ufuncs' own ``reduce``/``accumulate`` skip the Python layers of
    ``max``/``sum``/``cumsum``, and the CDF is the running sum of the unnormalised
    probabilities (the draw is scaled by their total) so nothing is normalised twice.
    """
    shifted = logits - np.maximum.reduce(logits, axis=1, keepdims=True)
    cdf = np.add.accumulate(np.exp(shifted), axis=1)
    total = cdf[:, -1]
    if deterministic:
        idx = shifted.argmax(axis=1)
    else:
        # u < 1, so u * total < total == cdf[:, -1] (float64 product of a float32 total):
        # at most n - 1 entries lie below, and the index needs no clamp.
        u = rng.random(logits.shape[0]) * total
        idx = np.add.reduce(cdf < u[:, None], axis=1)
    return idx, shifted[row_indices(len(idx)), idx] - np.log(total)


def categorical_evaluate(xp: Any, logits: Any, idx: Any) -> tuple[Any, Any, Any]:
    """Log-probabilities of 0-based ``idx [B]`` under ``logits [B, n]``, and entropies."""
    logp = xp.log_softmax(logits)
    probs = xp.exp(logp)
    entropy = -xp.sum_rows(probs * logp)
    return xp.take_rows(logp, idx), entropy, (logp, probs, idx, entropy)


def categorical_evaluate_vjp(
    tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float
) -> np.ndarray:
    """d(loss)/d(logits): ``g * (one_hot - p)`` from the log-prob, and from the mean entropy
    ``-p * (log p + H) * g_H / B``."""
    logp, probs, idx, entropy = tape
    neg = -g_log_prob
    g = neg[:, None] * probs
    if g_mean_entropy:
        g += (-g_mean_entropy / probs.shape[0]) * probs * (logp + entropy[:, None])
    g[row_indices(probs.shape[0]), idx] -= neg
    return g


# -- MultiCategorical -------------------------------------------------------------------------
def _splits(sizes: list[int]) -> list[tuple[int, int]]:
    bounds = np.cumsum([0, *sizes]).tolist()
    return list(itertools.pairwise(bounds))


def multi_categorical_sample(
    logits: np.ndarray, sizes: list[int], rng: np.random.Generator, deterministic: bool
) -> tuple[np.ndarray, np.ndarray]:
    """One categorical per dimension: ``(indices [B, len(sizes)], summed log_probs [B])``."""
    picks, log_prob = [], np.zeros(logits.shape[0], dtype=np.float32)
    for a, b in _splits(sizes):
        idx, logp = categorical_sample(logits[:, a:b], rng, deterministic)
        picks.append(idx)
        log_prob += logp
    return np.stack(picks, axis=1), log_prob


def multi_categorical_evaluate(
    xp: Any, logits: Any, idx: Any, sizes: list[int]
) -> tuple[Any, Any, Any]:
    """Summed log-probabilities and entropies of 0-based ``idx [B, len(sizes)]``."""
    log_prob = entropy = None
    tapes = []
    for i, (a, b) in enumerate(_splits(sizes)):
        lp, ent, tape = categorical_evaluate(xp, logits[:, a:b], idx[:, i])
        log_prob = lp if log_prob is None else log_prob + lp
        entropy = ent if entropy is None else entropy + ent
        tapes.append(tape)
    return log_prob, entropy, (tapes, sizes)


def multi_categorical_evaluate_vjp(
    tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float
) -> np.ndarray:
    tapes, _ = tape
    return np.concatenate(
        [categorical_evaluate_vjp(t, g_log_prob, g_mean_entropy) for t in tapes], axis=1
    )


# -- Bernoulli --------------------------------------------------------------------------------
def bernoulli_sample(
    logits: np.ndarray, rng: np.random.Generator, deterministic: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Bits ``[B, n]`` (float32 0/1) and their summed log-probabilities ``[B]``."""
    if deterministic:
        bits = logits > 0.0
    else:
        bits = rng.random(logits.shape) < 1.0 / (1.0 + np.exp(-logits))
    log_prob = -np.logaddexp(0.0, np.where(bits, -logits, logits)).sum(axis=1)
    return bits.astype(np.float32), log_prob.astype(np.float32)


def bernoulli_evaluate(xp: Any, logits: Any, bits: Any) -> tuple[Any, Any, Any]:
    """``log p(bits) = -softplus(-z)`` for a 1 and ``-softplus(z)`` for a 0, summed; entropy
    ``softplus(z) - z * sigmoid(z)`` summed over the bits."""
    signed = xp.where(bits > 0.5, -logits, logits)
    log_prob = -xp.sum_rows(xp.softplus(signed))
    sig = 1.0 / (1.0 + xp.exp(-logits))
    entropy = xp.sum_rows(xp.softplus(logits) - logits * sig)
    return log_prob, entropy, (logits, bits, sig)


def bernoulli_evaluate_vjp(tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float) -> np.ndarray:
    logits, bits, sig = tape
    g = g_log_prob[:, None] * (bits - sig)
    if g_mean_entropy:  # dH/dz = -z * s * (1 - s)
        g -= (g_mean_entropy / logits.shape[0]) * logits * sig * (1.0 - sig)
    return g.astype(np.float32, copy=False)


# -- Gaussian with a state-independent log-std (PPO) -------------------------------------------
def gaussian_sample(
    mean: np.ndarray, log_std: np.ndarray, rng: np.random.Generator, deterministic: bool
) -> tuple[np.ndarray, np.ndarray]:
    """``mean + std * noise`` (or the mean) and the log-densities ``[B]``."""
    noise = np.zeros_like(mean) if deterministic else rng.standard_normal(mean.shape, np.float32)
    actions = mean + noise * np.exp(log_std)
    log_prob = (-0.5 * noise**2 - log_std - LOG_SQRT_2PI).sum(axis=1)
    return actions, log_prob.astype(np.float32)


def gaussian_evaluate(xp: Any, mean: Any, log_std: Any, actions: Any) -> tuple[Any, Any, Any]:
    """Log-densities of ``actions [B, d]``; the entropy is one number (no row dependence)."""
    inv_std = xp.exp(-log_std)
    z = (actions - mean) * inv_std
    log_prob = xp.sum_rows(-0.5 * z * z - log_std - LOG_SQRT_2PI)
    if log_std.ndim == 1:
        entropy = xp.sum(0.5 + LOG_SQRT_2PI + log_std)
    else:  # a log-std per row (SB3's distributions accept one; the algorithms do not use it)
        entropy = xp.sum_rows(0.5 + LOG_SQRT_2PI + log_std + 0.0 * mean)
    return log_prob, entropy, (z, inv_std)


def gaussian_evaluate_vjp(
    tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(d/d mean [B, d], d/d log_std [d])``."""
    z, inv_std = tape
    g_mean = g_log_prob[:, None] * z * inv_std
    g_log_std = (g_log_prob[:, None] * (z * z - 1.0)).sum(axis=0) + g_mean_entropy
    return g_mean, g_log_std


# -- tanh-squashed Gaussian (SAC) --------------------------------------------------------------
def squashed_gaussian_rsample(xp: Any, mean: Any, log_std: Any, noise: Any) -> tuple[Any, Any, Any]:
    """Reparameterised ``a = tanh(mean + std * noise)`` with ``log_std`` clipped to SB3's
    ``[-20, 2]``, and ``log pi(a) = log N(u) - sum log(1 - a^2 + 1e-6)``: ``(a, log_prob, tape)``.
    ``noise`` is standard normal, drawn by the caller."""
    clipped = xp.clip(log_std, LOG_STD_MIN, LOG_STD_MAX)
    std = xp.exp(clipped)
    u = mean + std * noise
    a = xp.tanh(u)
    one_minus = 1.0 - a * a
    log_prob = xp.sum_rows(-0.5 * noise * noise - clipped - LOG_SQRT_2PI) - xp.sum_rows(
        xp.log(one_minus + SQUASH_EPS)
    )
    return a, log_prob, (log_std, std, noise, a, one_minus)


def squashed_gaussian_rsample_vjp(
    tape: Any, g_action: np.ndarray | None, g_log_prob: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """``(d/d mean, d/d log_std)`` from the gradients on the action and on its log-prob.

    d a/du = 1 - a^2; d/du of ``-log(1 - a^2 + eps)`` is ``2a(1 - a^2) / (1 - a^2 + eps)``;
    u = mean + std * noise; the Gaussian term's gradient is -1 per log-std (the standardised
    value is the noise itself). Outside the log-std bounds the clip passes no gradient."""
    log_std, std, noise, a, one_minus = tape
    g_u = np.zeros_like(a)
    if g_action is not None:
        g_u += g_action * one_minus
    if g_log_prob is not None:
        g_u += g_log_prob[:, None] * (2.0 * a * one_minus / (one_minus + SQUASH_EPS))
    g_log_std = g_u * std * noise
    if g_log_prob is not None:
        g_log_std -= g_log_prob[:, None]
    inside = (log_std >= LOG_STD_MIN) & (log_std <= LOG_STD_MAX)
    return g_u, g_log_std * inside


# -- deterministic tanh (TD3, DDPG) ------------------------------------------------------------
def tanh_action(xp: Any, x: Any) -> tuple[Any, Any]:
    """Actions in ``(-1, 1)``: ``(tanh(x), tape)``."""
    a = xp.tanh(x)
    return a, a


def tanh_action_vjp(tape: Any, g_action: np.ndarray) -> np.ndarray:
    return g_action * (1.0 - tape * tape)


def squash_correction(xp: Any, actions: Any) -> Any:
    """``sum log(1 - a^2 + 1e-6)`` per row: what tanh takes off a Gaussian's log-density
    (the original SAC's correction, with SB3's epsilon)."""
    return xp.sum_rows(xp.log(1.0 - actions * actions + SQUASH_EPS))


def tanh_inverse(xp: Any, y: Any) -> Any:
    """``atanh`` of actions clipped one float32 epsilon inside ``(-1, 1)`` (SB3's
    ``TanhBijector.inverse``, so a saturated action has a finite pre-image)."""
    y = xp.clip(y, -1.0 + F32_EPS, 1.0 - F32_EPS)
    return 0.5 * (xp.log1p(y) - xp.log1p(-y))


# -- gSDE ----------------------------------------------------------------------------------------
def sde_std(
    xp: Any, log_std: Any, use_expln: bool, full_std: bool, action_dim: int
) -> tuple[Any, Any]:
    """The exploration weights' std ``[L, d]`` from ``log_std`` (``[L, d]``, or ``[L, 1]``
    shared by every action dimension when not ``full_std``): ``exp``, or with ``use_expln``
    ``exp`` below 0 and ``log1p(x + 1e-6) + 1`` above (it grows slowly, SB3's expln).
    Returns ``(std, tape)``."""
    if use_expln:
        above_zero = log_std > 0
        below = xp.exp(log_std) * (log_std <= 0)
        std = below + (xp.log1p(log_std * above_zero + SDE_EPS) + 1.0) * above_zero
    else:
        std = xp.exp(log_std)
    tape = (log_std, std, use_expln, full_std)
    return (std if full_std else xp.repeat_cols(std, action_dim)), tape


def sde_std_vjp(tape: Any, g_std: np.ndarray) -> np.ndarray:
    """d(loss)/d(log_std) from d(loss)/d(std ``[L, d]``)."""
    log_std, std, use_expln, full_std = tape
    if not full_std:
        g_std = g_std.sum(axis=1, keepdims=True)
    if use_expln:
        above_zero = log_std > 0
        slope = np.where(above_zero, 1.0 / (1.0 + log_std * above_zero + SDE_EPS), std)
        return (g_std * slope).astype(np.float32, copy=False)
    return (g_std * std).astype(np.float32, copy=False)


def sde_noise(xp: Any, latent: Any, matrix: Any, matrices: Any) -> Any:
    """The action noise ``latent @ W`` ``[B, d]`` (SB3's ``get_noise``): one matrix
    ``matrix [L, d]`` for a batch of one or a batch whose size is not the number of
    ``matrices [n, L, d]`` (or without them); else row ``i`` with ``matrices[i]`` (one per env)."""
    if matrices is None or latent.shape[0] == 1 or latent.shape[0] != matrices.shape[0]:
        return latent @ matrix
    return (latent[:, None, :] @ matrices)[:, 0, :]


def sde_log_prob(
    xp: Any, mean: Any, std: Any, latent: Any, gaussian_actions: Any, squash: bool
) -> tuple[Any, Any, Any]:
    """Log-densities of pre-squash ``gaussian_actions [B, d]`` under ``N(mean, sigma^2)`` with
    ``sigma = sqrt(latent^2 @ std^2 + 1e-6)`` per row, less ``sum log(1 - tanh(x)^2 + 1e-6)``
    when ``squash``; the entropies ``[B]`` (None when squashed: no closed form, as in SB3).
    ``latent`` is taken as given (pass it detached where the features are not learned)."""
    lat2 = latent * latent
    sigma = xp.sqrt(lat2 @ (std * std) + SDE_EPS)
    z = (gaussian_actions - mean) / sigma
    log_sigma = xp.log(sigma)
    log_prob = xp.sum_rows(-0.5 * z * z - log_sigma - LOG_SQRT_2PI)
    entropy = squashed = None
    if squash:
        squashed = xp.tanh(gaussian_actions)
        log_prob = log_prob - squash_correction(xp, squashed)
    else:
        entropy = xp.sum_rows(0.5 + LOG_SQRT_2PI + log_sigma)
    return log_prob, entropy, (latent, lat2, std, sigma, z, squashed)


def sde_log_prob_vjp(
    tape: Any, g_log_prob: np.ndarray, g_mean_entropy: float, latent_grad: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    """``(d/d mean, d/d std [L, d], d/d latent or None, d/d gaussian_actions)`` of
    ``sum(g_log_prob * log_prob) + g_mean_entropy * mean(entropy)``.

    With ``v = latent^2 @ std^2``: d log_prob/d sigma is ``(z^2 - 1) / sigma`` per entry,
    d entropy/d sigma ``1 / sigma``, d sigma/d v ``1 / (2 sigma)``; the squashing term
    adds ``2a(1 - a^2) / (1 - a^2 + eps)`` per action (``a = tanh(x)``)."""
    latent, lat2, std, sigma, z, squashed = tape
    g_lp = g_log_prob[:, None]
    g_x = g_lp * (-z / sigma)
    g_mean = -g_x
    g_sigma = g_lp * (z * z - 1.0) / sigma
    if squashed is None:
        if g_mean_entropy:
            g_sigma += (g_mean_entropy / sigma.shape[0]) / sigma
    else:
        one_minus = 1.0 - squashed * squashed
        g_x = g_x + g_lp * (2.0 * squashed * one_minus / (one_minus + SQUASH_EPS))
    g_var = g_sigma / (2.0 * sigma)
    g_std = 2.0 * std * (lat2.T @ g_var)
    g_latent = 2.0 * latent * (g_var @ (std * std).T) if latent_grad else None
    return g_mean, g_std, g_latent, g_x


def sde_rsample(
    xp: Any, mean: Any, std: Any, latent: Any, weights_noise: Any
) -> tuple[Any, Any, Any]:
    """SAC's reparameterised gSDE draw: ``W = std * weights_noise`` (standard normal
    ``[L, d]``, one matrix for the batch), ``a = tanh(mean + latent @ W)`` and its
    log-probability with the features learned (gradients reach ``latent`` through the noise
    and the variance): ``(a, log_prob, tape)``."""
    weights = std * weights_noise
    gaussian = mean + latent @ weights
    log_prob, _, tape = sde_log_prob(xp, mean, std, latent, gaussian, squash=True)
    return tape[5], log_prob, (tape, weights, weights_noise)


def sde_rsample_vjp(
    tape: Any, g_action: np.ndarray | None, g_log_prob: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(d/d mean, d/d std, d/d latent)`` from the gradients on the action and its
    log-prob (the draw ``u = mean + latent @ W`` passes d/du to each of its terms)."""
    lp_tape, weights, weights_noise = tape
    g_mean, g_std, g_latent, g_u = sde_log_prob_vjp(lp_tape, g_log_prob, 0.0, True)
    assert g_latent is not None
    if g_action is not None:
        a = lp_tape[5]
        g_u = g_u + g_action * (1.0 - a * a)
    latent = lp_tape[0]
    return g_mean + g_u, g_std + (latent.T @ g_u) * weights_noise, g_latent + g_u @ weights.T
