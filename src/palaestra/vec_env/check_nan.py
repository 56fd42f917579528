"""``VecCheckNan``: find where a NaN or an infinity entered training (SB3's wrapper).

Actions are checked on the way in (a NaN there came from the model), observations and rewards
on the way out (from the env); the message names which, with the last value from the other side.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from palaestra.spaces import Dict
from palaestra.vec_env.base import StepReturn, VecEnv, VecEnvWrapper

# Where a bad value came from, by the event that saw it.
_ORIGIN = {
    "reset": "environment observation (at reset)",
    "step_wait": "environment, Last given value was: \r\n\taction={actions}",
    "step_async": "RL model, Last given value was: \r\n\tobservations={observations}",
}


class VecCheckNan(VecEnvWrapper):
    """Warn (or raise ``ValueError`` with ``raise_exception=True``) on NaN, and on ±inf unless
    ``check_inf=False``; with ``warn_once`` (the default) only the first finding warns."""

    def __init__(
        self,
        venv: VecEnv,
        raise_exception: bool = False,
        warn_once: bool = True,
        check_inf: bool = True,
    ) -> None:
        super().__init__(venv)
        if isinstance(venv.action_space, Dict):
            raise NotImplementedError("VecCheckNan doesn't support dict action spaces")
        self.raise_exception, self.warn_once, self.check_inf = raise_exception, warn_once, check_inf
        self._user_warned = False
        self._actions: Any = None
        self._observations: Any = None

    def step_async(self, actions: np.ndarray) -> None:
        """Check the actions, then send them."""
        self._check_val("step_async", actions=actions)
        self._actions = actions
        self.venv.step_async(actions)

    def step_wait(self) -> StepReturn:
        """Step, then check observations, rewards and dones."""
        observations, rewards, dones, infos = self.venv.step_wait()
        self._check_val("step_wait", observations=observations, rewards=rewards, dones=dones)
        self._observations = observations
        return observations, rewards, dones, infos

    def reset(self) -> Any:
        """Reset, then check the observations."""
        observations = self.venv.reset()
        self._check_val("reset", observations=observations)
        self._observations = observations
        return observations

    def check_array_value(self, name: str, value: np.ndarray) -> list[tuple[str, str]]:
        """``(name, "inf"/"nan")`` for each kind of bad value in ``value``."""
        found = []
        if self.check_inf and np.any(np.isinf(value)):
            found.append((name, "inf"))
        if np.any(np.isnan(value)):
            found.append((name, "nan"))
        return found

    def _check_val(self, event: str, **values: Any) -> None:
        if not self.raise_exception and self.warn_once and self._user_warned:
            return  # warned once already: checking costs time for nothing
        found: list[tuple[str, str]] = []
        for name, value in values.items():
            if isinstance(value, (np.ndarray, list)):
                found += self.check_array_value(name, np.asarray(value))
            elif isinstance(value, dict):
                for key, item in value.items():
                    found += self.check_array_value(f"{name}.{key}", item)
            elif isinstance(value, tuple):
                for i, item in enumerate(value):
                    found += self.check_array_value(f"{name}.{i}", item)
            else:
                raise TypeError(f"Unsupported observation type {type(value)}.")
        if not found:
            return
        self._user_warned = True
        where = _ORIGIN[event].format(actions=self._actions, observations=self._observations)
        message = ", ".join(f"found {kind} in {name}" for name, kind in found)
        message += f".\r\nOriginated from the {where}"
        if self.raise_exception:
            raise ValueError(message)
        warnings.warn(message, UserWarning, stacklevel=2)
