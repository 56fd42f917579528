"""What the algorithms need to know about spaces: storage shapes/dtypes, batch detection,
image detection, and a JSON codec so model files describe their spaces without pickle."""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.error import InvalidObservation, UnsupportedSpace

__all__ = [
    "allocate",
    "is_image_space",
    "is_image_space_channels_first",
    "is_vectorized_observation",
    "refuse_reset_tuple",
    "space_from_json",
    "space_to_json",
]


def is_image_space(space: spaces.Space[Any]) -> bool:
    """A uint8 ``Box`` of rank 3 with bounds 0..255, as SB3's ``is_image_space`` decides."""
    return (
        isinstance(space, spaces.Box)
        and len(space.shape) == 3
        and space.dtype == np.uint8
        and bool(np.all(space.low == 0))
        and bool(np.all(space.high == 255))
    )


def is_image_space_channels_first(space: spaces.Box) -> bool:
    """The smallest axis is the channel axis (SB3's rule): first means CHW, else HWC."""
    return int(np.argmin(space.shape)) == 0


def allocate(space: spaces.Space[Any], lead: tuple[int, ...]) -> Any:
    """Zeroed storage for ``lead``-shaped batches of samples of ``space`` (dicts per key)."""
    if isinstance(space, spaces.Dict):
        return {key: allocate(sub, lead) for key, sub in space.spaces.items()}
    if isinstance(space, (spaces.Box, spaces.Discrete, spaces.MultiDiscrete, spaces.MultiBinary)):
        shape: tuple[int, ...] = tuple(space.shape or ())
        return np.zeros(lead + shape, dtype=space.dtype)
    raise UnsupportedSpace(
        f"palaestra.algos does not support {type(space).__name__} spaces: {space}"
    )


def refuse_reset_tuple(observation: Any) -> None:
    """SB3's ``ValueError`` for ``predict((obs, info))``: a Gym-style reset return handed to a
    VecEnv-style call."""
    pair = isinstance(observation, tuple) and len(observation) == 2
    if pair and isinstance(observation[1], dict):
        raise ValueError(
            "You have passed a tuple to the predict() function instead of a Numpy array or a "
            "Dict. You are probably mixing Gym API with SB3 VecEnv API: `obs, info = "
            "env.reset()` (Gym) vs `obs = vec_env.reset()` (SB3 VecEnv)."
        )


def is_vectorized_observation(obs: Any, space: spaces.Space[Any]) -> bool:
    """True for a batch ``[n, *shape]``, False for one observation; ``ValueError`` otherwise.

    The shape rules and messages follow SB3's ``BasePolicy.predict``.
    """
    if isinstance(space, spaces.Dict):
        if not isinstance(obs, dict):
            raise InvalidObservation(
                f"Expected a dict observation for {space}, got {obs!r:.200} ({type(obs).__name__})"
            )
        flags = {key: is_vectorized_observation(obs[key], sub) for key, sub in space.spaces.items()}
        if len(set(flags.values())) > 1:
            raise ValueError(f"Observation keys disagree on batching: {flags}")
        return next(iter(flags.values()))
    if isinstance(obs, dict):
        # SB3 asserts this; without the check the dict becomes an object array and fails deep
        # in torch
        raise InvalidObservation(
            f"The observation {obs!r:.200} is a dict, but the observation space is {space}: "
            "pass an observation of that space (or a batch of them)"
        )
    shape = np.shape(obs)
    single: tuple[int, ...] = (
        tuple(space.shape or ()) if not isinstance(space, spaces.Discrete) else ()
    )
    if shape == single:
        return False
    if len(shape) == len(single) + 1 and shape[1:] == single:
        return True
    raise ValueError(
        f"Error: Unexpected observation shape {shape} for {type(space).__name__} environment, "
        f"please use {single} or (n_env, {', '.join(map(str, single))}) for the observation shape."
    )


def space_to_json(space: spaces.Space[Any]) -> dict[str, Any]:
    """Describe the spaces algorithms accept as plain JSON."""
    if isinstance(space, spaces.Box):
        return {
            "type": "Box",
            "low": space.low.tolist(),
            "high": space.high.tolist(),
            "shape": list(space.shape),
            "dtype": np.dtype(space.dtype).str,
        }
    if isinstance(space, spaces.Discrete):
        return {"type": "Discrete", "n": int(space.n), "start": int(space.start)}
    if isinstance(space, spaces.MultiDiscrete):
        return {
            "type": "MultiDiscrete",
            "nvec": space.nvec.tolist(),
            "start": space.start.tolist(),
            "dtype": np.dtype(space.dtype).str,
        }
    if isinstance(space, spaces.MultiBinary):
        return {"type": "MultiBinary", "n": np.asarray(space.n).tolist()}
    if isinstance(space, spaces.Dict):
        return {"type": "Dict", "spaces": {k: space_to_json(s) for k, s in space.spaces.items()}}
    raise TypeError(f"cannot store a {type(space).__name__} space in a model file")


_DTYPES = {"<f4", "<f8", "<f2", "|u1", "|i1", "<i2", "<u2", "<i4", "<u4", "<i8", "<u8", "|b1"}


def space_from_json(data: Any) -> spaces.Space[Any]:
    """Inverse of ``space_to_json``; ``ValueError`` on anything malformed."""
    try:
        kind = data["type"]
        if kind == "Box":
            dtype = _dtype(data["dtype"])
            low = np.asarray(data["low"], dtype=dtype)
            high = np.asarray(data["high"], dtype=dtype)
            return spaces.Box(low, high, tuple(int(d) for d in data["shape"]), dtype)
        if kind == "Discrete":
            return spaces.Discrete(int(data["n"]), start=int(data["start"]))
        if kind == "MultiDiscrete":
            dtype = _dtype(data["dtype"])
            return spaces.MultiDiscrete(
                np.asarray(data["nvec"]), dtype=dtype, start=np.asarray(data["start"])
            )
        if kind == "MultiBinary":
            return spaces.MultiBinary(data["n"])
        if kind == "Dict":
            return spaces.Dict({str(k): space_from_json(v) for k, v in data["spaces"].items()})
    except (KeyError, TypeError, ValueError, AssertionError) as exc:
        raise ValueError(f"malformed space description: {exc}") from exc
    raise ValueError(f"unknown space description {data!r:.200}")


def _dtype(code: Any) -> np.dtype[Any]:
    if code not in _DTYPES:
        raise ValueError(f"unsupported dtype {code!r}")
    return np.dtype(code)
