"""Evaluate a saved model on the env its run trained on, rebuilt the way the run built it.

Episodes are played by :func:`palaestra.algos.evaluate_policy` on a one-env copy of the run's
recipe (Monitor returns: a reward-shaping wrapper changes what the agent learned from, not
what is reported; for SB3's Atari recipe an episode is a whole game), observations normalized
with the run's saved statistics (``best_vecnormalize.npz`` for ``best_model.zip``: the ones it
was evaluated with during training). The first reset gets ``seed``; later ones continue its
generator.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from palaestra.core import Wrapper
from palaestra.runs import folder, recipe
from palaestra.runs.errors import RunError
from palaestra.runs.files import (
    BEST_MODEL_FILE,
    BEST_NORMALIZE_FILE,
    MODEL_FILE,
    NORMALIZE_FILE,
    is_goal_env,
    model_file,
)
from palaestra.runs.settings import ALGO_CLASSES, algo_class

__all__ = [
    "EvalResult",
    "evaluate_run",
    "load_model",
    "make_eval_env",
    "normalized_like",
    "play_episodes",
]


@dataclasses.dataclass
class EvalResult:
    """Per-episode returns, lengths (agent steps) and whether each episode terminated (rather
    than hit a time limit); ``frames`` and their real-time ``fps`` when recorded (else 0);
    ``games``: episodes are whole Atari games."""

    path: Path  # the model file
    env_id: str
    returns: list[float]
    lengths: list[int]
    terminated: list[bool]
    frames: list[np.ndarray]
    fps: float
    games: bool
    model: Any

    @property
    def mean_return(self) -> float:
        """The mean episode return."""
        return float(np.mean(self.returns))

    @property
    def success_rate(self) -> float | None:
        """The share of episodes that reached the goal, for goal envs (else None)."""
        return float(np.mean(self.terminated)) if is_goal_env(self.env_id) else None


def load_model(path: Path, device: str = "auto") -> Any:
    """A model of any algorithm the run API trains; which one comes from the file's metadata."""
    from palaestra.algos.common.model_io import read_manifest  # lazy: import-time — torch

    meta = read_manifest(path, "model").meta
    by_class = {cls: name for name, cls in ALGO_CLASSES.items()}
    algo = meta.get("algo")
    if algo not in by_class:
        raise RunError(
            f"{str(path)!r} holds a {algo!r} model",
            f"palaestra trains {', '.join(sorted(by_class))}",
        )
    return algo_class(by_class[algo]).load(path, device=device)


def _check_spaces(model: Any, venv: Any, env_id: str) -> None:
    for what, ours, theirs in (
        ("observations", model.observation_space, venv.observation_space),
        ("actions", model.action_space, venv.action_space),
    ):
        if ours != theirs:
            raise RunError(
                f"the model expects {what} {ours} but {env_id} has {theirs}",
                "pass --env with the env the model was trained on",
            )


class _FrameLog:
    """Collects a frame after each reset and each step of the one env under it: a gym wrapper
    inside the vector env for plain recipes (so an episode's last frame is kept), or the vector
    env's images for SB3's Atari recipe (whose lives end ``done`` without ending the game)."""

    def __init__(self) -> None:
        self.frames: list[Any] = []

    def wrapper(self, inner: Any) -> Any:

        log = self

        class RenderLog(Wrapper):
            def reset(self, **kwargs: Any) -> Any:
                out = self.env.reset(**kwargs)
                log.frames.append(self.env.render())
                return out

            def step(self, action: Any) -> Any:
                out = self.env.step(action)
                log.frames.append(self.env.render())
                return out

        def wrap(env: Any) -> Any:
            return RenderLog(inner(env) if inner is not None else env)

        return wrap

    def vec_wrapper(self, venv: Any) -> Any:
        from palaestra.vec_env import VecEnvWrapper  # lazy: import-time — multiprocessing

        log = self

        class VecRenderLog(VecEnvWrapper):
            def reset(self) -> Any:
                obs = self.venv.reset()
                log.frames.append(self.venv.get_images()[0])
                return obs

            def step_wait(self) -> Any:
                out = self.venv.step_wait()
                log.frames.append(self.venv.get_images()[0])
                return out

        return VecRenderLog(venv)


def _eval_env(config: dict[str, Any], seed: int | None, frames: _FrameLog | None) -> Any:
    """One env of the run's recipe, each episode under a Monitor."""
    from palaestra.vec_env import make_vec_env  # lazy: import-time — multiprocessing

    if recipe.uses_vec_pipeline(config):
        venv = recipe.make_vec(config, 1, seed, render=frames is not None)
        return venv if frames is None else frames.vec_wrapper(venv)
    kwargs = dict(config.get("env_kwargs") or {})
    if frames is not None:
        kwargs["render_mode"] = "rgb_array"
    return make_vec_env(
        config["env_id"],
        n_envs=1,
        seed=seed,
        env_kwargs=kwargs,
        wrapper_class=None if frames is None else frames.wrapper(None),
    )


def normalized_like(training_env: Any, venv: Any) -> Any:
    """``venv`` under a ``VecNormalize`` that normalizes observations as ``training_env`` (a
    ``VecNormalize``) does now, its statistics frozen and rewards left raw: SB3's eval env."""
    from palaestra.vec_env import VecNormalize  # lazy: import-time — multiprocessing

    out = VecNormalize(
        venv,
        training=False,
        norm_obs=training_env.norm_obs,
        norm_reward=False,
        clip_obs=training_env.clip_obs,
        epsilon=training_env.epsilon,
        norm_obs_keys=training_env.norm_obs_keys,  # a Dict env's normalised keys
    )
    out.obs_rms = copy.deepcopy(training_env.obs_rms)
    return out


