"""The settings of a training run: preset, then ``--config`` file, then ``--set key=value``.

Settings are plain data in the preset format (``policy``, ``n_envs``, ``n_timesteps``,
``hyperparams``, ``env_kwargs``, ``normalize``, ``env_wrapper``, and for Atari ``atari`` and
``frame_stack``; see :mod:`palaestra.runs.recipe`) plus ``seed``; ``config.json`` records them
exactly as resolved, so a run's ``config.json`` is itself a valid ``--config`` file.

An RL Zoo hyperparameter file (one section per env id, ``atari``, ``default``) is read as
the Zoo reads it: the section for the env id, its Zoo keys turned into these
(:mod:`palaestra.runs.zoo`), over the algorithm's defaults rather than a preset.

A settings file is data as a run folder is (people pass sweep folders around): its values are
held to a run folder's limits and the modules it names are imported only when the command
line allows them (:mod:`palaestra.runs.folder`); YAML is read with ``safe_load``, and a
``!!python/...`` tag is refused by name.
"""

from __future__ import annotations

import ast
import json
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from palaestra import presets
from palaestra.error import dependency_not_installed
from palaestra.runs import folder, known_names, run_callbacks, zoo
from palaestra.runs.algorithms import (
    ALGO_CLASSES,
    ALGOS,
    algo_class,
    check_algo,
    hyperparameter_names,
)
from palaestra.runs.errors import RunError
from palaestra.runs.files import REPLAY_ALGOS, note
from palaestra.runs.recipe import atari_defaults, check_pipeline, choose_policy, is_atari_id

__all__ = [
    "ALGOS",
    "ALGO_CLASSES",
    "REPLAY_ALGOS",
    "algo_class",
    "check_algo",
    "check_settings",
    "hyperparameter_names",
    "load_config_file",
    "resolve_settings",
    "zoo_section_settings",
]


def parse_value(text: str) -> Any:
    """``--set`` values: JSON, else a Python literal, else the text itself.

    >>> parse_value("[128, 128]"), parse_value("True"), parse_value("1e-3"), parse_value("relu")
    ([128, 128], True, 0.001, 'relu')
    """
    try:
        return json.loads(text)
    except ValueError:
        pass
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        return text


# Keys a --config file may carry that describe the run rather than configure it.
_RUN_KEYS = {"algo", "env_id", "preset", "device", "palaestra_version", "measured", "evaluation"}
_RUN_KEYS |= {"module_sha256"}
# What PyYAML's safe_load reports for a !!python/... tag it refuses to construct.
_PYTHON_TAG = re.compile(r"tag:yaml\.org,2002:python/([^'\s]*)")
_TOP_KEYS = (*presets.SETTINGS_KEYS, "seed")


