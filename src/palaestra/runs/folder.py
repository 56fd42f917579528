"""A run folder read back by ``eval``, ``record`` and ``train --resume``, and a settings file
read by ``train --config``, ``compare`` and a sweep's ``best.yaml``: data, never code.

Users share run folders and settings files, so their contents are checked like any input.
Following what they name can run code: an ``env_wrapper`` (``"shaping:BetterRewardShaping"``)
imports its module, and a run's ``env_id`` of the form ``module:Name-v0`` imports ``module``
(Gymnasium's convention). Only the command line may allow that: ``--allow-import MODULE``
(repeatable). Without it the command stops with one line saying what was refused and how to
allow it, before anything is imported; with it, a note says what will be imported, a missing
module is one line saying where it was looked for, and a module whose file differs from the
sha256 the run recorded (``module_sha256``) gets a warning. Names that are palaestra's own
(under ``palaestra``, or mapped by :mod:`palaestra.runs.known_names`) need no flag. What the
command line itself names (``train ALGO mygrid:Grid-v0``, ``--set env_wrapper=...``) is the
user's own request and needs no flag.

The values are checked too before they reach a constructor: the keys ``train`` writes and
their types, the sizes that allocate (``n_envs``, ``frame_stack``, the Atari screen) within
limits, and ``hyperparams`` through :func:`palaestra.algos.hyperparams.check_run_hyperparams`.
``status.json`` is checked when a resume starts, before any env or model is built.
"""

from __future__ import annotations

import math
import os
import re
import reprlib
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from palaestra import presets
from palaestra.runs import algorithms, known_names, recipe, run_callbacks
from palaestra.runs.errors import RunError
from palaestra.runs.files import CONFIG_FILE, note, read_json
from palaestra.runs.recipe import wrapper_module

__all__ = [
    "CONFIG_KEYS",
    "RESUME_KEYS",
    "check_imports",
    "check_inside",
    "check_run_config",
    "find_run_config",
    "module_hashes",
    "modules_named",
    "read_run_config",
    "read_status",
]

# The keys ``train`` writes to config.json, and what ``--resume`` needs among them.
CONFIG_KEYS = frozenset(
    {*presets.SETTINGS_KEYS, "seed", "algo", "env_id", "preset", "device", "palaestra_version"}
    | {"measured"}  # a preset's results, accepted by --config and dropped
    | {"evaluation"}  # train --eval-freq's schedule (runs.periodic_eval checks it)
    | {"module_sha256"}  # the user modules' files when the run started
)
TABLE = "palaestra.runs.known_names (docs/known_names.md)"
RESUME_KEYS = ("algo", "env_id", "policy", "n_envs", "n_timesteps", "hyperparams")
MAX_N_ENVS = 4096
MAX_FRAME_STACK = 256
MAX_STEPS = 10**15
_DEVICE = re.compile(r"auto|cpu|mps|cuda(:\d{1,3})?")
_SHA256 = re.compile(r"[0-9a-f]{64}")
_NORMALIZE_KEYS = {
    "training": bool,
    "norm_obs": bool,
    "norm_reward": bool,
    "clip_obs": float,
    "clip_reward": float,
    "gamma": float,
    "epsilon": float,
}
# AtariWrapper's arguments: (type, lowest, highest); the screen is allocated per env and frame.
_ATARI_LIMITS: dict[str, tuple[type, float, float]] = {
    "noop_max": (int, 0, 10_000),
    "frame_skip": (int, 1, 1_000),
    "screen_size": (int, 1, 1_024),
    "terminal_on_life_loss": (bool, 0, 1),
    "clip_reward": (bool, 0, 1),
    "action_repeat_probability": (float, 0.0, 1.0),
}


# -- imports -----------------------------------------------------------------------------------
def modules_named(config: dict[str, Any]) -> list[tuple[str, str, str]]:
    """``(setting, value, module)`` for each module following ``config`` would import that is
    not palaestra's own (a name under ``palaestra``, or one :mod:`known_names` maps to it)."""
    out: list[tuple[str, str, str]] = []
    env_id = config.get("env_id")
    if isinstance(env_id, str):
        module = recipe.env_id_module(env_id)
        if module and not known_names.is_palaestra(module):
            out.append(("env_id", env_id, module))
    for path, _ in recipe.wrapper_items(config.get("env_wrapper") or []):
        if known_names.palaestra_name("env_wrapper", path) is None:
            out.append(("env_wrapper", path, wrapper_module(path)[0]))
    for path, module in run_callbacks.unmapped_callbacks(config.get("callback")):
        out.append(("callback", path, module))
    return out


