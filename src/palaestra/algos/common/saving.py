"""Save, load and parameter transfer for algorithms, on top of ``model_io``'s safe archives.

A model file also holds the state of its ``learn`` loop (``meta["run"]`` and the ``run/``
arrays: the current observations, episode statistics, the torch generator, and what each
algorithm adds in ``_loop_state``), so that a loaded model continues a run exactly. The
current observations only make sense with the env they came from: saving tags that env with a
fresh token, and loading restores them only into an env carrying the same token (the same
object, not stepped by ``learn`` since, or one whose run state was restored from a file saved
with the model, see :func:`bind_env_token`).
"""

from __future__ import annotations

import functools
import math
import uuid
import weakref
from typing import Any

import numpy as np
import torch

from palaestra.algos.common.hyperparams import check_model_file, check_net_arch_weights
from palaestra.algos.common.model_io import (
    ArraySpec,
    Expect,
    ModelFileError,
    Sink,
    decode_classes,
    encode_classes,
    optimizer_from_arrays,
    optimizer_to_arrays,
    read_archive,
    read_arrays,
    read_manifest,
    write_archive,
)
from palaestra.algos.common.schedules import schedule_from_json, schedule_to_json
from palaestra.algos.common.spaces_util import space_from_json, space_to_json
from palaestra.algos.common.utils import get_system_info
from palaestra.utils.bounded_zip import short, summary

__all__ = [
    "bind_env_token",
    "env_token",
    "forget_env_token",
    "load_model",
    "save_model",
    "set_parameters",
]

COUNTERS = ("num_timesteps", "_episode_num", "_n_updates", "_progress_remaining")
_ENV_TOKENS: weakref.WeakKeyDictionary[Any, str] = weakref.WeakKeyDictionary()


def env_token(env: Any) -> str | None:
    """The token ``env`` got when a model last saved it (None if stepped since)."""
    return None if env is None else _ENV_TOKENS.get(env)


def bind_env_token(env: Any, token: str) -> None:
    """Declare ``env`` to be in the state a model file tagged ``token`` was saved with."""
    _ENV_TOKENS[env] = token


def forget_env_token(env: Any) -> None:
    """``env`` is being stepped: no saved model's observations fit it any more."""
    if env is not None:
        _ENV_TOKENS.pop(env, None)


# What SB3's ``save(exclude=..., include=...)`` may name that a palaestra file never holds
# (SB3 pickles these objects when included; palaestra files hold no objects).
_NEVER_SAVED = {
    "env": "the env (pass env= to load(), or save a VecNormalize with its own save())",
    "replay_buffer": "the replay buffer (use save_replay_buffer())",
    "rollout_buffer": "the rollout buffer (a partial rollout is kept in the run state)",
    "_vec_normalize_env": "the VecNormalize wrapper (use its save())",
    "_logger": "the logger",
    "_custom_logger": "the logger",
    "device": "the device (pass device= to load())",
    "tensorboard_log": "where learn() writes (a file may not choose it)",
}
# SB3 attribute names whose entry in a palaestra file has another name.
_ALIASES = {
    "_current_progress_remaining": "_progress_remaining",
    "_stats_window_size": "stats_window_size",
    "_np_random": "rng",
    "_rng": "rng",
}


def excluded_names(exclude: Any, include: Any) -> set[str]:
    """SB3's rule: ``exclude`` minus ``include`` (both lists of attribute names). Unknown
    names are ignored, as in SB3; ``include`` of an object palaestra never stores (the env,
    a buffer, the logger) is a ``ValueError`` saying where that object is saved instead."""
    names: list[set[str]] = []
    for what, value in (("exclude", exclude), ("include", include)):
        if value is None:
            names.append(set())
            continue
        if isinstance(value, (str, bytes)) or not all(isinstance(v, str) for v in value):
            raise TypeError(f"{what} must be a list of attribute names, got {value!r:.80}")
        names.append(set(value))
    dropped, kept = names
    unsavable = sorted(kept & set(_NEVER_SAVED))
    if unsavable:
        raise ValueError(
            f"include={sorted(kept)!r}: palaestra model files never hold "
            f"{_NEVER_SAVED[unsavable[0]]}; they are JSON and arrays, never pickled objects"
        )
    return {_ALIASES.get(n, n) for n in dropped - kept}


