"""Exploration noise for deterministic-policy algorithms (TD3, DDPG; SAC accepts it too), with
Stable-Baselines3's classes and formulas.

Unlike SB3, which draws from numpy's global generator, each call takes the generator to draw
from: the algorithms pass their own seeded one, so a seeded run repeats exactly and a saved
model continues the same draws. Called without one, a noise uses a generator of its own.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = [
    "ActionNoise",
    "NormalActionNoise",
    "OrnsteinUhlenbeckActionNoise",
    "VectorizedActionNoise",
]


class ActionNoise:
    """Base class: ``noise(rng)`` draws one sample, ``reset()`` starts a new episode."""

    _rng: np.random.Generator | None = None

    def _generator(self, rng: np.random.Generator | None) -> np.random.Generator:
        if rng is not None:
            return rng
        if self._rng is None:
            self._rng = np.random.default_rng()
        return self._rng

    def reset(self) -> None:
        """Called at the end of each episode (stateful noises restart)."""

    def __call__(self, rng: np.random.Generator | None = None) -> np.ndarray:
        raise NotImplementedError

    @property
    def shape(self) -> tuple[int, ...]:
        raise NotImplementedError


class NormalActionNoise(ActionNoise):
    """Gaussian noise ``N(mean, sigma)`` (arrays of the action's shape)."""

    def __init__(self, mean: Any, sigma: Any, dtype: Any = np.float32) -> None:
        self._mu, self._sigma = np.asarray(mean), np.asarray(sigma)
        self._dtype = dtype

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(np.broadcast_shapes(self._mu.shape, self._sigma.shape))

    def __call__(self, rng: np.random.Generator | None = None) -> np.ndarray:
        return self._generator(rng).normal(self._mu, self._sigma).astype(self._dtype)

    def __repr__(self) -> str:
        return f"NormalActionNoise(mu={self._mu}, sigma={self._sigma})"


class OrnsteinUhlenbeckActionNoise(ActionNoise):
    """Temporally correlated noise: ``x += theta (mean - x) dt + sigma sqrt(dt) N(0, 1)``."""

    noise_prev: np.ndarray

    def __init__(
        self,
        mean: Any,
        sigma: Any,
        theta: float = 0.15,
        dt: float = 1e-2,
        initial_noise: Any = None,
        dtype: Any = np.float32,
    ) -> None:
        self._mu, self._sigma = np.asarray(mean), np.asarray(sigma)
        self._theta, self._dt, self._dtype = theta, dt, dtype
        self.initial_noise = initial_noise
        self.reset()

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self._mu.shape)

    def __call__(self, rng: np.random.Generator | None = None) -> np.ndarray:
        draw = self._generator(rng).normal(size=self._mu.shape)
        noise = (
            self.noise_prev
            + self._theta * (self._mu - self.noise_prev) * self._dt
            + self._sigma * np.sqrt(self._dt) * draw
        )
        self.noise_prev = noise
        return noise.astype(self._dtype)

    def reset(self) -> None:
        self.noise_prev = (
            np.zeros_like(self._mu, dtype=np.float64)
            if self.initial_noise is None
            else np.asarray(self.initial_noise, dtype=np.float64)
        )

    def __repr__(self) -> str:
        return f"OrnsteinUhlenbeckActionNoise(mu={self._mu}, sigma={self._sigma})"


class VectorizedActionNoise(ActionNoise):
    """One copy of ``base_noise`` per env; ``reset(indices)`` restarts some of them."""

    def __init__(self, base_noise: ActionNoise, n_envs: int) -> None:
        if isinstance(n_envs, bool) or not isinstance(n_envs, (int, np.integer)) or n_envs < 1:
            raise ValueError(f"Expected n_envs={n_envs!r} to be positive integer greater than 0")
        if base_noise is None:  # SB3: a ValueError for None, a TypeError for other objects
            raise ValueError("Expected base_noise to be an instance of ActionNoise, not None")
        if not isinstance(base_noise, ActionNoise):
            raise TypeError(
                f"Expected base_noise to be an instance of ActionNoise, got {base_noise!r}"
            )
        self.base_noise, self.n_envs = base_noise, int(n_envs)
        self._noises = [copy.deepcopy(base_noise) for _ in range(self.n_envs)]

    @property
    def noises(self) -> list[ActionNoise]:
        """One noise per env."""
        return self._noises

    @noises.setter
    def noises(self, noises: Iterable[ActionNoise]) -> None:
        """Replace the per-env noises, as SB3: ``n_envs`` of them, each of the base noise's
        type, reset. A wrong count is a ``ValueError`` (SB3: ``AssertionError``)."""
        if isinstance(noises, ActionNoise) or not isinstance(noises, Iterable):
            raise TypeError(f"noises must be a list of {self.n_envs} ActionNoises, got {noises!r}")
        noises = list(noises)
        if len(noises) != self.n_envs:
            raise ValueError(f"Expected a list of {self.n_envs} ActionNoises, found {len(noises)}.")
        wrong = [
            i for i, noise in enumerate(noises) if not isinstance(noise, type(self.base_noise))
        ]
        if wrong:
            raise ValueError(
                f"Noise instances at indices {wrong} don't match the type of base_noise "
                f"{type(self.base_noise).__name__}"
            )
        for noise in noises:
            noise.reset()
        self._noises = noises

    @property
    def shape(self) -> tuple[int, ...]:
        return (self.n_envs, *self.base_noise.shape)

    def reset(self, indices: Iterable[int] | None = None) -> None:
        for index in range(self.n_envs) if indices is None else indices:
            self.noises[index].reset()

    def __call__(self, rng: np.random.Generator | None = None) -> np.ndarray:
        rng = self._generator(rng)
        return np.stack([noise(rng) for noise in self.noises])

    def __repr__(self) -> str:
        return f"VecNoise(BaseNoise={self.base_noise!r}), n_envs={self.n_envs})"


