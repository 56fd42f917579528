"""Checks that observe an environment's API use without changing what it returns.

``PassiveEnvChecker`` runs them on the first ``reset``/``step``/``render`` of every ``make()``'d
env, and ``check_env`` runs them too. Problems are warnings (``logger.warn``) when an env could
still work and ``AssertionError`` when it cannot; the messages are Gymnasium 1.x's, so that a
search for one finds the same explanation.
"""

from __future__ import annotations

import inspect
from typing import Any, SupportsFloat

import numpy as np

from palaestra import error, logger, spaces
from palaestra.core import Env, RenderFrame

__all__ = [
    "check_action_space",
    "check_obs",
    "check_observation_space",
    "check_space",
    "data_shares_objects",
    "env_data_reuse_passive_checker",
    "env_render_passive_checker",
    "env_reset_passive_checker",
    "env_step_passive_checker",
]


def _check_box_bounds(space: Any, space_type: str) -> None:
    for bound in ("low", "high"):
        shape = getattr(space, bound).shape
        assert shape == space.shape, (
            f"The Box {space_type} space shape and {bound} shape have different shapes, "
            f"{bound} shape: {shape}, box shape: {space.shape}"
        )
    if np.any(space.low == space.high):
        logger.warn(f"A Box {space_type} space maximum and minimum values are equal.")
    elif space_type == "observation" and np.any(space.high < space.low):
        logger.warn("A Box observation space low value is greater than a high value.")


def check_space(space: Any, space_type: str) -> None:
    """Assert that ``space`` is a well-formed palaestra space (recursing into composites)."""
    if not isinstance(space, spaces.Space):
        raise TypeError(
            f"{space_type} space does not inherit from `palaestra.spaces.Space`, "
            f"actual type: {type(space)}"
        )
    if isinstance(space, spaces.Box):
        _check_box_bounds(space, space_type)
    elif isinstance(space, spaces.Discrete):
        assert 0 < space.n, (
            f"Discrete {space_type} space's number of elements must be positive, "
            f"actual number of elements: {space.n}"
        )
        assert space.shape == (), (
            f"Discrete {space_type} space's shape should be empty, actual shape: {space.shape}"
        )
    elif isinstance(space, spaces.MultiDiscrete):
        assert space.shape == space.nvec.shape, (
            f"Multi-discrete {space_type} space's shape must be equal to the nvec shape, "
            f"space shape: {space.shape}, nvec shape: {space.nvec.shape}"
        )
        assert np.all(0 < space.nvec), (
            f"Multi-discrete {space_type} space's all nvec elements must be greater than 0, "
            f"actual nvec: {space.nvec}"
        )
    elif isinstance(space, spaces.MultiBinary):
        assert np.all(0 < np.asarray(space.shape)), (
            f"Multi-binary {space_type} space's all shape elements must be greater than 0, "
            f"actual shape: {space.shape}"
        )
    elif isinstance(space, spaces.Tuple):
        assert 0 < len(space.spaces), f"An empty Tuple {space_type} space is not allowed."
        for subspace in space.spaces:
            check_space(subspace, space_type)
    elif isinstance(space, spaces.Dict):
        assert 0 < len(space.spaces), f"An empty Dict {space_type} space is not allowed."
        for subspace in space.spaces.values():
            check_space(subspace, space_type)


def check_observation_space(observation_space: Any) -> None:
    """:func:`check_space` for an observation space."""
    check_space(observation_space, "observation")


def check_action_space(action_space: Any) -> None:
    """:func:`check_space` for an action space."""
    check_space(action_space, "action")


def check_obs(obs: Any, observation_space: Any, method_name: str) -> None:
    """Warn if ``obs`` (returned by ``method_name``) does not fit ``observation_space``."""
    pre = f"The obs returned by the `{method_name}()` method"
    if isinstance(observation_space, spaces.Discrete):
        if not isinstance(obs, (np.int64, int)):
            logger.warn(f"{pre} should be an int or np.int64, actual type: {type(obs)}")
    elif isinstance(observation_space, spaces.Box):
        if observation_space.shape != ():
            if not isinstance(obs, np.ndarray):
                logger.warn(f"{pre} was expecting a numpy array, actual type: {type(obs)}")
            elif obs.dtype != observation_space.dtype:
                logger.warn(
                    f"{pre} was expecting numpy array dtype to be {observation_space.dtype}, "
                    f"actual type: {obs.dtype}"
                )
    elif isinstance(observation_space, (spaces.MultiBinary, spaces.MultiDiscrete)):
        if not isinstance(obs, np.ndarray):
            logger.warn(f"{pre} was expecting a numpy array, actual type: {type(obs)}")
    elif isinstance(observation_space, spaces.Tuple):
        if not isinstance(obs, tuple):
            logger.warn(f"{pre} was expecting a tuple, actual type: {type(obs)}")
        assert len(obs) == len(observation_space.spaces), (
            f"{pre} length is not same as the observation space length, obs length: {len(obs)}, "
            f"space length: {len(observation_space.spaces)}"
        )
        for sub_obs, sub_space in zip(obs, observation_space.spaces):
            check_obs(sub_obs, sub_space, method_name)
    elif isinstance(observation_space, spaces.Dict):
        assert isinstance(obs, dict), f"{pre} must be a dict, actual type: {type(obs)}"
        assert obs.keys() == observation_space.spaces.keys(), (
            f"{pre} observation keys is not same as the observation space keys, obs keys: "
            f"{list(obs.keys())}, space keys: {list(observation_space.spaces.keys())}"
        )
        for key in observation_space.spaces:
            check_obs(obs[key], observation_space[key], method_name)
    try:
        if obs not in observation_space:
            logger.warn(f"{pre} is not within the observation space.")
    except Exception as e:
        logger.warn(f"{pre} is not within the observation space with exception: {e}")


