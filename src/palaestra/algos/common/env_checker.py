"""``check_env`` as Stable-Baselines3 has it (``stable_baselines3.common.env_checker``).

Gymnasium's API checks (:func:`palaestra.utils.env_checker.check_env`) say whether an env is a
correct env; these say whether the algorithms can train on it: spaces they do not support
(nested Dict, Tuple, Sequence, Graph, OneOf, non-zero ``start``, 2-D MultiDiscrete),
image observations that the ``CnnPolicy`` would misread, action bounds that hurt learning,
observations that miss their space, and NaN/inf in the first steps. Problems that stop training
raise ``AssertionError``/``TypeError``; the rest warn (``warn=True``), with SB3's messages.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.core import Env

__all__ = ["check_env"]

_SPACES_DOC = "cf. https://gymnasium.farama.org/api/spaces/"


def _warn(message: str) -> None:
    warnings.warn(message, UserWarning, stacklevel=3)


def _check_non_zero_start(space: Any, space_type: str = "observation", key: str = "") -> None:
    if isinstance(space, (spaces.Discrete, spaces.MultiDiscrete)) and not np.allclose(
        space.start, 0
    ):
        maybe_key = f"(key='{key}')" if key else ""
        _warn(
            f"{type(space).__name__} {space_type} space {maybe_key} with a non-zero start "
            f"(start={space.start}) is not supported by Stable-Baselines3. You can use a wrapper "
            "(see https://stable-baselines3.readthedocs.io/en/master/guide/custom_env.html) "
            f"or update your {space_type} space."
        )


def _channels_first(space: spaces.Box) -> bool:
    smallest = int(np.argmin(space.shape))
    if smallest == 1:
        _warn(
            "Treating image space as channels-last, while second dimension was smallest of the "
            "three."
        )
    return smallest == 0


def _check_image_input(space: spaces.Box, key: str = "") -> None:
    if space.dtype != np.uint8:
        _warn(
            f"It seems that your observation {key} is an image but its `dtype` is "
            f"({space.dtype}) whereas it has to be `np.uint8`. If your observation is not an "
            "image, we recommend you to flatten the observation to have only a 1D vector"
        )
    if np.any(space.low != 0) or np.any(space.high != 255):
        _warn(
            f"It seems that your observation space {key} is an image but the upper and lower "
            "bounds are not in [0, 255]. Because the CNN policy normalize automatically the "
            "observation you may encounter issue if the values are not in that range."
        )
    width_axis = -1 if _channels_first(space) else 0
    if space.shape[width_axis] < 36 or space.shape[1] < 36:
        _warn(
            "The minimal resolution for an image is 36x36 for the default `CnnPolicy`. You "
            "might need to use a custom features extractor cf. "
            "https://stable-baselines3.readthedocs.io/en/master/guide/custom_policy.html"
        )


def _check_unsupported_spaces(observation_space: Any, action_space: Any) -> bool:
    """Warn about spaces SB3's algorithms cannot take; True when value checks must be skipped."""
    skip = False
    inner: list[Any] = []
    if isinstance(observation_space, spaces.Dict):
        inner = list(observation_space.spaces.values())
        for key, space in observation_space.spaces.items():
            _check_non_zero_start(space, "observation", key)
        if any(isinstance(space, spaces.Dict) for space in inner):
            _warn(
                "Nested observation spaces are not supported by Stable Baselines3 (Dict spaces "
                "inside Dict space). You should flatten it to have only one level of keys.For "
                "example, `dict(space1=dict(space2=Box(), space3=Box()), spaces4=Discrete())` is "
                "not supported but `dict(space2=Box(), spaces3=Box(), spaces4=Discrete())` is."
            )
    if isinstance(observation_space, spaces.MultiDiscrete) and observation_space.nvec.ndim > 1:
        _warn(
            "The MultiDiscrete observation space uses a multidimensional array "
            f"{observation_space.nvec} which is currently not supported by Stable-Baselines3. "
            "Please convert it to a 1D array using a wrapper: "
            "https://github.com/DLR-RM/stable-baselines3/issues/1836."
        )
    if isinstance(observation_space, spaces.Tuple):
        inner = list(observation_space.spaces)
        _warn(
            "The observation space is a Tuple, this is currently not supported by Stable "
            "Baselines3. However, you can convert it to a Dict observation space (cf. "
            "https://gymnasium.farama.org/api/spaces/composite/#dict). which is supported by SB3."
        )
    if isinstance(observation_space, spaces.OneOf):
        _warn(
            "OneOf observation space is not supported by Stable-Baselines3. Note: The checks for "
            "returned values are skipped."
        )
        skip = True
    _check_non_zero_start(observation_space, "observation")
    if isinstance(observation_space, spaces.Sequence) or any(
        isinstance(s, spaces.Sequence) for s in inner
    ):
        _warn(
            "Sequence observation space is not supported by Stable-Baselines3. You can pad your "
            "observation to have a fixed size instead.\nNote: The checks for returned values "
            "are skipped."
        )
        skip = True
    if isinstance(observation_space, spaces.Graph) or any(
        isinstance(s, spaces.Graph) for s in inner
    ):
        _warn(
            "Graph observation space is not supported by Stable-Baselines3. Note: The checks "
            "for returned values are skipped."
        )
        skip = True
    if isinstance(action_space, spaces.MultiDiscrete) and action_space.nvec.ndim > 1:
        _warn(
            f"The MultiDiscrete action space uses a multidimensional array {action_space.nvec} "
            "which is currently not supported by Stable-Baselines3. Please convert it to a 1D "
            "array using a wrapper: "
            "https://stable-baselines3.readthedocs.io/en/master/guide/custom_env.html."
        )
    _check_non_zero_start(action_space, "action")
    if isinstance(action_space, (spaces.Dict, spaces.Tuple)):
        _warn(
            "The action space is not based off a numpy array. Typically this means it's either "
            "a Dict or Tuple space. This type of action space is currently not supported by "
            "Stable Baselines 3. You should try to flatten the action using a wrapper."
        )
    return skip


