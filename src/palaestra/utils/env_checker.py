"""``check_env``: actively exercise an environment and assert that it follows the API.

Where :mod:`palaestra.utils.passive_env_checker` only watches calls the user makes, this module
makes its own: it resets with seeds, steps twice from the same state, renders every declared
mode and closes twice. Checks and messages follow Gymnasium 1.x's ``check_env`` (itself from
Stable-Baselines3), so an env that passes one passes the other.
"""

from __future__ import annotations

import inspect
from copy import deepcopy
from itertools import combinations
from typing import Any

import numpy as np

from palaestra import error, logger, spaces
from palaestra.core import Env
from palaestra.utils.passive_env_checker import (
    check_action_space,
    check_observation_space,
    data_shares_objects,
    env_render_passive_checker,
    env_reset_passive_checker,
    env_step_passive_checker,
)

__all__ = [
    "check_env",
    "check_reset_options",
    "check_reset_return_info_deprecation",
    "check_reset_return_type",
    "check_reset_seed_determinism",
    "check_returned_data_not_reused",
    "check_seed_deprecation",
    "check_space_limit",
    "check_step_determinism",
    "data_equivalence",
]


def data_equivalence(data_1: Any, data_2: Any, exact: bool = False) -> bool:
    """Whether two observations/infos are equal: same types and structure, arrays ``allclose``.

    >>> data_equivalence({"a": np.ones(2)}, {"a": np.ones(2) + 1e-9})
    True
    >>> data_equivalence(np.ones(2), np.ones(2, dtype=np.float32))
    False
    """
    if type(data_1) is not type(data_2):
        return False
    if isinstance(data_1, dict):
        return data_1.keys() == data_2.keys() and all(
            data_equivalence(data_1[k], data_2[k], exact) for k in data_1
        )
    if isinstance(data_1, (tuple, list)):
        return len(data_1) == len(data_2) and all(
            data_equivalence(a, b, exact) for a, b in zip(data_1, data_2)
        )
    if isinstance(data_1, np.ndarray):
        if data_1.shape != data_2.shape or data_1.dtype != data_2.dtype:
            return False
        if data_1.dtype == object:
            return all(data_equivalence(a, b, exact) for a, b in zip(data_1, data_2))
        if exact:
            return bool(np.all(data_1 == data_2))
        return bool(np.allclose(data_1, data_2, rtol=1e-5, atol=1e-5))
    return bool(data_1 == data_2)  # np.bool_ from numpy scalars, hence bool()


def _accepts(env: Env[Any, Any], name: str) -> bool:
    params = inspect.signature(env.reset).parameters
    return name in params or (
        "kwargs" in params and params["kwargs"].kind is inspect.Parameter.VAR_KEYWORD
    )


def _reset_in_space(env: Env[Any, Any], call: str, **kwargs: Any) -> Any:
    # deepcopy: an env that refills one buffer would otherwise change what we compare later.
    obs = deepcopy(env.reset(**kwargs)[0])
    assert obs in env.observation_space, (
        f"The observation returned by `{call}` is not within the observation space."
    )
    return obs


