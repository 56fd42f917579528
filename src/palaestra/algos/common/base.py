"""What DQN and PPO share: env wrapping, device/threads, seeding, progress and schedules,
episode statistics, logging, ``predict``'s shape rules, and save/load (through ``saving``).

Progress and resuming: ``progress_remaining = 1 - num_timesteps / total`` as in SB3, where
``total`` is the run's budget: ``total_timesteps`` of a fresh ``learn``, and with
``reset_num_timesteps=False`` the steps already done plus the new ``total_timesteps``. So a run
stopped at step t of T and continued with ``learn(T - t, reset_num_timesteps=False)`` follows
the schedules of the run never stopped, to the bit; and a finished run given more steps trains
as if it had been planned for the larger budget from the start (a linear learning rate that
reached 0 at T picks up at ``lr0 * (1 - T / T')``), never at a silent zero learning rate.

Exact resume: a saved model holds what its ``learn`` loop needs to continue (the current
observations, a partial rollout, the counters of an unfinished collection, the generators it
draws from). ``load(path, env=venv)`` continues from the saved observations when ``venv`` is
the env the model was saved with and has not been stepped by a ``learn`` since (or had its
run state restored next to the model, as ``palaestra train --resume`` does); any other env
starts new episodes, as in SB3.
"""

from __future__ import annotations

import contextlib
import inspect
import os
import sys
import time
import warnings
from collections import deque
from collections.abc import Iterator, Mapping
from typing import Any, ClassVar

import numpy as np
import torch

from palaestra import error, spaces
from palaestra.algos.common import saving
from palaestra.algos.common.callbacks import (
    BaseCallback,
    CallbackList,
    ProgressBarCallback,
    convert_callback,
)
from palaestra.algos.common.eager_optimizer import build_optimizer
from palaestra.algos.common.logger import HumanOutputFormat, Logger, configure
from palaestra.algos.common.policies import extractor_class
from palaestra.algos.common.preprocessing import check_for_nested_spaces
from palaestra.algos.common.schedules import Schedule
from palaestra.algos.common.settings import Settings
from palaestra.algos.common.spaces_util import (
    is_image_space,
    is_vectorized_observation,
    refuse_reset_tuple,
)
from palaestra.algos.common.utils import (
    check_for_correct_spaces,
    get_device,
    get_latest_run_id,
    safe_mean,
)
from palaestra.algos.learners import Group, Learner, Net, build_learner
from palaestra.core import Env, Wrapper
from palaestra.envs.registration import make
from palaestra.wrappers.monitor import Monitor

__all__ = ["BaseAlgorithm", "maybe_make_env", "resolve_device", "round_up_steps"]


def maybe_make_env(env: Any, verbose: int) -> Any:
    """An id string made into an env (``render_mode="rgb_array"`` where the env takes it, so
    videos can be recorded); anything else returned as it is (SB3's helper)."""
    if not isinstance(env, str):
        return env
    if verbose >= 1:
        print(f"Creating environment from the given name '{env}'")
    try:
        return make(env, render_mode="rgb_array")
    except TypeError:  # the env's constructor has no render_mode
        return make(env)


def resolve_device(device: torch.device | str, policy: str | type) -> torch.device:
    """``"auto"``: cuda for CNN policies when available, else the CPU; anything else as given,
    except that a CUDA device on a machine without CUDA is the CPU (SB3's ``get_device``, so
    code written with ``device="cuda"`` runs on CPU-only machines as under SB3)."""
    if device == "auto":
        # CNNs gain from a GPU; small MLPs are faster on the CPU (no transfers per step).
        wants_gpu = policy in ("CnnPolicy", "MultiInputPolicy")
        return torch.device("cuda" if wants_gpu and torch.cuda.is_available() else "cpu")
    return get_device(device)


