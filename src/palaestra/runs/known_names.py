"""Names from SB3, Gymnasium and RL Zoo settings files that palaestra maps to its own code.

A settings file (``train --config``, a sweep's ``best.yaml``, an RL Zoo hyperparameter file)
or a run folder may name code: an ``env_wrapper`` (``"gymnasium.wrappers.TimeLimit"``), a
callback, an activation function inside ``policy_kwargs``. Importing a module such a file names
runs that module, so palaestra imports nothing a file names unless the command line allows it
(``--allow-import MODULE``, :mod:`palaestra.runs.folder`). Two kinds of names need no flag,
because they resolve to code palaestra ships:

- a name under ``palaestra`` itself (``palaestra.wrappers:TimeLimit``), except the wrappers
  that write files or open windows (:data:`SIDE_EFFECT_WRAPPERS`: ``Monitor``,
  ``RecordVideo``, ``HumanRendering``), whose arguments would let a file choose where;
- a name this table maps to its palaestra equivalent: the wrappers of Gymnasium and SB3's Atari
  wrappers (their palaestra classes take the same arguments), the torch activations RL Zoo
  files write as ``nn.ReLU`` or ``th.nn.Tanh``, and SB3's callbacks.

This module is the one table (``docs/known_names.md`` shows it; a test keeps the two equal);
whatever reads foreign settings files maps names through :func:`palaestra_name`. It imports
nothing. RL Zoo hyperparameter files (:mod:`palaestra.runs.zoo`) use it twice: a Python-literal
``policy_kwargs`` string may name exactly the :data:`ACTIVATIONS` (``"dict(activation_fn=
nn.ReLU)"``, read by :mod:`palaestra.runs.literal`, never ``eval``), and an ``env_wrapper``
naming SB3's ``AtariWrapper`` becomes palaestra's Atari recipe (``atari``).

Not mapped, because palaestra has no equivalent: ``rl_zoo3.wrappers.*`` (FrameSkip,
HistoryWrapper, TimeFeatureWrapper, ...), ``sb3_contrib.common.wrappers.TimeFeatureWrapper``,
``rl_zoo3.callbacks.*``, activations other than those below (``nn.GELU``, ``nn.SiLU``), and
SB3's ``RMSpropTFLike`` optimizer (the Zoo's A2C ``atari`` section names it).
"""

from __future__ import annotations

__all__ = [
    "ACTIVATIONS",
    "CALLBACKS",
    "ENV_WRAPPERS",
    "KINDS",
    "SIDE_EFFECT_WRAPPERS",
    "is_palaestra",
    "markdown_table",
    "palaestra_name",
]

_GYMNASIUM_WRAPPERS = (
    "AddRenderObservation",
    "AtariPreprocessing",
    "ClipAction",
    "ClipReward",
    "DelayObservation",
    "DtypeObservation",
    "FilterObservation",
    "FlattenObservation",
    "FrameStackObservation",
    "GrayscaleObservation",
    "MaxAndSkipObservation",
    "NormalizeObservation",
    "NormalizeReward",
    "RecordEpisodeStatistics",
    "RescaleAction",
    "RescaleObservation",
    "ReshapeObservation",
    "ResizeObservation",
    "StickyAction",
    "TimeAwareObservation",
    "TimeLimit",
)
_SB3_ATARI_WRAPPERS = (
    "AtariWrapper",
    "ClipRewardEnv",
    "EpisodicLifeEnv",
    "FireResetEnv",
    "MaxAndSkipEnv",
    "NoopResetEnv",
    "StickyActionEnv",
    "WarpFrame",
)
_SB3_CALLBACKS = (
    "CheckpointCallback",
    "EvalCallback",
    "EveryNTimesteps",
    "ProgressBarCallback",
    "StopTrainingOnMaxEpisodes",
    "StopTrainingOnNoModelImprovement",
    "StopTrainingOnRewardThreshold",
)