def data_shares_objects(data_1: Any, data_2: Any) -> bool:
    """Whether two returned values share a mutable object (array memory, dict), by identity.

    >>> buffer = np.zeros(3)
    >>> data_shares_objects(buffer, buffer[:]), data_shares_objects(buffer, buffer.copy())
    (True, False)
    """
    if type(data_1) is not type(data_2):
        return False
    if isinstance(data_1, dict):
        return data_1 is data_2 or any(
            data_shares_objects(data_1[k], data_2[k]) for k in data_1.keys() & data_2.keys()
        )
    if isinstance(data_1, tuple):  # immutable itself, but may hold mutable data
        return any(data_shares_objects(a, b) for a, b in zip(data_1, data_2))
    if isinstance(data_1, np.ndarray):
        if data_1.dtype == object:
            return data_1 is data_2 or any(
                data_shares_objects(a, b) for a, b in zip(data_1.flat, data_2.flat)
            )
        # shares_memory also catches a fresh view of a reused buffer, e.g. `buffer[:]`.
        return bool(np.shares_memory(data_1, data_2))
    # Immutable scalars are interned (`is` would match equal ints); unknown objects are skipped.
    return False


def env_data_reuse_passive_checker(
    previous_data: tuple[Any, dict[str, Any]] | None,
    data: tuple[Any, dict[str, Any]],
    previous_source: str,
    source: str,
) -> None:
    """Warn if two calls returned observations or infos that share an object.

    Users keep what an env returns (replay buffers), so an env that refills one buffer in place
    silently corrupts their data.
    """
    if previous_data is None:
        return
    for what, previous, current in zip(("observations", "infos"), previous_data, data):
        if data_shares_objects(previous, current):
            singular = "observation" if what == "observations" else "info"
            logger.warn(
                f"The {what} returned by `{previous_source}` and the following `{source}` share "
                "an object, therefore, modifying one will modify the other. Environments should "
                f"return new {singular} data on every call as users commonly keep the data "
                "returned to them."
            )


def env_reset_passive_checker(env: Env[Any, Any], **kwargs: Any) -> Any:
    """Check ``reset``'s signature and its ``(obs, info)``; return what it returned."""
    signature = inspect.signature(env.reset)
    params = signature.parameters
    if "seed" not in params and "kwargs" not in params:
        logger.deprecation(
            "Current palaestra version requires that `Env.reset` can be passed a `seed` instead "
            "of using `Env.seed` for resetting the environment random number generator."
        )
    elif "seed" in params and params["seed"].default is not None:
        logger.warn(
            "The default seed argument in `Env.reset` should be `None`, otherwise the environment "
            f"will by default always be deterministic. Actual default: {params['seed']}"
        )
    if "options" not in params and "kwargs" not in params:
        logger.deprecation(
            "Current palaestra version requires that `Env.reset` can be passed `options` to allow "
            "the environment initialisation to be passed additional information."
        )
    result = env.reset(**kwargs)
    if not isinstance(result, tuple):
        logger.warn(
            "The result returned by `env.reset()` was not a tuple of the form `(obs, info)`, where "
            "`obs` is a observation and `info` is a dictionary containing additional information. "
            f"Actual type: `{type(result)}`"
        )
    elif len(result) != 2:
        logger.warn(
            "The result returned by `env.reset()` should be `(obs, info)` by default, , where "
            "`obs` is a observation and `info` is a dictionary containing additional information."
        )
    else:
        obs, info = result
        check_obs(obs, env.observation_space, "reset")
        assert isinstance(info, dict), (
            "The second element returned by `env.reset()` was not a dictionary, "
            f"actual type: {type(info)}"
        )
    return result


def _check_step_flag(name: str, value: Any) -> None:
    # np.bool_ is numpy's boolean; Python's bool is what most envs return.
    if not isinstance(value, (bool, np.bool_)):
        logger.warn(f"Expects `{name}` signal to be a boolean, actual type: {type(value)}")


