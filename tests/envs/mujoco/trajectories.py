"""One recorded run of a MuJoCo env, written so both libraries run the same code.

:func:`record` steps an env made by a given ``make`` (palaestra's or Gymnasium's) through a
:class:`Run` and encodes every reset and step as plain bytes and type names, so that two runs
compare with ``==`` and the first difference can be shown. ``python -m
tests.envs.mujoco.trajectories OUT`` runs the runs given as JSON on stdin on palaestra with
``gymnasium`` blocked from import, and pickles the records and every path MuJoCo compiled to
``OUT``.
"""

from __future__ import annotations

import dataclasses
import json
import pickle
import sys
from collections.abc import Callable
from typing import Any

import numpy as np


@dataclasses.dataclass(frozen=True)
class Run:
    """An env id and kwargs, the reset seeds in order (then unseeded resets), the number of
    steps, and how actions are drawn: ``"uniform"`` (numpy draws 20% past the bounds, so
    MuJoCo's clamping is exercised) or ``"sample"`` (the env's own seeded action space)."""

    env_id: str
    kwargs: dict[str, Any]
    seeds: tuple[int, ...]
    steps: int
    actions: str
    action_seed: int
    max_episode_steps: int | None = None


def encode(value: Any) -> Any:
    """A value as ``(type name, dtype, bytes)``: equal encodings are equal bits and types."""
    if isinstance(value, dict):
        return {key: encode(item) for key, item in value.items()}
    if isinstance(value, (np.ndarray, np.generic)):
        return (type(value).__name__, value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, float):
        return ("float", np.float64(value).tobytes())
    return (type(value).__name__, repr(value))


def record(make: Callable[..., Any], run: Run) -> list[Any]:
    """Every reset and step of ``run`` on an env made by ``make``, encoded."""
    kwargs = dict(run.kwargs)
    if run.max_episode_steps is not None:
        kwargs["max_episode_steps"] = run.max_episode_steps
    env = make(run.env_id, **kwargs)
    space = env.action_space
    low, high = space.low.astype(np.float64), space.high.astype(np.float64)
    rng = np.random.default_rng(run.action_seed)
    if run.actions == "sample":
        space.seed(run.action_seed)
    seeds = list(run.seeds)
    obs, info = env.reset(seed=seeds.pop(0))
    out: list[Any] = [("reset", encode(obs), encode(info))]
    for _ in range(run.steps):
        if run.actions == "sample":
            action = space.sample()
        else:
            width = high - low
            action = rng.uniform(low - 0.2 * width, high + 0.2 * width).astype(np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        out.append(
            (
                "step",
                encode(action),
                encode(obs),
                encode(reward),
                terminated,
                truncated,
                encode(info),
            )
        )
        if terminated or truncated:
            obs, info = env.reset(seed=seeds.pop(0)) if seeds else env.reset()
            out.append(("reset", encode(obs), encode(info)))
    env.close()
    return out


def _record_compiled_paths() -> list[str]:
    """Patch ``mujoco.MjModel``'s constructors to note every model file compiled."""
    import mujoco

    paths: list[str] = []
    original = mujoco.MjModel.from_xml_path

    def from_xml_path(path: str, *args: Any, **kwargs: Any) -> Any:
        paths.append(str(path))
        return original(path, *args, **kwargs)

    def refuse(*args: Any, **kwargs: Any) -> Any:
        paths.append("<not a file: from_xml_string/from_binary_path>")
        raise AssertionError("palaestra compiled a model that is not one of its files")

    mujoco.MjModel.from_xml_path = staticmethod(from_xml_path)
    mujoco.MjModel.from_xml_string = staticmethod(refuse)
    mujoco.MjModel.from_binary_path = staticmethod(refuse)
    return paths


def main(out_path: str) -> None:
    """The runs on stdin (JSON list), on palaestra with gymnasium blocked, pickled to out_path."""
    sys.modules["gymnasium"] = None  # type: ignore[assignment]  # any import of it fails
    runs = [Run(**{**r, "seeds": tuple(r["seeds"])}) for r in json.load(sys.stdin)]
    paths = _record_compiled_paths()
    import palaestra

    records = [record(palaestra.make, run) for run in runs]
    result = {
        "records": records,
        "compiled": paths,
        "package": palaestra.__file__,
        "gymnasium_loaded": [name for name in sys.modules if name.startswith("gymnasium.")],
    }
    with open(out_path, "wb") as file:
        pickle.dump(result, file)


if __name__ == "__main__":
    main(sys.argv[1])