def _check_box_obs(space: spaces.Box, key: str = "") -> None:
    if len(space.shape) == 3:
        _check_image_input(space, key)
    if len(space.shape) not in (1, 3):
        _warn(
            f"Your observation {key} has an unconventional shape (neither an image, nor a 1D "
            "vector). We recommend you to flatten the observation to have only a 1D vector or "
            "use a custom policy to properly process the data."
        )


def _check_action_space(action_space: Any) -> None:
    if not isinstance(action_space, spaces.Box):
        return
    low, high = action_space.low, action_space.high
    if np.any(np.abs(low) != np.abs(high)) or np.any(low != -1) or np.any(high != 1):
        _warn(
            "We recommend you to use a symmetric and normalized Box action space (range=[-1, 1]) "
            "cf. https://stable-baselines3.readthedocs.io/en/master/guide/rl_tips.html"
        )
    if not np.all(np.isfinite(np.array([low, high]))):
        raise AssertionError("Continuous action space must have a finite lower and upper bound")
    if action_space.dtype != np.dtype(np.float32):
        _warn(
            f"Your action space has dtype {action_space.dtype}, we recommend using np.float32 to "
            "avoid cast errors."
        )


def _check_obs(obs: Any, space: Any, method: str) -> None:
    """The observation returned by ``method`` is of ``space``'s kind, shape, dtype and bounds."""
    if not isinstance(space, spaces.Tuple) and isinstance(obs, tuple):
        raise AssertionError(
            f"The observation returned by the `{method}()` method should be a single value, "
            "not a tuple"
        )
    if isinstance(space, spaces.Discrete):
        if not np.issubdtype(type(obs), np.integer):
            raise AssertionError(f"The observation returned by `{method}()` method must be an int")
    elif not isinstance(space, (spaces.Dict, spaces.Tuple)) and not isinstance(obs, np.ndarray):
        raise AssertionError(
            f"The observation returned by `{method}()` method must be a numpy array"
        )
    if isinstance(obs, np.ndarray):
        if space.shape != obs.shape:
            raise AssertionError(
                f"The observation returned by the `{method}()` method does not match the shape "
                f"of the given observation space {space}. Expected: {space.shape}, actual "
                f"shape: {obs.shape}"
            )
        if not np.can_cast(obs.dtype, space.dtype):
            raise AssertionError(
                f"The observation returned by the `{method}()` method does not match the data "
                f"type (cannot cast) of the given observation space {space}. Expected: "
                f"{space.dtype}, actual dtype: {obs.dtype}"
            )
        if isinstance(space, spaces.Box):
            outside = np.logical_or(obs < space.low, obs > space.high)
            if outside.any():
                rows = [
                    f"Expected: {space.low[i]} <= obs[{','.join(map(str, i))}] <= "
                    f"{space.high[i]}, actual value: {obs[i]} \n"
                    for i in zip(*np.nonzero(outside))
                ]
                raise AssertionError(
                    f"The observation returned by the `{method}()` method does not match the "
                    f"bounds of the given observation space {space}. \n"
                    f"{len(rows)} invalid indices: \n" + "".join(rows)
                )
    if not space.contains(obs):
        raise AssertionError(
            f"The observation returned by the `{method}()` method does not match the given "
            f"observation space {space}"
        )