def check_reset_seed_determinism(env: Env[Any, Any]) -> None:
    """Same seed → same observations and generator state; another seed → another state."""
    if not _accepts(env, "seed"):
        raise error.Error(
            "The `reset` method does not provide a `seed` or `**kwargs` keyword argument."
        )
    try:
        obs_1 = _reset_in_space(env, "env.reset(seed=123)", seed=123)
        assert env.unwrapped._np_random is not None, (
            "Expects the random number generator to have been generated given a seed was passed "
            "to reset. Most likely the environment reset function does not call "
            "`super().reset(seed=seed)`."
        )
        rng_1 = deepcopy(env.unwrapped._np_random)
        obs_2 = _reset_in_space(env, "env.reset()")
        obs_3 = _reset_in_space(env, "env.reset(seed=123)", seed=123)
        rng_3 = deepcopy(env.unwrapped._np_random)
        obs_4 = _reset_in_space(env, "env.reset()")
        if env.spec is not None and env.spec.nondeterministic is False:
            assert data_equivalence(obs_1, obs_3), (
                "Using `env.reset(seed=123)` is non-deterministic as the observations are not "
                "equivalent."
            )
            assert data_equivalence(obs_2, obs_4), (
                "Using `env.reset(seed=123)` then `env.reset()` is non-deterministic as the "
                "observations are not equivalent."
            )
            if not data_equivalence(obs_1, obs_3, exact=True):
                logger.warn(
                    "Using `env.reset(seed=123)` observations are not equal although similar."
                )
            if not data_equivalence(obs_2, obs_4, exact=True):
                logger.warn(
                    "Using `env.reset(seed=123)` then `env.reset()` observations are not equal "
                    "although similar."
                )
        assert rng_1.bit_generator.state == rng_3.bit_generator.state, (
            "Most likely the environment reset function does not call `super().reset(seed=seed)` "
            "as the random generates are not same when the same seeds are passed to `env.reset`."
        )
        _reset_in_space(env, "env.reset(seed=456)", seed=456)
        assert env.unwrapped._np_random.bit_generator.state != rng_1.bit_generator.state, (
            "Most likely the environment reset function does not call `super().reset(seed=seed)` "
            "as the random number generators are not different when different seeds are passed "
            "to `env.reset`."
        )
    except TypeError as e:
        raise AssertionError(
            "The environment cannot be reset with a random seed, even though `seed` or `kwargs` "
            "appear in the signature. This should never happen, please report this issue. "
            f"The error was: {e}"
        ) from e
    seed_param = inspect.signature(env.reset).parameters.get("seed")
    if seed_param is not None and seed_param.default is not None:
        logger.warn(
            "The default seed argument in reset should be `None`, otherwise the environment will "
            f"by default always be deterministic. Actual default: {seed_param.default}"
        )


def check_reset_options(env: Env[Any, Any]) -> None:
    """``reset(options={})`` must work."""
    if not _accepts(env, "options"):
        raise error.Error(
            "The `reset` method does not provide an `options` or `**kwargs` keyword argument."
        )
    try:
        env.reset(options={})
    except TypeError as e:
        raise AssertionError(
            "The environment cannot be reset with options, even though `options` or `**kwargs` "
            "appear in the signature. This should never happen, please report this issue. "
            f"The error was: {e}"
        ) from e


def check_step_determinism(env: Env[Any, Any], seed: int = 123) -> None:
    """The same seed and action give the same transition (unless the spec says otherwise)."""
    if env.spec is not None and env.spec.nondeterministic is True:
        return
    env.action_space.seed(seed)
    action = env.action_space.sample()
    env.reset(seed=seed)
    obs_0, rew_0, term_0, trunc_0, info_0 = env.step(action)
    obs_0 = deepcopy(obs_0)  # before a reused buffer is refilled by the next step
    assert env.unwrapped._np_random is not None, (
        "env.reset() should have initialized env._np_random"
    )
    rng_0 = deepcopy(env.unwrapped._np_random)
    env.reset(seed=seed)
    obs_1, rew_1, term_1, trunc_1, info_1 = env.step(action)
    assert env.unwrapped._np_random.bit_generator.state == rng_0.bit_generator.state, (
        "The `.np_random` is not properly been updated after step."
    )
    for what, first, second in (("observations", obs_0, obs_1), ("rewards", rew_0, rew_1)):
        assert data_equivalence(first, second), (
            f"Deterministic step {what} are not equivalent for the same seed and action"
        )
        if not data_equivalence(first, second, exact=True):
            logger.warn(
                f"Step {what} are not equal although similar given the same seed and action"
            )
    assert data_equivalence(term_0, term_1, exact=True), (
        "Deterministic step termination are not equivalent for the same seed and action"
    )
    assert trunc_0 is False and trunc_1 is False, (
        "Environment truncates after 1 step, something has gone very wrong."
    )
    assert data_equivalence(info_0, info_1), (
        "Deterministic step info are not equivalent for the same seed and action"
    )
    if not data_equivalence(info_0, info_1, exact=True):
        logger.warn("Step info are not equal although similar given the same seed and action")