def check_imports(
    config: dict[str, Any], source: str, allowed: Sequence[str], what: str = "run folder"
) -> None:
    """``RunError`` for the first module ``config`` (read from a ``what``: ``"run folder"`` or
    ``"settings file"``) names that ``allowed`` does not hold (the fix lists every flag
    needed), or that cannot be found; a note on stderr for each module that will be imported,
    and a warning when its file differs from the one ``config``'s ``module_sha256`` records."""
    named = modules_named(config)
    refused = [(s, v, m) for s, v, m in named if m not in allowed]
    if refused:
        setting, value, module = refused[0]
        flags = " ".join(f"--allow-import {m}" for m in dict.fromkeys(m for _, _, m in refused))
        fix = f"pass {flags} to allow it"
        if "." not in module and recipe.locate_module(module) is None:  # finding runs no code
            fix = f"run from the folder that holds module {module!r}, and {fix}"
        if setting in ("env_wrapper", "callback"):
            label = "wrapper" if setting == "env_wrapper" else setting
            fix += f"; {label} names in {TABLE} need no flag"
        raise RunError(
            f"{source} names {setting} {value!r}, which would import module {module!r}; "
            f"palaestra runs no code named by a {what}",
            fix,
        )
    recorded = config.get("module_sha256") or {}
    warned: set[str] = set()
    for setting, value, module in named:
        if recipe.locate_module(module) is None:
            raise RunError(
                f"{source} names {setting} {value!r}, but module {module!r} is not found from "
                f"{os.getcwd()}",
                f"run from the folder that holds it, with --allow-import {module}",
            )
        note(f"importing module {module!r} for {setting} {value!r} of {source} (allowed)")
        now, then = recipe.module_sha256(module), recorded.get(module)
        if then is not None and now != then and module not in warned:
            warned.add(module)
            print(
                f"palaestra: warning: module {module!r} ({recipe.locate_module(module)}) is not "
                f"the file {source} recorded (sha256 {then[:12]}..., now "
                f"{(now or 'no file')[:12]}...): results may differ from the run's",
                file=sys.stderr,
                flush=True,
            )
    unused = sorted(set(allowed) - {m for _, _, m in named})
    if unused:
        note(f"--allow-import {', '.join(unused)}: {source} names no such module")


def module_hashes(config: dict[str, Any]) -> dict[str, str]:
    """``{module: sha256 of its file}`` for the modules ``config`` names that are not
    palaestra's own (what ``config.json`` records as ``module_sha256``, so that a later
    ``eval`` can warn when the file changed); call it once they are imported."""
    hashes: dict[str, str] = {}
    for _, _, module in modules_named(config):
        digest = recipe.module_sha256(module)
        if digest is not None:
            hashes[module] = digest
    return hashes


def check_inside(path: Path, root: Path, what: str) -> None:
    """``RunError`` unless ``path`` (which may not exist yet) and the entries directly in it
    are no symbolic links and stay inside ``root``: a shared folder whose ``trials/`` (or
    ``trials/7``) links elsewhere must not make palaestra write there."""
    base = root.resolve()
    entries = [path, *(sorted(path.iterdir()) if path.is_dir() else [])]
    for entry in entries:
        target = entry.resolve()
        if entry.is_symlink() or not target.is_relative_to(base):
            raise RunError(
                f"{what} {str(entry)!r} links to {str(target)!r}, outside {str(root)!r}",
                "remove the link: palaestra writes only inside the folder",
            )


# -- values ------------------------------------------------------------------------------------
def _fail(source: str, key: str, value: Any, expected: str) -> RunError:
    return RunError(
        f"{source}: {key} must be {expected}, got {reprlib.repr(value)}",
        "fix the file, or start a new run",
    )


