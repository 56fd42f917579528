"""What a model file or a run folder may hand an algorithm's constructor, and within which limits.

A model file or a run folder is data that someone else may have written. Its values reach
``DQN(...)`` / ``PPO(...)`` / ``A2C(...)`` only through the checks here, one function per source:

- :func:`check_model_file` (``load``): only the keys the algorithm itself saves
  (``_hyperparameters()`` and ``_schedules()``), so a file cannot choose where ``learn()``
  writes (``tensorboard_log``), the device, the thread count or ``_init_setup_model``; numbers
  of the right type inside ranges that bound what they allocate (a 10^12-row replay buffer is
  refused before anything is allocated); schedules of known shapes; ``policy_kwargs`` with the
  keys the policies take, bounded layer widths and depths, and networks no larger than the
  weights the file holds (:func:`check_net_arch_weights`).
- :func:`check_run_hyperparams` (``palaestra eval``/``record``/``train --resume``): a run
  folder's ``hyperparams`` hold only constructor hyperparameters, and the numbers among them
  pass the same ranges.

The user's own Python is not limited: ``load(..., **kwargs)`` and ``custom_objects`` override
what the file says after these checks, and a class the file names still resolves only through
``model_io.decode_classes`` (which refuses anything outside torch and palaestra).
"""

from __future__ import annotations

import itertools
import math
import reprlib
from collections.abc import Callable, Mapping
from typing import Any

from palaestra.algos.common.action_noise import noise_from_json
from palaestra.algos.common.model_io import ModelFileError

__all__ = [
    "MAX_BATCH_SIZE",
    "MAX_BUFFER_SIZE",
    "MAX_NET_PARAMETERS",
    "MAX_NET_WIDTH",
    "MAX_N_ENVS",
    "MAX_N_STEPS",
    "check_model_file",
    "check_net_arch_weights",
    "check_run_hyperparams",
    "declare_rules",
]

# Limits far above any published setting (SB3 and RL-Zoo use buffers of 10^4..10^6 rows,
# rollouts of 8..8192 steps, layers of 64..512 units) and far below what exhausts memory.
MAX_BUFFER_SIZE = 100_000_000  # replay buffer transitions
MAX_N_STEPS = 1_000_000  # PPO/A2C rollout steps per env
MAX_BATCH_SIZE = 1_000_000
MAX_N_ENVS = 65_536
MAX_NET_WIDTH = 65_536  # units of one layer
MAX_NET_DEPTH = 64  # hidden layers
# weights between the hidden layers of a run folder's networks (400 MB of float32); a model
# file is bounded by the weights it holds instead (check_net_arch_weights)
MAX_NET_PARAMETERS = 100_000_000
MAX_STEPS = 10**15  # anything counted in env steps
MAX_TABLE = 100_000  # points of a tabulated schedule

# A check returns None for an acceptable value, else what was expected ("an integer in ...").
Check = Callable[[Any], str | None]


def _short(value: Any) -> str:
    """A bounded repr: a crafted value may be a huge or deeply nested structure."""
    return reprlib.repr(value)


def _integer(low: int, high: int) -> Check:
    def check(value: Any) -> str | None:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            return f"an integer from {low} to {high}"
        return None

    return check


def _number(low: float, high: float, *, low_open: bool = False, infinite: bool = False) -> Check:
    """An int or float in ``[low, high]`` (``(low, high]`` when ``low_open``); no NaN, and no
    infinity unless ``infinite`` (``max_grad_norm=inf``: no clipping)."""
    left = "(" if low_open else "["

    def check(value: Any) -> str | None:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        ok = ok and not math.isnan(value) and (infinite or math.isfinite(value))
        ok = ok and (value > low if low_open else value >= low) and value <= high
        return None if ok else f"a number in {left}{low}, {high}]"

    return check


def _boolean(value: Any) -> str | None:
    return None if isinstance(value, bool) else "true or false"


def _backend(value: Any) -> str | None:
    return None if value in ("auto", "numpy", "torch") else "'auto', 'numpy' or 'torch'"


def _optional(check: Check) -> Check:
    def optional(value: Any) -> str | None:
        problem = None if value is None else check(value)
        return None if problem is None else f"null or {problem}"

    return optional