def _check_dict_obs(obs: Any, space: spaces.Dict, method: str) -> None:
    if not isinstance(obs, dict):
        raise AssertionError(f"The observation returned by `{method}()` must be a dictionary")
    if obs.keys() != space.spaces.keys():
        raise AssertionError(
            f"The observation keys returned by `{method}()` must match the observation space "
            f"keys: {obs.keys()} != {space.spaces.keys()}"
        )
    for key, sub in space.spaces.items():
        try:
            _check_obs(obs[key], sub, method)
        except AssertionError as e:
            raise AssertionError(f"Error while checking key={key}: " + str(e)) from e


def _is_goal_env(env: Env[Any, Any]) -> bool:
    return hasattr(env.unwrapped, "compute_reward")


def _check_goal_obs(space: spaces.Dict, method: str) -> None:
    if len(space.spaces) < 3:
        raise AssertionError(
            "A goal conditioned env must contain at least 3 observation keys: `observation`, "
            "`achieved_goal`, and `desired_goal`. The current observation contains "
            f"{len(space.spaces)} keys: {list(space.spaces)}"
        )
    for key in ("achieved_goal", "desired_goal"):
        if key not in space.spaces:
            raise AssertionError(
                f"The observation returned by the `{method}()` method of a goal-conditioned env "
                f"requires the '{key}' key to be part of the observation dictionary. Current "
                f"keys are {list(space.spaces)}"
            )


def _check_returned_values(env: Env[Any, Any], observation_space: Any, action_space: Any) -> None:
    result = env.reset()
    if not isinstance(result, tuple):
        raise AssertionError("`reset()` must return a tuple (obs, info)")
    if len(result) != 2:
        raise AssertionError(
            f"`reset()` must return a tuple of size 2 (obs, info), not {len(result)}"
        )
    obs, info = result
    if not isinstance(info, dict):
        raise AssertionError(
            f"The second element of the tuple return by `reset()` must be a dictionary not {info}"
        )
    goal = _is_goal_env(env)
    if goal:
        _check_goal_obs(observation_space, "reset")
    elif isinstance(observation_space, spaces.Dict):
        _check_dict_obs(obs, observation_space, "reset")
    else:
        _check_obs(obs, observation_space, "reset")

    data = env.step(action_space.sample())
    if len(data) != 5:
        raise AssertionError(
            "The `step()` method must return five values: obs, reward, terminated, truncated, "
            f"info. Actual: {len(data)} values returned."
        )
    obs, reward, terminated, truncated, info = data
    if isinstance(observation_space, spaces.Dict):
        if goal:
            _check_goal_obs(observation_space, "step")
        _check_dict_obs(obs, observation_space, "step")
    else:
        _check_obs(obs, observation_space, "step")
    if not isinstance(reward, (float, int)):  # an int is fine: it is cast to float
        raise AssertionError("The reward returned by `step()` must be a float")
    if not isinstance(terminated, bool):
        raise AssertionError("The `terminated` signal must be a boolean")
    if not isinstance(truncated, bool):
        raise AssertionError("The `truncated` signal must be a boolean")
    if not isinstance(info, dict):
        raise AssertionError("The `info` returned by `step()` must be a python dictionary")
    if goal:
        compute = env.get_wrapper_attr("compute_reward")
        if reward != compute(obs["achieved_goal"], obs["desired_goal"], info):
            raise AssertionError("The reward was not computed with `compute_reward()`")


