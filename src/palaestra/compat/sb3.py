"""``from_sb3(path, env=None)``: an SB3 DQN/PPO ``MlpPolicy`` file as a palaestra model.

>>> from palaestra.compat import from_sb3
>>> model = from_sb3("dqn_cartpole.zip")             # doctest: +SKIP
>>> action, _ = model.predict(obs, deterministic=True)  # doctest: +SKIP

Nothing is unpickled (see :mod:`palaestra.compat.sb3_file`). The network shape comes from the
weights themselves; the activation, optimizer and settings from the plain-JSON parts of
``data``. What a file keeps only in pickled form is not recovered and takes palaestra's
default unless given as a keyword: DQN's ``train_freq``, non-constant schedules, and the
optimizer state (``policy.optimizer.pth``), so further training starts a fresh optimizer.
Needs torch (``palaestra[train]``) but neither SB3 nor Gymnasium.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from palaestra.error import dependency_not_installed

try:
    import torch
except ImportError as exc:  # the one dependency from_sb3 has: say which extra ships it
    raise dependency_not_installed("torch", "train", "palaestra.compat.from_sb3") from exc

from palaestra import spaces
from palaestra.algos import DQN, PPO
from palaestra.algos.common.model_io import ModelFileError, PathLike, decode_classes
from palaestra.algos.common.networks import preprocessed_dim
from palaestra.compat.sb3_file import MISSING, SB3File, plain_value, read_sb3_file, sb3_type
from palaestra.compat.sb3_file import space_from_sb3 as _space_from_sb3
from palaestra.core import Env
from palaestra.utils.bounded_zip import short, summary

__all__ = ["from_sb3"]

_ALGOS: dict[str, type[DQN] | type[PPO]] = {"DQN": DQN, "PPO": PPO}
_SETTINGS = {
    "DQN": (
        "learning_rate buffer_size learning_starts batch_size tau gamma gradient_steps "
        "target_update_interval exploration_fraction exploration_initial_eps "
        "exploration_final_eps max_grad_norm n_steps seed"
    ).split(),
    "PPO": (
        "learning_rate n_steps batch_size n_epochs gamma gae_lambda clip_range clip_range_vf "
        "normalize_advantage ent_coef vf_coef max_grad_norm target_kl seed"
    ).split(),
}
# policy_kwargs an MlpPolicy file may carry, and what becomes of them.
_KWARGS_USED = {"activation_fn", "normalize_images", "optimizer_class", "optimizer_kwargs"}
_KWARGS_FROM_WEIGHTS = {"net_arch", "ortho_init", "log_std_init", "share_features_extractor"}
_MLP_OBSERVATIONS = (spaces.Box, spaces.Discrete, spaces.MultiDiscrete, spaces.MultiBinary)
_CLASS = re.compile(r"^<class '([\w.]+)\.(\w+)'>$")


def from_sb3(
    path: PathLike, env: Any = None, device: torch.device | str = "auto", **kwargs: Any
) -> DQN | PPO:
    """Load an SB3 ``DQN`` or ``PPO`` ``MlpPolicy`` model file as a palaestra ``DQN``/``PPO``.

    ``env`` (an id, a palaestra env or VecEnv, or a ``gymnasium.Env``) gives exact spaces and
    lets the model train; without it the spaces are rebuilt from the file's description.
    ``kwargs`` override hyperparameters. Raises ``ModelFileError`` for files that are not SB3
    models or hold another algorithm or policy, and ``UnsafeFileError`` if ``policy.pth``
    names code to run (nothing is run).
    """
    file = read_sb3_file(path)
    if file.algo not in _ALGOS:
        raise ModelFileError(
            f"{file.name} holds an SB3 {file.algo} model; from_sb3 reads DQN and PPO models"
        )
    if file.data.get("use_sde"):
        raise ModelFileError(f"{file.name}: gSDE (use_sde=True) models are not supported")
    cls = _ALGOS[file.algo]
    state, net_arch = _dqn_state(file) if cls is DQN else _ppo_state(file)
    policy_kwargs = {**_policy_kwargs(file), "net_arch": net_arch}
    settings = {
        k: v for k in _SETTINGS[file.algo] if (v := plain_value(file.data.get(k))) is not MISSING
    }
    settings.update(kwargs)
    env = _palaestra_env(env)
    try:
        model: Any = cls(
            "MlpPolicy",
            env,
            device=device,
            policy_kwargs=policy_kwargs,
            _init_setup_model=False,
            **settings,
        )
    except ValueError as exc:  # a Dict env: the model file's MlpPolicy cannot take it
        if "MultiInputPolicy" not in str(exc):
            raise
        raise ModelFileError(
            f"{file.name}: the env has Dict observations; from_sb3 reads MlpPolicy models "
            "(Box, Discrete, MultiDiscrete or MultiBinary observations), not MultiInputPolicy ones"
        ) from exc
    obs_space, act_space = _spaces(file, model if env is not None else None)
    model.observation_space, model.action_space = obs_space, act_space
    if env is None:
        model.n_envs = int(plain_value(file.data.get("n_envs")) or 1)
    _check_widths(file, obs_space, act_space, state)
    model._setup_model()
    tensors = {k: torch.from_numpy(np.ascontiguousarray(v)) for k, v in state.items()}
    # every policy parameter, exactly (an SB3 file's optimizer state is not read)
    model.policy.load_state_dict(tensors, strict=True)
    for name in ("num_timesteps", "_episode_num", "_n_updates", "exploration_rate", "_n_calls"):
        value = plain_value(file.data.get(name, MISSING))
        if isinstance(value, (int, float)) and hasattr(model, name):
            setattr(model, name, value)
    return model


def _palaestra_env(env: Any) -> Any:
    if env is None or isinstance(env, (str, Env)):
        return env
    from palaestra.vec_env import VecEnv  # lazy: import-time — cloudpickle

    if isinstance(env, VecEnv):
        return env
    try:
        from palaestra.compat.adapters import from_gymnasium  # lazy: optional-dep — gymnasium

        return from_gymnasium(env)
    except (ImportError, TypeError) as exc:
        raise TypeError(
            f"env must be an id string, a palaestra Env or VecEnv, or a gymnasium.Env; "
            f"got {type(env).__name__}"
        ) from exc


# -- weights -----------------------------------------------------------------------------------
def _linear_stack(state: dict[str, np.ndarray], prefix: str, name: str) -> list[int]:
    """Indices of the Linear layers of the ``nn.Sequential`` at ``prefix`` (0, 2, 4 ...: each
    followed by an activation, which holds no weights)."""
    pattern = re.compile(re.escape(prefix) + r"(\d{1,6})\.(weight|bias)$")
    indices = sorted({int(m.group(1)) for k in state if (m := pattern.match(k))})
    if indices != list(range(0, 2 * len(indices), 2)):
        raise ModelFileError(
            f"{name}: {prefix}* has layers {summary(indices, items=8)}; an MlpPolicy has Linear "
            "layers at 0, 2, 4 ..."
        )
    return indices


def _take(
    state: dict[str, np.ndarray], mapping: dict[str, str], name: str
) -> dict[str, np.ndarray]:
    """Rename SB3 keys to palaestra's; any SB3 key left over means another policy type."""
    left = set(state) - set(mapping)
    if left:
        raise ModelFileError(
            f"{name}: policy has parameters {summary(sorted(left))} that an MlpPolicy does not; "
            "from_sb3 reads MlpPolicy models only (not CnnPolicy, MultiInputPolicy or custom "
            "feature extractors)"
        )
    missing = set(mapping) - set(state)
    if missing:
        raise ModelFileError(f"{name}: policy lacks parameters {summary(sorted(missing))}")
    return {ours: state[theirs] for theirs, ours in mapping.items()}