def noise_to_json(noise: ActionNoise | None) -> dict[str, Any] | None:
    """A noise and its state as JSON, so a model file restores it (SB3 pickles it)."""
    if noise is None:
        return None
    if isinstance(noise, VectorizedActionNoise):
        return {
            "type": "VectorizedActionNoise",
            "n_envs": noise.n_envs,
            "base": noise_to_json(noise.base_noise),
            "noises": [noise_to_json(n) for n in noise.noises],
        }
    if isinstance(noise, NormalActionNoise):
        return {
            "type": "NormalActionNoise",
            "mean": noise._mu.tolist(),
            "sigma": noise._sigma.tolist(),
        }
    if isinstance(noise, OrnsteinUhlenbeckActionNoise):
        initial = noise.initial_noise
        return {
            "type": "OrnsteinUhlenbeckActionNoise",
            "mean": noise._mu.tolist(),
            "sigma": noise._sigma.tolist(),
            "theta": noise._theta,
            "dt": noise._dt,
            "initial_noise": None if initial is None else np.asarray(initial).tolist(),
            "noise_prev": noise.noise_prev.tolist(),
        }
    raise TypeError(f"cannot save action noise of type {type(noise).__name__}")


def noise_from_json(data: Any, depth: int = 0) -> ActionNoise:
    """Inverse of ``noise_to_json``; ``ValueError`` naming what is malformed.

    A preset writes only ``type``, ``mean`` and ``sigma``: an Ornstein-Uhlenbeck noise's
    ``theta``, ``dt`` and ``initial_noise`` then take SB3's constructor defaults and its state
    starts at ``initial_noise`` (zeros), as a new noise does.

    >>> noise_from_json({"type": "OrnsteinUhlenbeckActionNoise", "mean": [0.0], "sigma": [0.5]})
    OrnsteinUhlenbeckActionNoise(mu=[0.], sigma=[0.5])
    """
    if not isinstance(data, dict) or depth > 1:
        raise ValueError(f"action_noise must be a saved noise mapping, got {data!r:.80}")
    kind = data.get("type")
    try:
        if kind == "VectorizedActionNoise":
            vec = VectorizedActionNoise(noise_from_json(data["base"], 1), data["n_envs"])
            noises = [noise_from_json(n, 1) for n in data["noises"]]
            if len(noises) != vec.n_envs:
                raise ValueError(f"{len(noises)} noises for {vec.n_envs} envs")
            vec._noises = noises  # with their saved states (the setter resets them)
            return vec
        mean = np.asarray(data["mean"], dtype=np.float64)
        sigma = np.asarray(data["sigma"], dtype=np.float64)
        if mean.ndim > 3 or sigma.shape != mean.shape or not np.isfinite(mean).all():
            raise ValueError(f"mean {mean.shape} and sigma {sigma.shape} do not match")
        if kind == "NormalActionNoise":
            return NormalActionNoise(mean, sigma)
        if kind == "OrnsteinUhlenbeckActionNoise":
            initial = data.get("initial_noise")
            ou = OrnsteinUhlenbeckActionNoise(
                mean,
                sigma,
                float(data.get("theta", 0.15)),
                float(data.get("dt", 1e-2)),
                None if initial is None else np.asarray(initial, dtype=np.float64),
            )
            if "noise_prev" in data:  # a saved noise continues where it stopped
                prev = np.asarray(data["noise_prev"], dtype=np.float64)
                if prev.shape != mean.shape:
                    raise ValueError(f"noise_prev {prev.shape} does not match mean {mean.shape}")
                ou.noise_prev = prev
            elif ou.noise_prev.shape != mean.shape:
                raise ValueError(f"initial_noise does not match mean {mean.shape}")
            return ou
    except KeyError as exc:
        raise ValueError(f"malformed action_noise {kind!r}: missing key {exc}") from exc
    except (TypeError, ValueError) as exc:
        raise ValueError(f"malformed action_noise {kind!r}: {exc}") from exc
    raise ValueError(f"unknown action_noise type {kind!r}")
