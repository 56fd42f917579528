"""The ``VecNormalize`` statistics file: an ``.npz`` of plain arrays plus a JSON string.

Written atomically and read back without pickle: loading a file never runs code (SB3 pickles
the whole wrapper). Loading checks every member's size, dtype and shape before reading it and
every value after (finite means, non-negative variances, positive counts, settings of the
right types), so a damaged or crafted file is a ``ModelFileError`` naming the file and what is
wrong.

Two layouts. ``palaestra.VecNormalize/1`` (Box observations, or none normalised) holds
``obs_mean``, ``obs_var``, ``ret_mean`` and ``ret_var`` and the settings with ``obs_count``;
it is what every Box ``save`` still writes, byte for byte as before. ``.../2`` (Dict
observations) holds one ``obs_mean_<i>``/``obs_var_<i>`` pair per normalised key, the keys in
order in the settings (``norm_obs_keys``) with their counts (``obs_counts``): numbered members,
so a key can be any string.
"""

from __future__ import annotations

import json
import math
import os
import zipfile
import zlib
from typing import TYPE_CHECKING, Any

import numpy as np

from palaestra.spaces import Dict
from palaestra.utils.atomic_write import atomic_write
from palaestra.utils.bounded_zip import ModelFileError, check_members, read_npy, short
from palaestra.wrappers.running_mean_std import RunningMeanStd

if TYPE_CHECKING:
    from palaestra.vec_env.base import VecEnv
    from palaestra.vec_env.normalize import VecNormalize

BOX_FORMAT = "palaestra.VecNormalize/1"
DICT_FORMAT = "palaestra.VecNormalize/2"
_MAX_SETTINGS = 1 << 16  # bytes of the settings JSON (a few hundred in practice)
_FLAGS = ("training", "norm_obs", "norm_reward")
_POSITIVE = ("clip_obs", "clip_reward", "epsilon", "ret_count")
_OPTIONS = ("training", "norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma", "epsilon")


def save(norm: VecNormalize, save_path: str | os.PathLike[str]) -> None:
    """Write ``norm``'s statistics and settings to ``save_path`` (no pickle)."""
    settings: dict[str, Any] = {
        "format": DICT_FORMAT if isinstance(norm.obs_rms, dict) else BOX_FORMAT,
        **{key: getattr(norm, key) for key in _OPTIONS},
    }
    arrays: dict[str, Any] = {}  # name -> array
    if isinstance(norm.obs_rms, dict):
        settings["norm_obs_keys"] = list(norm.obs_rms)
        settings["obs_counts"] = [float(rms.count) for rms in norm.obs_rms.values()]
        for i, rms in enumerate(norm.obs_rms.values()):
            arrays[f"obs_mean_{i}"], arrays[f"obs_var_{i}"] = rms.mean, rms.var
    else:
        settings["obs_count"] = float(norm.obs_rms.count)
        arrays["obs_mean"], arrays["obs_var"] = norm.obs_rms.mean, norm.obs_rms.var
    settings["ret_count"] = float(norm.ret_rms.count)
    arrays["ret_mean"] = np.asarray(norm.ret_rms.mean)
    arrays["ret_var"] = np.asarray(norm.ret_rms.var)
    with atomic_write(save_path, "wb") as f:  # a crash mid-save keeps the old file
        np.savez(f, settings=np.array(json.dumps(settings)), **arrays)