def _train_freq(value: Any) -> str | None:
    expected = 'a positive integer or [n, "step"|"episode"]'
    if isinstance(value, list) and len(value) == 2:
        n, unit = value
        return (
            None if _integer(1, MAX_STEPS)(n) is None and unit in ("step", "episode") else expected
        )
    return None if _integer(1, MAX_STEPS)(value) is None else expected


def _class_ref(value: Any) -> str | None:
    """``{"__class__": "module:qualname"}``; which modules may be named is
    ``model_io.decode_classes``'s decision (it asks for ``custom_objects`` otherwise)."""
    if (
        isinstance(value, dict)
        and set(value) == {"__class__"}
        and isinstance(value["__class__"], str)
    ):
        return None
    return 'a class as {"__class__": "module:qualname"}'


def _mapping(rules: Mapping[str, Check]) -> Check:
    """A mapping whose keys are among ``rules``, each value passing its rule."""

    def check(value: Any) -> str | None:
        if not isinstance(value, dict):
            return f"a mapping with keys among {sorted(rules)}"
        for key, item in value.items():
            if key not in rules:
                return f"a mapping with keys among {sorted(rules)} (not {_short(key)})"
            problem = rules[key](item)
            if problem is not None:
                return f"{key} to be {problem}, not {_short(item)}"
        return None

    return check


def _layers(value: Any) -> str | None:
    expected = f"a list of at most {MAX_NET_DEPTH} layer widths from 1 to {MAX_NET_WIDTH}"
    if not isinstance(value, list) or len(value) > MAX_NET_DEPTH:
        return expected
    if any(_integer(1, MAX_NET_WIDTH)(w) is not None for w in value):
        return expected
    return None


def _weights_between(layers: Any) -> int:
    """The weights between a list of hidden layers (0 for anything else)."""
    if not isinstance(layers, list) or not all(isinstance(w, int) for w in layers):
        return 0
    return sum(a * b for a, b in itertools.pairwise(layers))


def _arch_weights(net_arch: Any) -> int:
    """The weights between hidden layers ``net_arch`` asks for: a lower bound on the
    parameters of the networks built from it (each is built at least once)."""
    if isinstance(net_arch, dict):
        return sum(_weights_between(layers) for layers in net_arch.values())
    return _weights_between(net_arch)


def _capped_layers(value: Any) -> str | None:
    """``_layers``, and at most MAX_NET_PARAMETERS weights between them (run folders, whose
    networks are built from these values with no weights to bound them)."""
    problem = _layers(value)
    if problem is None and _weights_between(value) > MAX_NET_PARAMETERS:
        return f"layers with at most {MAX_NET_PARAMETERS} weights between them"
    return problem


def _net_arch(value: Any, layers: Check = _layers) -> str | None:
    """A list of widths, or ``{"pi": [...], "vf": [...]}`` (PPO's separate networks)."""
    if isinstance(value, dict):
        return _mapping({"pi": layers, "vf": layers})(value)
    return layers(value)


def check_net_arch_weights(policy_kwargs: Any, declared: Mapping[str, Any], source: str) -> None:
    """``ModelFileError`` unless a model file's ``policy/`` arrays (``model_io.ArraySpec``s,
    each already checked against the bytes its member holds) declare at least the weights its
    ``net_arch`` makes the model allocate: the networks are built before their weights are
    read, so a small file must not ask for a large one. The bound is the file's own size, not
    a fixed count: whatever ``save`` writes, ``load`` reads."""
    net_arch = policy_kwargs.get("net_arch") if isinstance(policy_kwargs, dict) else None
    needed = _arch_weights(net_arch)
    held = sum(
        math.prod(spec.shape) for name, spec in declared.items() if name.startswith("policy/")
    )
    if needed > held:
        raise ModelFileError(
            f"{source}: policy_kwargs net_arch={_short(net_arch)} needs at least {needed} "
            f"weights, but the file's parameters hold {held}"
        )


