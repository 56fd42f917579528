"""Tuned hyperparameters per (algorithm, env id), shipped as ``presets.json``.

A preset is plain data: the policy name, the number of envs, the training budget and the
algorithm's constructor kwargs. Three forms stand for objects JSON cannot hold:
``"lin_<x>"`` is a linear schedule from ``x`` to 0, ``policy_kwargs.activation_fn`` names a
torch activation (``"relu"``, ``"tanh"``, …), and ``action_noise`` is a mapping such as
``{"type": "OrnsteinUhlenbeckActionNoise", "mean": [0.0], "sigma": [0.5]}`` (one mean and sigma
per action dimension; the form a model file saves a noise in, its state left out).
:func:`resolve` turns them into the objects; the rest of the data passes through unchanged, so
what ``config.json`` records is what was trained.

>>> preset = get_preset("ppo", "CartPole-v1")
>>> preset["n_envs"], preset["hyperparams"]["n_steps"]
(8, 32)
"""

from __future__ import annotations

import copy
import json
from functools import cache
from importlib import resources
from typing import Any

__all__ = [
    "SETTINGS_KEYS",
    "PresetError",
    "available",
    "base_settings",
    "get_preset",
    "has_preset",
    "measured_shortfall",
    "merge",
    "resolve",
]

# The keys of one preset besides its measurements; ``hyperparams`` holds constructor kwargs.
# ``atari`` (SB3's Atari recipe), ``frame_stack`` and ``env_wrapper`` (a Gymnasium wrapper class
# as ``"module:Class"``, applied to each env over its Monitor) are optional: absent means off.
SETTINGS_KEYS = (
    "policy",
    "n_envs",
    "n_timesteps",
    "hyperparams",
    "env_kwargs",
    "normalize",
    "atari",
    "frame_stack",
    "env_wrapper",
    "callback",
)

ACTIVATIONS = {"relu": "ReLU", "tanh": "Tanh", "elu": "ELU", "leaky_relu": "LeakyReLU"}


class PresetError(KeyError):
    """No preset for the requested algorithm, env id or name."""

    def __str__(self) -> str:
        return str(self.args[0])


@cache
def _table() -> dict[str, Any]:
    text = resources.files(__package__).joinpath("presets.json").read_text(encoding="utf-8")
    table = json.loads(text)
    table.pop("_format", None)
    return table


def available() -> dict[str, dict[str, list[str]]]:
    """``{algo: {env_id: [preset names]}}`` for every shipped preset."""
    return {
        algo: {env: sorted(names) for env, names in envs.items()} for algo, envs in _table().items()
    }


def get_preset(algo: str, env_id: str, name: str = "default") -> dict[str, Any]:
    """A deep copy of one preset's data (strings not yet resolved; see :func:`resolve`)."""
    table = _table()
    algo_key = algo.lower()
    if algo_key not in table:
        raise PresetError(
            f"no presets for algorithm {algo!r}; algorithms with presets: {sorted(table)}"
        )
    envs = table[algo_key]
    if env_id not in envs:
        raise PresetError(
            f"no {algo_key} preset for env {env_id!r}; {algo_key} presets exist for {sorted(envs)}"
        )
    if name not in envs[env_id]:
        raise PresetError(
            f"no {algo_key} preset named {name!r} for {env_id}; choose from {sorted(envs[env_id])}"
        )
    return copy.deepcopy(envs[env_id][name])


def has_preset(algo: str, env_id: str, name: str = "default") -> bool:
    """Whether :func:`get_preset` would find ``(algo, env_id, name)``."""
    return name in _table().get(algo.lower(), {}).get(env_id, {})