def _integer(source: str, key: str, value: Any, low: int, high: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _fail(source, key, value, f"an integer from {low} to {high}")


def _check_atari(source: str, atari: Any) -> None:
    if atari is None or isinstance(atari, bool):
        return
    if not isinstance(atari, dict):
        raise _fail(source, "atari", atari, "true/false or AtariWrapper kwargs")
    for key, value in atari.items():
        if key not in _ATARI_LIMITS:
            raise _fail(source, "atari", key, f"a mapping with keys among {sorted(_ATARI_LIMITS)}")
        kind, low, high = _ATARI_LIMITS[key]
        ok = isinstance(value, bool) if kind is bool else not isinstance(value, bool)
        ok = ok and isinstance(value, (int, float) if kind is float else kind)
        if not ok or not low <= value <= high:
            raise _fail(source, f"atari.{key}", value, f"a {kind.__name__} from {low} to {high}")


def _check_normalize(source: str, normalize: Any) -> None:
    if normalize is None or isinstance(normalize, bool):
        return
    if not isinstance(normalize, dict):
        raise _fail(source, "normalize", normalize, "true/false or VecNormalize kwargs")
    for key, value in normalize.items():
        kind = _NORMALIZE_KEYS.get(key)
        if kind is None:
            raise _fail(
                source, "normalize", key, f"a mapping with keys among {sorted(_NORMALIZE_KEYS)}"
            )
        ok = isinstance(value, bool) if kind is bool else not isinstance(value, bool)
        if kind is float:
            ok = ok and isinstance(value, (int, float)) and math.isfinite(value) and value >= 0
        if not ok:
            raise _fail(source, f"normalize.{key}", value, f"a {kind.__name__}")


def _check_keys(config: dict[str, Any], source: str, required: Sequence[str]) -> None:
    unknown = sorted(str(k) for k in config if k not in CONFIG_KEYS)
    if unknown:
        raise RunError(
            f"{source} holds unknown key(s) {unknown}",
            f"a run's config.json holds only {', '.join(sorted(CONFIG_KEYS))}",
        )
    missing = [k for k in required if k not in config]
    if missing:
        raise RunError(f"{source} lacks {', '.join(missing)}", "fix the file, or start a new run")


def _check_names(config: dict[str, Any], source: str) -> None:
    for key in ("algo", "env_id", "policy", "preset", "palaestra_version", "device"):
        if key not in config or (key == "preset" and config[key] is None):  # null: no preset
            continue
        value = config[key]
        if not isinstance(value, str) or not 0 < len(value) <= 200:
            raise _fail(source, key, value, "a name")
    if "algo" in config and config["algo"].lower() not in algorithms.ALGOS:
        raise _fail(source, "algo", config["algo"], f"one of {', '.join(algorithms.ALGOS)}")
    if "device" in config and not _DEVICE.fullmatch(config["device"]):
        raise _fail(source, "device", config["device"], "auto, cpu, mps or cuda[:N]")
    if config.get("seed") is not None:
        _integer(source, "seed", config["seed"], 0, 2**64 - 1)


def _wrapper_args(item: dict[Any, Any]) -> bool:
    """Whether ``{name: kwargs}`` has a name and a mapping of keyword arguments (or null)."""
    ((name, kwargs),) = item.items()
    kwargs = {} if kwargs is None else kwargs
    return (
        isinstance(name, str)
        and isinstance(kwargs, dict)
        and all(isinstance(k, str) and k.isidentifier() for k in kwargs)
    )


def _check_pipeline(config: dict[str, Any], source: str) -> None:
    """The env settings: sizes within limits, the shapes ``pipeline`` expects."""
    for key, high in (("n_envs", MAX_N_ENVS), ("n_timesteps", MAX_STEPS)):
        if key in config:
            _integer(source, key, config[key], 1, high)
    if config.get("frame_stack") is not None:
        _integer(source, "frame_stack", config["frame_stack"], 1, MAX_FRAME_STACK)
    env_kwargs = config.get("env_kwargs")
    if env_kwargs is not None and not (
        isinstance(env_kwargs, dict) and all(isinstance(k, str) for k in env_kwargs)
    ):
        raise _fail(source, "env_kwargs", env_kwargs, "a mapping of keyword arguments")
    wrappers = config.get("env_wrapper")
    listed = wrappers if isinstance(wrappers, list) else [wrappers]
    if wrappers is not None and not (
        len(listed) <= 16
        and all(
            isinstance(w, str) or (isinstance(w, dict) and len(w) == 1 and _wrapper_args(w))
            for w in listed
        )
    ):
        raise _fail(
            source,
            "env_wrapper",
            wrappers,
            "'module:Class' or a list of them (each may be {'module:Class': {kwargs}})",
        )
    callbacks = config.get("callback")
    listed = callbacks if isinstance(callbacks, list) else [callbacks]
    if callbacks is not None and not (
        len(listed) <= 16
        and all(
            isinstance(c, str) or (isinstance(c, dict) and len(c) == 1 and _wrapper_args(c))
            for c in listed
        )
    ):
        raise _fail(
            source,
            "callback",
            callbacks,
            "'module:Class' or a list of them (each may be {'module:Class': {kwargs}})",
        )
    _check_atari(source, config.get("atari"))
    _check_normalize(source, config.get("normalize"))
    hashes = config.get("module_sha256")
    if hashes is not None and not (
        isinstance(hashes, dict)
        and len(hashes) <= 64
        and all(
            isinstance(k, str) and 0 < len(k) <= 200 and isinstance(v, str) and _SHA256.fullmatch(v)
            for k, v in hashes.items()
        )
    ):
        raise _fail(source, "module_sha256", hashes, "a mapping of module names to sha256 digests")


def check_run_config(
    config: dict[str, Any], source: str, required: Sequence[str] = ("env_id",)
) -> None:
    """``RunError`` unless ``config`` holds only the keys ``train`` writes, ``required`` among
    them, with usable types and values within limits. Imports no user module."""
    _check_keys(config, source, required)
    _check_names(config, source)
    _check_pipeline(config, source)
    if "hyperparams" in config:
        from palaestra.algos.common.hyperparams import (  # lazy: import-time — torch
            check_run_hyperparams,  # lazy: import-time — torch
        )

        algo = algorithms.check_algo(str(config.get("algo")))
        names = set(algorithms.hyperparameter_names(algo))
        try:
            check_run_hyperparams(algo, config["hyperparams"], names, source)
        except ValueError as exc:
            raise RunError(str(exc), "fix the file, or start a new run") from None


def read_run_config(
    path: Path,
    allowed: Sequence[str],
    required: Sequence[str] = ("env_id",),
    env_id: str | None = None,
) -> dict[str, Any]:
    """``config.json`` at ``path``, checked (:func:`check_run_config`) and with every module it
    names allowed by ``allowed`` (:func:`check_imports`). ``env_id`` (``--env``, the command
    line's own) replaces the run's id, whose module is then not imported."""
    config = read_json(path, "run config")
    check_run_config(config, str(path), required)
    gated = config if env_id is None else {k: v for k, v in config.items() if k != "env_id"}
    check_imports(gated, str(path), allowed)
    return config


def find_run_config(
    model_path: Path, allowed: Sequence[str], env_id: str | None = None
) -> dict[str, Any] | None:
    """The checked ``config.json`` of the run a model file belongs to (its folder, or the
    folder above for ``checkpoints/``), or None (``common.find_run_config``'s search)."""
    for folder in (model_path.parent, model_path.parent.parent):
        candidate = folder / CONFIG_FILE
        if candidate.is_file():
            return read_run_config(candidate, allowed, env_id=env_id)
    if allowed:
        note(f"--allow-import {', '.join(allowed)}: no config.json beside {model_path}")
    return None


def read_status(path: Path) -> dict[str, Any]:
    """``status.json`` at ``path``: ``RunError`` unless it is a mapping whose step counts are
    integers >= 0 (the total >= 1), whose wall time is a finite number >= 0 and whose state is
    a name. Keys it does not know are left alone."""
    status = read_json(path, "run status")
    source = str(path)
    for key in ("status", "num_timesteps", "total_timesteps", "wall_time_s"):
        if key not in status:
            raise RunError(f"{source} lacks {key}", "fix the file, or start a new run")
    if not isinstance(status["status"], str):
        raise _fail(source, "status", status["status"], "a name")
    _integer(source, "num_timesteps", status["num_timesteps"], 0, MAX_STEPS)
    _integer(source, "total_timesteps", status["total_timesteps"], 1, MAX_STEPS)
    wall = status["wall_time_s"]
    if isinstance(wall, bool) or not isinstance(wall, (int, float)) or not 0 <= wall < math.inf:
        raise _fail(source, "wall_time_s", wall, "a number of seconds >= 0")
    return status
