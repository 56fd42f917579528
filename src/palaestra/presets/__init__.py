"""Tuned hyperparameters per (algorithm, env id), shipped as ``presets.json``.

A preset is plain data: the policy name, the number of envs, the training budget and the
algorithm's constructor kwargs. Two string forms stand for objects JSON cannot hold:
``"lin_<x>"`` is a linear schedule from ``x`` to 0, and ``policy_kwargs.activation_fn`` names a
torch activation (``"relu"``, ``"tanh"``, …). :func:`resolve` turns them into the objects; the
rest of the data passes through unchanged, so what ``config.json`` records is what was trained.

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

__all__ = ["PresetError", "available", "get_preset", "resolve"]

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


def resolve(hyperparams: dict[str, Any]) -> dict[str, Any]:
    """Constructor kwargs with ``"lin_<x>"`` schedules and activation names turned into objects."""
    from palaestra.algos.schedules import LinearSchedule

    out: dict[str, Any] = {}
    for key, value in hyperparams.items():
        if isinstance(value, str) and value.startswith("lin_"):
            out[key] = LinearSchedule(float(value[4:]), 0.0)
        elif key == "policy_kwargs" and isinstance(value, dict):
            out[key] = _resolve_policy_kwargs(value)
        else:
            out[key] = value
    return out


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