def measured_shortfall(
    algo: str, env_id: str, name: str | None, seed: int | None = None
) -> str | None:
    """What a run of the preset should know before it starts when the preset's recorded
    results (``measured``: per seed, the mean return of 100 deterministic episodes after
    training) fall short of the target on some seeds: which seeds, their figures, and whether
    ``seed`` is one of them. None when every measured seed reached the target, or nothing was
    measured against one.

    >>> measured_shortfall("a2c", "CartPole-v1", "default") is None  # 5 of 5 reached 475
    True
    >>> measured_shortfall("ddpg", "Pendulum-v1", "default", seed=0).split("; ")[-1]
    'this run uses seed 0'
    """
    if name is None or not has_preset(algo, env_id, name):
        return None
    measured = _table()[algo.lower()][env_id][name].get("measured") or {}
    seeds, returns, target = (measured.get(k) for k in ("seeds", "mean_return", "target"))
    if not (isinstance(seeds, list) and isinstance(returns, list) and len(seeds) == len(returns)):
        return None
    if not isinstance(target, (int, float)):
        return None
    short = [(s, r) for s, r in zip(seeds, returns) if r < target]
    if not short:
        return None
    which = "seed" + "s" * (len(short) > 1)
    text = (
        f"the {algo.lower()} preset {name!r} for {env_id} fell short of its target on some seeds "
        f"when measured: {which} {', '.join(str(s) for s, _ in short)} ended at "
        f"{', '.join(f'{r:.1f}' for _, r in short)} (target {target:g}; mean return of 100 "
        f"deterministic episodes after training); {len(seeds) - len(short)} of {len(seeds)} "
        f"seeds reached it, median {measured.get('median_return', float('nan')):.1f}"
    )
    if str(measured.get("note", "")).startswith("TARGET NOT MET"):
        text += "; recorded as TARGET NOT MET"
    if seed is not None and seed in {s for s, _ in short}:
        text += f"; this run uses seed {seed}"
    return text


def base_settings(n_timesteps: int = 100_000) -> dict[str, Any]:
    """Settings with no preset: the algorithm's own defaults, one env, an MLP policy."""
    return {
        "policy": "MlpPolicy",
        "n_envs": 1,
        "n_timesteps": n_timesteps,
        "hyperparams": {},
        "env_kwargs": {},
        "normalize": False,
    }


def merge(base: dict[str, Any], override: dict[str, Any]) -> dict[str, Any]:
    """``base`` updated by ``override``, dicts merged key by key (so overriding
    ``policy_kwargs.net_arch`` keeps ``policy_kwargs.activation_fn``).

    >>> merge({"a": 1, "k": {"x": 1, "y": 2}}, {"k": {"y": 3}})
    {'a': 1, 'k': {'x': 1, 'y': 3}}
    """
    out = copy.deepcopy(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def resolve(hyperparams: dict[str, Any]) -> dict[str, Any]:
    """Constructor kwargs with ``"lin_<x>"`` schedules, activation names and action-noise
    mappings turned into objects."""
    from palaestra.algos.common.schedules import LinearSchedule  # lazy: import-time — torch

    out: dict[str, Any] = {}
    for key, value in hyperparams.items():
        if isinstance(value, str) and value.startswith("lin_"):
            out[key] = LinearSchedule(_lin_start(key, value), 0.0)
        elif key == "policy_kwargs" and isinstance(value, dict):
            out[key] = _resolve_policy_kwargs(value)
        elif key == "action_noise" and value is not None:
            out[key] = _resolve_action_noise(value)
        else:
            out[key] = value
    return out


def _lin_start(key: str, value: str) -> float:
    try:
        return float(value[4:])
    except ValueError:
        raise PresetError(
            f"{key}={value!r} is not a linear schedule; write 'lin_<start>', e.g. 'lin_0.001'"
        ) from None


def _resolve_policy_kwargs(policy_kwargs: dict[str, Any]) -> dict[str, Any]:
    out = dict(policy_kwargs)
    name = out.get("activation_fn")
    if isinstance(name, str):
        if name.lower() not in ACTIVATIONS:
            raise PresetError(
                f"unknown activation_fn {name!r}; expected one of {sorted(ACTIVATIONS)}"
            )
        import torch.nn

        out["activation_fn"] = getattr(torch.nn, ACTIVATIONS[name.lower()])
    return out


def _resolve_action_noise(value: Any) -> Any:
    from palaestra.algos.common.action_noise import (  # lazy: import-time — torch
        ActionNoise,
        noise_from_json,
    )

    if isinstance(value, ActionNoise):  # a --set from Python code, already an object
        return value
    try:
        return noise_from_json(value)
    except ValueError as exc:
        raise PresetError(
            f"action_noise={value!r} is not an action noise ({exc}); write e.g. "
            '{"type": "OrnsteinUhlenbeckActionNoise", "mean": [0.0], "sigma": [0.5]} or '
            '{"type": "NormalActionNoise", "mean": [0.0], "sigma": [0.1]}'
        ) from None