def _check_spaces(env: Env[Any, Any]) -> None:
    for name in ("observation", "action"):
        space = getattr(env, f"{name}_space", None)
        if space is None:
            raise AssertionError(f"You must specify an {name} space ({_SPACES_DOC})")
        if not isinstance(space, spaces.Space):
            raise AssertionError(
                f"The {name} space must inherit from palaestra.spaces ({_SPACES_DOC})"
            )
    if _is_goal_env(env):
        print(
            "We detected your env to be a GoalEnv because `env.compute_reward()` was defined.\n"
            "If it's not the case, please rename `env.compute_reward()` to something else to "
            "avoid False positives."
        )
        if not isinstance(env.observation_space, spaces.Dict):
            raise AssertionError(
                "Goal conditioned envs (previously gym.GoalEnv) require the observation space "
                "to be palaestra.spaces.Dict."
            )


def _nested(space: Any) -> bool:
    if isinstance(space, (spaces.Dict, spaces.Tuple)):
        inner = space.spaces.values() if isinstance(space, spaces.Dict) else space.spaces
        return any(isinstance(s, (spaces.Dict, spaces.Tuple)) for s in inner)
    return False


def _check_nan(env: Env[Any, Any]) -> None:
    """Ten random steps through ``VecCheckNan``: a NaN or inf in them warns."""
    from palaestra.vec_env import DummyVecEnv, VecCheckNan  # lazy: import-time — cloudpickle

    vec_env = VecCheckNan(DummyVecEnv([lambda: env]))
    vec_env.reset()
    array_actions = not isinstance(env.action_space, (spaces.Tuple, spaces.Dict))
    for _ in range(10):
        action = env.action_space.sample()
        vec_env.step(np.array([action]) if array_actions else [action])


def _check_render(env: Env[Any, Any], warn: bool) -> None:
    if env.metadata.get("render_modes") is None and warn:
        _warn(
            "No render modes was declared in the environment (env.metadata['render_modes'] is "
            "None or not defined), you may have trouble when calling `.render()`"
        )
    if env.render_mode:
        env.render()
    env.close()


def check_env(env: Env[Any, Any], warn: bool = True, skip_render_check: bool = True) -> None:
    """Check that ``env`` follows the env API and that SB3-style algorithms can train on it.

    ``warn`` adds warnings about spaces and bounds that train badly or not at all;
    ``skip_render_check=False`` also renders once and closes. Raises ``AssertionError`` (SB3's
    type) for a broken env and ``TypeError`` when ``reset`` takes no ``seed``.
    """
    if not isinstance(env, Env):
        raise AssertionError(
            "Your environment must inherit from the palaestra.Env class (a gymnasium.Env goes "
            "through palaestra.compat.from_gymnasium) cf. https://gymnasium.farama.org/api/env/"
        )
    _check_spaces(env)
    observation_space, action_space = env.observation_space, env.action_space
    try:
        env.reset(seed=0)
    except TypeError as e:
        raise TypeError("The reset() method must accept a `seed` parameter") from e
    skip = False
    if warn:
        skip = _check_unsupported_spaces(observation_space, action_space)
        boxes = (
            observation_space.spaces
            if isinstance(observation_space, spaces.Dict)
            else {"": observation_space}
        )
        for key, space in boxes.items():
            if isinstance(space, spaces.Box):
                _check_box_obs(space, key)
        _check_action_space(action_space)
    if skip:
        return  # Sequence, Graph, OneOf: values cannot be checked element-wise
    _check_returned_values(env, observation_space, action_space)
    if not skip_render_check:
        _check_render(env, warn)
    # Nested observations and Dict actions cannot go through a VecEnv of SB3's kind; their
    # warning has been given above.
    if not _nested(observation_space) and not isinstance(action_space, spaces.Dict):
        _check_nan(env)