def check_returned_data_not_reused(env: Env[Any, Any], seed: int = 123) -> None:
    """No two calls of reset/step may return observations or infos sharing an object."""
    env.action_space.seed(seed)
    calls = [("env.reset() (call 1)", env.reset(seed=seed))]
    for _ in range(2):
        obs, _, terminated, truncated, info = env.step(env.action_space.sample())
        calls.append((f"env.step() (call {len(calls) + 1})", (obs, info)))
        if terminated or truncated:
            break
    calls.append((f"env.reset() (call {len(calls) + 1})", env.reset(seed=seed)))
    for (source_1, (obs_1, info_1)), (source_2, (obs_2, info_2)) in combinations(calls, 2):
        assert not data_shares_objects(obs_1, obs_2), (
            f"The observations returned by `{source_1}` and `{source_2}` share an object, "
            "therefore, modifying one will modify the other. Environments must return new "
            "observation data on every call as users keep the data returned to them."
        )
        assert not data_shares_objects(info_1, info_2), (
            f"The infos returned by `{source_1}` and `{source_2}` share an object, therefore, "
            "modifying one will modify the other. Environments must return new info data on "
            "every call as users keep the data returned to them."
        )


def check_reset_return_type(env: Env[Any, Any]) -> None:
    """``reset()`` returns ``(obs in observation_space, dict)``."""
    result = env.reset()
    assert isinstance(result, tuple), (
        "The result returned by `env.reset()` was not a tuple of the form `(obs, info)`, where "
        "`obs` is a observation and `info` is a dictionary containing additional information. "
        f"Actual type: `{type(result)}`"
    )
    assert len(result) == 2, (
        f"Calling the reset method did not return a 2-tuple, actual length: {len(result)}"
    )
    obs, info = result
    assert obs in env.observation_space, (
        "The first element returned by `env.reset()` is not within the observation space."
    )
    assert isinstance(info, dict), (
        "The second element returned by `env.reset()` was not a dictionary, "
        f"actual type: {type(info)}"
    )


def check_space_limit(space: Any, space_type: str) -> None:
    """Warn about infinite ``Box`` bounds and non-normalized ``Box`` action spaces."""
    if isinstance(space, spaces.Box):
        if np.any(np.equal(space.low, -np.inf)):
            logger.warn(
                f"A Box {space_type} space minimum value is -infinity. This is probably too low."
            )
        if np.any(np.equal(space.high, np.inf)):
            logger.warn(
                f"A Box {space_type} space maximum value is infinity. This is probably too high."
            )
        # Learning algorithms assume actions in [-1, 1] (or [0, 1]); SB3's advice.
        if space_type == "action" and len(space.shape) == 1:
            asymmetric = np.logical_and(space.low != 0, np.abs(space.low) != np.abs(space.high))
            if np.any(asymmetric) or np.any(space.low < -1) or np.any(space.high > 1):
                logger.warn(
                    "For Box action spaces, we recommend using a symmetric and normalized space "
                    "(range=[-1, 1] or [0, 1]). See "
                    "https://stable-baselines3.readthedocs.io/en/master/guide/rl_tips.html for "
                    "more information."
                )
    elif isinstance(space, spaces.Tuple):
        for subspace in space.spaces:
            check_space_limit(subspace, space_type)
    elif isinstance(space, spaces.Dict):
        for subspace in space.values():
            check_space_limit(subspace, space_type)


