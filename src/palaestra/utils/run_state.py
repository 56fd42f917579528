"""Run state: what a stateful object needs to continue exactly where it stopped, as JSON
metadata plus named arrays.

Exact resume (a run stopped and continued ends with the same bits as one never stopped)
needs everything that evolves while training: env rows and their generators, step counters,
episode accumulators, normalisation statistics. Each such class lists those attributes in a
``RUN_STATE`` tuple; :func:`capture` turns them into ``(meta, arrays)`` (the layout
``model_io`` archives hold, so reading one back never unpickles anything) and :func:`restore`
writes them back *in place*, so views and shared lists stay shared.

Restoring checks the whole state against the object first (every array's dtype and shape,
every generator's kind, every scalar's type) and changes nothing unless all of it fits: a
state from another env, another ``n_envs`` or a crafted file is refused with a
:class:`~palaestra.error.RunStateError` that names the field.

Attribute kinds: numpy arrays (copied), ``np.random.Generator`` (its bit generator's state),
lists of generators or ``None`` (per-row generators), JSON scalars and flat lists of them,
nested objects that have a ``RUN_STATE`` of their own, and dicts of such objects keyed by
strings (one per ``Dict`` observation key: ``VecNormalize.obs_rms``); a dict's objects are
numbered in its arrays' names, so any key string is safe.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra.error import RunStateError

__all__ = ["State", "capture", "restore", "supports_run_state"]

State = tuple[dict[str, Any], dict[str, np.ndarray]]
_SCALARS = (bool, int, float, str, type(None))


def supports_run_state(obj: Any) -> bool:
    """Whether ``obj`` lists its run state (``RUN_STATE``) and can be captured."""
    return isinstance(getattr(obj, "RUN_STATE", None), tuple)


def capture(obj: Any, prefix: str = "") -> State:
    """``obj``'s ``RUN_STATE`` attributes as ``(meta, arrays)``; arrays are copies, named
    ``prefix + attribute`` (nested objects add ``attribute/``)."""
    if not supports_run_state(obj):
        raise RunStateError(f"{type(obj).__name__} cannot save its run state")
    meta: dict[str, Any] = {}
    arrays: dict[str, np.ndarray] = {}
    for name in obj.RUN_STATE:
        value = getattr(obj, name)
        key = prefix + name
        if isinstance(value, (np.ndarray, np.generic)):  # 0-d results come back as scalars
            arrays[key] = np.array(value)
        elif isinstance(value, np.random.Generator):
            meta[name] = {"generator": value.bit_generator.state}
        elif isinstance(value, list) and any(isinstance(v, np.random.Generator) for v in value):
            meta[name] = {"generators": [_generator_state(v, key) for v in value]}
        elif supports_run_state(value):
            sub_meta, sub_arrays = capture(value, key + "/")
            meta[name] = {"object": sub_meta}
            arrays.update(sub_arrays)
        elif _is_object_dict(value):
            pairs = []
            for i, (item_key, item) in enumerate(value.items()):
                sub_meta, sub_arrays = capture(item, f"{key}/{i}/")
                pairs.append([item_key, sub_meta])
                arrays.update(sub_arrays)
            meta[name] = {"objects": pairs}
        else:
            meta[name] = {"value": _plain(value, key)}
    return meta, arrays


def restore(obj: Any, state: State, prefix: str = "") -> None:
    """Write a :func:`capture` state back into ``obj``; all or nothing."""
    ops: list[Callable[[], None]] = []
    _plan(obj, state[0], state[1], prefix, ops)
    for op in ops:
        op()


def _is_object_dict(value: Any) -> bool:
    """A non-empty dict of string keys to objects that have a run state."""
    return (
        isinstance(value, dict)
        and bool(value)
        and all(isinstance(k, str) and supports_run_state(v) for k, v in value.items())
    )


def _generator_state(value: Any, key: str) -> dict[str, Any] | None:
    if value is None:
        return None
    if not isinstance(value, np.random.Generator):
        raise RunStateError(f"{key}: expected generators or None, got {type(value).__name__}")
    return dict(value.bit_generator.state)


def _plain(value: Any, key: str) -> Any:
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, _SCALARS):
        return value
    if isinstance(value, (list, tuple)):
        return [_plain(v, key) for v in value]
    raise RunStateError(f"{key}: cannot save a {type(value).__name__} in a run state")


def _plan(
    obj: Any,
    meta: dict[str, Any],
    arrays: dict[str, np.ndarray],
    prefix: str,
    ops: list[Callable[[], None]],
) -> None:
    """Check ``meta``/``arrays`` against ``obj`` and queue the writes into ``ops``."""
    if not supports_run_state(obj):
        raise RunStateError(f"{type(obj).__name__} cannot restore a run state")
    if not isinstance(meta, dict):
        raise RunStateError(f"{prefix or 'run state'}: expected a mapping")
    for name in obj.RUN_STATE:
        key = prefix + name
        current = getattr(obj, name)
        if isinstance(current, (np.ndarray, np.generic)):
            ops.append(_plan_array(obj, name, current, arrays.get(key), key))
            continue
        entry = meta.get(name)
        if not isinstance(entry, dict) or len(entry) != 1:
            raise RunStateError(f"run state lacks {key!r} (or it is malformed)")
        ((kind, saved),) = entry.items()
        if kind == "object" and supports_run_state(current):
            _plan(current, saved, arrays, key + "/", ops)
        elif kind == "objects" and _is_object_dict(current):
            _plan_objects(current, saved, arrays, key, ops)
        elif kind == "generator" and isinstance(current, np.random.Generator):
            ops.append(_plan_generator(current, saved, key))
        elif kind == "generators" and isinstance(current, list):
            ops.append(_plan_generators(current, saved, key))
        elif kind == "value" and not isinstance(current, (np.random.Generator, list)):
            ops.append(_plan_value(obj, name, current, saved, key))
        elif kind == "value" and isinstance(current, list):
            ops.append(_plan_list(current, saved, key))
        else:
            raise RunStateError(f"run state field {key!r} holds a {kind}, which does not fit")


def _plan_objects(
    current: dict[str, Any],
    saved: Any,
    arrays: dict[str, np.ndarray],
    key: str,
    ops: list[Callable[[], None]],
) -> None:
    """A dict of objects: the same keys in the same order, then each object in place."""
    pairs = saved if isinstance(saved, list) else []
    keys = [p[0] if isinstance(p, list) and len(p) == 2 else None for p in pairs]
    if not isinstance(saved, list) or keys != list(current):
        shown = keys if isinstance(saved, list) else type(saved).__name__
        raise RunStateError(
            f"run state {key!r} holds the keys {shown!r:.200}, this object has {list(current)!r}"
        )
    for i, (item_key, sub_meta) in enumerate(pairs):
        _plan(current[item_key], sub_meta, arrays, f"{key}/{i}/", ops)


def _plan_array(
    obj: Any, name: str, current: np.ndarray | np.generic, saved: Any, key: str
) -> Callable[[], None]:
    if not isinstance(saved, np.ndarray):
        raise RunStateError(f"run state lacks the array {key!r}")
    if saved.dtype != current.dtype or saved.shape != current.shape:
        raise RunStateError(
            f"run state array {key!r} is {saved.dtype}{list(saved.shape)}, "
            f"this object holds {current.dtype}{list(current.shape)}"
        )
    if isinstance(current, np.generic):  # a numpy scalar is immutable: rebind it
        return lambda: setattr(obj, name, saved[()])
    return lambda: np.copyto(getattr(obj, name), saved)


def _checked_generator_state(saved: Any, kind: str, key: str) -> dict[str, Any]:
    if not isinstance(saved, dict) or saved.get("bit_generator") != kind:
        got = saved.get("bit_generator") if isinstance(saved, dict) else type(saved).__name__
        raise RunStateError(f"run state {key!r} holds a {got!r} generator, expected {kind!r}")
    probe = getattr(np.random, kind)()
    try:  # numpy validates the fields; a bad state fails here, before anything changes
        probe.state = saved
    except (TypeError, ValueError, KeyError) as exc:
        raise RunStateError(f"run state {key!r}: malformed generator state ({exc})") from None
    return saved


def _plan_generator(current: np.random.Generator, saved: Any, key: str) -> Callable[[], None]:
    kind = type(current.bit_generator).__name__
    checked = _checked_generator_state(saved, kind, key)

    def apply() -> None:
        current.bit_generator.state = checked

    return apply


def _plan_generators(current: list[Any], saved: Any, key: str) -> Callable[[], None]:
    if not isinstance(saved, list) or len(saved) != len(current):
        raise RunStateError(
            f"run state {key!r} holds {len(saved) if isinstance(saved, list) else '?'} "
            f"generators, this object has {len(current)}"
        )
    checked = [
        None if s is None else _checked_generator_state(s, "PCG64", f"{key}[{i}]")
        for i, s in enumerate(saved)
    ]

    def apply() -> None:
        for i, state in enumerate(checked):
            if state is None:
                current[i] = None
                continue
            gen = current[i]
            if not isinstance(gen, np.random.Generator) or not isinstance(
                gen.bit_generator, np.random.PCG64
            ):
                gen = current[i] = np.random.Generator(np.random.PCG64())
            gen.bit_generator.state = state

    return apply


def _same_kind(current: Any, saved: Any) -> bool:
    if current is None or saved is None:
        return True
    if isinstance(current, bool) or isinstance(saved, bool):
        return isinstance(current, bool) and isinstance(saved, bool)
    if isinstance(current, float):
        return isinstance(saved, (int, float))
    return type(saved) is type(current)


def _plan_value(obj: Any, name: str, current: Any, saved: Any, key: str) -> Callable[[], None]:
    if isinstance(current, np.generic):
        current = current.item()
    if not isinstance(saved, _SCALARS) or not _same_kind(current, saved):
        raise RunStateError(
            f"run state {key!r} is {saved!r:.60}, expected a {type(current).__name__}"
        )
    value = float(saved) if isinstance(current, float) and saved is not None else saved
    return lambda: setattr(obj, name, value)


def _plan_list(current: list[Any], saved: Any, key: str) -> Callable[[], None]:
    if (
        not isinstance(saved, list)
        or len(saved) != len(current)
        or not all(isinstance(v, _SCALARS) and _same_kind(c, v) for c, v in zip(current, saved))
    ):
        raise RunStateError(f"run state {key!r} does not fit a list of {len(current)} values")

    def apply() -> None:
        current[:] = saved

    return apply