def _drop(meta: dict[str, Any], arrays: dict[str, np.ndarray], names: set[str]) -> None:
    """Remove what ``names`` (SB3 attribute names, see ``excluded_names``) stand for."""
    for section in ("hyperparameters", "schedules", "counters"):
        for name in names & set(meta[section]):
            del meta[section][name]
    for name in names & {"policy_kwargs", "observation_space", "action_space", "n_envs", "rng"}:
        del meta[name]
    run = meta["run"]
    if names & {"_last_obs", "_last_episode_starts", "n_envs"} and run["env_token"] is not None:
        # no observations to continue from: the loaded model starts new episodes (SB3 too)
        run.update(env_token=None, obs_keys=None, loop={})
        for key in [k for k in arrays if k.startswith("run/") and k != "run/torch_rng"]:
            del arrays[key]
    if "ep_info_buffer" in names:
        run["episodes"] = []
    if "ep_success_buffer" in names:
        run["successes"] = []


def save_model(model: Any, path: Any, exclude: Any = None, include: Any = None) -> None:
    """Everything needed to predict and to resume training, as JSON + arrays, less the
    attributes ``exclude`` names (SB3's ``save``: hyperparameters, schedules, counters,
    ``policy_kwargs``, spaces, episode statistics, ``_last_obs``); the parameters and
    optimizer states are always written, as in SB3."""
    import palaestra

    dropped = excluded_names(exclude, include)

    meta: dict[str, Any] = {
        "algo": type(model).__name__,
        "palaestra_version": palaestra.__version__,
        "torch_version": torch.__version__,
        "policy": encode_classes(model.policy_name),  # a name, or a policy class reference
        "policy_kwargs": encode_classes(model.policy_kwargs),
        "observation_space": space_to_json(model.observation_space),
        "action_space": space_to_json(model.action_space),
        "n_envs": model.n_envs,
        "hyperparameters": model._hyperparameters(),
        "schedules": {
            name: None if fn is None else schedule_to_json(fn)
            for name, fn in model._schedules().items()
        },
        "counters": {name: getattr(model, name) for name in (*COUNTERS, *model._extra_counters)},
        "rng": model._rng.bit_generator.state,
        "system_info": dict(_system_info()),  # for load(print_system_info=True)
    }
    # tensors: write_archive streams each to the file (a device tensor reaches the host one at
    # a time), so saving never holds a second copy of the model
    arrays: dict[str, Any] = {
        f"policy/{k}": v for k, v in model._policy_module().state_dict().items()
    }
    for key, (_, optimizer) in model._optimizers().items():
        meta[key], opt_arrays = optimizer_to_arrays(optimizer, key)
        arrays.update(opt_arrays)
    meta["run"], run_arrays = _run_state(model)
    arrays.update(run_arrays)
    _drop(meta, arrays, dropped)
    write_archive(path, "model", meta, arrays, compress=False)
    if meta["run"]["env_token"] is not None:
        bind_env_token(model.env, meta["run"]["env_token"])


@functools.cache
def _system_info() -> dict[str, str]:
    """This process's versions, looked up once (package metadata lookups take milliseconds:
    a small model saves in about as long)."""
    return get_system_info(print_info=False)[0]


def _run_state(model: Any) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """What ``learn`` needs to continue exactly (see the module docstring)."""
    arrays: dict[str, np.ndarray] = {"run/torch_rng": torch.get_rng_state().numpy()}
    obs = None if model._learning else model._last_obs  # mid-learn: the env moves on
    token = None
    if obs is not None and model.env is not None:
        token = uuid.uuid4().hex
        if isinstance(obs, dict):
            arrays.update({f"run/last_obs/{k}": np.asarray(v) for k, v in obs.items()})
        else:
            arrays["run/last_obs"] = np.asarray(obs)
        arrays["run/last_episode_starts"] = np.asarray(model._last_episode_starts, dtype=bool)
    loop_meta, loop_arrays = ({}, {}) if token is None else model._loop_state()
    arrays.update({f"run/loop/{k}": v for k, v in loop_arrays.items()})
    meta = {
        "env_token": token,
        "obs_keys": sorted(obs) if isinstance(obs, dict) else None,
        "episodes": [
            {"r": float(e["r"]), "l": int(e["l"]), "t": float(e.get("t", 0.0))}
            for e in model.ep_info_buffer
        ],
        "successes": [bool(s) for s in model.ep_success_buffer],
        "loop": loop_meta,
    }
    return meta, arrays


