"""The SB3 face over the vector engines: ``DummyVecEnv``, ``SubprocVecEnv``, ``BatchedVecEnv``.

Each is :class:`EngineVecEnv` over one engine of :mod:`palaestra.vector.engine`, driven in
SAME_STEP autoreset mode by the same :class:`~palaestra.vector.autoreset.Autoresetter` the
Gymnasium face uses; this module only reshapes a step into SB3's ``(obs, rewards, dones,
infos)`` with ``terminal_observation`` and ``TimeLimit.truncated``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from copy import deepcopy
from typing import TYPE_CHECKING, Any

import numpy as np

from palaestra import error
from palaestra.core import Env
from palaestra.spaces import Box, Dict, Discrete, MultiBinary, MultiDiscrete, Tuple
from palaestra.spaces.batched_samples import concatenate, create_empty_array
from palaestra.utils.run_state import State, supports_run_state
from palaestra.vec_env.base import Indices, StepReturn, VecEnv
from palaestra.vector.autoreset import Autoresetter, Transition
from palaestra.vector.engine import Engine, LoopEngine
from palaestra.vector.native_engine import NativeEngine
from palaestra.vector.process_engine import ProcessEngine
from palaestra.vector.vector_env import AutoresetMode

if TYPE_CHECKING:  # the env modules load only when a batch is made
    from palaestra.vector.native_engine import NativeBatch

__all__ = ["BatchedVecEnv", "DummyVecEnv", "EngineVecEnv", "SubprocVecEnv"]

# Single action spaces whose batch is an array indexed by row (SB3's and the engines' views
# of a batch agree); every other space batches into a tuple or dict of per-component arrays.
_ROW_SPACES = (Box, Discrete, MultiBinary, MultiDiscrete)


class EngineVecEnv(VecEnv):
    """An SB3 ``VecEnv`` whose envs are run by ``engine``; rewards come as ``reward_dtype``."""

    RUN_STATE = ("_driver", "_seeds")  # exact resume, where the engine has a run state

    def __init__(self, engine: Engine, reward_dtype: Any = np.float32) -> None:
        self.engine = engine
        self.closed = False
        self._driver = Autoresetter(engine, AutoresetMode.SAME_STEP)
        self._reward_dtype = np.dtype(reward_dtype)
        super().__init__(
            engine.num_envs, engine.single_observation_space, engine.single_action_space
        )

    def _check_open(self) -> None:
        # The engine closes itself when a worker dies: refuse from then on too.
        if self.closed or getattr(self.engine, "closed", False):
            raise error.ClosedEnvironmentError(
                f"Trying to operate on `{type(self).__name__}`, after a call to `close()`."
            )

    @staticmethod
    def _copy(obs: Any) -> Any:
        return obs.copy() if isinstance(obs, np.ndarray) else deepcopy(obs)

    def reset(self) -> Any:
        """Reset every env with the seeds/options set since the last reset."""
        self._check_open()
        n = self.num_envs
        if all(opts == self._options[0] for opts in self._options):
            obs, infos = self._driver.reset(self._seeds, self._options[0] or None)
            self.reset_infos = list(infos) if infos is not None else [{} for _ in range(n)]
        else:  # per-env options: one reset per env (rare, so the loop is fine)
            self.reset_infos = [{} for _ in range(n)]
            for i in range(n):
                mask = np.zeros(n, dtype=bool)
                mask[i] = True
                opts = {**self._options[i], "reset_mask": mask}
                obs, infos = self._driver.reset(self._seeds, opts)
                self.reset_infos[i] = infos[i] if infos is not None else {}
        self._reset_seeds()
        self._reset_options()
        return self._copy(obs)

    def step_async(self, actions: np.ndarray) -> None:
        """Send one action per env: ``actions[i]`` goes to env ``i``, as in SB3."""
        self._check_open()
        self._driver.begin_step(self._batched_actions(actions))

    def _batched_actions(self, actions: Any) -> Any:
        """SB3 indexes ``actions[i]`` for env i; the engines take an element of the batched
        action space. The two differ for composite spaces: a list of per-env Tuple or Dict
        actions becomes the batched tuple/dict here (passing it on unchanged would transpose
        Tuple actions between envs and leave envs unstepped, with no error)."""
        if isinstance(self.action_space, _ROW_SPACES):
            shape = tuple(self.action_space.shape or ())
            if self.num_envs == 1 and shape and np.shape(actions) == shape:
                # One env's action without the batch axis: SB3's DummyVecEnv takes it too
                return np.asarray(actions)[None]
            return actions  # array spaces index by row already
        if not isinstance(actions, (list, tuple)):
            return actions  # a dict is a batched Dict
        if len(actions) != self.num_envs:
            raise error.InvalidAction(
                f"Expected {self.num_envs} actions (one per env) for action space "
                f"{self.action_space}, got {len(actions)}: {actions!r}"
            )
        return concatenate(
            self.engine.single_action_space,
            actions,
            create_empty_array(self.engine.single_action_space, n=self.num_envs),
        )

    def step_wait(self) -> StepReturn:
        """``(obs, rewards, dones, infos)``; finished envs are already reset."""
        self._check_open()
        t = self._driver.finish_step()
        dones = t.terminated | t.truncated  # [N] bool, a new array
        return (
            self._copy(t.obs),
            t.rewards.astype(self._reward_dtype),
            dones,
            self._sb3_infos(t),
        )

    def _sb3_infos(self, t: Transition) -> list[dict[str, Any]]:
        # SB3 sets TimeLimit.truncated on every info: truncated and not terminated
        # (the gym 0.26 split, openai/gym#3102).
        # (SAME_STEP: no final rows means no row ended, so none was truncated.)
        if t.final_rows is not None and np.count_nonzero(t.truncated):
            time_limit = (t.truncated & ~t.terminated).tolist()
        else:  # most steps: no row out of time (no call, or one instead of three)
            time_limit = [False] * self.num_envs
        if t.infos is None:
            infos = [{"TimeLimit.truncated": tl} for tl in time_limit]
        else:
            infos = [{**info, "TimeLimit.truncated": tl} for info, tl in zip(t.infos, time_limit)]
        if t.final_rows is None:
            return infos
        assert t.final_obs is not None and t.final_infos is not None
        for j, i in enumerate(t.final_rows.tolist()):
            # The row's step info, not its reset info (that goes to reset_infos).
            self.reset_infos[i] = t.infos[i] if t.infos is not None else {}
            infos[i] = {
                **t.final_infos[j],
                "TimeLimit.truncated": time_limit[i],
                "terminal_observation": t.final_obs[j],
            }
        return infos

    def get_run_state(self) -> State:
        """The engine's rows, generators and counters (native batches only: the state of
        arbitrary Python envs is not palaestra's to see)."""
        if not supports_run_state(self.engine):
            raise error.RunStateError(
                f"{type(self).__name__} cannot save its envs' state (they are Python objects "
                "palaestra cannot see into); exact resume needs a native batch "
                "(make_vec_env on a built-in id, without wrapper_class)"
            )
        return super().get_run_state()

    def close(self) -> None:
        """Close the envs (and stop workers); idempotent."""
        if not self.closed:
            self.closed = True
            self.engine.close()

    def get_attr(self, attr_name: str, indices: Indices = None) -> list[Any]:
        """Attribute ``attr_name`` of each env in ``indices``."""
        self._check_open()
        return list(self.engine.call(attr_name, (), {}, self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: Indices = None) -> None:
        """Set ``attr_name`` to ``value`` on each env in ``indices``."""
        self._check_open()
        rows = self._get_indices(indices)
        self.engine.set_attr(attr_name, [value] * len(rows), rows)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Indices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Call ``method_name(*method_args, **method_kwargs)`` on each env in ``indices``."""
        self._check_open()
        rows = self._get_indices(indices)
        return list(self.engine.call(method_name, method_args, method_kwargs, rows))

    def env_is_wrapped(self, wrapper_class: type, indices: Indices = None) -> list[bool]:
        """Whether each env in ``indices`` has a ``wrapper_class`` layer."""
        self._check_open()
        return self.engine.is_wrapped(wrapper_class, self._get_indices(indices))

    def __del__(self) -> None:
        if not getattr(self, "closed", True):
            try:
                self.close()
            except Exception:  # interpreter shutdown
                pass


class DummyVecEnv(EngineVecEnv):
    """Envs in this process, stepped in a loop (SB3's signature; rewards float32)."""

    def __init__(self, env_fns: Sequence[Callable[[], Env[Any, Any]]]) -> None:
        engine = LoopEngine(env_fns, "same", "DummyVecEnv")
        if len({id(env.unwrapped) for env in engine.envs}) != len(engine.envs):
            # SB3's check (DLR-RM/stable-baselines3#1151): N views of one env step it N times.
            raise ValueError(
                "You tried to create multiple environments, but the function to create them "
                "returned the same instance instead of creating different objects. You are "
                "probably using `make_vec_env(lambda: env)` or `DummyVecEnv([lambda: env] * "
                "n_envs)`. You should replace `lambda: env` by a `make_env` function that "
                "creates a new instance of the environment at every call (using `gym.make()` "
                "for instance)."
            )
        space = engine.single_observation_space
        subs = space.spaces.values() if isinstance(space, Dict) else getattr(space, "spaces", ())
        if isinstance(space, (Dict, Tuple)) and any(isinstance(s, (Dict, Tuple)) for s in subs):
            engine.close()
            # SB3's check_for_nested_spaces: its buffers and policies take one level of keys
            raise NotImplementedError(
                "Nested observation spaces are not supported (Tuple/Dict space inside "
                f"Tuple/Dict space): got {space}"
            )
        self.envs = engine.envs
        super().__init__(engine, np.float32)
        self.metadata = self.envs[0].metadata  # SB3's DummyVecEnv: the first env's, shared


class SubprocVecEnv(EngineVecEnv):
    """One worker process per env (SB3's signature), observations in shared memory.

    ``start_method`` is "forkserver" (default where available, as in SB3), "spawn" or "fork".
    Not "fork" by default: the training process runs torch's threads, and a forked child copies
    the locks they hold. "forkserver" and "spawn" run the script again in each worker, so a
    script builds its vector envs under ``if __name__ == "__main__":`` (without it, the parent
    raises ``MissingMainGuardError`` saying so). A worker exception re-raises here with its
    class and traceback; a dead worker raises ``WorkerDiedError`` at once and closes the others.
    """

    def __init__(
        self, env_fns: Sequence[Callable[[], Env[Any, Any]]], start_method: str | None = None
    ) -> None:
        if start_method is None:
            import multiprocessing as mp

            methods = mp.get_all_start_methods()
            start_method = "forkserver" if "forkserver" in methods else "spawn"
        try:
            engine = ProcessEngine(env_fns, context=start_method, who="SubprocVecEnv")
        except error.SharedMemoryError:
            # SB3 pickles every observation; shared memory is palaestra's speed-up, so spaces
            # it cannot hold (Text, Graph, Sequence, custom) fall back to SB3's way.
            engine = ProcessEngine(
                env_fns, shared_memory=False, context=start_method, who="SubprocVecEnv"
            )
        super().__init__(engine, np.float64)  # SB3 stacks Python floats: float64


class BatchedVecEnv(EngineVecEnv):
    """A built-in env's native batch with SB3's API: what ``make_vec_env`` returns for the
    classic-control and toy-text ids (no Python loop over envs per step)."""

    def __init__(
        self,
        batch: NativeBatch,
        max_episode_steps: int | None = None,
        metadata: dict[str, Any] | None = None,
        render_mode: str | None = None,
    ) -> None:
        self.batch = batch
        self.spec: Any = None  # the EnvSpec when made from an id (make_vec_env sets it)
        engine = self._native = NativeEngine(batch, max_episode_steps, metadata, render_mode)
        super().__init__(engine, np.float32)
        self.metadata = engine.metadata  # the env's, as SB3's DummyVecEnv of those envs has

    def get_attr(self, attr_name: str, indices: Indices = None) -> list[Any]:
        """As ``EngineVecEnv.get_attr``; ``"spec"`` is each env's ``EnvSpec`` (as
        ``make_vec_env`` made them), which the batch itself does not hold."""
        if attr_name == "spec":
            self._check_open()
            return [self.spec for _ in self._get_indices(indices)]
        return super().get_attr(attr_name, indices)

    def get_images(self) -> Sequence[np.ndarray | None]:
        """Each row's ``rgb_array`` frame, drawn from the batch (no env objects to ask)."""
        self._check_open()
        return list(self._native.render())

    def env_method(
        self, method_name: str, *method_args: Any, indices: Indices = None, **method_kwargs: Any
    ) -> list[Any]:
        """As ``EngineVecEnv.env_method``; ``"render"`` draws the rows, as each env would."""
        if method_name == "render" and not method_args and not method_kwargs:
            self._check_open()
            return list(self._native.render(self._get_indices(indices)))
        return super().env_method(method_name, *method_args, indices=indices, **method_kwargs)
