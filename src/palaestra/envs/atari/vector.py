"""``AtariVectorEnv``: N Atari games behind the Gymnasium vector API, on ale-py's C++ threads.

``make_vec("ALE/Breakout-v5", num_envs=N)`` returns one (the ids' ``vector_entry_point``). The
arguments, defaults and observations are those of ale-py's ``AtariVectorEnv`` (what Gymnasium's
``make_vec`` gives for ALE ids): ``(4, 84, 84)`` uint8 grayscale stacks, frame skip 4 with
max-pooling, up to 30 no-op frames and FIRE after each reset, clipped rewards. Equal seeds and
actions give ale-py's observations, rewards, flags and infos.

Differences from ale-py's class, all on purpose:

- infos carry Gymnasium's ``_key`` masks; in SAME_STEP mode finished rows get
  ``final_obs``/``final_info`` (ale-py fills ``final_obs`` for every row);
- an int seed with a ``reset_mask`` seeds row ``i`` with ``seed + i`` (every palaestra vector
  env does; ale-py gives the k-th reset row ``seed + k``);
- bad actions raise ``InvalidAction`` (an out-of-range action hangs ale-py's worker thread);
- ``batch_size`` (asynchronous partial batches) must be 0; there is no ``xla()``.

Without ``ALEVectorInterface`` (ale-py < 0.11) the same constructor runs one worker process per
game: the single :class:`~palaestra.envs.atari.env.AtariEnv` with frameskip 1, then
``AtariPreprocessing``, FIRE on reset, reward clipping and a zero-padded frame stack. The
preprocessing is the same in meaning, not frame for frame (the no-op counts come from
another generator); ``maxpool=False``, ``life_loss_info`` and continuous actions need the
vector interface.
"""

from __future__ import annotations

import functools
from dataclasses import fields
from typing import Any

from palaestra import error
from palaestra.core import Env
from palaestra.envs.atari.ale_engine import ALESettings, ALEVectorEngine, vector_interface_available
from palaestra.envs.atari.env import AtariEnv
from palaestra.envs.atari.games import check_game
from palaestra.vector.engine import Engine
from palaestra.vector.engine_env import EngineVectorEnv
from palaestra.vector.process_engine import ProcessEngine
from palaestra.vector.vector_env import AutoresetMode
from palaestra.wrappers import AtariPreprocessing, ClipReward, FrameStackObservation
from palaestra.wrappers.atari import FireResetEnv

__all__ = ["AtariVectorEnv", "make_atari_engine"]

SETTING_NAMES = frozenset(f.name for f in fields(ALESettings))


def check_settings(settings: dict[str, Any], who: str) -> ALESettings:
    """``ALESettings`` from keyword arguments; unknown names get a ``TypeError`` listing all."""
    unknown = sorted(set(settings) - SETTING_NAMES)
    if unknown:
        raise TypeError(
            f"{who} got unexpected keyword arguments {unknown}; it takes ale-py's "
            f"AtariVectorEnv arguments: {sorted(SETTING_NAMES)}"
        )
    return ALESettings(**settings)


def make_atari_engine(
    game: str, num_envs: int, settings: ALESettings, frames_last: bool = False
) -> Engine:
    """ALE's threaded engine, or worker processes where ale-py has no vector interface."""
    if vector_interface_available():
        return ALEVectorEngine(game, num_envs, settings, frames_last)
    if frames_last:
        raise error.Error("frames_last needs ale-py's ALEVectorInterface (ale-py >= 0.11)")
    return _process_engine(check_game(game), num_envs, settings)


def _process_engine(game: str, num_envs: int, settings: ALESettings) -> Engine:
    unsupported = {
        "maxpool": not settings.maxpool,
        "life_loss_info": settings.life_loss_info,
        "continuous": settings.continuous,
    }
    names = [name for name, asked in unsupported.items() if asked]
    if names:
        raise error.Error(
            f"{names} need ale-py's ALEVectorInterface (ale-py >= 0.11), which the installed "
            "ale-py lacks: upgrade ale-py, or leave these settings at their defaults"
        )
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
    make_one = functools.partial(preprocessed_env, game, settings)
    return ProcessEngine([make_one] * num_envs, who="AtariVectorEnv")


def preprocessed_env(game: str, settings: ALESettings) -> Env[Any, Any]:
    """One game with wrappers that mean what ``settings`` mean to ``ALEVectorInterface``."""
    s = settings
    env: Env[Any, Any] = AtariEnv(
        game,
        frameskip=1,
        repeat_action_probability=s.repeat_action_probability,
        full_action_space=s.full_action_space,
        max_num_frames_per_episode=s.max_num_frames_per_episode,
    )
    env = AtariPreprocessing(
        env,
        noop_max=s.noop_max,
        frame_skip=s.frameskip,
        screen_size=(s.img_width, s.img_height),
        terminal_on_life_loss=s.episodic_life,
        grayscale_obs=s.grayscale,
    )
    if s.use_fire_reset and "FIRE" in env.unwrapped.get_action_meanings():  # type: ignore[attr-defined]
        env = FireResetEnv(env)
    if s.reward_clipping:
        env = ClipReward(env, -1.0, 1.0)
    # ALE clears its frame stack to zeros at each reset.
    return FrameStackObservation(env, s.stack_num, padding_type="zero")


class AtariVectorEnv(EngineVectorEnv):
    """``num_envs`` copies of ``game`` (a snake_case ROM id) as one vector env.

    Keyword arguments and defaults are ale-py's ``AtariVectorEnv``'s (see
    :class:`~palaestra.envs.atari.ale_engine.ALESettings`); ``autoreset_mode`` is NEXT_STEP,
    SAME_STEP or DISABLED.

    >>> import palaestra as gym
    >>> envs = gym.make_vec("ALE/Breakout-v5", num_envs=2)  # doctest: +SKIP
    >>> envs.reset(seed=0)[0].shape  # doctest: +SKIP
    (2, 4, 84, 84)
    """

    def __init__(
        self,
        game: str,
        num_envs: int = 1,
        *,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **settings: Any,
    ) -> None:
        self.game = game
        autoreset_mode = AutoresetMode(autoreset_mode)  # before any thread or process starts
        engine = make_atari_engine(game, num_envs, check_settings(settings, "AtariVectorEnv"))
        # ALE hands back a new observation array on every call: nothing to copy. Worker
        # processes write into one shared buffer, which must be copied.
        native = isinstance(engine, ALEVectorEngine)
        super().__init__(engine, copy=not native, autoreset_mode=autoreset_mode)