def env_step_passive_checker(
    env: Env[Any, Any], action: Any
) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
    """Step ``env`` with ``action`` and check the 5-tuple; return it unchanged.

    The action itself is not checked: some environments accept out-of-space actions on purpose.
    """
    result: Any = env.step(action)
    assert isinstance(result, tuple), (
        f"Expects step result to be a tuple, actual type: {type(result)}"
    )
    if len(result) == 4:
        logger.deprecation(
            "Core environment is written in old step API which returns one bool instead of two. "
            "It is recommended to rewrite the environment with new step API. "
        )
        obs, reward, done, info = result
        _check_step_flag("done", done)
    elif len(result) == 5:
        obs, reward, terminated, truncated, info = result
        _check_step_flag("terminated", terminated)
        _check_step_flag("truncated", truncated)
    else:
        raise error.Error(
            "Expected `Env.step` to return a four or five element tuple, actual number of "
            f"elements returned: {len(result)}."
        )
    check_obs(obs, env.observation_space, "step")
    if not (np.issubdtype(type(reward), np.integer) or np.issubdtype(type(reward), np.floating)):
        logger.warn(
            "The reward returned by `step()` must be a float, int, np.integer or np.floating, "
            f"actual type: {type(reward)}"
        )
    elif np.isnan(reward):
        logger.warn("The reward is a NaN value.")
    elif np.isinf(reward):
        logger.warn("The reward is an inf value.")
    assert isinstance(info, dict), (
        f"The `info` returned by `step()` must be a python dictionary, actual type: {type(info)}"
    )
    return result


def _check_render_metadata(env: Env[Any, Any]) -> None:
    render_modes = env.metadata.get("render_modes")
    if render_modes is None:
        logger.warn(
            "No render modes was declared in the environment (env.metadata['render_modes'] is "
            "None or not defined), you may have trouble when calling `.render()`."
        )
        return
    if not isinstance(render_modes, (list, tuple)):
        logger.warn(
            "Expects the render_modes to be a sequence (i.e. list, tuple), "
            f"actual type: {type(render_modes)}"
        )
    elif not all(isinstance(mode, str) for mode in render_modes):
        logger.warn(
            "Expects all render modes to be strings, "
            f"actual types: {[type(mode) for mode in render_modes]}"
        )
    # `render_fps` only matters when the env can render at all.
    render_fps = env.metadata.get("render_fps")
    if len(render_modes) > 0:
        if render_fps is None:
            logger.warn(
                "No render fps was declared in the environment (env.metadata['render_fps'] is "
                "None or not defined), rendering may occur at inconsistent fps."
            )
        elif not (
            np.issubdtype(type(render_fps), np.integer)
            or np.issubdtype(type(render_fps), np.floating)
        ):
            logger.warn(
                "Expects the `env.metadata['render_fps']` to be an integer or a float, "
                f"actual type: {type(render_fps)}"
            )
        else:
            assert render_fps > 0, (
                "Expects the `env.metadata['render_fps']` to be greater than zero, "
                f"actual value: {render_fps}"
            )
        assert env.render_mode is None or env.render_mode in render_modes, (
            "The environment was initialized successfully however with an unsupported render "
            f"mode. Render mode: {env.render_mode}, modes: {render_modes}"
        )
    else:
        assert env.render_mode is None, (
            "With no render_modes, expects the Env.render_mode to be None, "
            f"actual value: {env.render_mode}"
        )


def _check_render_return(render_mode: str, frame: Any) -> None:
    """Warn if ``frame`` is not what ``render_mode`` promises (a list of them for ``*_list``)."""
    if render_mode == "human":
        if frame is not None:
            logger.warn(f"Human rendering should return `None`, got {type(frame)}")
    elif render_mode == "rgb_array":
        if not isinstance(frame, np.ndarray):
            logger.warn(f"RGB-array rendering should return a numpy array, got {type(frame)}")
            return
        pre = "RGB-array rendering should return a numpy array"
        if frame.dtype != np.uint8:
            logger.warn(f"{pre} with dtype uint8, got {frame.dtype}")
        if frame.ndim != 3:
            logger.warn(f"{pre} with three axes, got {frame.ndim}")
        elif frame.shape[2] != 3:
            logger.warn(f"{pre} in which the last axis has three dimensions, got {frame.shape[2]}")
    elif render_mode == "depth_array":
        if not isinstance(frame, np.ndarray):
            logger.warn(f"Depth-array rendering should return a numpy array, got {type(frame)}")
        elif frame.ndim != 2:
            logger.warn(
                f"Depth-array rendering should return a numpy array with two axes, got {frame.ndim}"
            )
    elif render_mode in ("ansi", "ascii"):
        if not isinstance(frame, str):
            logger.warn(f"ANSI/ASCII rendering should produce a string, got {type(frame)}")
    elif render_mode.endswith("_list"):
        if not isinstance(frame, list):
            logger.warn(f"Render mode `{render_mode}` should produce a list, got {type(frame)}")
        else:
            for item in frame:
                _check_render_return(render_mode[: -len("_list")], item)


def env_render_passive_checker(env: Env[Any, Any]) -> RenderFrame | list[RenderFrame] | None:
    """Check the render metadata, call ``render()``, and check the frame for the render mode."""
    _check_render_metadata(env)
    result = env.render()
    if env.render_mode is not None:
        _check_render_return(env.render_mode, result)
    return result