def _sequential(prefix: str, ours: str, indices: list[int]) -> dict[str, str]:
    return {f"{prefix}{i}.{p}": f"{ours}{i}.{p}" for i in indices for p in ("weight", "bias")}


def _dqn_state(file: SB3File) -> tuple[dict[str, np.ndarray], list[int]]:
    """SB3 ``q_net.q_net.{0,2,..,2L}`` (hidden layers then output) -> palaestra ``q_net.mlp.*``
    and ``q_net.head``; the same for the target network."""
    mapping: dict[str, str] = {}
    widths: list[int] = []
    for net in ("q_net", "q_net_target"):
        indices = _linear_stack(file.state_dict, f"{net}.q_net.", file.name)
        if not indices:
            raise ModelFileError(f"{file.name}: DQN policy has no {net}.q_net layers")
        *hidden, out = indices
        mapping.update(_sequential(f"{net}.q_net.", f"{net}.mlp.", hidden))
        mapping.update({f"{net}.q_net.{out}.{p}": f"{net}.head.{p}" for p in ("weight", "bias")})
        widths = [file.state_dict[f"{net}.q_net.{i}.weight"].shape[0] for i in hidden]
    return _take(file.state_dict, mapping, file.name), widths


def _ppo_state(file: SB3File) -> tuple[dict[str, np.ndarray], dict[str, list[int]]]:
    """SB3 ``mlp_extractor.{policy,value}_net.*``, ``action_net``, ``value_net``, ``log_std``
    -> palaestra ``pi_net.*``, ``vf_net.*``, ``action_head.net``, ``value_head``,
    ``action_head.log_std``."""
    sd, mapping, arch = file.state_dict, {}, {}  # arch: SB3's net_arch=dict(pi=..., vf=...)
    for theirs, ours, key in (("policy_net", "pi_net", "pi"), ("value_net", "vf_net", "vf")):
        prefix = f"mlp_extractor.{theirs}."
        indices = _linear_stack(sd, prefix, file.name)
        mapping.update(_sequential(prefix, f"{ours}.", indices))
        arch[key] = [sd[f"{prefix}{i}.weight"].shape[0] for i in indices]
    for theirs, ours in (("action_net", "action_head.net"), ("value_net", "value_head")):
        mapping.update({f"{theirs}.{p}": f"{ours}.{p}" for p in ("weight", "bias")})
    if "log_std" in sd:
        mapping["log_std"] = "action_head.log_std"
    return _take(sd, mapping, file.name), arch