def check_reset_return_info_deprecation(env: Env[Any, Any]) -> None:
    """Warn if ``env.reset`` still takes Gymnasium 0.x's ``return_info`` argument."""
    if "return_info" in inspect.signature(env.reset).parameters:
        logger.warn(
            "`return_info` is deprecated as an optional argument to `reset`. `reset`should now "
            "always return `obs, info` where `obs` is an observation, and `info` is a "
            "dictionarycontaining additional information."
        )


def check_seed_deprecation(env: Env[Any, Any]) -> None:
    """Warn if the env still has Gymnasium 0.x's ``seed()`` method."""
    if callable(getattr(env, "seed", None)):
        logger.warn(
            "Official support for the `seed` function is dropped. Standard practice is to reset "
            "palaestra environments using `env.reset(seed=<desired seed>)`"
        )


def _check_render_and_close(
    env: Env[Any, Any], skip_render_check: bool, skip_close_check: bool
) -> None:
    if not skip_render_check:
        if env.render_mode is not None:
            env_render_passive_checker(env)
        if env.spec is not None:
            for render_mode in env.metadata["render_modes"]:
                new_env = env.spec.make(render_mode=render_mode)
                new_env.reset()
                env_render_passive_checker(new_env)
                new_env.close()
        else:
            logger.warn(
                "Not able to test alternative render modes due to the environment not having a "
                "spec. Try instantiating the environment through `palaestra.make`"
            )
    if not skip_close_check and env.spec is not None:
        new_env = env.spec.make()
        new_env.close()
        try:
            new_env.close()
        except Exception as e:
            logger.warn(
                "Calling `env.close()` on the closed environment should be allowed, but it raised "
                f"an exception: {e}"
            )


def check_env(
    env: Env[Any, Any],
    warn: bool | None = None,
    skip_render_check: bool = False,
    skip_close_check: bool = False,
) -> None:
    """Check that ``env`` follows palaestra's (Gymnasium's) environment API.

    Checks the spaces, ``reset`` and ``step`` signatures and return values, seeding
    determinism, that returned data is never reused, every declared render mode, and that
    ``close`` may be called twice. Raises on errors, warns on likely mistakes.
    Pass the unwrapped env (``env.unwrapped``) for the most precise results.

    Args:
        env: the environment to check.
        warn: ignored (kept for compatibility; it used to silence some warnings).
        skip_render_check: do not call ``render`` (e.g. on machines without a display).
        skip_close_check: do not make a new env to call ``close`` twice on it.
    """
    if warn is not None:
        logger.warn("`check_env(warn=...)` parameter is now ignored.")
    if not isinstance(env, Env):
        raise TypeError(
            "The environment must inherit from the palaestra.Env class, actual class: "
            f"{type(env)}. See https://gymnasium.farama.org/introduction/create_custom_env/ for "
            "more info."
        )
    if env.unwrapped is not env:
        logger.warn(
            f"The environment ({env}) is different from the unwrapped version ({env.unwrapped}). "
            "This could effect the environment checker as the environment most likely has a "
            "wrapper applied to it. We recommend using the raw environment for `check_env` using "
            "`env.unwrapped`."
        )
    for space_type, check_space in (
        ("action", check_action_space),
        ("observation", check_observation_space),
    ):
        if not hasattr(env, f"{space_type}_space"):
            raise AttributeError(
                f"The environment must specify an {space_type} space. See "
                "https://gymnasium.farama.org/introduction/create_custom_env/ for more info."
            )
        space = getattr(env, f"{space_type}_space")
        check_space(space)
        check_space_limit(space, space_type)

    check_seed_deprecation(env)
    check_reset_return_info_deprecation(env)
    check_reset_return_type(env)
    check_reset_seed_determinism(env)
    check_reset_options(env)

    env_reset_passive_checker(env)
    env_step_passive_checker(env, env.action_space.sample())
    check_step_determinism(env)
    check_returned_data_not_reused(env)

    _check_render_and_close(env, skip_render_check, skip_close_check)
