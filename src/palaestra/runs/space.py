"""A hyperparameter search space: each name mapped to a list of choices or to a numeric range.

Names are the algorithm's constructor keywords, or ``n_envs``; dotted names reach inside dicts
(``policy_kwargs.net_arch``). Ranges are ``{low, high, log, step}``; integer bounds give an
integer range. :func:`space_from_mapping` checks a space (unknown names, impossible ranges);
the sampling side turns it into Optuna distributions and sampled values back into settings.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from palaestra.runs.errors import RunError
from palaestra.runs.settings import hyperparameter_names, load_config_file

__all__ = [
    "Choice",
    "Param",
    "Range",
    "distributions",
    "load_space",
    "settings_of",
    "space_from_mapping",
]


@dataclasses.dataclass(frozen=True)
class Choice:
    """One of ``values`` (JSON values: numbers, strings, lists, mappings, null)."""

    values: tuple[Any, ...]


@dataclasses.dataclass(frozen=True)
class Range:
    """A number in ``[low, high]``: an integer when both bounds are, log-uniform with
    ``log``, on a grid of ``step`` when given."""

    low: float
    high: float
    log: bool = False
    step: float | None = None
    integer: bool = False


Param = Choice | Range


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _parse(name: str, value: Any, source: str) -> Param:
    if isinstance(value, list):
        if not value:
            raise RunError(f"{source}: {name} has no choices", "list at least one value")
        return Choice(tuple(value))
    if not isinstance(value, Mapping):
        raise RunError(
            f"{source}: {name} must be a list of choices or a range, got {value!r}",
            "e.g. [64, 128] or {low: 0.0001, high: 0.01, log: true}",
        )
    unknown = sorted(set(value) - {"low", "high", "log", "step"})
    if unknown or "low" not in value or "high" not in value:
        raise RunError(
            f"{source}: range {name} must have low and high (and optionally log, step), "
            f"got keys {sorted(value)}",
            "e.g. {low: 0.9, high: 0.999}",
        )
    low, high, log, step = value["low"], value["high"], value.get("log", False), value.get("step")
    if not (_number(low) and _number(high)):
        raise RunError(f"{source}: {name} bounds must be numbers, got {low!r} and {high!r}")
    if not low < high:
        raise RunError(
            f"{source}: impossible range for {name}: low {low} is not below high {high}",
            "swap or fix the bounds",
        )
    if not isinstance(log, bool):
        raise RunError(f"{source}: {name}.log must be true or false, got {log!r}")
    if log and low <= 0:
        raise RunError(
            f"{source}: impossible range for {name}: a log range needs low > 0, got {low}",
            "raise low, or drop log",
        )
    if step is not None and not (_number(step) and 0 < step <= high - low):
        raise RunError(f"{source}: {name}.step must be a number in (0, high - low], got {step!r}")
    if step is not None and log:
        raise RunError(f"{source}: {name} cannot have both step and log", "drop one")
    integer = all(isinstance(v, int) for v in (low, high)) and (
        step is None or isinstance(step, int)
    )
    return Range(float(low), float(high), log, None if step is None else float(step), integer)


def space_from_mapping(
    data: Mapping[str, Any], algo: str, source: str = "search space"
) -> dict[str, Param]:
    """A checked search space for ``algo``: ``RunError`` naming an unknown hyperparameter or
    an impossible range."""
    if not isinstance(data, Mapping) or not data:
        raise RunError(f"{source} must map hyperparameter names to choices or ranges")
    valid = {*hyperparameter_names(algo), "n_envs"}
    space: dict[str, Param] = {}
    for name, value in data.items():
        head = str(name).split(".")[0]
        if head not in valid or not all(str(name).split(".")):
            raise RunError(
                f"{source}: unknown {algo} hyperparameter {name!r}",
                f"valid names: {', '.join(sorted(valid))}",
            )
        space[str(name)] = _parse(str(name), value, source)
    return space


def load_space(path: str | Path, algo: str) -> dict[str, Param]:
    """The search space in a ``.yaml``/``.json`` file (see the module's docstring)."""
    return space_from_mapping(load_config_file(str(path)), algo, f"search space {str(path)!r}")


# -- sampling ----------------------------------------------------------------------------------
def distributions(space: Mapping[str, Param]) -> dict[str, Any]:
    """Optuna distributions; choices are stored as JSON text (Optuna's categorical values are
    scalars, and a net_arch is a list)."""
    import optuna

    out: dict[str, Any] = {}
    for name, param in space.items():
        if isinstance(param, Choice):
            out[name] = optuna.distributions.CategoricalDistribution(
                [json.dumps(v, sort_keys=True) for v in param.values]
            )
        elif param.integer:
            out[name] = optuna.distributions.IntDistribution(
                int(param.low), int(param.high), log=param.log, step=int(param.step or 1)
            )
        else:
            out[name] = optuna.distributions.FloatDistribution(
                param.low, param.high, log=param.log, step=param.step
            )
    return out


def settings_of(params: Mapping[str, Any], space: Mapping[str, Param]) -> dict[str, Any]:
    """Sampled values -> nested settings overrides (``policy_kwargs.net_arch`` -> a dict)."""
    out: dict[str, Any] = {}
    for name, value in params.items():
        if isinstance(space[name], Choice):
            value = json.loads(value)
        node = out
        *parents, leaf = name.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return out