def load_config_file(path: str) -> dict[str, Any]:
    """A ``.json``, ``.yaml`` or ``.yml`` file holding one mapping."""
    file = Path(path)
    suffix = file.suffix.lower()
    if suffix not in (".json", ".yaml", ".yml"):
        raise RunError(f"config file {path!r} has an unknown suffix", "use .json, .yaml or .yml")
    try:
        text = file.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RunError(f"no config file at {path!r}", "check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RunError(f"cannot read config file {path!r}: {exc}", "check the file") from None
    if suffix == ".json":
        try:
            data = json.loads(text)
        except ValueError as exc:
            raise RunError(f"malformed JSON in {path!r}: {exc}", "fix the file") from None
    else:
        try:
            import yaml
        except ImportError:
            raise dependency_not_installed(
                "PyYAML", "sweep", f"reading the YAML config {path!r}; or write it as JSON"
            ) from None
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            where = getattr(exc, "problem_mark", None)
            at = f" at line {where.line + 1}, column {where.column + 1}" if where else ""
            problem = getattr(exc, "problem", None) or type(exc).__name__
            tag = _PYTHON_TAG.search(str(problem))
            if tag:  # safe_load builds no Python object; say so rather than "malformed"
                raise RunError(
                    f"config file {path!r} uses the YAML tag '!!python/{tag.group(1)}'{at}; "
                    "palaestra reads settings files as plain data and builds no Python object",
                    "remove the tag: write the value as plain YAML",
                ) from None
            raise RunError(f"malformed YAML in {path!r}{at}: {problem}", "fix the file") from None
    if not isinstance(data, dict):
        raise RunError(
            f"config file {path!r} holds a {type(data).__name__}, not a mapping",
            "write keys such as hyperparams, n_envs, n_timesteps at the top level",
        )
    return data


def _valid_keys(algo: str) -> list[str]:
    return sorted({*_TOP_KEYS, *hyperparameter_names(algo)} - {"hyperparams"})


def _split(algo: str, data: dict[str, Any], source: str) -> dict[str, Any]:
    """A flat or preset-shaped mapping -> settings (hyperparameters under ``hyperparams``)."""
    names = set(hyperparameter_names(algo))
    out: dict[str, Any] = {}
    hyper: dict[str, Any] = {}
    nested = data.get("hyperparams", {})
    if not isinstance(nested, dict):
        raise RunError(f"{source}: hyperparams must be a mapping, got {nested!r}", "fix it")
    for key, value in [*data.items(), *nested.items()]:
        if key == "hyperparams" or key in _RUN_KEYS:
            continue
        if key in _TOP_KEYS:
            out[key] = value
        elif key in names:
            hyper[key] = value
        else:
            raise RunError(
                f"{source}: unknown {algo} setting {key!r}",
                f"valid keys: {', '.join(_valid_keys(algo))}",
            )
    for key in ("policy_kwargs", "replay_buffer_kwargs"):
        if isinstance(hyper.get(key), str):  # RL Zoo's "dict(net_arch=[64, 64])", read as data
            hyper[key] = zoo.kwargs_value(key, hyper[key], source)
    kwargs = hyper.get("policy_kwargs")
    if isinstance(kwargs, dict) and isinstance(kwargs.get("activation_fn"), str):
        # RL Zoo writes nn.ReLU / th.nn.Tanh; presets name torch's activations "relu", "tanh"
        name = known_names.palaestra_name("activation_fn", kwargs["activation_fn"])
        hyper["policy_kwargs"] = {**kwargs, "activation_fn": name or kwargs["activation_fn"]}
    if hyper:
        out["hyperparams"] = hyper
    return out


def _check_run_keys(algo: str, env_id: str, data: dict[str, Any], source: str) -> None:
    for key, expected in (("algo", algo), ("env_id", env_id)):
        if key in data and str(data[key]).lower() != expected.lower():
            raise RunError(
                f"{source} is for {key} {data[key]!r}, not {expected!r}",
                f"remove its {key!r} key or train {data[key]}",
            )


def parse_set(algo: str, assignments: list[str]) -> dict[str, Any]:
    """``["learning_starts=100", "policy_kwargs.net_arch=[64,64]"]`` -> nested settings."""
    data: dict[str, Any] = {}
    for item in assignments:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise RunError(f"--set {item!r} is not key=value", "e.g. --set learning_rate=0.001")
        parts = key.split(".")
        if parts[0] == "hyperparams":
            parts = parts[1:]
        if not parts or not all(parts):
            raise RunError(f"--set {item!r}: malformed key {key!r}", "e.g. policy_kwargs.net_arch")
        if parts[0] not in {*_TOP_KEYS, *hyperparameter_names(algo)} - {"hyperparams"}:
            raise RunError(
                f"unknown --set key {parts[0]!r} for {algo}",
                f"valid keys: {', '.join(_valid_keys(algo))}",
            )
        node = data
        for part in parts[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise RunError(f"--set {item!r} conflicts with an earlier --set", "set it once")
            node = child
        node[parts[-1]] = parse_value(text)
    return _split(algo, data, "--set")


def _policy_keys(algo: str) -> set[str]:
    """The keyword arguments ``algo``'s policy takes (its declared rules)."""
    from palaestra.algos.common.hyperparams import POLICY_KWARGS  # lazy: import-time — torch

    algo_class(algo)  # its package declares the rules
    return set(POLICY_KWARGS[ALGO_CLASSES[algo]])


def zoo_section_settings(
    algo: str, section: Mapping[str, Any], source: str, action_size: Callable[[], int]
) -> dict[str, Any]:
    """One section of an RL Zoo file as checked settings (:func:`palaestra.runs.zoo.
    section_settings`, then a run folder's limits); ``RunError`` naming the first key it
    cannot take. ``action_size()``: the env's action dimensions, asked for ``noise_type`` only.
    Imports no module the section names (the caller gates them: :func:`folder.check_imports`)."""
    data = zoo.section_settings(algo, section, source, _policy_keys(algo), action_size)
    return _checked(algo, data, source)


def _checked(algo: str, data: dict[str, Any], source: str) -> dict[str, Any]:
    settings = _split(algo, data, source)
    try:
        folder.check_run_config({**settings, "algo": algo}, source, required=())
    except RunError as exc:
        raise RunError(exc.what, "fix the file") from None
    return settings


def _load_file(
    algo: str, env_id: str, path: str, allow_import: Sequence[str]
) -> tuple[dict[str, Any], str | None]:
    """A settings file's settings and, for an RL Zoo file, the section used (else None),
    held to a run folder's rules: no module it names is imported unless ``allow_import`` holds
    it (its ``env_id`` must be the command line's, which is the user's own), and its values
    within a run folder's limits."""
    source = f"config file {path!r}"
    data = load_config_file(path)
    section = None
    if zoo.is_zoo_file(data, {*_TOP_KEYS, *hyperparameter_names(algo), *_RUN_KEYS}):
        section, values = zoo.pick_section(data, env_id, source)
        source = f"{source} section {section!r}"
        given_kwargs = values.get("env_kwargs")
        kwargs: dict[str, Any] = given_kwargs if isinstance(given_kwargs, dict) else {}
        settings = zoo_section_settings(
            algo, values, source, lambda: zoo.action_size(env_id, kwargs)
        )
    else:
        _check_run_keys(algo, env_id, data, source)
        settings = _checked(algo, data, source)
    folder.check_imports(settings, source, allow_import, "settings file")
    return settings, section


def resolve_settings(
    algo: str,
    env_id: str,
    preset: str | None = None,
    config: str | Path | Mapping[str, Any] | None = None,
    assignments: Sequence[str] = (),
    overrides: Mapping[str, Any] | None = None,
    allow_import: Sequence[str] = (),
) -> tuple[dict[str, Any], str | None, list[str]]:
    """``(settings, preset name used or None, notes for the user)``: the preset (the
    ``default`` one when it exists), then ``config`` (a settings file, or a mapping of the same
    keys), then ``assignments`` (``"key=value"`` strings), then ``overrides`` (nested settings).

    A settings file is data like a run folder: the modules it names are imported only when
    ``allow_import`` holds them (a mapping, ``assignments`` and ``overrides`` are the caller's
    own). An RL Zoo file's section replaces the default preset (``preset`` still goes beneath
    it). With no preset, the policy follows the env's observations unless given
    (:func:`~palaestra.runs.recipe.choose_policy`)."""
    notes: list[str] = []
    given: list[dict[str, Any]] = []
    section = None
    if isinstance(config, Mapping):
        given.append(_split(algo, dict(config), "settings"))
    elif config is not None:
        layer, section = _load_file(algo, env_id, str(config), allow_import)
        given.append(layer)
    elif allow_import:
        note(f"--allow-import {', '.join(allow_import)}: no settings file to apply it to")
    if preset is not None:
        try:
            settings = presets.get_preset(algo, env_id, preset)
        except presets.PresetError as exc:
            raise RunError(str(exc), "pick another --preset, or drop it") from None
        used: str | None = preset
    elif section is not None:  # the Zoo's section is the whole recipe, as in the Zoo
        settings, used = presets.base_settings(), None
        if is_atari_id(env_id):
            settings.update(atari_defaults())
        notes.append(
            f"settings from section {section!r} of the RL Zoo file {str(config)!r} over the "
            f"{algo.upper()} defaults (SB3's), not a preset"
        )
    elif presets.has_preset(algo, env_id):
        settings, used = presets.get_preset(algo, env_id), "default"
    elif is_atari_id(env_id):
        settings, used = {**presets.base_settings(), **atari_defaults()}, None
        notes.append(
            f"no preset for {algo} on {env_id}: using the {algo.upper()} defaults on SB3's "
            "Atari recipe (AtariWrapper, 4 stacked frames, CnnPolicy)"
        )
    else:
        settings, used = presets.base_settings(), None
    settings.pop("measured", None)
    settings = {**presets.base_settings(), **settings}
    if assignments:
        given.append(parse_set(algo, list(assignments)))
    if overrides:
        given.append(_split(algo, dict(overrides), "overrides"))
    for layer in given:
        settings = presets.merge(settings, layer)
    if used is None and not is_atari_id(env_id):
        defaults = f"no preset for {algo} on {env_id}: using the {algo.upper()} defaults"
        defaults += " (SB3's) with"
        if section is not None:
            defaults = f"section {section!r} of the RL Zoo file names no policy: using"
        if any("policy" in layer for layer in given):
            if section is None:
                notes.append(f"{defaults} the policy given, {settings['policy']}")
        else:
            settings["policy"], why = choose_policy(settings, env_id)
            notes.append(f"{defaults} {settings['policy']}, chosen for its {why}")
    return settings, used, notes


def _positive_int(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise RunError(f"{what} must be a positive integer, got {value!r}", f"fix {what}")
    return value


def check_settings(settings: dict[str, Any], env_id: str) -> None:
    """``RunError`` unless the top-level settings have usable types and values for ``env_id``."""
    _positive_int(settings["n_envs"], "n_envs")
    _positive_int(settings["n_timesteps"], "n_timesteps")
    seed = settings.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise RunError(f"seed must be an integer, got {seed!r}", "fix seed")
    if not isinstance(settings["policy"], str):
        raise RunError(f"policy must be a name, got {settings['policy']!r}", "e.g. MlpPolicy")
    if not isinstance(settings.get("env_kwargs") or {}, dict):
        raise RunError(f"env_kwargs must be a mapping, got {settings['env_kwargs']!r}", "fix it")
    if not isinstance(settings.get("normalize", False), (bool, dict)):
        raise RunError(
            f"normalize must be true/false or VecNormalize kwargs, got {settings['normalize']!r}",
            "fix it",
        )
    check_pipeline(settings, env_id)
    run_callbacks.build_callbacks(settings)  # imports them: a bad name fails before training
