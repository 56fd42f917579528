"""The env pipeline a run trains on, rebuilt the same way by ``eval``, ``record`` and the
end-of-training evaluation.

Most runs train on ``make_vec_env`` (under ``VecNormalize`` when asked) and are evaluated on
one ``palaestra.make`` env. Two settings change that:

- ``atari``: ``true`` or ``AtariWrapper`` kwargs. SB3's Atari recipe: ``make_atari_env``, i.e.
  per env a ``Monitor`` then ``AtariWrapper`` (no-op starts, frame skip with max-pool, a lost
  life ends a training episode, FIRE on reset, 84x84 gray, rewards clipped to their sign).
  ``ALE/*-v5`` ids skip frames themselves, so Atari presets set ``env_kwargs.frameskip=1`` and
  let the wrapper skip 4 (as RL-Zoo does); v5's sticky actions (ALE, per frame) stay.
- ``frame_stack``: ``VecFrameStack(n_stack=frame_stack)`` on top.
- ``env_wrapper``: ``"module:Class"`` (or a list of them, innermost first), a wrapper class
  that ``make_vec_env`` applies to each env over its ``Monitor`` (SB3's ``wrapper_class``), so
  the episode log keeps the env's own returns: a reward-shaping wrapper changes what the agent
  learns from, not what the curves and ``compare`` report. The module is imported from the
  current folder first (``python -m`` style), so a ``shaping.py`` beside the run works; the
  name must be a ``palaestra.Wrapper`` subclass. Gymnasium's and SB3's wrapper names
  (``gymnasium.wrappers.TimeLimit``) are palaestra's classes
  (:mod:`palaestra.runs.known_names`). A module named by a run folder or a settings file is
  imported only when the command line allows it (:mod:`palaestra.runs.folder`).

An env id ``module:Name-v0`` (Gymnasium's convention) imports ``module`` from the current folder
first, as ``palaestra.make`` does, so a user's ``mygrid.py`` that calls ``palaestra.register``
trains from the command line. With no preset, :func:`choose_policy` picks the policy from the
env's observation space, as SB3 users pick it by hand.

Such a run is evaluated on the same pipeline with one env, and an evaluation episode is a
whole game: the Monitor under the ``AtariWrapper`` reports it (all lives, unclipped score),
which is what SB3's ``evaluate_policy`` counts too.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import os
import sys
from collections.abc import Callable
from typing import Any

import palaestra
from palaestra import spaces
from palaestra.core import Wrapper
from palaestra.envs.atari.checks import import_ale_py
from palaestra.envs.atari.games import ENTRY_POINT as ATARI_ENTRY_POINT
from palaestra.runs import known_names
from palaestra.runs.errors import RunError

__all__ = [
    "ATARI_ENTRY_POINT",
    "atari_defaults",
    "atari_kwargs",
    "check_pipeline",
    "choose_policy",
    "env_id_module",
    "env_wrapper",
    "import_env_module",
    "import_user_module",
    "is_atari_id",
    "locate_module",
    "make_vec",
    "module_sha256",
    "registered_id",
    "render_fps",
    "uses_vec_pipeline",
    "wrapper_items",
    "wrapper_module",
]

ATARI_HZ = 60.0  # frames the (NTSC) Atari 2600 draws per second
# AtariWrapper's keyword arguments (SB3's names), the only keys an ``atari`` mapping may hold.
WRAPPER_KEYS = (
    "noop_max",
    "frame_skip",
    "screen_size",
    "terminal_on_life_loss",
    "clip_reward",
    "action_repeat_probability",
)


def env_id_module(env_id: str) -> str | None:
    """The module ``palaestra.make(env_id)`` imports first (``module:Name-v0``), or None.
    ``gymnasium:<id>`` uses the installed Gymnasium, whose own ``module:`` prefix counts.

    >>> env_id_module("mygrid:GridWorld-v0"), env_id_module("CartPole-v1")
    ('mygrid', None)
    """
    module, sep, _ = env_id.removeprefix("gymnasium:").rpartition(":")
    return module if sep else None


def registered_id(env_id: str) -> str:
    """The id the registry holds for ``env_id``: without its ``module:`` part (Gymnasium ids
    kept whole, ``palaestra.spec`` reads them).

    >>> registered_id("mygrid:GridWorld-v0"), registered_id("ALE/Pong-v5")
    ('GridWorld-v0', 'ALE/Pong-v5')
    """
    if env_id.startswith("gymnasium:"):
        return env_id
    return env_id.rpartition(":")[2]


def _cwd_importable() -> None:
    """As ``python -m`` does: the current folder first on the path. The console script does
    not put it there, and a user's ``mygrid.py`` or ``shaping.py`` sits in it."""
    if "" not in sys.path:
        sys.path.insert(0, "")


