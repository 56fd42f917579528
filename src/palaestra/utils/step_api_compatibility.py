"""Gymnasium's step-API converters: the old ``(obs, reward, done, info)`` and the new
``(obs, reward, terminated, truncated, info)`` into one another, for single and vector envs.

The old API marks a time-limit end with ``info["TimeLimit.truncated"]``: converting to the
new API reads (and removes) it, converting to the old API writes it where an episode ended.
Vector infos may be a list of dicts (SB3's ``VecEnv``) or Gymnasium's dict of arrays.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "convert_to_done_step_api",
    "convert_to_terminated_truncated_step_api",
    "step_api_compatibility",
]

_KEY = "TimeLimit.truncated"


def _check_length(step_returns: tuple[Any, ...], allowed: tuple[int, int]) -> None:
    if len(step_returns) not in allowed:
        raise ValueError(
            f"step returns must have 4 items (obs, reward, done, info) or 5 (obs, reward, "
            f"terminated, truncated, info), got {len(step_returns)}"
        )


def _bad_infos(infos: Any) -> TypeError:
    return TypeError(
        "Unexpected value of infos, as is_vector_env=True, expects `infos` to be a list or "
        f"dict, actual type: {type(infos)}"
    )


def convert_to_terminated_truncated_step_api(
    step_returns: tuple[Any, ...], is_vector_env: bool = False
) -> tuple[Any, ...]:
    """``(obs, reward, done, info)`` -> ``(obs, reward, terminated, truncated, info)``; new-API
    returns pass through unchanged."""
    _check_length(step_returns, (4, 5))
    if len(step_returns) == 5:
        return step_returns
    obs, rewards, dones, infos = step_returns
    if not is_vector_env:
        truncated = infos.pop(_KEY, False)
        return obs, rewards, dones and not truncated, dones and truncated, infos
    if isinstance(infos, list):
        truncated = np.array([info.pop(_KEY, False) for info in infos])
    elif isinstance(infos, dict):
        truncated = infos.pop(_KEY, np.zeros(len(dones), dtype=bool))
    else:
        raise _bad_infos(infos)
    terminated = np.logical_and(dones, np.logical_not(truncated))
    return obs, rewards, terminated, np.logical_and(dones, truncated), infos


def convert_to_done_step_api(
    step_returns: tuple[Any, ...], is_vector_env: bool = False
) -> tuple[Any, ...]:
    """``(obs, reward, terminated, truncated, info)`` -> ``(obs, reward, done, info)`` with
    ``info["TimeLimit.truncated"]`` where an episode ended; old-API returns pass through."""
    _check_length(step_returns, (4, 5))
    if len(step_returns) == 4:
        return step_returns
    obs, rewards, terminated, truncated, infos = step_returns
    if not is_vector_env:
        if terminated or truncated:
            infos[_KEY] = truncated and not terminated
        return obs, rewards, terminated or truncated, infos
    if isinstance(infos, list):
        for info, env_terminated, env_truncated in zip(infos, terminated, truncated, strict=True):
            if env_terminated or env_truncated:
                info[_KEY] = env_truncated and not env_terminated
    elif isinstance(infos, dict):
        if np.any(terminated) or np.any(truncated):
            infos[_KEY] = np.logical_and(truncated, np.logical_not(terminated))
    else:
        raise _bad_infos(infos)
    return obs, rewards, np.logical_or(terminated, truncated), infos


def step_api_compatibility(
    step_returns: tuple[Any, ...],
    output_truncation_bool: bool = True,
    is_vector_env: bool = False,
) -> tuple[Any, ...]:
    """Step returns in the new API (``output_truncation_bool=True``) or the old one, whatever
    API they came in.

    >>> obs, reward, done, info = step_api_compatibility(
    ...     (0, 1.0, False, True, {}), output_truncation_bool=False)
    >>> done, info
    (True, {'TimeLimit.truncated': True})
    """
    if output_truncation_bool:
        return convert_to_terminated_truncated_step_api(step_returns, is_vector_env)
    return convert_to_done_step_api(step_returns, is_vector_env)