# -- the rules ---------------------------------------------------------------------------------
_PROBABILITY = _number(0.0, 1.0)
_COMMON: dict[str, Check] = {
    "gamma": _PROBABILITY,
    "max_grad_norm": _number(0.0, math.inf, low_open=True, infinite=True),
    "verbose": _integer(0, 2),
    "seed": _optional(_integer(0, 2**64 - 1)),  # torch.manual_seed's and numpy's range
    "stats_window_size": _integer(1, 1_000_000),
}
_COMMON_NO_CLIP = {k: v for k, v in _COMMON.items() if k != "max_grad_norm"}


def _action_noise(value: Any) -> str | None:
    if value is None:
        return None
    try:
        noise_from_json(value)
    except (ValueError, TypeError):
        return "a saved NormalActionNoise, OrnsteinUhlenbeckActionNoise or VectorizedActionNoise"
    return None


# What every off-policy algorithm saves (DQN, SAC, TD3, DDPG...), action_noise aside.
_REPLAY: dict[str, Check] = {
    "buffer_size": _integer(1, MAX_BUFFER_SIZE),
    "learning_starts": _integer(0, MAX_STEPS),
    "batch_size": _integer(1, MAX_BATCH_SIZE),
    "tau": _PROBABILITY,
    "train_freq": _train_freq,
    "gradient_steps": _integer(-1, MAX_BATCH_SIZE),  # -1: as many as env steps collected
    "replay_buffer_class": lambda v: (
        None if v is None or v == "HerReplayBuffer" else "null or 'HerReplayBuffer'"
    ),
    "replay_buffer_kwargs": _mapping(
        {
            "handle_timeout_termination": _boolean,
            # HerReplayBuffer's
            "n_sampled_goal": _integer(0, 1_000_000),
            "goal_selection_strategy": lambda v: (
                None if v in ("future", "final", "episode") else "'future', 'final' or 'episode'"
            ),
            "copy_info_dict": _boolean,
            "frame_margin": _number(0.0, 10.0),
            "layout": lambda v: (
                None
                if isinstance(v, list)
                and len(v) == 2
                and _optional(_integer(0, 8))(v[0]) is None
                and _integer(1, MAX_NET_WIDTH)(v[1]) is None
                else "[axis or null, channels]"
            ),
        }
    ),
    "optimize_memory_usage": _boolean,
    # n-step returns: sampling holds O(batch) memory whatever the window (common.nstep)
    "n_steps": _integer(1, MAX_STEPS),
}
_OFF_POLICY: dict[str, Check] = {**_REPLAY, "action_noise": _action_noise}
_LEARNING_RATE: dict[str, Check] = {"learning_rate": _number(0.0, 1e6)}
_OPTIMIZER_KWARGS: dict[str, Check] = {  # torch.optim's numeric options (lr: the schedule's)
    "eps": _number(0.0, 1.0),
    "betas": lambda v: (
        None
        if isinstance(v, list) and len(v) == 2 and all(_number(0.0, 1.0)(b) is None for b in v)
        else "[beta1, beta2] in [0, 1]"
    ),
    "weight_decay": _number(0.0, 1e6),
    "momentum": _number(0.0, 1.0),
    "alpha": _number(0.0, 1.0),
    "dampening": _number(0.0, 1.0),
    "amsgrad": _boolean,
    "centered": _boolean,
    "nesterov": _boolean,
    "maximize": _boolean,
}
_EXTRACTOR_KWARGS: dict[str, Check] = {  # NatureCNN's and CombinedExtractor's
    "features_dim": _integer(1, MAX_NET_WIDTH),
    "cnn_output_dim": _integer(1, MAX_NET_WIDTH),
}
_POLICY_COMMON: dict[str, Check] = {
    "net_arch": _optional(_net_arch),
    "activation_fn": _class_ref,
    "features_extractor_class": _class_ref,
    "features_extractor_kwargs": _optional(_mapping(_EXTRACTOR_KWARGS)),
    "normalize_images": _boolean,
    "optimizer_class": _class_ref,
    "optimizer_kwargs": _optional(_mapping(_OPTIMIZER_KWARGS)),
    "share_features_extractor": _boolean,
    "backend": _backend,  # which learner trains the policy (learners.build_learner)
}
_ACTOR_CRITIC = {
    **_POLICY_COMMON,
    "net_arch": _optional(
        lambda v: _mapping({"pi": _layers, "qf": _layers})(v) if isinstance(v, dict) else _layers(v)
    ),
    "n_critics": _integer(1, 64),
}
_ON_POLICY_ACTOR_CRITIC = {  # PPO's and A2C's ActorCritic
    **_POLICY_COMMON,
    "ortho_init": _boolean,
    "log_std_init": _number(-20.0, 20.0),
    "use_sde": _boolean,  # gSDE's (the algorithm's use_sde; equal if given)
    "full_std": _boolean,
    "use_expln": _boolean,
    "squash_output": _boolean,
}
_SDE = {"use_sde": _boolean, "sde_sample_freq": _integer(-1, MAX_STEPS)}