def import_user_module(module_name: str, what: str) -> Any:
    """Import ``module_name`` (the current folder first on the path) for ``what`` (e.g.
    ``"env id 'mygrid:GridWorld-v0'"``); ``RunError`` naming both when it cannot be imported.
    The caller decides whether the module may run (:mod:`palaestra.runs.folder`)."""
    _cwd_importable()
    try:
        return importlib.import_module(module_name)
    except ImportError as exc:
        raise RunError(
            f"cannot import module {module_name!r} of {what}: {exc}",
            "run from the folder that holds it, or fix the name",
        ) from None


def import_env_module(env_id: str, what: str) -> str | None:
    """Import the user's module that ``env_id`` (``module:Name-v0``) names, for ``what``, as
    ``palaestra.make`` would; return its name (None when the id names none). A
    ``gymnasium:`` id imports nothing here: Gymnasium imports its own ``module:``."""
    module = env_id_module(env_id)
    if module and not env_id.startswith("gymnasium:"):
        import_user_module(module, what)
    return module


def locate_module(module_name: str) -> str | None:
    """Where ``module_name`` would be imported from (the current folder first on the path):
    its file, ``"built-in"``, ..., or None when it cannot be found. Executes no module code for
    a top-level name; a dotted name imports its parent packages, so ask that only for a module
    allowed to run."""
    _cwd_importable()
    try:
        found = importlib.util.find_spec(module_name)
    except (ImportError, ValueError):
        return None
    if found is None:
        return None
    return str(found.origin or "namespace package")