def _load_run_state(model: Any, meta: Any, arrays: dict[str, np.ndarray], source: str) -> None:
    """Inverse of ``_run_state``; files saved before it existed have no ``run`` entry."""
    if meta is None:
        return
    try:
        model.ep_info_buffer.extend(dict(e) for e in meta["episodes"])
        model.ep_success_buffer.extend(bool(s) for s in meta["successes"])
        rng = arrays.get("run/torch_rng")
        if rng is not None:
            probe = torch.Generator()
            probe.set_state(torch.from_numpy(rng.copy()))  # refuses a malformed state
            model._torch_rng_to_restore = probe.get_state()
        token = meta["env_token"]
        if token is None or model.env is None or env_token(model.env) != token:
            return  # another env: learn() starts new episodes
        loop = {k[len("run/loop/") :]: v for k, v in arrays.items() if k.startswith("run/loop/")}
        model._load_loop_state(meta["loop"], loop)
        keys = meta["obs_keys"]
        if keys is None:
            obs: Any = arrays["run/last_obs"]
        else:
            obs = {k: arrays[f"run/last_obs/{k}"] for k in keys}
        starts = arrays["run/last_episode_starts"]
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        raise ModelFileError(f"{source}: malformed run state ({exc!r})") from exc
    n = model.env.num_envs
    space = model.env.observation_space  # (normalised observations may leave its bounds)
    shapes = (
        {"": (obs.shape, space.shape)}
        if keys is None
        else {k: (obs[k].shape, space[k].shape) for k in keys}
    )
    if starts.shape != (n,) or any(got != (n, *want) for got, want in shapes.values()):
        raise ModelFileError(f"{source}: saved observations do not fit the env ({n} envs)")
    model._last_obs, model._last_episode_starts = obs, starts


def load_model(
    cls: Any,
    path: Any,
    env: Any,
    device: Any,
    custom: dict[str, Any],
    kwargs: dict[str, Any],
    print_system_info: bool = False,
) -> Any:
    # The arrays are read only once the model is built from the metadata, so that a file
    # declaring parameters this model does not have is refused before they are allocated.
    if print_system_info:
        print("== CURRENT SYSTEM INFO ==")
        get_system_info()
    manifest = read_manifest(path, "model")
    meta = manifest.meta
    algo = meta.get("algo")
    if algo != cls.__name__:
        raise ModelFileError(f"{path} holds a {algo} model; load it with {algo}.load()")
    if print_system_info:
        _print_saved_system_info(meta)
    _convert_old_net_arch(meta)
    check_model_file(algo, meta, str(path))  # types, ranges, allowed keys: before any use
    # A network is built before its weights are read: the file must hold what it declares
    # (a stored member holds its bytes on disk, see model_io), not a fixed weight count.
    check_net_arch_weights(meta.get("policy_kwargs", {}), manifest.declared, str(path))
    if "observation_space" not in meta or "action_space" not in meta:
        # saved with exclude=["observation_space"] or ["action_space"]: SB3's error and words
        raise KeyError(
            f"{path}: the observation_space and action_space were not saved "
            "(save(exclude=...) dropped them), can't verify new environments"
        )
    try:
        hyper = dict(meta["hyperparameters"])
        for name, sched in meta["schedules"].items():
            hyper[name] = None if sched is None else schedule_from_json(sched)
        policy_kwargs = decode_classes(meta.get("policy_kwargs", {}), custom)
        observation_space = space_from_json(meta["observation_space"])
        action_space = space_from_json(meta["action_space"])
        n_envs, counters = int(meta.get("n_envs", 1)), dict(meta["counters"])
        policy = meta["policy"]
        if isinstance(policy, dict):  # a custom policy class: through custom_objects only
            policy = custom.get("policy_class") or decode_classes(policy, custom)
        policy = policy if isinstance(policy, type) else str(policy)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, ModelFileError):
            raise
        raise ModelFileError(f"{path}: malformed model metadata ({exc!r})") from exc
    if "policy_kwargs" in custom:
        policy_kwargs = custom["policy_kwargs"]
    kwargs = dict(kwargs)
    if "policy_kwargs" in kwargs:
        _check_same_policy_kwargs(kwargs.pop("policy_kwargs"), policy_kwargs)
    hyper.update({k: v for k, v in custom.items() if k in hyper})
    hyper.update(kwargs)
    model = cls(
        policy, None, device=device, policy_kwargs=policy_kwargs, _init_setup_model=False, **hyper
    )
    model.observation_space, model.action_space, model.n_envs = (
        observation_space,
        action_space,
        n_envs,
    )
    if env is not None:
        venv = model._wrap_env(env)
        _check_spaces(model, venv)
        model.env, model.n_envs = venv, venv.num_envs
    model._setup_model()
    expect = _fits(model, exact_match=True, source=str(path))
    arrays = read_arrays(manifest, expect=expect, sink=_into_policy(model))
    _load_optimizers(model, meta, arrays, str(path))
    for name, value in counters.items():
        if name in (*COUNTERS, *model._extra_counters):
            setattr(model, name, _counter(name, value, str(path)))
    try:
        if "rng" in meta:  # absent: saved with exclude=["_rng"]; the seed's generator stays
            model._rng.bit_generator.state = meta["rng"]
    except (TypeError, ValueError, KeyError) as exc:
        raise ModelFileError(f"{path}: malformed generator state") from exc
    _load_run_state(model, meta.get("run"), arrays, str(path))
    return model


