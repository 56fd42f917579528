"""Training callbacks with SB3's names and hooks.

A callback sees ``self.model``, ``self.training_env``, ``self.num_timesteps``, ``self.n_calls``,
``self.logger`` and, in ``self.locals``, a small documented dict refreshed every step (not the
training loop's ``locals()``): ``actions``, ``new_obs``, ``rewards``, ``dones``, ``infos``,
``total_timesteps`` (and ``iteration`` for PPO). A plain function ``f(locals_, globals_)`` works
as a callback too; unlike SB3, a function returning ``None`` does not stop training.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from palaestra.algos.common import evaluation
from palaestra.error import InvalidCallback, dependency_not_installed
from palaestra.utils.atomic_write import atomic_write

__all__ = [
    "BaseCallback",
    "CallbackList",
    "CheckpointCallback",
    "ConvertCallback",
    "EvalCallback",
    "EventCallback",
    "EveryNTimesteps",
    "LogEveryNTimesteps",
    "ProgressBarCallback",
    "StopTrainingOnMaxEpisodes",
    "StopTrainingOnNoModelImprovement",
    "StopTrainingOnRewardThreshold",
    "convert_callback",
]


class BaseCallback:
    """Override the ``_on_*`` hooks; ``_on_step`` returns False to stop training."""

    def __init__(self, verbose: int = 0) -> None:
        self.verbose = verbose
        self.model: Any = None
        self.n_calls = 0
        self.num_timesteps = 0
        self.locals: dict[str, Any] = {}
        self.globals: dict[str, Any] = {}
        self.parent: BaseCallback | None = None

    @property
    def training_env(self) -> Any:
        return self.model.get_env()

    @property
    def logger(self) -> Any:
        return self.model.logger

    def init_callback(self, model: Any) -> None:
        self.model = model
        self._init_callback()

    def on_training_start(self, locals_: dict[str, Any], globals_: dict[str, Any]) -> None:
        self.locals, self.globals = locals_, globals_
        self.num_timesteps = self.model.num_timesteps
        self._on_training_start()

    def on_rollout_start(self) -> None:
        self._on_rollout_start()

    def on_step(self) -> bool:
        self.n_calls += 1
        self.num_timesteps = self.model.num_timesteps
        return bool(self._on_step())

    def on_rollout_end(self) -> None:
        self._on_rollout_end()

    def on_training_end(self) -> None:
        self._on_training_end()

    def update_locals(self, locals_: dict[str, Any]) -> None:
        self.locals.update(locals_)
        self.update_child_locals(locals_)

    def update_child_locals(self, locals_: dict[str, Any]) -> None:
        pass

    def _init_callback(self) -> None:
        pass

    def _on_training_start(self) -> None:
        pass

    def _on_rollout_start(self) -> None:
        pass

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        pass

    def _on_training_end(self) -> None:
        pass


class CallbackList(BaseCallback):
    """Run several callbacks in order; training stops if any returns False."""

    def __init__(self, callbacks: list[BaseCallback]) -> None:
        super().__init__()
        self.callbacks = list(callbacks)

    def _init_callback(self) -> None:
        for cb in self.callbacks:
            cb.init_callback(self.model)
            # The list's parent is its children's parent (SB3 #1791): a CallbackList passed as
            # EvalCallback(callback_on_new_best=...) gives each child the EvalCallback.
            cb.parent = self.parent

    def _on_training_start(self) -> None:
        for cb in self.callbacks:
            cb.on_training_start(self.locals, self.globals)

    def _on_rollout_start(self) -> None:
        for cb in self.callbacks:
            cb.on_rollout_start()

    def _on_step(self) -> bool:
        results = [cb.on_step() for cb in self.callbacks]  # every callback runs, as in SB3
        return all(results)

    def _on_rollout_end(self) -> None:
        for cb in self.callbacks:
            cb.on_rollout_end()

    def _on_training_end(self) -> None:
        for cb in self.callbacks:
            cb.on_training_end()

    def update_child_locals(self, locals_: dict[str, Any]) -> None:
        for cb in self.callbacks:
            cb.update_locals(locals_)


class ConvertCallback(BaseCallback):
    """Wrap ``f(locals_, globals_) -> bool | None``; only an explicit False stops training."""

    def __init__(self, callback: Callable[[dict[str, Any], dict[str, Any]], Any], verbose: int = 0):
        super().__init__(verbose)
        self.callback = callback

    def _on_step(self) -> bool:
        return self.callback(self.locals, self.globals) is not False


def convert_callback(callback: Any) -> BaseCallback:
    """``None``, a list, a function or a callback -> one ``BaseCallback``."""
    if callback is None:
        return BaseCallback()
    if isinstance(callback, list):
        return CallbackList([convert_callback(cb) for cb in callback])
    if isinstance(callback, BaseCallback):
        return callback
    expected = "a BaseCallback instance, a function f(locals, globals) or a list of them"
    if isinstance(callback, type):
        # a class is callable, but calling it with (locals, globals) builds a callback instead
        # of running one: SB3 fails there with an argument-count TypeError
        raise InvalidCallback(
            f"callback={callback!r} is a class: pass an instance, e.g. "
            f"callback={callback.__name__}(...) (expected {expected})"
        )
    if callable(callback):
        return ConvertCallback(callback)
    raise InvalidCallback(f"callback must be {expected}, got {callback!r:.200}")


class EventCallback(BaseCallback):
    """Base of callbacks that trigger ``callback`` on an event: call :meth:`_on_event` from
    ``_on_step`` when it happens (SB3's ``EventCallback``)."""

    def __init__(self, callback: BaseCallback | None = None, verbose: int = 0) -> None:
        super().__init__(verbose)
        self.callback = callback
        if callback is not None:
            callback.parent = self

    def _init_callback(self) -> None:
        if self.callback is not None:
            self.callback.init_callback(self.model)

    def _on_training_start(self) -> None:
        if self.callback is not None:
            self.callback.on_training_start(self.locals, self.globals)

    def _on_event(self) -> bool:
        return self.callback.on_step() if self.callback is not None else True

    def update_child_locals(self, locals_: dict[str, Any]) -> None:
        if self.callback is not None:
            self.callback.update_locals(locals_)


class EveryNTimesteps(BaseCallback):
    """Trigger ``callback`` every ``n_steps`` env steps."""

    def __init__(self, n_steps: int, callback: BaseCallback) -> None:
        super().__init__()
        self.n_steps, self.callback, self.last_time_trigger = n_steps, callback, 0
        callback.parent = self

    def _init_callback(self) -> None:
        self.callback.init_callback(self.model)

    def _on_training_start(self) -> None:
        self.callback.on_training_start(self.locals, self.globals)

    def _on_step(self) -> bool:
        if self.num_timesteps - self.last_time_trigger >= self.n_steps:
            self.last_time_trigger = self.num_timesteps
            return self.callback.on_step()
        return True

    def update_child_locals(self, locals_: dict[str, Any]) -> None:
        self.callback.update_locals(locals_)


class LogEveryNTimesteps(EveryNTimesteps):
    """Dump the model's logs every ``n_steps`` env steps (``model.dump_logs()``, as SB3)."""

    def __init__(self, n_steps: int) -> None:
        super().__init__(n_steps, callback=convert_callback(self._log_data))

    def _log_data(self, _locals: dict[str, Any], _globals: dict[str, Any]) -> bool:
        self.model.dump_logs()
        return True


class StopTrainingOnMaxEpisodes(BaseCallback):
    """Stop after ``max_episodes`` episodes per env (``* n_envs`` in total), as SB3."""

    def __init__(self, max_episodes: int, verbose: int = 0) -> None:
        super().__init__(verbose)
        self.max_episodes, self.n_episodes = max_episodes, 0

    def _on_step(self) -> bool:
        self.n_episodes += int(np.sum(self.locals["dones"]))
        keep = self.n_episodes < self.max_episodes * self.training_env.num_envs
        if not keep and self.verbose >= 1:
            print(f"Stopping training: reached max_episodes={self.max_episodes}")
        return keep


class StopTrainingOnRewardThreshold(BaseCallback):
    """Used as ``EvalCallback(callback_on_new_best=...)``: stop once the best mean reward of
    the evaluations reaches ``reward_threshold``."""

    def __init__(self, reward_threshold: float, verbose: int = 0) -> None:
        super().__init__(verbose)
        self.reward_threshold = reward_threshold

    def _on_step(self) -> bool:
        if not isinstance(self.parent, EvalCallback):
            raise TypeError("StopTrainingOnRewardThreshold must be used with an EvalCallback")
        keep = bool(self.parent.best_mean_reward < self.reward_threshold)
        if not keep and self.verbose >= 1:
            print(
                f"Stopping training because the mean reward {self.parent.best_mean_reward:.2f} "
                f"is above the threshold {self.reward_threshold}"
            )
        return keep


class StopTrainingOnNoModelImprovement(BaseCallback):
    """Used as ``EvalCallback(callback_after_eval=...)``: stop when more than
    ``max_no_improvement_evals`` evaluations in a row brought no new best mean reward, counting
    only after the first ``min_evals`` evaluations (SB3's rule)."""

    def __init__(self, max_no_improvement_evals: int, min_evals: int = 0, verbose: int = 0):
        super().__init__(verbose)
        self.max_no_improvement_evals = max_no_improvement_evals
        self.min_evals = min_evals
        self.last_best_mean_reward = -np.inf
        self.no_improvement_evals = 0

    def _on_step(self) -> bool:
        if not isinstance(self.parent, EvalCallback):
            raise TypeError("StopTrainingOnNoModelImprovement must be used with an EvalCallback")
        keep = True
        if self.n_calls > self.min_evals:
            if self.parent.best_mean_reward > self.last_best_mean_reward:
                self.no_improvement_evals = 0
            else:
                self.no_improvement_evals += 1
                keep = self.no_improvement_evals <= self.max_no_improvement_evals
        self.last_best_mean_reward = self.parent.best_mean_reward
        if not keep and self.verbose >= 1:
            print(
                "Stopping training because there was no new best model in the last "
                f"{self.no_improvement_evals:d} evaluations"
            )
        return keep


class CheckpointCallback(BaseCallback):
    """Save ``{name_prefix}_{steps}_steps.zip`` every ``save_freq`` calls (steps of the vec env);
    optionally the replay buffer as ``{name_prefix}_replay_buffer_{steps}_steps.zip`` and the
    ``VecNormalize`` statistics as ``{name_prefix}_vecnormalize_{steps}_steps.npz`` (SB3
    pickles both to ``.pkl``; palaestra's files are not pickles, so they are not named so)."""

    def __init__(
        self,
        save_freq: int,
        save_path: str,
        name_prefix: str = "rl_model",
        save_replay_buffer: bool = False,
        save_vecnormalize: bool = False,
        verbose: int = 0,
    ) -> None:
        super().__init__(verbose)
        self.save_freq, self.save_path, self.name_prefix = save_freq, save_path, name_prefix
        self.save_replay_buffer = save_replay_buffer
        self.save_vecnormalize = save_vecnormalize

    def _init_callback(self) -> None:
        os.makedirs(self.save_path, exist_ok=True)

    def _checkpoint_path(self, kind: str = "", extension: str = "zip") -> str:
        return os.path.join(
            self.save_path, f"{self.name_prefix}_{kind}{self.num_timesteps}_steps.{extension}"
        )

    def _on_step(self) -> bool:
        if self.n_calls % self.save_freq == 0:
            path = self._checkpoint_path()
            self.model.save(path)
            if self.verbose >= 2:
                print(f"Saving model checkpoint to {path}")
            if self.save_replay_buffer and getattr(self.model, "replay_buffer", None) is not None:
                self.model.save_replay_buffer(self._checkpoint_path("replay_buffer_"))
            normalize = _vec_normalize(self.model)
            if self.save_vecnormalize and normalize is not None:
                path = self._checkpoint_path("vecnormalize_", "npz")
                normalize.save(path)
                if self.verbose >= 2:
                    print(f"Saving model VecNormalize to {path}")
        return True


class EvalCallback(BaseCallback):
    """Evaluate every ``eval_freq`` calls; log ``eval/mean_reward``, keep the best model."""

    def __init__(
        self,
        eval_env: Any,
        callback_on_new_best: BaseCallback | None = None,
        callback_after_eval: BaseCallback | None = None,
        n_eval_episodes: int = 5,
        eval_freq: int = 10000,
        log_path: str | None = None,
        best_model_save_path: str | None = None,
        deterministic: bool = True,
        render: bool = False,
        verbose: int = 1,
        warn: bool = True,
    ) -> None:
        super().__init__(verbose)
        self.eval_env, self.n_eval_episodes, self.eval_freq = eval_env, n_eval_episodes, eval_freq
        self.callback_on_new_best, self.callback_after_eval = (
            callback_on_new_best,
            callback_after_eval,
        )
        for cb in (callback_on_new_best, callback_after_eval):
            if cb is not None:
                cb.parent = self
        self.log_path = os.path.join(log_path, "evaluations") if log_path else None
        self.best_model_save_path = best_model_save_path
        self.deterministic, self.render, self.warn = deterministic, render, warn
        self.best_mean_reward, self.last_mean_reward = -np.inf, -np.inf
        self.evaluations_timesteps: list[int] = []
        self.evaluations_results: list[list[float]] = []
        self.evaluations_length: list[list[int]] = []
        self._is_success_buffer: list[bool] = []  # info["is_success"] of this evaluation
        self.evaluations_successes: list[list[bool]] = []

    def _log_success_callback(self, locals_: dict[str, Any], globals_: dict[str, Any]) -> None:
        """Collect ``info["is_success"]`` at each episode end (SB3's success rate)."""
        if locals_["done"]:
            success = locals_["info"].get("is_success")
            if success is not None:
                self._is_success_buffer.append(success)

    def _init_callback(self) -> None:
        from palaestra.vec_env import VecMonitor, engine_vec_env  # lazy: import-time — cloudpickle

        def face(env: Any) -> Any:
            while isinstance(env, VecMonitor):  # where SB3 has a Monitor on each env
                env = env.venv
            return env

        # SB3 evaluates a single env in a DummyVecEnv, and warns when the training env is
        # another type of VecEnv (a VecNormalize on one side only...): results would differ.
        # palaestra picks the engine (a native batch for a built-in id, where SB3 always has a
        # DummyVecEnv) and make_vec_env adds a VecMonitor: engine faces count as one type.
        eval_env = face(self.eval_env)
        vectorized = hasattr(eval_env, "step_async") and hasattr(eval_env, "num_envs")
        plain = not vectorized or isinstance(eval_env, engine_vec_env.EngineVecEnv)
        eval_type = engine_vec_env.EngineVecEnv if plain else type(eval_env)
        if not isinstance(face(self.training_env), eval_type):
            warnings.warn(
                "Training and eval env are not of the same type"
                f"{self.training_env} != {self.eval_env}",
                stacklevel=2,
            )
        for path in (self.best_model_save_path, self.log_path and os.path.dirname(self.log_path)):
            if path:
                os.makedirs(path, exist_ok=True)
        for cb in (self.callback_on_new_best, self.callback_after_eval):
            if cb is not None:
                cb.init_callback(self.model)

    def _on_step(self) -> bool:
        if self.eval_freq <= 0 or self.n_calls % self.eval_freq != 0:
            return True
        if _vec_normalize(self.model) is not None:
            # SB3 evaluates with the training env's normalisation statistics: without this the
            # eval env's VecNormalize keeps its own (never updated) ones, and eval rewards,
            # best_model and threshold stopping are wrong.
            from palaestra.vec_env.util import (  # lazy: import-time — cloudpickle
                sync_envs_normalization,
            )

            try:
                sync_envs_normalization(self.training_env, self.eval_env)
            except AttributeError as e:
                raise AssertionError(
                    "Training and eval env are not wrapped the same way (both need the same "
                    "VecEnvWrapper layers, VecNormalize included)"
                ) from e
        self._is_success_buffer = []
        result: Any = evaluation.evaluate_policy(
            self.model,
            self.eval_env,
            n_eval_episodes=self.n_eval_episodes,
            deterministic=self.deterministic,
            render=self.render,
            return_episode_rewards=True,
            warn=self.warn,
            callback=self._log_success_callback,
        )
        rewards, lengths = result
        self.evaluations_timesteps.append(self.num_timesteps)
        self.evaluations_results.append([float(r) for r in rewards])
        self.evaluations_length.append([int(n) for n in lengths])
        if self.log_path is not None:
            # np.savez's own naming (".npz" added), written atomically.
            path = self.log_path if self.log_path.endswith(".npz") else self.log_path + ".npz"
            successes: dict[str, Any] = {}
            if self._is_success_buffer:
                self.evaluations_successes.append(self._is_success_buffer)
                successes["successes"] = self.evaluations_successes
            with atomic_write(path, "wb") as file:
                np.savez(
                    file,
                    timesteps=self.evaluations_timesteps,
                    results=self.evaluations_results,
                    ep_lengths=self.evaluations_length,
                    **successes,
                )
        mean_reward, std_reward = float(np.mean(rewards)), float(np.std(rewards))
        mean_length, std_length = float(np.mean(lengths)), float(np.std(lengths))
        self.last_mean_reward = mean_reward
        if self.verbose >= 1:
            print(
                f"Eval num_timesteps={self.num_timesteps}, "
                f"episode_reward={mean_reward:.2f} +/- {std_reward:.2f}"
            )
            print(f"Episode length: {mean_length:.2f} +/- {std_length:.2f}")
        self.logger.record("eval/mean_reward", mean_reward)
        self.logger.record("eval/mean_ep_length", mean_length)
        if self._is_success_buffer:
            success_rate = float(np.mean(self._is_success_buffer))
            if self.verbose >= 1:
                print(f"Success rate: {100 * success_rate:.2f}%")
            self.logger.record("eval/success_rate", success_rate)
        self.logger.record("time/total_timesteps", self.num_timesteps, exclude="tensorboard")
        self.logger.dump(self.num_timesteps)
        keep = True
        if mean_reward > self.best_mean_reward:
            if self.verbose >= 1:
                print("New best mean reward!")
            if self.best_model_save_path is not None:
                self.model.save(os.path.join(self.best_model_save_path, "best_model"))
            self.best_mean_reward = mean_reward
            if self.callback_on_new_best is not None:
                keep = self.callback_on_new_best.on_step()
        if self.callback_after_eval is not None:
            keep = self.callback_after_eval.on_step() and keep
        return keep

    def update_child_locals(self, locals_: dict[str, Any]) -> None:
        for cb in (self.callback_on_new_best, self.callback_after_eval):
            if cb is not None:
                cb.update_locals(locals_)


def _vec_normalize(model: Any) -> Any:
    """The ``VecNormalize`` layer of the model's env, or None (SB3's
    ``model.get_vec_normalize_env()``)."""
    getter = getattr(model, "get_vec_normalize_env", None)
    if getter is not None:
        return getter()
    from palaestra.vec_env import VecEnv, unwrap_vec_normalize  # lazy: import-time — cloudpickle

    env = model.get_env()
    return unwrap_vec_normalize(env) if isinstance(env, VecEnv) else None


class ProgressBarCallback(BaseCallback):
    """A tqdm bar over the timesteps of this ``learn`` call (tqdm only; SB3 also needs rich)."""

    def __init__(self) -> None:
        super().__init__()
        try:
            from tqdm.auto import tqdm
        except ImportError as exc:
            raise dependency_not_installed("tqdm", "progress", "progress_bar=True") from exc
        self._tqdm = tqdm
        self.pbar: Any = None

    def _on_training_start(self) -> None:
        self.pbar = self._tqdm(total=self.locals["total_timesteps"] - self.model.num_timesteps)

    def _on_step(self) -> bool:
        self.pbar.update(self.model.n_envs)
        return True

    def _on_training_end(self) -> None:
        self.pbar.refresh()
        self.pbar.close()
