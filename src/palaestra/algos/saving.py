"""Save, load and parameter transfer for algorithms, on top of ``model_io``'s safe archives."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

from palaestra.algos.model_io import (
    ArraySpec,
    Expect,
    ModelFileError,
    decode_classes,
    encode_classes,
    optimizer_from_arrays,
    optimizer_to_arrays,
    read_archive,
    read_arrays,
    read_manifest,
    write_archive,
)
from palaestra.algos.schedules import schedule_from_json, schedule_to_json
from palaestra.algos.spaces_util import space_from_json, space_to_json

__all__ = ["load_model", "save_model", "set_parameters"]

COUNTERS = ("num_timesteps", "_episode_num", "_n_updates", "_progress_remaining")


def save_model(model: Any, path: Any) -> None:
    """Everything needed to predict and to resume training, as JSON + arrays."""
    import palaestra

    opt_meta, opt_arrays = optimizer_to_arrays(model.optimizer, "optimizer")
    meta = {
        "algo": type(model).__name__,
        "palaestra_version": palaestra.__version__,
        "torch_version": torch.__version__,
        "policy": model.policy_name,
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
        "optimizer": opt_meta,
    }
    arrays = {f"policy/{k}": v.detach().cpu().numpy() for k, v in model.policy.state_dict().items()}
    arrays.update(opt_arrays)
    write_archive(path, "model", meta, arrays)


def load_model(
    cls: Any, path: Any, env: Any, device: Any, custom: dict[str, Any], kwargs: dict[str, Any]
) -> Any:
    # The arrays are read only once the model is built from the metadata, so that a file
    # declaring parameters this model does not have is refused before they are allocated.
    manifest = read_manifest(path, "model")
    meta = manifest.meta
    algo = meta.get("algo")
    if algo != cls.__name__:
        raise ModelFileError(f"{path} holds a {algo} model; load it with {algo}.load()")
    try:
        hyper = dict(meta["hyperparameters"])
        for name, sched in meta["schedules"].items():
            hyper[name] = None if sched is None else schedule_from_json(sched)
        policy_kwargs = decode_classes(meta["policy_kwargs"], custom)
        observation_space = space_from_json(meta["observation_space"])
        action_space = space_from_json(meta["action_space"])
        n_envs, counters = int(meta["n_envs"]), dict(meta["counters"])
        policy = str(meta["policy"])
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, ModelFileError):
            raise
        raise ModelFileError(f"{path}: malformed model metadata ({exc!r})") from exc
    if "policy_kwargs" in custom:
        policy_kwargs = custom["policy_kwargs"]
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
    arrays = read_arrays(manifest, expect=_fits(model, exact_match=True, source=str(path)))
    _load_policy(model, arrays, exact_match=True, source=str(path))
    optimizer_from_arrays(model.optimizer, meta["optimizer"], arrays, "optimizer")
    for name, value in counters.items():
        if name in (*COUNTERS, *model._extra_counters):
            setattr(model, name, value)
    try:
        model._rng.bit_generator.state = meta["rng"]
    except (TypeError, ValueError, KeyError) as exc:
        raise ModelFileError(f"{path}: malformed generator state") from exc
    return model


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
    params = {f"policy/{k}": tuple(v.shape) for k, v in model.policy.state_dict().items()}
    shapes = [tuple(p.shape) for g in model.optimizer.param_groups for p in g["params"]]

    def expect(meta: dict[str, Any], declared: dict[str, ArraySpec]) -> None:
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
            elif name.startswith("optimizer/"):
                index = name[len("optimizer/") :].partition("/")[0]
                known = index.isascii() and index.isdigit() and int(index) < len(shapes)
                want = shapes[int(index)] if known else None
                # Per-parameter optimizer state is shaped like its parameter (Adam's moments)
                # or is one number (its step count: shape () or, from the numpy trainer, (1,)).
                if want is None or (spec.shape != want and math.prod(spec.shape) > 1):
                    raise ModelFileError(
                        f"{source}: optimizer state {name[:80]!r} {spec.shape} does not fit "
                        "this model's parameters"
                    )

    return expect


def _load_policy(model: Any, arrays: dict[str, np.ndarray], exact_match: bool, source: str) -> None:
    state = {
        k[len("policy/") :]: torch.from_numpy(v.copy())
        for k, v in arrays.items()
        if k.startswith("policy/")
    }
    expected = model.policy.state_dict()
    for key, tensor in state.items():
        if key in expected and tuple(expected[key].shape) != tuple(tensor.shape):
            raise ModelFileError(
                f"{source}: parameter {key!r} has shape {tuple(tensor.shape)}, "
                f"this model expects {tuple(expected[key].shape)}"
            )
    try:
        model.policy.load_state_dict(state, strict=exact_match)
    except RuntimeError as exc:
        raise ModelFileError(f"{source}: parameters do not fit this model ({exc})") from exc


def set_parameters(model: Any, source: Any, exact_match: bool) -> None:
    """From ``get_parameters()`` output or a model file path."""
    if isinstance(source, dict):
        if "policy" not in source:
            raise ValueError(
                f"expected keys 'policy' (and 'policy.optimizer'), got {sorted(source)}"
            )
        model.policy.load_state_dict(source["policy"], strict=exact_match)
        if "policy.optimizer" in source:
            model.optimizer.load_state_dict(source["policy.optimizer"])
        return
    meta, arrays = read_archive(source, "model", expect=_fits(model, exact_match, str(source)))
    _load_policy(model, arrays, exact_match, str(source))
    if "optimizer" in meta:
        optimizer_from_arrays(model.optimizer, meta["optimizer"], arrays, "optimizer")