def load(load_path: str | os.PathLike[str], venv: VecEnv, cls: type[VecNormalize]) -> VecNormalize:
    """A ``cls`` around ``venv`` with the statistics saved at ``load_path``; ``ModelFileError``
    naming the file for anything else (see the module docstring)."""
    name = str(load_path)
    try:
        with zipfile.ZipFile(load_path) as zf:
            members = check_members(zf, name)
            settings = _read_settings(zf, members, name)
            norm = _build(cls, venv, settings, name)
            obs_rms = _read_obs_stats(zf, members, norm, settings, name)
            ret_mean, ret_var = (
                _read_stat(zf, members, key, (), name, "returns have") for key in _RET
            )
    except zipfile.BadZipFile as e:
        if _is_pickle(load_path):
            raise ModelFileError(
                f"{name} is a pickle (what Stable-Baselines3's VecNormalize.save writes); "
                "palaestra never unpickles (a pickle can run code) and reads only the .npz "
                "file its own VecNormalize.save writes. To carry SB3 statistics over, load "
                "them with SB3 where you trust the file and set obs_rms/ret_rms (mean, var, "
                "count) on a palaestra VecNormalize, then save that."
            ) from None
        raise ModelFileError(
            f"{name} is not a palaestra VecNormalize file (palaestra reads the .npz file "
            f"VecNormalize.save writes: {e})"
        ) from e
    except (EOFError, zlib.error) as e:
        raise ModelFileError(f"{name} is truncated or corrupt ({short(e)})") from e
    norm.obs_rms = obs_rms
    norm.ret_rms.mean, norm.ret_rms.var = ret_mean[()], ret_var[()]
    norm.ret_rms.count = float(settings["ret_count"])
    return norm


_RET = ("ret_mean", "ret_var")


def _build(
    cls: type[VecNormalize], venv: VecEnv, settings: dict[str, Any], name: str
) -> VecNormalize:
    """The wrapper the settings describe, refused (naming the file) where they do not fit."""
    space = venv.observation_space
    kwargs = {key: settings[key] for key in _OPTIONS}
    if "norm_obs_keys" in settings:
        if not isinstance(space, Dict):
            raise ModelFileError(
                f"{name} holds statistics of Dict observation keys "
                f"{short(settings['norm_obs_keys'])}, but the env's observations are {space}"
            )
        missing = [k for k in settings["norm_obs_keys"] if k not in space.spaces]
        if missing:
            raise ModelFileError(
                f"{name} holds statistics of observation keys {short(missing)} that the env's "
                f"observations lack (they have {short(list(space.spaces))})"
            )
        kwargs["norm_obs_keys"] = settings["norm_obs_keys"]
    elif settings["norm_obs"] and isinstance(space, Dict):
        raise ModelFileError(
            f"{name} holds statistics of Box observations (format {BOX_FORMAT}), but the env's "
            f"observations are {short(space, 200)}"
        )
    try:
        return cls(venv, **kwargs)
    except ValueError as e:
        raise ModelFileError(f"{name}: its settings do not fit the env ({short(e, 300)})") from e


def _read_obs_stats(
    zf: zipfile.ZipFile,
    members: dict[str, zipfile.ZipInfo],
    norm: VecNormalize,
    settings: dict[str, Any],
    name: str,
) -> RunningMeanStd | dict[str, RunningMeanStd]:
    """The observation statistics, checked against the shapes ``norm`` was built with."""

    def stats(
        suffix: str, shape: tuple[int, ...], count: float, what: str, label: str = ""
    ) -> RunningMeanStd:
        rms = RunningMeanStd(shape=shape)
        rms.mean, rms.var = (
            _read_stat(zf, members, f"obs_{stat}{suffix}", shape, name, what, label)
            for stat in ("mean", "var")
        )
        rms.count = count
        return rms

    if isinstance(norm.obs_rms, dict):
        out = {}
        for i, (key, rms) in enumerate(norm.obs_rms.items()):
            label = f"of key {short(repr(key), 80)}"
            what = f"{short(repr(key), 80)} observations have"
            out[key] = stats(f"_{i}", rms.mean.shape, settings["obs_counts"][i], what, label)
        return out
    return stats("", norm.obs_rms.mean.shape, settings["obs_count"], "observations have")


def _is_pickle(path: str | os.PathLike[str]) -> bool:
    """Whether the file starts like a pickle of protocol 2 or later (``0x80``, version)."""
    try:
        with open(path, "rb") as file:
            head = file.read(2)
    except OSError:
        return False
    return len(head) == 2 and head[0] == 0x80 and 2 <= head[1] <= 5