# Each algorithm's rules, declared by its package (``algos/<algo>/hyperparams.py``) through
# declare_rules: the keys of its ``_hyperparameters()``, each schedule's values (a learning rate,
# a clip range...), and the keyword arguments of its policy plus the optimizer's. Tests keep
# them equal to what the algorithm saves and what its policy takes.
HYPERPARAMETERS: dict[str, dict[str, Check]] = {}
SCHEDULES: dict[str, dict[str, Check]] = {}
POLICY_KWARGS: dict[str, dict[str, Check]] = {}


def declare_rules(
    algo: str,
    hyperparameters: Mapping[str, Check],
    schedules: Mapping[str, Check],
    policy_kwargs: Mapping[str, Check],
) -> None:
    """Record the rules for the class named ``algo`` (``"DQN"``); its package calls this."""
    HYPERPARAMETERS[algo] = dict(hyperparameters)
    SCHEDULES[algo] = dict(schedules)
    POLICY_KWARGS[algo] = dict(policy_kwargs)


def _ours(ref: Any, packages: tuple[str, ...]) -> bool:
    """Whether a class reference names a class of one of ``packages`` (absent: the default)."""
    if not isinstance(ref, dict):
        return True  # absent (the default), or malformed: _class_ref refuses it
    return str(ref.get("__class__", "")).startswith(packages)


def _check_policy_kwargs(algo: str, value: Any, source: str, policy: Any = None) -> None:
    if not isinstance(value, dict):
        raise ModelFileError(f"{source}: policy_kwargs must be a mapping, got {_short(value)}")
    rules = dict(POLICY_KWARGS[algo])
    if not _ours(policy, ("palaestra.",)):
        # A user's policy class (loaded through custom_objects only) takes its own keywords;
        # ours keep their rules, and classes in any value still resolve as decode_classes says.
        for key in set(value) - set(rules):
            rules[key] = lambda v: None
    # A user's own extractor or optimizer (loaded through custom_objects) takes its own kwargs.
    if not _ours(value.get("features_extractor_class"), ("palaestra.",)):
        rules["features_extractor_kwargs"] = _optional(_mapping_of_any)
    if not _ours(value.get("optimizer_class"), ("torch.optim",)):
        rules["optimizer_kwargs"] = _optional(_mapping_of_any)
    _check_each(value, rules, source, "policy_kwargs")


def _mapping_of_any(value: Any) -> str | None:
    return None if isinstance(value, dict) else "a mapping"


def _check_each(values: dict[str, Any], rules: Mapping[str, Check], source: str, what: str) -> None:
    for key, value in values.items():
        if key not in rules:
            raise ModelFileError(
                f"{source}: {what} names {_short(key)}, which a model file may not set "
                f"(it may set {', '.join(sorted(rules))})"
            )
        problem = rules[key](value)
        if problem is not None:
            raise ModelFileError(
                f"{source}: {what} {key}={_short(value)} is refused: expected {problem}"
            )


