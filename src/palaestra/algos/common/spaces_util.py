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
    "is_vectorized_box_observation",
    "is_vectorized_dict_observation",
    "is_vectorized_discrete_observation",
    "is_vectorized_multibinary_observation",
    "is_vectorized_multidiscrete_observation",
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


def is_vectorized_box_observation(observation: Any, observation_space: spaces.Box) -> bool:
    """True for a batch ``[n, *shape]``, False for one observation, ``ValueError`` otherwise
    (SB3's words)."""
    shape, single = np.shape(observation), tuple(observation_space.shape)
    if shape == single:
        return False
    if shape[1:] == single:
        return True
    raise ValueError(
        f"Error: Unexpected observation shape {shape} for Box environment, please use "
        f"{single} or (n_env, {', '.join(map(str, single))}) for the observation shape."
    )


def is_vectorized_discrete_observation(
    observation: Any, observation_space: spaces.Discrete
) -> bool:
    """An int or a 0-d array: one observation; a 1-d array: a batch (SB3's rules)."""
    shape = np.shape(observation)
    if shape == ():
        return False
    if len(shape) == 1:
        return True
    raise ValueError(
        f"Error: Unexpected observation shape {shape} for Discrete environment, please use () "
        "or (n_env,) for the observation shape."
    )


def is_vectorized_multidiscrete_observation(
    observation: Any, observation_space: spaces.MultiDiscrete
) -> bool:
    """``(len(nvec),)``: one observation; ``(n, len(nvec))``: a batch (SB3's rules)."""
    shape, single = np.shape(observation), tuple(observation_space.shape)
    if shape == single:
        return False
    if len(shape) == len(single) + 1 and shape[1:] == single:
        return True
    width = ", ".join(map(str, single))
    raise ValueError(
        f"Error: Unexpected observation shape {shape} for MultiDiscrete environment, please use "
        f"({width},) or (n_env, {width}) for the observation shape."
    )


def is_vectorized_multibinary_observation(
    observation: Any, observation_space: spaces.MultiBinary
) -> bool:
    """The space's shape: one observation; one more leading axis: a batch (SB3's rules)."""
    shape, single = np.shape(observation), tuple(observation_space.shape)
    if shape == single:
        return False
    if len(shape) == len(single) + 1 and shape[1:] == single:
        return True
    raise ValueError(
        f"Error: Unexpected observation shape {shape} for MultiBinary environment, please use "
        f"{single} or (n_env, {observation_space.n}) for the observation shape."
    )


def is_vectorized_dict_observation(observation: Any, observation_space: spaces.Dict) -> bool:
    """Every key one observation (False) or every key a batch (True); a mix is a
    ``ValueError`` naming the first key that disagrees (SB3's words)."""
    if not isinstance(observation, dict):
        raise InvalidObservation(
            f"Expected a dict observation for {observation_space}, got {observation!r:.200} "
            f"({type(observation).__name__})"
        )
    items = observation_space.spaces.items()
    if all(np.shape(observation[key]) == tuple(sub.shape or ()) for key, sub in items):
        return False
    for key, sub in items:
        if np.shape(observation[key])[1:] != tuple(sub.shape or ()):
            try:
                is_vectorized_observation(observation[key], sub)
                reason = ""
            except ValueError as exc:
                reason = str(exc)
            raise ValueError(
                "There seems to be a mix of vectorized and non-vectorized observations. "
                f"Unexpected observation shape {np.shape(observation[key])} for key {key} of "
                f"type {sub}. {reason}"
            )
    return True


_IS_VECTORIZED: dict[type, Any] = {
    spaces.Box: is_vectorized_box_observation,
    spaces.Discrete: is_vectorized_discrete_observation,
    spaces.MultiDiscrete: is_vectorized_multidiscrete_observation,
    spaces.MultiBinary: is_vectorized_multibinary_observation,
    spaces.Dict: is_vectorized_dict_observation,
}


def is_vectorized_observation(obs: Any, space: spaces.Space[Any]) -> bool:
    """True for a batch ``[n, *shape]``, False for one observation; ``ValueError`` otherwise.

    SB3's ``is_vectorized_observation``: its shape rules and messages, per space type. A dict
    on a non-Dict space (or the reverse) is an ``InvalidObservation`` naming it.
    """
    if isinstance(obs, dict) and not isinstance(space, spaces.Dict):
        # SB3 asserts this; without the check the dict becomes an object array and fails deep
        # in torch
        raise InvalidObservation(
            f"The observation {obs!r:.200} is a dict, but the observation space is {space}: "
            "pass an observation of that space (or a batch of them)"
        )
    for space_type, check in _IS_VECTORIZED.items():
        if isinstance(space, space_type):
            return bool(check(obs, space))
    raise ValueError(
        f"Error: Cannot determine if the observation is vectorized with the space type {space}."
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