def make_eval_env(config: dict[str, Any], training_env: Any, seed: int | None) -> Any:
    """One env of the run's recipe for evaluations during training, each episode under a
    Monitor, wrapped as ``training_env`` is in ``VecNormalize`` (so that
    ``sync_envs_normalization`` can copy the training statistics into it)."""
    from palaestra.vec_env import VecNormalize  # lazy: import-time — multiprocessing

    venv = _eval_env(config, seed, None)
    return normalized_like(training_env, venv) if isinstance(training_env, VecNormalize) else venv


def play_episodes(
    model: Any, venv: Any, episodes: int, deterministic: bool = True
) -> tuple[list[float], list[int], list[bool]]:
    """``(returns, lengths, terminated)`` of ``episodes`` Monitor episodes of ``model`` on the
    one-env ``venv`` (seed it first: ``venv.seed(seed)``), played by ``evaluate_policy``.
    Lengths count agent steps (under SB3's Atari recipe the Monitor counts frames) and an
    episode ends when the Monitor reports one, so an Atari game is all of its lives."""
    from palaestra.algos.common.evaluation import evaluate_policy  # lazy: import-time — torch

    terminated: list[bool] = []
    lengths: list[int] = []
    steps = 0

    def ended(locals_: dict[str, Any], _: dict[str, Any]) -> None:
        nonlocal steps
        steps += 1
        info = locals_["info"]
        if locals_["done"] and "episode" in info:
            terminated.append(not info.get("TimeLimit.truncated", False))
            lengths.append(steps)
            steps = 0

    returns, _ = evaluate_policy(
        model,
        venv,
        n_eval_episodes=episodes,
        deterministic=deterministic,
        callback=ended,
        return_episode_rewards=True,
        warn=False,
    )
    return [float(r) for r in returns], lengths, terminated  # type: ignore[union-attr]


def evaluate_run(
    run: str | Path,
    episodes: int = 10,
    deterministic: bool = True,
    seed: int | None = 0,
    env_id: str | None = None,
    allow_import: Sequence[str] = (),
    record: bool = False,
    device: str = "auto",
    model: Any = None,
    spec: Any = None,
) -> EvalResult:
    """Play ``episodes`` episodes of the model at ``run`` (a run folder, or a model file in
    one) on the env its run trained on, or on ``env_id``. ``allow_import``: the modules the
    run's ``config.json`` may import; ``record``: keep a frame after each reset and step;
    ``model``: an already loaded model (default: load it); ``spec``: the run's
    :class:`~palaestra.runs.spec.RunSpec` when the caller built it (its own description: not
    read back from ``config.json``)."""
    if episodes < 1:
        raise RunError(f"episodes must be at least 1, got {episodes}", "e.g. --episodes 10")
    given = Path(run) / MODEL_FILE
    path = (
        given if model is not None and spec is not None and Path(run).is_dir() else model_file(run)
    )
    if spec is not None:
        config: dict[str, Any] | None = spec.to_config()
    else:
        config = folder.find_run_config(path, allow_import, env_id)
    if model is None:
        model = load_model(path, device)
    kwargs = dict(config.get("env_kwargs") or {}) if config else {}
    if env_id is None:
        if config is None or not isinstance(config.get("env_id"), str):
            raise RunError(
                f"cannot tell which env {str(path)!r} was trained on (no config.json beside it)",
                "pass --env ID",
            )
        env_id = str(config["env_id"])
    elif config and config.get("env_id") != env_id:
        kwargs = {}  # another env: the run's env kwargs need not apply
    config = {**(config or {}), "env_id": env_id, "env_kwargs": kwargs}
    games = recipe.atari_kwargs(config) is not None
    if games and not recipe.is_atari_id(env_id):
        raise RunError(
            f"the model was trained on SB3's Atari recipe; {env_id} is not an Atari game",
            "pass --env with an Atari id",
        )
    frames = _FrameLog() if record else None
    venv = _eval_env(config, seed, frames)
    try:
        _check_spaces(model, venv, env_id)
        from palaestra.vec_env import VecNormalize  # lazy: import-time — multiprocessing

        training_env = model.get_env()
        stats = path.parent / NORMALIZE_FILE
        if path.name == BEST_MODEL_FILE and (path.parent / BEST_NORMALIZE_FILE).is_file():
            stats = path.parent / BEST_NORMALIZE_FILE
        if isinstance(training_env, VecNormalize):  # a model in training: its statistics now
            venv = normalized_like(training_env, venv)
        elif stats.is_file():
            venv = VecNormalize.load(str(stats), venv)
            venv.training, venv.norm_reward = False, False
        returns, lengths, terminated = play_episodes(model, venv, episodes, deterministic)
        fps = recipe.render_fps(venv, config) if frames is not None else 0.0
    finally:
        venv.close()
    shown: list[Any] = []
    if frames is not None:  # the reset after the last episode is not part of the recording
        shown = frames.frames[
            : sum(lengths) + (1 if recipe.uses_vec_pipeline(config) else episodes)
        ]
    return EvalResult(
        path,
        env_id,
        returns,
        lengths,
        terminated,
        shown,
        fps,
        games,
        model,
    )
