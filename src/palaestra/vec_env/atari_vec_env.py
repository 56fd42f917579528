"""``AtariVecEnv``: the native vector Atari (ale-py's C++ threads) with SB3's ``VecEnv`` API.

The same engine as :class:`palaestra.envs.atari.vector.AtariVectorEnv`, driven in SAME_STEP
mode: ``reset()`` returns observations only, a finished game is reset at once and its last
observation goes to ``infos[i]["terminal_observation"]``, ``TimeLimit.truncated`` marks ALE's
frame limit. With ``life_loss_info=True`` a lost life is a ``done`` whose
``terminal_observation`` is also the next observation: the game goes on.

``make_atari_env(..., vec_env_cls=AtariVecEnv)`` builds one from SB3's recipe settings through
:func:`atari_wrapper_settings`; see there for what maps and what differs.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from palaestra.envs.atari.ale_engine import ALESettings, ALEVectorEngine
from palaestra.envs.atari.games import ENTRY_POINT as _ATARI_ENTRY_POINT
from palaestra.envs.atari.vector import check_settings, make_atari_engine
from palaestra.envs.lookup import resolve_id
from palaestra.vec_env.base import StepReturn
from palaestra.vec_env.engine_vec_env import EngineVecEnv
from palaestra.vec_env.monitor import VecMonitor

__all__ = ["AtariGameMonitor", "AtariVecEnv", "atari_wrapper_settings"]

# The settings of an Atari id's spec that ALEVectorInterface also has.
_SPEC_SETTINGS = ("repeat_action_probability", "full_action_space", "frameskip")


def _game_and_defaults(env_id: str) -> tuple[str, dict[str, Any], Any]:
    """``(game, settings from the id's spec, spec)`` for an Atari id; a bare ROM id as is."""
    if "/" not in env_id and "-v" not in env_id:
        return env_id, {}, None

    spec = resolve_id(env_id)
    if spec.entry_point != _ATARI_ENTRY_POINT:
        raise ValueError(f"AtariVecEnv needs an Atari id such as 'ALE/Breakout-v5', got {env_id!r}")
    defaults = {k: spec.kwargs[k] for k in _SPEC_SETTINGS if k in spec.kwargs}
    frames = spec.kwargs.get("max_num_frames_per_episode")
    if frames is not None:
        defaults["max_num_frames_per_episode"] = frames
    return spec.kwargs["game"], defaults, spec


class AtariVecEnv(EngineVecEnv):
    """``n_envs`` Atari games as an SB3 ``VecEnv`` (rewards float32).

    ``env_id`` is an Atari id (``"ALE/Breakout-v5"``: its spec's sticky actions, frame skip and
    frame limit become defaults) or a ROM id (``"breakout"``: ale-py's vector defaults).
    ``settings`` are ale-py's ``AtariVectorEnv`` arguments; ``frames_last=True`` with
    ``stack_num=1`` gives ``(H, W, C)`` frames as SB3's ``AtariWrapper`` does.

    >>> venv = AtariVecEnv("ALE/Breakout-v5", n_envs=2)  # doctest: +SKIP
    >>> venv.reset().shape  # doctest: +SKIP
    (2, 4, 84, 84)
    """

    def __init__(
        self, env_id: str, n_envs: int = 1, *, frames_last: bool = False, **settings: Any
    ) -> None:
        game, defaults, self.spec = _game_and_defaults(env_id)
        options = check_settings({**defaults, **settings}, "AtariVecEnv")
        super().__init__(make_atari_engine(game, n_envs, options, frames_last), np.float32)


class AtariGameMonitor(VecMonitor):
    """A ``VecMonitor`` whose episodes are whole games with their unclipped score, as SB3's
    ``Monitor`` under ``AtariWrapper`` sees them: a lost life is not an episode end, and
    ``"l"`` is the game's length in frames (ALE's ``episode_frame_number``)."""

    def __init__(self, venv: AtariVecEnv) -> None:
        if not isinstance(venv.engine, ALEVectorEngine):
            raise TypeError("AtariGameMonitor needs an AtariVecEnv on ale-py's vector interface")
        super().__init__(venv)
        self.engine = venv.engine

    def step_wait(self) -> StepReturn:
        """Step; add ``episode`` to the infos of envs whose game ended."""
        obs, rewards, dones, infos = self.venv.step_wait()
        engine = self.engine
        self.episode_returns += engine.raw_rewards
        over = dones if engine.continuing is None else dones & ~engine.continuing
        if over.any():
            now = round(time.time() - self.t_start, 6)
            for i in np.flatnonzero(over).tolist():
                info = dict(infos[i])  # the last step's info (the reset one is in reset_infos)
                info["episode"] = {
                    "r": float(self.episode_returns[i]),
                    "l": int(info["episode_frame_number"]),
                    "t": now,
                }
                infos[i] = info
                self.episode_count += 1
                self.episode_returns[i] = 0
        return obs, rewards, dones, infos


# SB3 AtariWrapper's arguments and defaults.
_WRAPPER_DEFAULTS: dict[str, Any] = {
    "noop_max": 30,
    "frame_skip": 4,
    "screen_size": 84,
    "terminal_on_life_loss": True,
    "clip_reward": True,
    "action_repeat_probability": 0.0,
}


def atari_wrapper_settings(
    env_id: Any, wrapper_kwargs: dict[str, Any], env_kwargs: dict[str, Any]
) -> tuple[str, ALESettings] | str:
    """``(game, settings)`` that mean to ``ALEVectorInterface`` what SB3's recipe (``Monitor``,
    then ``AtariWrapper(**wrapper_kwargs)``, around ``make(env_id, **env_kwargs)``) means; or
    the reason there are none.

    Maps: ``noop_max``, ``frame_skip`` (max over the last two frames), ``screen_size``,
    ``terminal_on_life_loss`` (ALE's ``life_loss_info``: terminated, and the game goes on),
    ``clip_reward``, sticky actions (the wrapper's or the env's, not both), FIRE on reset, the
    env's frame limit and action set. The env must not skip frames itself (``frameskip=1``).

    Not frame for frame the same: ALE draws 0 to ``noop_max - 1`` no-op frames (SB3: 1 to
    ``noop_max``) from its own generator; it presses FIRE for one frame (SB3: FIRE, then action
    2, one agent step each) and not after a lost life (SB3 resets with a no-op step and FIRE);
    it max-pools grayscale frames (SB3 max-pools RGB, then converts).
    """
    if not isinstance(env_id, str):
        return "env_id is a callable, not an Atari id"

    spec = resolve_id(env_id)
    if spec.entry_point != _ATARI_ENTRY_POINT:
        return f"{env_id!r} is not an Atari id"
    kwargs = {**spec.kwargs, **env_kwargs}
    game = kwargs.pop("game")
    if kwargs.pop("frameskip", 4) != 1:
        return "the env skips frames itself (AtariWrapper expects frameskip=1)"
    env_sticky = kwargs.pop("repeat_action_probability", 0.25)
    full_action_space = kwargs.pop("full_action_space", False)
    frames = kwargs.pop("max_num_frames_per_episode", None)
    if kwargs:
        return f"env_kwargs {sorted(kwargs)} have no ALEVectorInterface counterpart"
    unknown = sorted(set(wrapper_kwargs) - set(_WRAPPER_DEFAULTS))
    if unknown:
        return f"wrapper_kwargs {unknown} are not AtariWrapper arguments"
    w = {**_WRAPPER_DEFAULTS, **wrapper_kwargs}
    sticky = w["action_repeat_probability"]
    if sticky > 0 and env_sticky > 0:
        return "both the env and the wrapper repeat actions"
    return game, ALESettings(
        repeat_action_probability=max(sticky, env_sticky),
        full_action_space=full_action_space,
        max_num_frames_per_episode=2**31 - 1 if frames is None else frames,
        img_height=w["screen_size"],
        img_width=w["screen_size"],
        stack_num=1,
        frameskip=w["frame_skip"],
        noop_max=w["noop_max"],
        life_loss_info=w["terminal_on_life_loss"],
        reward_clipping=w["clip_reward"],
    )