def module_sha256(module_name: str) -> str | None:
    """The sha256 of the file ``module_name`` is imported from, or None when it has none (see
    :func:`locate_module`)."""
    origin = locate_module(module_name)
    if origin is None or not os.path.isfile(origin):
        return None
    digest = hashlib.sha256()
    with open(origin, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def is_atari_id(env_id: str) -> bool:
    """Whether ``env_id`` is registered as an ALE game (no ale-py import)."""
    return palaestra.spec(registered_id(env_id)).entry_point == ATARI_ENTRY_POINT


def atari_defaults() -> dict[str, Any]:
    """Settings for an Atari id that has no preset: the recipe, a CNN, 4 stacked frames."""
    return {
        "policy": "CnnPolicy",
        "env_kwargs": {"frameskip": 1},
        "atari": True,
        "frame_stack": 4,
    }


def atari_kwargs(config: dict[str, Any]) -> dict[str, Any] | None:
    """The run's ``AtariWrapper`` kwargs (``true`` and ``{}``: SB3's defaults), or None when
    the run does not use the Atari recipe (``atari`` absent, false or null)."""
    atari = config.get("atari")
    if atari is None or atari is False:
        return None
    return dict(atari) if isinstance(atari, dict) else {}


def _stack(config: dict[str, Any]) -> int:
    value = config.get("frame_stack")
    return 1 if value is None else int(value)


def uses_vec_pipeline(config: dict[str, Any]) -> bool:
    """Whether a run's env is more than ``palaestra.make`` (Atari recipe, frame stack or an
    env wrapper)."""
    return atari_kwargs(config) is not None or _stack(config) > 1 or bool(config.get("env_wrapper"))


WRAPPER_FIX = "write env_wrapper as 'module:Class', e.g. shaping:BetterRewardShaping"


def wrapper_module(path: Any, setting: str = "env_wrapper") -> tuple[str, str]:
    """``"module:Class"`` (or ``"module.Class"``) -> ``(module, class name)``; ``RunError``
    naming ``setting`` for anything else. Imports nothing."""
    fix = WRAPPER_FIX if setting == "env_wrapper" else f"write {setting} as 'module:Class'"
    if not isinstance(path, str) or not path.strip():
        raise RunError(f"{setting} must be 'module:Class', got {path!r}", fix)
    module_name, sep, name = path.partition(":")
    if not sep:
        module_name, _, name = path.rpartition(".")
    if not module_name or not name:
        raise RunError(f"{setting} {path!r} names no module and class", fix)
    return module_name, name


def wrapper_items(value: Any, setting: str = "env_wrapper") -> list[tuple[str, dict[str, Any]]]:
    """A run's ``env_wrapper`` (or ``callback``: ``setting``) as ``[(name, kwargs)]``,
    innermost first: a name, a one-key mapping ``{name: kwargs}`` (RL Zoo's form, e.g.
    ``{"gymnasium.wrappers.TimeLimit": {"max_episode_steps": 100}}``), or a list of them.
    Imports nothing.

    >>> wrapper_items(["a:W", {"b:V": {"k": 1}}, {"c:U": None}])
    [('a:W', {}), ('b:V', {'k': 1}), ('c:U', {})]
    """
    out = []
    for item in value if isinstance(value, list) else [value]:
        if isinstance(item, dict) and len(item) == 1:
            ((name, kwargs),) = item.items()
            if kwargs is None:
                kwargs = {}
            if not (isinstance(kwargs, dict) and all(isinstance(k, str) for k in kwargs)):
                raise RunError(
                    f"{setting} {name!r} takes a mapping of keyword arguments, got {kwargs!r}",
                    "e.g. {'gymnasium.wrappers.TimeLimit': {'max_episode_steps': 100}}",
                )
            out.append((name, dict(kwargs)))
        else:
            out.append((item, {}))
    for name, _ in out:
        wrapper_module(name, setting)
    return out


def _import_wrapper(path: Any) -> type[Any]:
    """The wrapper class named by ``"module:Class"``: a ``palaestra.Wrapper`` subclass, never
    just any callable (``"os:system"`` would run a shell command on the env's repr)."""
    wrapper_module(path)  # a malformed name fails as itself, before the table is asked
    module_name, name = wrapper_module(known_names.palaestra_name("env_wrapper", path) or path)
    module = import_user_module(module_name, f"env_wrapper {path!r}")
    cls = getattr(module, name, None)
    if cls is None:
        raise RunError(f"module {module_name!r} has no class {name!r} (env_wrapper)", WRAPPER_FIX)
    if not (isinstance(cls, type) and issubclass(cls, Wrapper)):
        kind = "a class but no Wrapper" if isinstance(cls, type) else f"a {type(cls).__name__}"
        raise RunError(
            f"env_wrapper {path!r} is {kind}, not a wrapper class",
            "name a subclass of palaestra.Wrapper (gym.Wrapper, gym.RewardWrapper, ...)",
        )
    return cls


def env_wrapper(config: dict[str, Any]) -> Callable[[Any], Any] | None:
    """The run's ``env_wrapper`` setting as one callable (a list applies innermost first), or
    None when it has none. ``RunError`` when a wrapper does not take its keyword arguments."""
    value = config.get("env_wrapper")
    if not value:
        return None
    classes = []
    for name, kwargs in wrapper_items(value):
        cls = _import_wrapper(name)
        try:  # the env comes first; the kwargs must fit the rest of the signature
            inspect.signature(cls).bind(None, **kwargs)
        except TypeError as exc:
            raise RunError(
                f"env_wrapper {name!r} does not take {kwargs}: {exc}", "fix its arguments"
            ) from None
        except ValueError:  # no signature to check against (a builtin): the call will tell
            pass
        classes.append((cls, kwargs))

    def wrap(env: Any) -> Any:
        for cls, kwargs in classes:
            env = cls(env, **kwargs)
        return env

    return wrap


def choose_policy(settings: dict[str, Any], env_id: str) -> tuple[str, str]:
    """``(policy, why)`` for a run with no preset, from the observation space of one env of
    its recipe (env kwargs and wrapper applied): ``MultiInputPolicy`` for a ``Dict`` space,
    ``CnnPolicy`` for an image ``Box`` (SB3's ``is_image_space``), else ``MlpPolicy``."""
    from palaestra.algos.common.spaces_util import is_image_space  # lazy: import-time — torch

    try:
        env = palaestra.make(env_id, **(settings.get("env_kwargs") or {}))
    except (TypeError, ValueError) as exc:  # an env kwarg the env does not take, or refuses
        kwargs = settings.get("env_kwargs") or {}
        raise RunError(
            f"cannot make {env_id} with env_kwargs {kwargs}: {exc}", "fix env_kwargs"
        ) from None
    try:
        wrap = env_wrapper(settings)
        space = (wrap(env) if wrap is not None else env).observation_space
    finally:
        env.close()
    if isinstance(space, spaces.Dict):
        return "MultiInputPolicy", "Dict observations"
    if is_image_space(space):
        return "CnnPolicy", f"image observations {space.shape}"
    return "MlpPolicy", f"{type(space).__name__} observations"


def check_pipeline(settings: dict[str, Any], env_id: str) -> None:
    """``RunError`` unless ``atari`` and ``frame_stack`` are usable for ``env_id``."""
    atari = settings.get("atari")
    stack = settings.get("frame_stack")
    if stack is not None:
        from palaestra.vec_env.image import check_n_stack  # lazy: import-time — multiprocessing

        try:
            check_n_stack(stack, name="frame_stack")
        except (TypeError, ValueError) as exc:
            raise RunError(str(exc), "e.g. 4, or null for no stack") from None
    if not isinstance(atari, (bool, dict, type(None))):
        raise RunError(f"atari must be true/false or AtariWrapper kwargs, got {atari!r}", "fix it")
    env_wrapper(settings)  # imports it: a bad name fails before training starts
    if atari_kwargs(settings) is None:
        return
    if settings.get("env_wrapper"):
        raise RunError("env_wrapper does not apply to the Atari recipe", "drop one of them")
    if isinstance(atari, dict):
        unknown = sorted(set(atari) - set(WRAPPER_KEYS))
        if unknown:
            raise RunError(
                f"unknown AtariWrapper setting(s) {unknown} in atari",
                f"valid keys: {', '.join(WRAPPER_KEYS)}",
            )
    if not is_atari_id(env_id):
        raise RunError(f"atari is set but {env_id} is not an Atari game", "drop atari")
    if settings.get("normalize"):
        raise RunError("normalize does not apply to the Atari recipe", "drop normalize or atari")
    import_ale_py()  # before torch is imported: a missing ale-py fails at once, in one line


def make_vec(config: dict[str, Any], n_envs: int, seed: int | None, render: bool = False) -> Any:
    """``n_envs`` envs of the run's pipeline (without ``VecNormalize``)."""
    from palaestra.vec_env import (  # lazy: import-time — multiprocessing
        VecFrameStack,
        make_atari_env,
        make_vec_env,
    )

    env_id = config["env_id"]
    env_kwargs = dict(config.get("env_kwargs") or {})
    wrapper_kwargs = atari_kwargs(config)
    if wrapper_kwargs is not None:
        import_ale_py()  # eval and record reach here without check_pipeline
        try:  # string Atari ids render rgb_array frames already
            venv = make_atari_env(
                env_id,
                n_envs=n_envs,
                seed=seed,
                wrapper_kwargs=wrapper_kwargs,
                env_kwargs=env_kwargs,
            )
        except (TypeError, ValueError) as exc:  # AtariWrapper's checks of its arguments
            raise RunError(f"invalid atari settings {wrapper_kwargs}: {exc}", "fix atari") from None
    else:
        if render:
            env_kwargs["render_mode"] = "rgb_array"
        venv = make_vec_env(
            env_id,
            n_envs=n_envs,
            seed=seed,
            env_kwargs=env_kwargs,
            wrapper_class=env_wrapper(config),
        )
    if _stack(config) > 1:
        venv = VecFrameStack(venv, n_stack=_stack(config))
    return venv


def render_fps(venv: Any, config: dict[str, Any]) -> float:
    """Frames per second of a recording, one rendered frame per agent step: for Atari the
    console's 60 Hz over the wrapper's frame skip (real game speed), else the env's
    ``render_fps`` (default 30)."""
    wrapper_kwargs = atari_kwargs(config)
    if wrapper_kwargs is not None:
        return ATARI_HZ / max(int(wrapper_kwargs.get("frame_skip", 4)), 1)
    metadata = venv.get_attr("metadata")[0] or {}
    return float(metadata.get("render_fps") or 30)
