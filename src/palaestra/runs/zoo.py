"""RL Zoo hyperparameter files (``rl_zoo3/hyperparams/ppo.yml`` and the files users keep in
that form) read as palaestra settings: ``palaestra train ppo CartPole-v1 --config ppo.yml``.

Such a file holds one section per env id, plus ``atari`` (for every Atari id without its own
section) and ``default`` (for any other id); the Zoo picks the section in that order, and so
does :func:`pick_section`. YAML merge keys (``<<: *pybullet-defaults``) are YAML's own and
``safe_load`` applies them. A section is the whole recipe, as in the Zoo: it is applied over the
algorithm's defaults, not over a palaestra preset (``--preset`` puts one beneath it).

:func:`section_settings` turns a section's Zoo keys into palaestra's:

- ``n_timesteps`` (often ``!!float 1e6``) -> an integer; ``policy``, ``n_envs``,
  ``frame_stack``, ``env_kwargs`` and the constructor's hyperparameters pass as they are, and
  schedules such as ``lin_3e-4`` are the presets' own form (:func:`palaestra.presets.resolve`);
- ``normalize``: true/false, a mapping, or a string such as ``"{'norm_obs': False}"``;
- ``policy_kwargs`` and ``replay_buffer_kwargs`` written as Python (``"dict(net_arch=[64, 64],
  activation_fn=nn.ReLU)"``) are read by :func:`palaestra.runs.literal.literal`, never ``eval``;
  names resolve through :mod:`palaestra.runs.known_names` (``nn.ReLU`` -> ``"relu"``), and a
  key the algorithm's policy does not take is refused by name;
- ``env_wrapper``: SB3's ``AtariWrapper`` becomes palaestra's Atari recipe (``atari``, its
  keyword arguments kept); other names stay, and the trust gate maps them through the same
  table or asks for ``--allow-import`` (:mod:`palaestra.runs.folder`);
- ``noise_type``/``noise_std`` -> ``action_noise`` over the env's action dimensions, as the Zoo
  builds it (``normal``: ``NormalActionNoise``; ``ornstein-uhlenbeck``);
- ``callback`` passes as it is: SB3's names map through the same table, other modules need
  ``--allow-import`` (:mod:`palaestra.runs.run_callbacks`);
- ``replay_buffer_class: HerReplayBuffer`` names palaestra's ``HerReplayBuffer``; another
  class is refused;
- keys palaestra's settings cannot take (``vec_env_wrapper``, ``monitor_kwargs``) are refused,
  each with why.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping
from typing import Any

import palaestra
from palaestra import spaces
from palaestra.runs import known_names
from palaestra.runs.errors import RunError
from palaestra.runs.literal import literal
from palaestra.runs.recipe import WRAPPER_KEYS, is_atari_id, registered_id, wrapper_items

__all__ = [
    "REFUSED",
    "action_size",
    "is_zoo_file",
    "kwargs_value",
    "pick_section",
    "section_settings",
]

ATARI_WRAPPER = "palaestra.wrappers.atari:AtariWrapper"
# Zoo keys palaestra's settings do not take, and why (the error says it).
REFUSED: dict[str, str] = {
    "vec_env_wrapper": (
        "palaestra's settings take no VecEnv wrapper; frame_stack and normalize are the "
        "VecFrameStack and VecNormalize of a run"
    ),
    "monitor_kwargs": "every palaestra run logs each episode itself (episodes.csv)",
}
# The replay buffer classes a section may name (the Zoo writes SB3's class name; palaestra's
# settings name HerReplayBuffer so too, see off_policy.REPLAY_BUFFER_CLASSES).
_BUFFER_CLASSES = {
    "HerReplayBuffer": "HerReplayBuffer",
    "stable_baselines3.HerReplayBuffer": "HerReplayBuffer",
    "stable_baselines3.her.HerReplayBuffer": "HerReplayBuffer",
}
_NOISES = {"normal": "NormalActionNoise", "ornstein-uhlenbeck": "OrnsteinUhlenbeckActionNoise"}


def is_zoo_file(data: Mapping[str, Any], setting_keys: Collection[str]) -> bool:
    """Whether a settings file is sectioned as the Zoo's: every value a mapping and no key a
    palaestra setting (``setting_keys``), except an ``atari`` section, told from palaestra's
    ``atari`` (AtariWrapper kwargs) by holding other keys.

    >>> is_zoo_file({"default": {"policy": "MlpPolicy"}}, {"policy"})
    True
    >>> is_zoo_file({"atari": {"noop_max": 10}}, {"atari"})
    False
    """
    if not data or not all(isinstance(v, dict) for v in data.values()):
        return False
    zoo_atari = isinstance(data.get("atari"), dict) and bool(set(data["atari"]) - set(WRAPPER_KEYS))
    return all(key not in setting_keys or (key == "atari" and zoo_atari) for key in data)


def pick_section(data: Mapping[str, Any], env_id: str, source: str) -> tuple[str, dict[str, Any]]:
    """``(name, section)`` the Zoo would use for ``env_id``: its own, else ``atari`` for an
    Atari id, else ``default``; ``RunError`` listing the sections when none applies."""
    candidates = [env_id, registered_id(env_id)]
    if is_atari_id(env_id):
        candidates.append("atari")
    candidates.append("default")
    for name in candidates:
        if name in data:
            return name, dict(data[name])
    shown = ", ".join(repr(k) for k in list(data)[:20]) + (", ..." if len(data) > 20 else "")
    raise RunError(
        f"{source} (an RL Zoo hyperparameter file) has no section {env_id!r}"
        f"{', atari' if 'atari' in candidates else ''} or 'default'; its sections: {shown}",
        f"add a section named {env_id}, or train an env it has",
    )


def section_settings(
    algo: str,
    section: Mapping[str, Any],
    source: str,
    policy_keys: Collection[str],
    action_size: Callable[[], int],
) -> dict[str, Any]:
    """A Zoo section as palaestra's flat settings (the keys ``train --config`` takes);
    ``RunError`` naming the first key it cannot take and why. ``policy_keys``: the keyword
    arguments ``algo``'s policy takes; ``action_size()``: the env's action dimensions (asked
    only for ``noise_type``)."""
    out: dict[str, Any] = {}
    for key, value in section.items():
        if key in REFUSED:
            raise RunError(f"{source}: {key} {value!r} is refused: {REFUSED[key]}", "remove it")
        if key == "n_timesteps":
            out[key] = _steps(value, source)
        elif key == "policy":
            if isinstance(value, str) and "." in value:
                raise RunError(
                    f"{source}: policy {value!r} names a class; palaestra's settings name a "
                    "policy of the algorithm",
                    "use MlpPolicy, CnnPolicy or MultiInputPolicy",
                )
            out[key] = value
        elif key == "normalize":
            out[key] = _normalize(value, source)
        elif key == "replay_buffer_class":
            if value not in _BUFFER_CLASSES:
                raise RunError(
                    f"{source}: replay_buffer_class {value!r} is refused: palaestra's "
                    "algorithms take HerReplayBuffer or none",
                    "remove it",
                )
            out[key] = _BUFFER_CLASSES[value]
        elif key in ("policy_kwargs", "replay_buffer_kwargs"):
            out[key] = kwargs_value(key, value, source)
            if key == "policy_kwargs":
                _check_policy_keys(algo, out[key], source, policy_keys)
        elif key == "env_wrapper":
            out.update(_wrappers(value, source))
        elif key not in ("noise_type", "noise_std"):
            out[key] = value
    noise = _noise(section, source, action_size)
    if noise is not None:
        out["action_noise"] = noise
    return out


def _steps(value: Any, source: str) -> int:
    """``!!float 1e6`` -> ``1000000``, as the Zoo's ``int(n_timesteps)`` (a fraction refused)."""
    if (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(value)
        and float(value).is_integer()
    ):
        return int(value)
    raise RunError(f"{source}: n_timesteps must be a whole number, got {value!r}", "fix it")