def _print_saved_system_info(meta: dict[str, Any]) -> None:
    """SB3's ``== SAVED MODEL SYSTEM INFO ==`` block, from what ``save`` recorded (files
    from before it did: the versions they name). Text from the file is shortened and never
    formatted as anything but text."""
    info = meta.get("system_info")
    if not isinstance(info, dict):
        info = {
            "palaestra": meta.get("palaestra_version", "unknown"),
            "PyTorch": meta.get("torch_version", "unknown"),
        }
    print("== SAVED MODEL SYSTEM INFO ==")
    print("".join(f"- {short(key, 40)}: {short(value, 200)!s}\n" for key, value in info.items()))


def _convert_old_net_arch(meta: dict[str, Any]) -> None:
    """SB3's conversion of a pre-1.8 ``net_arch=[dict(pi=..., vf=...)]`` saved in a file to
    ``dict(pi=..., vf=...)`` (its load does so too, silently)."""
    kwargs = meta.get("policy_kwargs")
    if not isinstance(kwargs, dict):
        return
    arch = kwargs.get("net_arch")
    if isinstance(arch, list) and arch and isinstance(arch[0], dict):
        kwargs["net_arch"] = arch[0]


def _check_same_policy_kwargs(given: Any, stored: Any) -> None:
    """SB3's ``load(path, policy_kwargs=...)``: accepted when it equals what the file holds
    (the model is rebuilt from the file's), a ``ValueError`` otherwise. Compared as the file
    keeps them, so ``(64, 64)`` equals the ``[64, 64]`` JSON gives back."""
    try:
        same = encode_classes(given) == encode_classes(stored)
    except TypeError:  # a value JSON cannot hold: compare as it is
        same = given == stored
    if not same:
        raise ValueError(
            "The specified policy kwargs do not equal the stored policy kwargs."
            f"Stored kwargs: {summary(stored)}, specified kwargs: {summary(given)}"
        )


def _into_policy(model: Any) -> Sink:
    """A ``read_arrays`` sink that reads each ``policy/`` array straight into the model's
    parameter or buffer (a CPU tensor of the file's dtype: no copy at all; otherwise one array
    at a time through the host), so loading holds no second copy of the model."""
    state = model._policy_module().state_dict()  # detached tensors sharing their storage

    def sink(name: str, spec: ArraySpec, read: Any) -> bool:
        target = state.get(name[len("policy/") :]) if name.startswith("policy/") else None
        if target is None or tuple(target.shape) != spec.shape:
            return False  # _fits refused what does not fit; anything else: the dict path
        with torch.no_grad():
            direct = target.device.type == "cpu" and target.is_contiguous()
            if direct and _numpy_dtype(target) == spec.dtype:
                read(target.numpy())
            else:
                target.copy_(torch.from_numpy(read(None)))
        return True

    return sink


def _numpy_dtype(tensor: torch.Tensor) -> np.dtype | None:
    try:
        return torch.empty(0, dtype=tensor.dtype).numpy().dtype
    except TypeError:
        return None


# Counters that are fractions (schedules' progress, epsilon); the others count steps.
_FRACTIONS = ("_progress_remaining", "exploration_rate")