def _check_schedule(name: str, data: Any, rule: Check, source: str) -> None:
    """A saved schedule (``schedules.schedule_to_json``) whose values pass ``rule``."""
    if data is None and name == "clip_range_vf":  # None: no value clipping
        return
    fields = {
        "constant": ("value",),
        "linear": ("start", "end", "end_fraction"),
        "table": ("values",),
    }
    kind = data.get("type") if isinstance(data, dict) else None
    if kind not in fields or set(data) != {"type", *fields[kind]}:
        raise ModelFileError(f"{source}: schedule {name} is malformed: {_short(data)}")
    checks: list[tuple[Any, Check]]
    if kind == "constant":
        checks = [(data["value"], rule)]
    elif kind == "linear":
        checks = [(data["start"], rule), (data["end"], rule), (data["end_fraction"], _PROBABILITY)]
    else:
        values = data["values"]
        if not isinstance(values, list) or not 2 <= len(values) <= MAX_TABLE:
            raise ModelFileError(
                f"{source}: schedule {name} must list 2 to {MAX_TABLE} values, got {_short(values)}"
            )
        checks = [(v, rule) for v in values]
    for value, check in checks:
        problem = check(value)
        if problem is not None:
            raise ModelFileError(
                f"{source}: schedule {name} holds {_short(value)}: expected {problem}"
            )


def check_model_file(algo: str, meta: Any, source: str) -> None:
    """``ModelFileError`` unless the hyperparameters, schedules, ``policy_kwargs`` and
    ``n_envs`` in a model file's metadata are ones ``algo``'s constructor may receive from a
    file (see the module docstring). Run before anything is built from them."""
    if algo not in HYPERPARAMETERS:
        raise ModelFileError(f"{source}: no hyperparameter rules for {algo!r}")
    if not isinstance(meta, dict):
        raise ModelFileError(f"{source}: malformed model metadata")
    hyper, schedules = meta.get("hyperparameters"), meta.get("schedules")
    if not isinstance(hyper, dict) or not isinstance(schedules, dict):
        raise ModelFileError(f"{source}: hyperparameters and schedules must be mappings")
    _check_each(hyper, HYPERPARAMETERS[algo], source, "hyperparameters")
    for name, data in schedules.items():
        if name not in SCHEDULES[algo]:
            raise ModelFileError(
                f"{source}: schedules name {_short(name)}, which a model file may not set "
                f"(it may set {', '.join(sorted(SCHEDULES[algo]))})"
            )
        _check_schedule(name, data, SCHEDULES[algo][name], source)
    _check_policy_kwargs(algo, meta.get("policy_kwargs", {}), source, meta.get("policy"))
    problem = _integer(1, MAX_N_ENVS)(meta.get("n_envs", 1))  # absent: save(exclude=...)
    if problem is not None:
        raise ModelFileError(
            f"{source}: n_envs={_short(meta.get('n_envs'))} is refused: expected {problem}"
        )


def check_run_hyperparams(algo: str, hyperparams: Any, allowed: set[str], source: str) -> None:
    """``ValueError`` unless a run folder's ``hyperparams`` is a mapping of ``allowed``
    constructor hyperparameters, each passing the model-file range where one exists.

    Schedules and activations stay in the preset format (``"lin_0.001"``, ``"relu"``), which
    :func:`palaestra.presets.resolve` checks when it resolves them."""
    if not isinstance(hyperparams, dict):
        raise ValueError(f"{source}: hyperparams must be a mapping, got {_short(hyperparams)}")
    unknown = sorted(str(k) for k in hyperparams if k not in allowed)
    if unknown:
        raise ValueError(
            f"{source}: hyperparams names {_short(unknown[0])}, which is not a {algo} "
            "hyperparameter"
        )
    rules = HYPERPARAMETERS.get(algo.upper(), {})
    checks = [(key, value, rules[key]) for key, value in hyperparams.items() if key in rules]
    policy_kwargs = hyperparams.get("policy_kwargs")
    if policy_kwargs is not None and not isinstance(policy_kwargs, dict):
        checks.append(("policy_kwargs", policy_kwargs, _mapping_of_any))
    elif policy_kwargs is not None:
        net_arch = policy_kwargs.get("net_arch")
        rule = _optional(lambda v: _net_arch(v, _capped_layers))
        checks.append(("policy_kwargs.net_arch", net_arch, rule))
    for key, value, rule in checks:
        problem = rule(value)
        if problem is not None:
            raise ValueError(
                f"{source}: hyperparams {key}={_short(value)} is refused: expected {problem}"
            )