def _normalize(value: Any, source: str) -> Any:
    if isinstance(value, str):  # the Zoo's "{'norm_obs': False, 'norm_reward': True}"
        value = literal(value, f"{source}: normalize", {})
        if not isinstance(value, dict):
            raise RunError(
                f"{source}: normalize must give VecNormalize kwargs as {{...}}, got {value!r}",
                "e.g. \"{'norm_obs': True, 'norm_reward': False}\"",
            )
    return value


def kwargs_value(key: str, value: Any, source: str) -> Any:
    """``policy_kwargs``-like ``value``: a mapping, or the Zoo's Python string read as data
    (:func:`palaestra.runs.literal.literal`, names from ``known_names.ACTIVATIONS``)."""
    if isinstance(value, str):
        value = literal(value, f"{source}: {key}", known_names.ACTIVATIONS)
    if not isinstance(value, dict):
        raise RunError(f"{source}: {key} must be dict(...), got {value!r}", "fix it")
    return value


def _check_policy_keys(
    algo: str, kwargs: dict[str, Any], source: str, policy_keys: Collection[str]
) -> None:
    for name in kwargs:
        if name not in policy_keys:
            raise RunError(
                f"{source}: policy_kwargs {name}={kwargs[name]!r} is refused: palaestra's "
                f"{algo.upper()} policy takes no {name!r}",
                f"it takes {', '.join(sorted(policy_keys))}",
            )