def _counter(name: str, value: Any, source: str) -> int | float:
    """A counter read from a file: a non-negative int, or a fraction in [0, 1]."""
    if name in _FRACTIONS:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and 0 <= value <= 1
        if ok:
            return float(value)
        raise ModelFileError(f"{source}: counter {name}={value!r:.40} is not in [0, 1]")
    if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 2**62:
        return value
    raise ModelFileError(f"{source}: counter {name}={value!r:.40} is not a non-negative integer")


def _check_spaces(model: Any, venv: Any) -> None:
    if venv.observation_space != model.observation_space:
        raise ValueError(
            f"Observation spaces do not match: {venv.observation_space} != "
            f"{model.observation_space}"
        )
    if venv.action_space != model.action_space:
        raise ValueError(f"Action spaces do not match: {venv.action_space} != {model.action_space}")


def _fits(model: Any, exact_match: bool, source: str) -> Expect:
    """An ``expect`` hook for ``read_arrays``: the file's ``policy/`` and ``optimizer/`` arrays
    must have this model's shapes (and, with ``exact_match``, its parameter names), checked
    before any of them is read. Other arrays are left to their own readers' checks."""
    params = {f"policy/{k}": tuple(v.shape) for k, v in model._policy_module().state_dict().items()}
    shapes = {
        key: [tuple(p.shape) for g in opt.param_groups for p in g["params"]]
        for key, (_, opt) in model._optimizers().items()
    }

    def expect(meta: dict[str, Any], declared: dict[str, ArraySpec]) -> None:
        missing = sorted(set(params) - set(declared))
        if exact_match and missing:  # what load_state_dict(strict=True) says, before reading
            raise ModelFileError(
                f"{source}: parameters do not fit this model (missing parameter "
                f"{missing[0][len('policy/') :][:80]!r})"
            )
        for name, spec in declared.items():
            if name.startswith("policy/"):
                want = params.get(name)
                if want is None and exact_match:
                    raise ModelFileError(
                        f"{source}: parameters do not fit this model (unexpected parameter "
                        f"{name[len('policy/') :][:80]!r})"
                    )
                if want is not None and spec.shape != want:
                    raise ModelFileError(
                        f"{source}: parameter {name[len('policy/') :]!r} has shape "
                        f"{spec.shape}, this model expects {want}"
                    )
            elif name.partition("/")[0] in shapes:
                key, _, rest = name.partition("/")
                index = rest.partition("/")[0]
                known = index.isascii() and index.isdigit() and int(index) < len(shapes[key])
                want = shapes[key][int(index)] if known else None
                # Per-parameter optimizer state is shaped like its parameter (Adam's moments)
                # or is one number (its step count: shape () or, from the numpy trainer, (1,)).
                if want is None or (spec.shape != want and math.prod(spec.shape) > 1):
                    raise ModelFileError(
                        f"{source}: optimizer state {name[:80]!r} {spec.shape} does not fit "
                        "this model's parameters"
                    )
            elif name.startswith("run/"):
                _check_run_array(model, meta, name, spec.shape, source)

    return expect


def _check_run_array(
    model: Any, meta: dict[str, Any], name: str, shape: tuple[int, ...], source: str
) -> None:
    """A learn-loop array fits the model: observations and episode starts of the saved
    ``n_envs`` envs, a rollout no longer than the buffer's, a torch generator state of a few
    KiB. (``n_envs`` is the file's: the model may be loaded with another number of envs.)"""
    n = int(meta.get("n_envs", 1))  # absent (excluded): the file holds no observations
    space = model.observation_space
    if name == "run/torch_rng":
        fits = math.prod(shape) <= 1 << 16
    elif name == "run/last_episode_starts":
        fits = shape == (n,)
    elif name == "run/last_obs":
        fits = shape == (n, *(space.shape or ()))
    elif name.startswith("run/last_obs/"):
        key = name[len("run/last_obs/") :]
        sub = getattr(space, "spaces", {}).get(key)
        fits = sub is not None and shape == (n, *(sub.shape or ()))
    elif name.startswith("run/loop/sde/"):  # gSDE's exploration matrices: one, one per env
        matrix = model._sde_matrix_shape()
        fits = matrix is not None and shape in (matrix, (n, *matrix))
    elif name.startswith("run/loop/"):
        buffer = getattr(model, "rollout_buffer", None)
        column = None if buffer is None else buffer._columns().get(name[len("run/loop/") :])
        fits = (
            column is not None
            and len(shape) == column.ndim
            and shape[2:] == column.shape[2:]
            and shape[0] <= column.shape[0]
            and shape[1] == n
        )
    else:
        fits = False
    if not fits:
        raise ModelFileError(f"{source}: run state array {name[:80]!r} {shape} does not fit")