# env_wrapper: the name a foreign file writes -> palaestra's "module:Class".
ENV_WRAPPERS: dict[str, str] = {
    **{f"gymnasium.wrappers.{n}": f"palaestra.wrappers:{n}" for n in _GYMNASIUM_WRAPPERS},
    # The submodule paths RL Zoo files write (Gymnasium 1.x, then 0.29's older names).
    "gymnasium.wrappers.common.TimeLimit": "palaestra.wrappers:TimeLimit",
    "gymnasium.wrappers.transform_observation.GrayscaleObservation": (
        "palaestra.wrappers:GrayscaleObservation"
    ),
    "gymnasium.wrappers.transform_observation.ResizeObservation": (
        "palaestra.wrappers:ResizeObservation"
    ),
    "gymnasium.wrappers.time_limit.TimeLimit": "palaestra.wrappers:TimeLimit",
    "gymnasium.wrappers.resize_observation.ResizeObservation": (
        "palaestra.wrappers:ResizeObservation"
    ),
    "gymnasium.wrappers.gray_scale_observation.GrayScaleObservation": (
        "palaestra.wrappers:GrayscaleObservation"
    ),
    "gymnasium.wrappers.GrayScaleObservation": "palaestra.wrappers:GrayscaleObservation",
    **{
        f"stable_baselines3.common.atari_wrappers.{n}": f"palaestra.wrappers.atari:{n}"
        for n in _SB3_ATARI_WRAPPERS
    },
}
# Wrappers that write files or open windows where their arguments say: a file naming one
# (with keyword arguments, RL Zoo's form) could choose where palaestra writes, so these are
# never "palaestra's own" for the gate, whatever their module (every env is under a Monitor
# already).
SIDE_EFFECT_WRAPPERS = frozenset({"Monitor", "RecordVideo", "HumanRendering"})

# policy_kwargs.activation_fn: RL Zoo's spelling -> the name presets use ("relu", ...).
ACTIVATIONS: dict[str, str] = {
    f"{prefix}{torch_name}": name
    for torch_name, name in (
        ("ReLU", "relu"),
        ("Tanh", "tanh"),
        ("ELU", "elu"),
        ("LeakyReLU", "leaky_relu"),
    )
    for prefix in ("nn.", "th.nn.", "torch.nn.")
}

# callback (RL Zoo's key, palaestra.runs.run_callbacks): SB3 -> palaestra.
CALLBACKS: dict[str, str] = {
    f"stable_baselines3.common.callbacks.{n}": f"palaestra.algos.callbacks:{n}"
    for n in _SB3_CALLBACKS
}

KINDS: dict[str, dict[str, str]] = {
    "env_wrapper": ENV_WRAPPERS,
    "activation_fn": ACTIVATIONS,
    "callback": CALLBACKS,
}


def is_palaestra(module: str) -> bool:
    """Whether ``module`` is palaestra's own (``palaestra`` or under it).

    >>> is_palaestra("palaestra.wrappers"), is_palaestra("palaestra_evil"), is_palaestra("os")
    (True, False, False)
    """
    return module == "palaestra" or module.startswith("palaestra.")


def palaestra_name(kind: str, name: str) -> str | None:
    """The palaestra name ``name`` resolves to as a ``kind`` (a key of :data:`KINDS`): itself
    when it is under ``palaestra``, its mapping in the table, else None. ``"module:Class"``
    and ``"module.Class"`` are the same name.

    >>> palaestra_name("env_wrapper", "gymnasium.wrappers:TimeLimit")
    'palaestra.wrappers:TimeLimit'
    >>> palaestra_name("activation_fn", "th.nn.Tanh"), palaestra_name("env_wrapper", "mine:Wrap")
    ('tanh', None)
    """
    table = KINDS[kind]
    if not isinstance(name, str):
        return None
    dotted = name.replace(":", ".")
    if dotted in table:
        return table[dotted]
    module = name.partition(":")[0] if ":" in name else name.rpartition(".")[0]
    if kind == "env_wrapper" and dotted.rpartition(".")[2] in SIDE_EFFECT_WRAPPERS:
        return None
    return name if is_palaestra(module) else None


def markdown_table() -> str:
    """The table as ``docs/known_names.md`` shows it (a test keeps the page equal to it)."""
    rows = ["| Setting | Name in the file | palaestra's |", "|---|---|---|"]
    for kind, table in KINDS.items():
        rows += [f"| `{kind}` | `{name}` | `{ours}` |" for name, ours in table.items()]
    return "\n".join(rows) + "\n"