def _wrappers(value: Any, source: str) -> dict[str, Any]:
    """``env_wrapper`` as settings: SB3's ``AtariWrapper`` is palaestra's Atari recipe."""
    try:
        items = wrapper_items(value)
    except RunError as exc:
        raise RunError(f"{source}: {exc.what}", exc.fix) from None
    atari = [
        kwargs
        for name, kwargs in items
        if known_names.palaestra_name("env_wrapper", name) == ATARI_WRAPPER
    ]
    if not atari:
        return {"env_wrapper": value}
    if len(items) > 1:
        raise RunError(
            f"{source}: env_wrapper {value!r} is refused: palaestra's Atari recipe (atari: "
            "AtariWrapper under a Monitor) takes no other env wrapper",
            "keep AtariWrapper alone",
        )
    return {"atari": atari[0] or True}


def _noise(section: Mapping[str, Any], source: str, action_size: Callable[[], int]) -> Any:
    kind, std = section.get("noise_type"), section.get("noise_std")
    if kind is None:
        if std is not None:
            raise RunError(f"{source}: noise_std {std!r} without noise_type", "add noise_type")
        return None
    name = _NOISES.get(kind.strip()) if isinstance(kind, str) else None
    if name is None:
        raise RunError(
            f"{source}: noise_type {kind!r} is refused: expected one of {sorted(_NOISES)}",
            "fix it",
        )
    size = action_size()
    sigma: list[Any] = std if isinstance(std, list) else [std] * size
    if len(sigma) != size or not all(
        isinstance(s, (int, float)) and not isinstance(s, bool) and math.isfinite(s) and s >= 0
        for s in sigma
    ):
        raise RunError(
            f"{source}: noise_std must be a number >= 0 (or {size} of them), got {std!r}",
            "fix it",
        )
    return {"type": name, "mean": [0.0] * size, "sigma": [float(s) for s in sigma]}


def action_size(env_id: str, env_kwargs: Mapping[str, Any]) -> int:
    """The action dimensions of ``env_id`` (made with ``env_kwargs``), as the Zoo sizes its
    action noise; ``RunError`` for actions that are not a ``Box``."""
    env = palaestra.make(env_id, **dict(env_kwargs))
    try:
        space = env.action_space
    finally:
        env.close()
    if not isinstance(space, spaces.Box):
        raise RunError(
            f"noise_type adds noise to continuous actions; {env_id} has {space}",
            "remove noise_type and noise_std",
        )
    return int(space.shape[0])