def _load_policy(model: Any, arrays: dict[str, np.ndarray], exact_match: bool, source: str) -> None:
    state = {
        k[len("policy/") :]: torch.from_numpy(v.copy())
        for k, v in arrays.items()
        if k.startswith("policy/")
    }
    expected = model._policy_module().state_dict()
    for key, tensor in state.items():
        if key in expected and tuple(expected[key].shape) != tuple(tensor.shape):
            raise ModelFileError(
                f"{source}: parameter {key!r} has shape {tuple(tensor.shape)}, "
                f"this model expects {tuple(expected[key].shape)}"
            )
    try:
        model._policy_module().load_state_dict(state, strict=exact_match)
    except RuntimeError as exc:
        raise ModelFileError(f"{source}: parameters do not fit this model ({exc})") from exc


def set_parameters(model: Any, source: Any, exact_match: bool) -> None:
    """From ``get_parameters()`` output or a model file path (SB3's rules, see
    ``BaseAlgorithm.set_parameters``)."""
    if not isinstance(source, dict):
        meta, arrays = read_archive(source, "model", expect=_fits(model, exact_match, str(source)))
        _load_policy(model, arrays, exact_match, str(source))
        _load_optimizers(model, meta, arrays, str(source), required=exact_match)
        return
    optimizers = {name: optimizer for _, (name, optimizer) in model._optimizers().items()}
    targets = {name: optimizers.get(name) or _object_named(model, name) for name in source}
    expected = {"policy", *optimizers}
    if exact_match and set(source) != expected:
        raise ValueError(
            "Names of parameters do not match agents' parameters: "
            f"expected {sorted(expected)}, got {sorted(source)}"
        )
    if exact_match:  # check every module before changing any
        for name, target in targets.items():
            if isinstance(target, torch.nn.Module):
                _check_state_dict_keys(name, target, source[name])
    for name, target in targets.items():
        if isinstance(target, torch.optim.Optimizer):
            target.load_state_dict(source[name])  # SB3: optimizers take no strict flag
        else:
            target.load_state_dict(source[name], strict=exact_match)


def _object_named(model: Any, name: Any) -> Any:
    """The module ``name`` stands for (``"policy"``, ``"q_net"``, ``"policy.q_net"``...), read
    as SB3's ``recursive_getattr`` does; ``ValueError`` for anything else."""
    target: Any = model
    try:
        for part in str(name).split("."):
            target = getattr(target, part)
    except AttributeError:
        target = None
    target = getattr(target, "_orig_mod", target)  # model.policy = torch.compile(...)
    if not isinstance(name, str) or not isinstance(target, torch.nn.Module):
        raise ValueError(
            f"Key {name!r} is an invalid object name: expected 'policy', an optimizer name "
            "from get_parameters() or a module attribute of the model"
        )
    return target


def _check_state_dict_keys(name: str, module: torch.nn.Module, state: Any) -> None:
    """torch's strict ``load_state_dict`` check (its ``RuntimeError``, which SB3 lets through),
    made before any module is changed: torch raises only after loading the matching keys."""
    if not isinstance(state, dict):
        raise TypeError(f"parameters for {name!r} must be a state_dict, got {type(state)}")
    want, got = set(module.state_dict()), set(state)
    if want != got:
        raise RuntimeError(
            f"Error(s) in loading state_dict for {name!r}: missing keys "
            f"{sorted(want - got)[:5]}, unexpected keys {sorted(got - want)[:5]}"
        )


def _load_optimizers(
    model: Any, meta: Any, arrays: dict[str, np.ndarray], source: str, required: bool = True
) -> None:
    """Each optimizer's state from the file (``"optimizer"`` for DQN/PPO, one entry per
    optimizer otherwise)."""
    for key, (_, optimizer) in model._optimizers().items():
        if key not in meta:
            if required:
                raise ModelFileError(f"{source}: no state for the {key!r} optimizer")
            continue
        optimizer_from_arrays(optimizer, meta[key], arrays, key)