class BaseAlgorithm:
    """Shared state and services; subclasses build networks in ``_setup_model`` and
    implement ``learn`` and ``_predict``."""

    supported_action_spaces: tuple[type, ...] = ()
    # Policy classes the algorithm takes in place of a name (PPO/A2C: ActorCriticPolicy)
    _policy_class_base: type | None = None
    # SB3's ``policy_aliases``: the class each policy name stands for (off-policy algorithms).
    policy_aliases: ClassVar[dict[str, type[torch.nn.Module]]] = {}
    _extra_counters: tuple[str, ...] = ()
    # Constructor arguments a model file does not keep (schedules are kept apart, in
    # ``_schedules``): the policy and its kwargs have entries of their own; where to log, the
    # device and the thread count are the loading machine's, never the file's.
    _not_saved: ClassVar[frozenset[str]] = frozenset(
        {"policy", "env", "policy_kwargs", "_init_setup_model"}
        | {"tensorboard_log", "device", "num_threads"}
    )
    # Saved constructor arguments whose value lives in an attribute of another name.
    _saved_from: ClassVar[dict[str, str]] = {"stats_window_size": "_stats_window_size"}
    lr_schedule: Schedule
    learner: Learner
    _policy: torch.nn.Module
    _policy_shown: Any  # a wrapper assigned to model.policy (torch.compile's), or None
    _optimizer: torch.optim.Optimizer

    # The torch objects users and files see; reading them hands the parameters to torch
    # (``Learner.to_torch``): see ``learners.learner`` on ownership.
    @property
    def policy(self) -> Any:
        """The policy's torch module, up to date (SB3's ``model.policy``): the object last
        assigned to it, such as ``torch.compile(model.policy)``."""
        self.learner.to_torch()
        return self._policy if self._policy_shown is None else self._policy_shown

    @policy.setter
    def policy(self, value: Any) -> None:
        """SB3's ``model.policy = ...``. A wrapper of the model's own policy
        (``torch.compile``'s, with ``_orig_mod``) is what ``model.policy`` shows from then on;
        the model acts and trains through its learner on the same parameters. Another policy
        of the algorithm's family and spaces replaces the model's: the learner and the
        optimizers are built again for it (fresh optimizer state, as the policy's own
        optimizer would be in SB3), so ``predict`` and ``learn`` use it at once."""
        inner: Any = getattr(value, "_orig_mod", value)
        family = self._policy_family()
        if not isinstance(inner, family):
            raise TypeError(
                f"{type(self).__name__}.policy must be a {family.__name__} (or a module "
                f"wrapping one, such as torch.compile's), got {type(value).__name__}"
            )
        if inner is not self._policy:
            for name in ("observation_space", "action_space"):
                theirs, ours = getattr(inner, name, None), getattr(self, name)
                if theirs != ours:
                    raise ValueError(
                        f"the new policy's {name} {theirs} differs from the model's {ours}"
                    )
            self.learner.to_torch()
            self._use_policy(inner.to(self.device))
        self._policy_shown = None if value is inner else value

    def _policy_family(self) -> type[torch.nn.Module]:
        """The class a policy assigned to ``model.policy`` must be an instance of."""
        return self.policy_aliases.get("MlpPolicy", torch.nn.Module)

    def _use_policy(self, policy: Any) -> None:
        """Build the learner and optimizers for ``policy`` (each algorithm)."""
        raise NotImplementedError

    def _policy_module(self) -> torch.nn.Module:
        """The policy module itself, up to date (not a wrapper assigned to ``policy``)."""
        self.learner.to_torch()
        return self._policy

    def _set_training_mode(self, mode: bool, acting_only_in_torch: bool = True) -> None:
        """SB3's ``policy.set_training_mode``: training mode inside ``train()``, evaluation
        mode when acting (dropout off, batch norm on its running statistics). Where the numpy
        learner runs the nets, which are MLPs without such layers, the torch modules are not
        run at all and ``acting_only_in_torch`` skips the switch (it costs a module walk)."""
        if acting_only_in_torch and self.learner.backend != "torch":
            return
        if self._policy.training != mode:
            getattr(self._policy, "set_training_mode", self._policy.train)(mode)

    @property
    def optimizer(self) -> torch.optim.Optimizer:
        """The torch optimizer, with the learner's current state."""
        self.learner.to_torch()
        return self._optimizer

    def _set_learner(
        self,
        policy: torch.nn.Module,
        optimizer: torch.optim.Optimizer,
        backend: Any,
        nets: dict[str, Net],
        groups: dict[str, Group],
        joint: dict[tuple[str, ...], Any] | None = None,
    ) -> None:
        """Pick the learner for these nets (``policy_kwargs["backend"]``) and say which."""
        if not isinstance(backend, str):
            raise ValueError(f"policy_kwargs backend must be a string, got {backend!r}")
        self._policy, self._optimizer = policy, optimizer
        self._policy_shown = None  # what was assigned to model.policy, if a wrapper
        self.learner = build_learner(backend, nets, groups, self.device, joint or {})
        if self.verbose >= 1:
            print(f"Training with the {self.learner.describe()}")

    def _configure(self, arguments: Mapping[str, Any]) -> None:
        """An algorithm's whole constructor body: ``self._configure(locals())``. Each class
        takes its own arguments in ``_take_settings``; one that none takes is a ``TypeError``
        (see ``settings``). Then the networks are built, unless ``_init_setup_model`` is False."""
        settings = Settings(type(self).__name__, arguments)
        self._take_settings(settings)
        init_setup_model = settings["_init_setup_model"]
        settings.check_all_taken()
        self._setup_model_if(init_setup_model)

    def _take_settings(self, settings: Settings) -> None:
        """Take this class's constructor arguments by name and set itself up from them.
        Subclasses take theirs (checks first), call ``super()``, then do what needs the env
        (``self.env``, ``self.n_envs``). Here: the policy, env, device, threads, logging."""
        policy = settings["policy"]
        if isinstance(policy, type):
            base = self._policy_class_base
            if base is None or not issubclass(policy, base):
                article = "an" if base is not None and base.__name__[0] in "AEIOU" else "a"
                takes = (
                    "a policy name"
                    if base is None
                    else f"a policy name or {article} {base.__name__} subclass"
                )
                raise ValueError(
                    f"{type(self).__name__} takes {takes} ('MlpPolicy', 'CnnPolicy', "
                    f"'MultiInputPolicy'), got the class {policy.__name__}"
                    f"{' from ' + policy.__module__ if base is not None else ''}; custom "
                    "networks also go in policy_kwargs (features_extractor_class=..., "
                    "net_arch=...)"
                )
        else:
            extractor_class(policy)  # unknown names fail here, before any env work
        self.policy_name, self.policy_kwargs = policy, dict(settings["policy_kwargs"] or {})
        # The name an alias class stands for (DQN's MlpPolicy is DQNPolicy): it gets the
        # same device and threads as the name; a user's subclass keeps torch's defaults.
        policy = next((name for name, cls in self.policy_aliases.items() if cls is policy), policy)
        self.verbose, self.seed = settings["verbose"], settings["seed"]
        self.tensorboard_log = settings["tensorboard_log"]
        self.device = self._resolve_device(settings["device"], policy)
        if self.verbose >= 1:
            print(f"Using {self.device} device")
        # Small nets are fastest on one thread; torch's default (all cores) only adds overhead.
        num_threads = settings["num_threads"]
        threads = num_threads if num_threads is not None else (1 if policy == "MlpPolicy" else None)
        if threads is not None and self.device.type == "cpu":
            torch.set_num_threads(threads)
        self.num_timesteps, self._episode_num, self._n_updates = 0, 0, 0
        self._total_timesteps, self._num_timesteps_at_start = 0, 0
        self._progress_remaining = 1.0
        self._torch_rng_to_restore: torch.Tensor | None = None
        self._learning = False  # inside learn's loop (see _learning_session)
        self._stats_window_size = settings["stats_window_size"]
        self.ep_info_buffer: deque[dict[str, Any]] = deque(maxlen=self._stats_window_size)
        self.ep_success_buffer: deque[bool] = deque(maxlen=self._stats_window_size)
        self._rng = np.random.default_rng(self.seed)
        self._logger: Logger | None = None
        self._custom_logger = False
        self._last_obs: Any = None
        self._last_episode_starts: np.ndarray | None = None
        self.start_time = 0
        self.env: Any = None
        self.n_envs = 1
        env = settings["env"]
        if env is not None:
            self.env = self._wrap_env(env)
            self.observation_space, self.action_space = (
                self.env.observation_space,
                self.env.action_space,
            )
            self.n_envs = self.env.num_envs
            check_for_nested_spaces(self.observation_space)
            # SB3 catches the common mistake the same way (a Dict would flatten to nonsense)
            if policy in ("MlpPolicy", "CnnPolicy") and isinstance(
                self.observation_space, spaces.Dict
            ):
                raise ValueError(
                    "You must use `MultiInputPolicy` when working with dict observation space, "
                    f"not {policy}"
                )
            if not isinstance(self.action_space, self.supported_action_spaces):
                names = ", ".join(s.__name__ for s in self.supported_action_spaces)
                raise error.UnsupportedSpace(
                    f"{type(self).__name__} does not support {self.action_space} "
                    f"action spaces; supported: {names}"
                )

    # -- environment ---------------------------------------------------------------------------
    def _wrap_env(self, env: Any) -> Any:
        """Id string / Env / VecEnv -> a monitored VecEnv (SB3's ``_wrap_env``)."""
        from palaestra.vec_env import (  # lazy: import-time — cloudpickle
            DummyVecEnv,
            VecEnv,
            make_vec_env,
        )

        if isinstance(env, str):
            return make_vec_env(env, n_envs=1)  # the native batch of a built-in id, monitored
        if isinstance(env, VecEnv):
            return env
        if not isinstance(env, Env):
            raise TypeError(
                f"env must be an id string, an Env or a VecEnv, got {type(env).__name__}"
            )
        inner: Any = env
        while isinstance(inner, Wrapper) and not isinstance(inner, Monitor):
            inner = inner.env
        if not isinstance(inner, Monitor):
            if self.verbose >= 1:
                print("Wrapping the env with a `Monitor` wrapper")
            env = Monitor(env)
        if self.verbose >= 1:
            print("Wrapping the env in a DummyVecEnv.")
        return DummyVecEnv([lambda: env])

    def get_env(self) -> Any:
        """The VecEnv being trained on (None for a model loaded without one)."""
        return self.env

    def get_vec_normalize_env(self) -> Any:
        """The ``VecNormalize`` layer of the training env, or None (SB3's
        ``get_vec_normalize_env``: e.g. to save its statistics next to the model)."""
        from palaestra.vec_env import unwrap_vec_normalize  # lazy: import-time — cloudpickle

        return None if self.env is None else unwrap_vec_normalize(self.env)

    def set_env(self, env: Any, force_reset: bool = True) -> None:
        """Train on another env with the same spaces (SB3: ``ValueError`` when they differ)."""
        venv = self._wrap_env(env)
        check_for_correct_spaces(venv, self.observation_space, self.action_space)
        n_changed = venv.num_envs != self.n_envs
        self.env, self.n_envs = venv, venv.num_envs
        if n_changed:
            self._on_n_envs_changed()
        if force_reset or n_changed:
            self._last_obs = None

    def _on_n_envs_changed(self) -> None:
        """Rebuild per-env buffers (subclasses)."""

    def _on_env_reset(self, restart: bool) -> None:
        """``learn`` is about to reset the env (``restart``: and the step count): drop what an
        unfinished collection left that only fits the old episodes (subclasses)."""

    def _loop_state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """What an unfinished collection holds, for the model file (subclasses)."""
        return {}, {}

    def _load_loop_state(self, meta: Any, arrays: dict[str, np.ndarray]) -> None:
        """Restore ``_loop_state`` output; ``ValueError``/``KeyError`` if it does not fit."""

    def _sde_matrix_shape(self) -> tuple[int, ...] | None:
        """The shape of one gSDE exploration matrix (None without gSDE), which a model file's
        run state may hold."""
        return None

    def _make_optimizer(
        self,
        params: list[torch.nn.Parameter],
        optimizer_class: type,
        optimizer_kwargs: dict[str, Any],
    ) -> torch.optim.Optimizer:
        """SB3's optimizer choice; Adam on the CPU runs fused (one kernel for all tensors:
        the per-tensor loop costs more than the math for small nets) unless told otherwise.
        Built without importing torch's compiler (``eager_optimizer``: seconds at start-up)."""
        kwargs = dict(optimizer_kwargs)
        lr = self.lr_schedule(1.0)
        fusable = optimizer_class is torch.optim.Adam and self.device.type == "cpu"
        if fusable and "fused" not in kwargs and "foreach" not in kwargs:
            try:
                return build_optimizer(optimizer_class, params, lr=lr, fused=True, **kwargs)
            except (RuntimeError, TypeError, ValueError):  # older torch: no fused CPU Adam
                pass
        return build_optimizer(optimizer_class, params, lr=lr, **kwargs)

    def _setup_model(self) -> None:
        """Build the policy, the learner and any buffer (each algorithm)."""
        raise NotImplementedError

    def _setup_model_if(self, init_setup_model: bool) -> None:
        """Build the networks now (SB3's ``_init_setup_model``), which needs an env."""
        if not init_setup_model:
            return
        if self.env is None:
            raise ValueError(
                f"{type(self).__name__} needs an env (an id string, an Env or a VecEnv)"
            )
        self._setup_model()

    # -- device, seeding ---------------------------------------------------------------------
    def _resolve_device(self, device: torch.device | str, policy: str | type) -> torch.device:
        return resolve_device(device, policy)

    def set_random_seed(self, seed: int | None = None) -> None:
        """Seed torch, this model's generator, the action space and the env's next reset."""
        if seed is None:
            return
        torch.manual_seed(seed)
        self._rng = np.random.default_rng(seed)
        self.action_space.seed(seed)
        if self.env is not None:
            self.env.seed(seed)

    # -- learn bookkeeping ---------------------------------------------------------------------
    def final_timesteps(self, total_timesteps: int) -> int:
        """The step count ``learn`` stops at when it trains on to ``total_timesteps`` steps in
        all (``learn(total_timesteps - num_timesteps, reset_num_timesteps=False)``): every env
        steps at once, so the count rises by ``n_envs``; on-policy algorithms finish their
        rollout and off-policy ones their ``train_freq`` collection (SB3's loops, which check
        the budget only between two of them)."""
        return round_up_steps(self.num_timesteps, self.num_timesteps, total_timesteps, self.n_envs)

    def _setup_learn(
        self,
        total_timesteps: int,
        callback: Any,
        reset_num_timesteps: bool,
        tb_log_name: str,
        progress_bar: bool,
    ) -> BaseCallback:
        if isinstance(total_timesteps, bool) or not isinstance(total_timesteps, (int, np.integer)):
            raise TypeError(f"total_timesteps must be an int, got {total_timesteps!r}")
        if total_timesteps <= 0:
            raise ValueError(f"total_timesteps must be positive, got {total_timesteps}")
        if self.env is None:
            raise ValueError("This model has no environment: pass env= to load() or call set_env()")
        self.start_time = time.time_ns()
        saving.forget_env_token(self.env)  # stepping it ends "as saved"
        if reset_num_timesteps or self._last_obs is None:
            if reset_num_timesteps:
                self.num_timesteps, self._episode_num = 0, 0
                self.ep_info_buffer.clear()
                self.ep_success_buffer.clear()
            self._on_env_reset(restart=reset_num_timesteps)
            self._last_obs = self.env.reset()
            self._last_episode_starts = np.ones((self.env.num_envs,), dtype=bool)
        elif self._torch_rng_to_restore is not None:
            # A loaded model continuing its run draws on from where it was saved.
            torch.set_rng_state(self._torch_rng_to_restore)
        self._torch_rng_to_restore = None
        self._num_timesteps_at_start = self.num_timesteps
        self._total_timesteps = self.num_timesteps + int(total_timesteps)
        self._update_progress()
        lr = self.lr_schedule(self._progress_remaining)
        if lr == 0:
            warnings.warn(
                f"the learning rate is 0 at the start of this learn call (progress remaining "
                f"{self._progress_remaining:.3g}): updates will not change the weights",
                stacklevel=3,
            )
        if not self._custom_logger:
            self._logger = self._make_logger(tb_log_name, reset_num_timesteps)
        cb = convert_callback(callback)
        if progress_bar:
            cb = CallbackList([cb, ProgressBarCallback()])
        cb.init_callback(self)
        return cb

    @contextlib.contextmanager
    def _learning_session(self) -> Iterator[None]:
        """Marks the body of ``learn``: a model saved from a callback inside it keeps no
        observations to continue from (the env moves on after the save). At its end the torch
        modules are brought up to date, so a reference to ``model.policy`` kept from before
        sees the trained parameters."""
        self._learning = True
        try:
            yield
        finally:
            self._learning = False
            self.learner.to_torch()

    def _update_progress(self) -> None:
        """SB3's ``1 - num_timesteps / total``, one formula for fresh, resumed and extended
        runs (so a resumed run computes exactly the values the uninterrupted one did)."""
        progress = 1.0 - float(self.num_timesteps) / float(self._total_timesteps)
        self._progress_remaining = max(progress, 0.0)  # the last rollout may overshoot

    def _update_learning_rate(self, group: str) -> float:
        lr = self.lr_schedule(self._progress_remaining)
        self.learner.set_learning_rate(group, lr)
        self.logger.record("train/learning_rate", lr)
        return lr

    def _stepped(
        self,
        callback: BaseCallback,
        actions: Any,
        new_obs: Any,
        rewards: np.ndarray,
        dones: np.ndarray,
        infos: list[dict[str, Any]],
    ) -> bool:
        """Count an env step, show it to the callbacks (SB3's ``locals`` keys) and note the
        episodes it finished; whether to keep training."""
        self.num_timesteps += self.n_envs
        callback.update_locals(
            dict(actions=actions, new_obs=new_obs, rewards=rewards, dones=dones, infos=infos)
        )
        running = bool(callback.on_step())
        self._update_info_buffer(infos, dones)
        return running

    def _update_info_buffer(self, infos: list[dict[str, Any]], dones: np.ndarray) -> None:
        """Note finished episodes (``episode``) and, where an env is done, ``is_success``."""
        for info in infos:
            episode = info.get("episode")
            if episode is not None:
                self.ep_info_buffer.append(episode)
        if np.count_nonzero(dones):  # runs every env step: the success scan only at ends
            for i in np.flatnonzero(dones).tolist():
                success = infos[i].get("is_success")
                if success is not None:
                    self.ep_success_buffer.append(bool(success))

    # -- logging -------------------------------------------------------------------------------
    @property
    def logger(self) -> Logger:
        if self._logger is None:
            self._logger = Logger(None, [])
        return self._logger

    def set_logger(self, logger: Logger) -> None:
        """Use ``logger`` (e.g. ``configure(folder, ["stdout", "csv"])``) for every ``learn``."""
        self._logger, self._custom_logger = logger, True

    def _make_logger(self, tb_log_name: str, reset_num_timesteps: bool) -> Logger:
        formats = ["stdout"] if self.verbose >= 1 else []
        if self.tensorboard_log is None:
            # stdout only: no folder to create (SB3 makes an empty temp dir here)
            return Logger(None, [HumanOutputFormat(sys.stdout)] if formats else [])
        latest = get_latest_run_id(self.tensorboard_log, tb_log_name)
        # Going on (reset_num_timesteps=False) writes into the latest run's folder; with none
        # yet, into _1 (SB3: _0)
        run_id = latest + (1 if reset_num_timesteps or latest == 0 else 0)
        folder = os.path.join(self.tensorboard_log, f"{tb_log_name}_{run_id}")
        return configure(folder, [*formats, "tensorboard"])

    def _record_episode_stats(self) -> None:
        elapsed = max((time.time_ns() - self.start_time) / 1e9, sys.float_info.epsilon)
        fps = int((self.num_timesteps - self._num_timesteps_at_start) / elapsed)
        if self.ep_info_buffer:
            self.logger.record(
                "rollout/ep_rew_mean", safe_mean([e["r"] for e in self.ep_info_buffer])
            )
            self.logger.record(
                "rollout/ep_len_mean", safe_mean([e["l"] for e in self.ep_info_buffer])
            )
        self.logger.record("time/fps", fps)
        self.logger.record("time/time_elapsed", int(elapsed), exclude="tensorboard")
        self.logger.record("time/total_timesteps", self.num_timesteps, exclude="tensorboard")
        if self.ep_success_buffer:
            self.logger.record(
                "rollout/success_rate", safe_mean([float(s) for s in self.ep_success_buffer])
            )

    def _callback_locals(self, **values: Any) -> dict[str, Any]:
        return {"total_timesteps": self._total_timesteps, **values}

    # -- predict -------------------------------------------------------------------------------
    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
    ) -> tuple[np.ndarray, Any]:
        """Actions for one observation or a batch ``[n_env, *obs_shape]`` (SB3's rules)."""
        refuse_reset_tuple(observation)
        vectorized = is_vectorized_observation(observation, self.observation_space)
        if not vectorized:
            if isinstance(observation, dict):
                observation = {k: np.asarray(v)[None] for k, v in observation.items()}
            else:
                observation = np.asarray(observation)[None]
        self._set_training_mode(False, acting_only_in_torch=False)
        actions = self._predict(observation, deterministic)
        actions = actions.reshape((-1, *(self.action_space.shape or ())))
        if isinstance(self.action_space, spaces.Box):
            actions = np.clip(actions, self.action_space.low, self.action_space.high)
        else:
            actions = actions.astype(self.action_space.dtype, copy=False)
        return (actions if vectorized else actions.squeeze(axis=0)), state

    def _predict(self, observation: Any, deterministic: bool) -> np.ndarray:
        raise NotImplementedError

    # -- persistence: see saving.py ------------------------------------------------------------
    def save(self, path: Any, exclude: Any = None, include: Any = None) -> None:
        """Write the model (hyperparameters, spaces, weights, optimizer, counters) as a zip.

        ``exclude``: attribute names to leave out (SB3's ``save``: hyperparameters such as
        ``"verbose"``, schedules, counters, ``"policy_kwargs"``...; a loaded model gets the
        constructor's defaults for them); ``include`` takes names back out of ``exclude``.
        Weights and optimizer states are always written."""
        saving.save_model(self, path, exclude, include)

    @classmethod
    def load(
        cls,
        path: Any,
        env: Any = None,
        device: torch.device | str = "auto",
        custom_objects: dict[str, Any] | None = None,
        print_system_info: bool = False,
        **kwargs: Any,
    ) -> Any:
        """Rebuild a saved model; never unpickles. ``custom_objects`` overrides stored values
        (names the model does not save are ignored, as in SB3); ``print_system_info`` prints
        this system's versions and those the file was saved with; ``policy_kwargs`` may be
        passed when it equals the stored one (``ValueError`` otherwise, as in SB3); other
        ``kwargs`` set hyperparameters. Any model ``save`` wrote loads, whatever its size."""
        custom = custom_objects or {}
        return saving.load_model(cls, path, env, device, custom, kwargs, print_system_info)

    def _hyperparameters(self) -> dict[str, Any]:
        """What a model file keeps of the constructor's arguments, at their current values (so
        one changed on the model before ``save`` is saved as changed): every argument of this
        class's constructor but ``_not_saved`` and the schedules."""
        skip = self._not_saved | set(self._schedules())
        names = _constructor_arguments(type(self))
        return {name: self._saved_value(name) for name in names if name not in skip}

    def _saved_value(self, name: str) -> Any:
        """The value of the constructor argument ``name`` a model file keeps."""
        value = getattr(self, self._saved_from.get(name, name))
        return list(value) if isinstance(value, tuple) else value  # as JSON gives it back

    def _schedules(self) -> dict[str, Any]:
        """The schedules a model file keeps, by constructor argument."""
        return {"learning_rate": self.lr_schedule}

    def _optimizers(self) -> dict[str, tuple[str, torch.optim.Optimizer]]:
        """Each optimizer by its model-file key, with SB3's ``get_parameters`` key."""
        return {"optimizer": ("policy.optimizer", self.optimizer)}

    def get_parameters(self) -> dict[str, dict[str, Any]]:
        """``{"policy": state_dict, "policy.optimizer": optimizer state_dict}`` (SB3's keys;
        SAC: ``actor.optimizer``, ``critic.optimizer``, ``ent_coef_optimizer``)."""
        params = {"policy": self._policy_module().state_dict()}
        for _, (name, optimizer) in self._optimizers().items():
            params[name] = optimizer.state_dict()
        return params

    def set_parameters(
        self, load_path_or_dict: Any, exact_match: bool = True, device: torch.device | str = "auto"
    ) -> None:
        """Load parameters from ``get_parameters()`` output or from a model file.

        With ``exact_match`` (SB3's default) every object of ``get_parameters()`` must be
        given, and each module's parameters exactly: ``ValueError`` otherwise, raised before
        anything is changed. A name that is not an object of the model is always a
        ``ValueError``."""
        saving.set_parameters(self, load_path_or_dict, exact_match)

    def _uses_images(self) -> bool:
        sub = getattr(self.observation_space, "spaces", {"": self.observation_space})
        return any(is_image_space(s) for s in sub.values())


def _constructor_arguments(cls: type) -> list[str]:
    """The argument names ``cls(...)`` takes: its ``__init__``'s, and where that passes on
    ``**kwargs`` (a subclass changing a few defaults), those of the class above it too."""
    names: list[str] = []
    named = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    for klass in cls.__mro__:
        init = vars(klass).get("__init__")
        if init is None:
            continue
        params = list(inspect.signature(init).parameters.values())[1:]  # without self
        names += [p.name for p in params if p.kind in named and p.name not in names]
        if all(p.kind is not inspect.Parameter.VAR_KEYWORD for p in params):
            break
    return names


def round_up_steps(start: int, now: int, total: int, chunk: int) -> int:
    """Where a loop that runs whole ``chunk``-step pieces from step ``start`` while the count is
    below ``total`` stops, being at step ``now`` (``start <= now``).

    >>> round_up_steps(0, 0, 5000, 4096), round_up_steps(0, 4096, 4096, 4096)
    (8192, 4096)
    """
    if now >= total:
        return now
    return start + -(-(total - start) // chunk) * chunk