def _check_widths(
    file: SB3File, obs_space: spaces.Space[Any], act_space: spaces.Space[Any], state: dict[str, Any]
) -> None:
    """The first layer must read this observation space and the head write this action space."""
    first = next(
        (v for k, v in state.items() if k.endswith(".0.weight")),
        state.get("q_net.head.weight", state.get("action_head.net.weight")),
    )
    expected_in = preprocessed_dim(obs_space)
    if first is not None and first.shape[1] != expected_in:
        raise ModelFileError(
            f"{file.name}: the network reads {first.shape[1]} inputs, but observation space "
            f"{obs_space} gives {expected_in}"
        )
    head = state.get("q_net.head.weight", state.get("action_head.net.weight"))
    if isinstance(act_space, spaces.Discrete):
        expected_out = int(act_space.n)
    elif isinstance(act_space, spaces.MultiDiscrete):
        expected_out = int(act_space.nvec.sum())
    else:
        expected_out = int(np.prod(act_space.shape or ()))
    if head is not None and head.shape[0] != expected_out:
        raise ModelFileError(
            f"{file.name}: the network writes {head.shape[0]} outputs, but action space "
            f"{act_space} needs {expected_out}"
        )


# -- settings ----------------------------------------------------------------------------------
def _policy_kwargs(file: SB3File) -> dict[str, Any]:
    raw = file.data.get("policy_kwargs") or {}
    if not isinstance(raw, dict):
        raise ModelFileError(f"{file.name}: policy_kwargs is not a mapping")
    found = {k: v for k, v in raw.items() if not k.startswith(":")}
    extractor = str(found.pop("features_extractor_class", "FlattenExtractor"))
    if "FlattenExtractor" not in extractor:
        raise ModelFileError(
            f"{file.name}: features_extractor_class {short(extractor)} is not supported "
            "(from_sb3 reads MlpPolicy models with the default FlattenExtractor)"
        )
    unknown = set(found) - _KWARGS_USED - _KWARGS_FROM_WEIGHTS
    if unknown:
        raise ModelFileError(
            f"{file.name}: policy_kwargs {summary(sorted(unknown))} are not supported by from_sb3"
        )
    out: dict[str, Any] = {}
    for key in ("activation_fn", "optimizer_class"):
        if key in found:
            out[key] = _class(found[key], key, file.name)
    for key in ("normalize_images", "optimizer_kwargs"):
        if key in found:
            out[key] = found[key]
    return out


def _class(text: Any, key: str, name: str) -> type:
    """``"<class 'torch.nn.modules.activation.ReLU'>"`` (SB3's str of a pickled class) -> the
    class, resolved only inside torch.nn / torch.optim by ``model_io.decode_classes``."""
    match = _CLASS.match(str(text))
    if not match:
        raise ModelFileError(f"{name}: policy_kwargs[{key!r}] = {summary(text)} is not a class")
    cls: type = decode_classes({"__class__": f"{match.group(1)}:{match.group(2)}"}, {})
    return cls


def _spaces(file: SB3File, model: Any) -> tuple[spaces.Space[Any], spaces.Space[Any]]:
    """The env's spaces (checked against the file's description) or the rebuilt ones."""
    described = []
    for what in ("observation", "action"):
        desc: Any = file.data.get(f"{what}_space")
        if model is None:
            described.append(_space_from_sb3(desc, what, file.name))
            continue
        space = getattr(model, f"{what}_space")
        kind = sb3_type(desc)
        shape = desc.get("_shape") if isinstance(desc, dict) else None
        if kind != type(space).__name__ or (shape is not None and shape != list(space.shape or ())):
            raise ValueError(
                f"The env's {what} space {space} does not match the SB3 model's "
                f"({kind} of shape {summary(shape)})"
            )
        if isinstance(space, spaces.Discrete) and str(desc.get("n")) != str(int(space.n)):
            raise ValueError(
                f"The env's {what} space {space} does not match the SB3 model's "
                f"(Discrete({summary(desc.get('n'))}))"
            )
        described.append(space)
    if not isinstance(described[0], _MLP_OBSERVATIONS):
        raise ModelFileError(
            f"{file.name}: observation space {described[0]} is not supported; from_sb3 reads "
            "MlpPolicy models (Box, Discrete, MultiDiscrete or MultiBinary observations), not "
            "MultiInputPolicy ones"
        )
    return described[0], described[1]