def _read_settings(
    zf: zipfile.ZipFile, members: dict[str, zipfile.ZipInfo], name: str
) -> dict[str, Any]:
    """The settings JSON, every key present with a value of the right type and range."""
    if "settings.npy" not in members:
        raise ModelFileError(f"{name} is not a palaestra VecNormalize file (no settings)")
    raw = read_npy(zf, members["settings.npy"], name, _MAX_SETTINGS, shape=())
    try:
        settings = json.loads(str(raw[()]))
    except (ValueError, RecursionError) as e:
        raise ModelFileError(f"{name}: its settings are not valid JSON ({short(e)})") from e
    if not isinstance(settings, dict) or settings.get("format") not in (BOX_FORMAT, DICT_FORMAT):
        raise ModelFileError(f"{name} is not a palaestra VecNormalize file")
    for key in _FLAGS:
        _check(name, settings, key, isinstance(settings.get(key), bool), "true or false")
    for key in (*_POSITIVE, "gamma"):
        value = _number(settings.get(key))
        if key in _POSITIVE:
            _check(name, settings, key, value is not None and value > 0, "a finite number > 0")
        else:
            _check(name, settings, key, value is not None and 0 <= value <= 1, "a number in [0, 1]")
    checked = {
        **{k: settings[k] for k in _FLAGS},
        **{k: _number(settings[k]) for k in (*_POSITIVE, "gamma")},
    }
    if settings["format"] == BOX_FORMAT:
        count = _number(settings.get("obs_count"))
        _check(name, settings, "obs_count", count is not None and count > 0, "a finite number > 0")
        return {**checked, "obs_count": count}
    return {**checked, **_dict_settings(settings, name)}


def _dict_settings(settings: dict[str, Any], name: str) -> dict[str, Any]:
    """The per-key settings of a Dict file: distinct string keys, one positive count each."""
    _check(name, settings, "norm_obs", settings["norm_obs"], f"true in a {DICT_FORMAT} file")
    raw = settings.get("norm_obs_keys")
    keys: list[str] = raw if isinstance(raw, list) else []
    good = len(keys) > 0 and all(isinstance(k, str) for k in keys) and len(set(keys)) == len(keys)
    _check(name, settings, "norm_obs_keys", good, "a non-empty list of distinct strings")
    counts = settings.get("obs_counts")
    numbers = [_number(c) for c in counts] if isinstance(counts, list) else []
    good = len(numbers) == len(keys) and all(c is not None and c > 0 for c in numbers)
    _check(name, settings, "obs_counts", good, f"{len(keys)} finite numbers > 0, one per key")
    return {"norm_obs_keys": keys, "obs_counts": numbers}


def _check(name: str, settings: dict[str, Any], key: str, ok: bool, want: str) -> None:
    if not ok:
        raise ModelFileError(
            f"{name}: setting {key!r} is {short(repr(settings.get(key)), 60)}, expected {want}"
        )


def _number(value: Any) -> float | None:
    """``value`` as a finite float, or None (for bools, strings, NaN, huge ints ...)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _read_stat(
    zf: zipfile.ZipFile,
    members: dict[str, zipfile.ZipInfo],
    key: str,
    shape: tuple[int, ...],
    name: str,
    what: str,
    label: str = "",
) -> np.ndarray:
    """One statistic: float, of the env's shape, finite, and a variance never negative.

    ``what`` ends the shape message ("observations have"), ``label`` follows the statistic's
    name in messages ("of key 'pos'")."""
    stat = f"{key.rstrip('0123456789').rstrip('_')!r} statistics" + (f" {label}" if label else "")
    if f"{key}.npy" not in members:
        raise ModelFileError(f"{name}: the {stat} are missing")
    # float64 of the expected shape, checked before reading (plus room to read a wrong shape
    # and say so)
    limit = 8 * math.prod(shape) + (1 << 16)
    array = read_npy(zf, members[f"{key}.npy"], name, limit, {"<f8", "<f4"})
    if array.shape != shape:
        raise ModelFileError(
            f"{name}: saved {stat} have shape {array.shape}, but the env's {what} shape {shape}"
        )
    if not np.all(np.isfinite(array)):
        raise ModelFileError(f"{name}: the {stat} hold NaN or infinite values")
    if key.startswith("obs_var") or key == "ret_var":
        if np.any(array < 0):
            raise ModelFileError(f"{name}: the {stat} hold negative variances")
    return array.astype(np.float64)
