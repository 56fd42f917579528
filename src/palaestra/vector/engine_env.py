"""The Gymnasium face over an engine: ``reset -> (obs, infos)``, ``step -> 5-tuple``.

:class:`EngineVectorEnv` is the one implementation; ``SyncVectorEnv``, ``AsyncVectorEnv`` and
``BatchedVectorEnv`` are named constructors that choose the engine.
"""

from __future__ import annotations

from collections.abc import Sequence
from copy import deepcopy
from typing import Any

import numpy as np

from palaestra import error
from palaestra.vector.autoreset import Autoresetter, Transition
from palaestra.vector.engine import Engine
from palaestra.vector.infos import stack_infos, stack_transition_infos
from palaestra.vector.vector_env import AutoresetMode, StepReturn, VectorEnv


class EngineVectorEnv(VectorEnv[Any, Any, np.ndarray]):
    """A ``VectorEnv`` whose sub-envs are run by ``engine`` in ``autoreset_mode``.

    ``copy=True`` returns observations the caller may keep; ``False`` returns the engine's
    buffer, overwritten by the next call.
    """

    def __init__(
        self,
        engine: Engine,
        copy: bool = True,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
    ) -> None:
        self.engine = engine
        self.copy = copy
        self._driver = Autoresetter(engine, autoreset_mode)
        self.autoreset_mode = self._driver.mode
        self.num_envs = engine.num_envs
        self.metadata = dict(engine.metadata)
        self.metadata["autoreset_mode"] = self.autoreset_mode
        self.render_mode = engine.render_mode
        self.single_observation_space = engine.single_observation_space
        self.observation_space = engine.observation_space
        self.single_action_space = engine.single_action_space
        self.action_space = engine.action_space

    def _check_open(self) -> None:
        # The engine closes itself when a worker dies: refuse from then on too.
        if self.closed or getattr(self.engine, "closed", False):
            raise error.ClosedEnvironmentError(
                f"Trying to operate on `{type(self).__name__}`, after a call to `close()`."
            )

    def _out(self, obs: Any) -> Any:
        if not self.copy:
            return obs
        return obs.copy() if isinstance(obs, np.ndarray) else deepcopy(obs)

    def _step_return(self, t: Transition) -> StepReturn:
        """The 5-tuple ``step`` returns for a driver's transition ``t`` (fresh arrays)."""
        return (
            self._out(t.obs),
            t.rewards.copy(),
            t.terminated.copy(),
            t.truncated.copy(),
            stack_transition_infos(t, self.num_envs),
        )

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset all sub-envs (or ``options["reset_mask"]``'s); int seed ``s``: env i gets s+i."""
        self._check_open()
        obs, raw = self._driver.reset(seed, options)
        return self._out(obs), stack_infos(raw, self.num_envs)

    def step(self, actions: Any) -> StepReturn:
        """Step all sub-envs, autoresetting as ``metadata["autoreset_mode"]`` says."""
        self._check_open()
        return self._step_return(self._driver.step(actions))

    def render(self) -> tuple[Any, ...]:
        """Every sub-env's frame."""
        self._check_open()
        return self.engine.render()

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """Call method ``name`` on every sub-env (or read the attribute): one result each."""
        self._check_open()
        return self.engine.call(name, args, kwargs)

    def get_attr(self, name: str) -> tuple[Any, ...]:
        """Attribute ``name`` of every sub-env."""
        return self.call(name)

    def set_attr(self, name: str, values: Sequence[Any] | Any) -> None:
        """Set ``name`` on every sub-env: one value each (list/tuple) or one for all."""
        self._check_open()
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(
                "Values must be a list or tuple with length equal to the number of environments. "
                f"Got `{len(values)}` values for {self.num_envs} environments."
            )
        self.engine.set_attr(name, values)

    @property
    def np_random_seed(self) -> tuple[Any, ...]:  # type: ignore[override]
        """The sub-envs' seeds."""
        return self.get_attr("np_random_seed")

    @property  # type: ignore[misc]
    def np_random(self) -> tuple[Any, ...]:  # type: ignore[override]
        """The sub-envs' generators."""
        return self.get_attr("np_random")

    def close_extras(self, **kwargs: Any) -> None:
        """Close the engine (sub-envs, workers)."""
        engine = getattr(self, "engine", None)
        if engine is not None:
            engine.close()
