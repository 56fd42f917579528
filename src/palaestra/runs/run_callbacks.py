"""The ``callback`` setting: SB3 callbacks a settings file names (the RL Zoo's ``callback`` key),
built for a run's ``learn``.

The value has ``env_wrapper``'s form: ``"module:Class"``, a one-key mapping ``{name: kwargs}``
(the Zoo's form), or a list of them. Names resolve through the one table
(:data:`palaestra.runs.known_names.CALLBACKS`: SB3's ``stable_baselines3.common.callbacks.X``
is ``palaestra.algos.callbacks:X``); any other module (``rl_zoo3.callbacks``, the user's own)
needs ``--allow-import`` (:mod:`palaestra.runs.folder`). The class must be a palaestra
``BaseCallback``. SB3's callbacks that need objects a file cannot give (an eval env, another
callback) or that write where their arguments say are refused, each naming what does the job.
"""

from __future__ import annotations

from typing import Any

from palaestra.runs import known_names
from palaestra.runs.errors import RunError
from palaestra.runs.recipe import import_user_module, wrapper_items, wrapper_module

__all__ = ["REFUSED_CALLBACKS", "build_callbacks", "callback_items", "unmapped_callbacks"]

_INSIDE_EVAL = "it runs inside an EvalCallback (callback_on_new_best), which a file cannot give"
# SB3's callbacks (by class name) a settings file cannot use, and why.
REFUSED_CALLBACKS: dict[str, str] = {
    "CheckpointCallback": (
        "a run keeps its checkpoints in its folder: use `palaestra train --checkpoint-every N`"
    ),
    "EvalCallback": (
        "it needs an eval env, which a file cannot give: use `palaestra train --eval-freq N`"
    ),
    "EveryNTimesteps": "it wraps another callback object, which a file cannot give",
    "StopTrainingOnRewardThreshold": _INSIDE_EVAL,
    "StopTrainingOnNoModelImprovement": _INSIDE_EVAL,
}


def callback_items(value: Any) -> list[tuple[str, dict[str, Any]]]:
    """The ``callback`` setting as ``[(name, kwargs)]`` in order; imports nothing."""
    return wrapper_items(value, "callback") if value else []


def unmapped_callbacks(value: Any) -> list[tuple[str, str]]:
    """``(name, module)`` for each callback name the table does not map to palaestra's own
    code (what ``--allow-import`` must allow); imports nothing."""
    out = []
    for name, _ in callback_items(value):
        if known_names.palaestra_name("callback", name) is None:
            out.append((name, wrapper_module(name, "callback")[0]))
    return out


def build_callbacks(config: dict[str, Any]) -> list[Any]:
    """The run's ``callback`` setting as callback objects, in order (``RunError`` naming a
    refused, missing or unfitting one). The modules must have passed the import gate."""
    from palaestra.algos.common.callbacks import BaseCallback  # lazy: import-time — torch

    out = []
    for name, kwargs in callback_items(config.get("callback")):
        module_name, class_name = wrapper_module(
            known_names.palaestra_name("callback", name) or name, "callback"
        )
        if known_names.is_palaestra(module_name) and class_name in REFUSED_CALLBACKS:
            raise RunError(
                f"callback {name!r} is refused: {REFUSED_CALLBACKS[class_name]}", "remove it"
            )
        module = import_user_module(module_name, f"callback {name!r}")
        cls = getattr(module, class_name, None)
        if not (isinstance(cls, type) and issubclass(cls, BaseCallback)):
            kind = "missing" if cls is None else f"a {type(cls).__name__}"
            raise RunError(
                f"callback {name!r} is {kind}, not a palaestra callback class",
                "name a subclass of palaestra.algos.callbacks.BaseCallback",
            )
        try:
            out.append(cls(**kwargs))
        except (TypeError, ValueError) as exc:
            raise RunError(
                f"callback {name!r} does not take {kwargs}: {exc}", "fix its arguments"
            ) from None
    return out
