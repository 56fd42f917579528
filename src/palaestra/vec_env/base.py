"""The Stable-Baselines3 vector API: ``VecEnv`` and ``VecEnvWrapper``.

``reset()`` returns observations only; ``step()`` returns ``(obs, rewards, dones, infos)`` where
``infos`` is a list of dicts and a finished env is reset at once (its last observation goes to
``infos[i]["terminal_observation"]``, its reset info to ``reset_infos[i]``). Seeds and options
set with :meth:`VecEnv.seed` / :meth:`VecEnv.set_options` apply at the next ``reset()``.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping, Sequence
from copy import deepcopy
from typing import Any

import numpy as np

from palaestra import error
from palaestra.spaces import Space
from palaestra.utils import run_state
from palaestra.utils.run_state import State
from palaestra.vector.worker import Payload

Indices = int | Iterable[int] | None
StepReturn = tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]
# SB3's names for them (stable_baselines3.common.vec_env.base_vec_env)
VecEnvIndices = Indices
VecEnvObs = np.ndarray | dict[str, np.ndarray] | tuple[np.ndarray, ...]
VecEnvStepReturn = StepReturn


class CloudpickleWrapper(Payload):
    """SB3's wrapper: ``var`` (any object: lambdas, closures, local classes) pickled with
    cloudpickle, so it reaches a worker process under every start method. An object that
    cannot be pickled is a ``TypeError`` naming it when the wrapper is pickled."""

    def __init__(self, var: Any) -> None:
        super().__init__(var)

    @property
    def var(self) -> Any:
        """The wrapped object."""
        return self.fn

    @var.setter
    def var(self, value: Any) -> None:
        self.fn = value


class VecEnv:
    """Base of SB3-style vector envs: ``num_envs`` envs with *single* observation/action spaces."""

    # What exact resume saves (utils.run_state); None: this env cannot save its state.
    RUN_STATE: tuple[str, ...] | None = None

    def __init__(
        self, num_envs: int, observation_space: Space[Any], action_space: Space[Any]
    ) -> None:
        self.num_envs = num_envs
        self.observation_space = observation_space
        self.action_space = action_space
        self.reset_infos: list[dict[str, Any]] = [{} for _ in range(num_envs)]
        self._seeds: list[int | None] = [None] * num_envs
        self._options: list[dict[str, Any]] = [{} for _ in range(num_envs)]
        try:
            render_modes = self.get_attr("render_mode")
        except AttributeError:
            render_modes = [None] * num_envs
        if any(mode != render_modes[0] for mode in render_modes):
            raise ValueError(f"render_mode should be the same for all environments: {render_modes}")
        self.render_mode: str | None = render_modes[0]
        modes = [] if self.render_mode is None else [self.render_mode]
        if self.render_mode == "rgb_array":
            modes = ["human", "rgb_array"]
        self.metadata: dict[str, Any] = {"render_modes": modes}

    # -- exact resume ---------------------------------------------------------------------
    def get_run_state(self) -> State:
        """Everything stepping changes (env rows and their generators, counters, episode and
        normalisation statistics) as JSON + arrays, so that :meth:`set_run_state` on an env
        built the same way continues exactly from here. ``RunStateError`` for envs whose state
        palaestra cannot see (arbitrary Python envs in ``DummyVecEnv``/``SubprocVecEnv``)."""
        return run_state.capture(self)

    def set_run_state(self, state: State) -> None:
        """Continue from a :meth:`get_run_state` state (checked whole before anything changes)."""
        run_state.restore(self, state)

    # -- to implement ---------------------------------------------------------------------
    def reset(self) -> Any:
        """Reset every env; return the batch of observations."""
        raise NotImplementedError

    def step_async(self, actions: np.ndarray) -> None:
        """Start a step with one action per env."""
        raise NotImplementedError

    def step_wait(self) -> StepReturn:
        """Finish the step: ``(obs, rewards, dones, infos)``."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the envs; calling it twice is harmless."""
        raise NotImplementedError

    def get_attr(self, attr_name: str, indices: Indices = None) -> list[Any]:
        """Attribute ``attr_name`` of each env in ``indices``."""
        raise NotImplementedError

    def set_attr(self, attr_name: str, value: Any, indices: Indices = None) -> None:
        """Set ``attr_name`` to ``value`` on each env in ``indices``."""
        raise NotImplementedError

    def env_method(
        self, method_name: str, *method_args: Any, indices: Indices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Call ``method_name`` on each env in ``indices``."""
        raise NotImplementedError

    def env_is_wrapped(self, wrapper_class: type, indices: Indices = None) -> list[bool]:
        """Whether each env in ``indices`` is wrapped with ``wrapper_class``."""
        raise NotImplementedError

    # -- shared behaviour -----------------------------------------------------------------
    def step(self, actions: Any) -> StepReturn:
        """Step every env: ``(obs, rewards, dones, infos)``."""
        self.step_async(actions)
        return self.step_wait()

    def has_attr(self, attr_name: str) -> bool:
        """Whether the envs have attribute ``attr_name``."""
        try:
            self.get_attr(attr_name, indices=0)
            return True
        except AttributeError:
            return False

    def get_images(self) -> Sequence[np.ndarray | None]:
        """Each env's ``rgb_array`` frame."""
        if self.render_mode != "rgb_array":
            return [None] * self.num_envs
        return self.env_method("render")

    def render(self, mode: str | None = None) -> np.ndarray | None:
        """The envs' frames tiled into one image (``rgb_array``), or None.

        As SB3: ``mode`` is only for backward compatibility; one other than the envs'
        ``render_mode`` warns and returns None (``"human"`` over ``rgb_array`` envs is allowed
        and returns the tiled frame).
        """
        if mode == "human" and self.render_mode != mode:
            if self.render_mode != "rgb_array":
                warnings.warn(
                    f"You tried to render a VecEnv with mode='{mode}' but the render mode "
                    "defined when initializing the environment must be 'human' or "
                    f"'rgb_array', not '{self.render_mode}'.",
                    stacklevel=2,
                )
                return None
        elif mode and self.render_mode != mode:
            warnings.warn(
                "Starting from gymnasium v0.26, render modes are determined during the "
                "initialization of the environment. We allow to pass a mode argument to "
                f"maintain a backwards compatible VecEnv API, but the mode ({mode}) has to be "
                f"the same as the environment render mode ({self.render_mode}) which is not the "
                "case.",
                stacklevel=2,
            )
            return None
        mode = mode or self.render_mode
        if mode is None:
            warnings.warn(
                "You tried to call render() but no `render_mode` was passed to the env "
                "constructor.",
                stacklevel=2,
            )
            return None
        if self.render_mode != "rgb_array":
            self.env_method("render")
            return None
        frames = [f for f in self.get_images() if f is not None]
        return tile_images(frames) if frames else None

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed env i with ``seed + i`` at the next ``reset()`` (random base when None)."""
        if seed is None:
            seed = int(np.random.default_rng().integers(0, np.iinfo(np.uint32).max))
        self._seeds = [seed + i for i in range(self.num_envs)]
        return self._seeds

    def set_options(self, options: list[dict[str, Any]] | dict[str, Any] | None = None) -> None:
        """Reset options for the next ``reset()``: one dict for all envs or one per env.

        Anything else is refused here (``InvalidOptions``, a ``TypeError``; a list of the wrong
        length: ``OptionsCountError``), where SB3 accepts it and fails in ``reset``.
        """
        n = self.num_envs
        expected = f"a dict (the same options for every env) or a list of {n} dicts (one per env)"
        if options is None:
            options = {}
        if isinstance(options, Mapping):
            self._options = [deepcopy(dict(options)) for _ in range(n)]
            return
        if not isinstance(options, (list, tuple)):
            raise error.InvalidOptions(f"set_options expects {expected}, got {options!r:.200}")
        bad = [o for o in options if o is not None and not isinstance(o, Mapping)]
        if bad:
            raise error.InvalidOptions(
                f"set_options expects {expected}, got {options!r:.200}: "
                f"{bad[0]!r:.100} is not a dict"
            )
        if len(options) != n:
            raise error.OptionsCountError(
                f"set_options expects {expected}, got a list of {len(options)}: {options!r:.200}"
            )
        self._options = [{} if o is None else deepcopy(dict(o)) for o in options]

    def _reset_seeds(self) -> None:
        self._seeds = [None] * self.num_envs

    def _reset_options(self) -> None:
        self._options = [{} for _ in range(self.num_envs)]

    def _get_indices(self, indices: Indices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, (int, np.integer)):
            return [int(indices)]
        return list(indices)

    @property
    def unwrapped(self) -> VecEnv:
        """The vector env below every ``VecEnvWrapper``."""
        return self

    def __enter__(self) -> VecEnv:
        return self

    def __exit__(self, *args: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"{type(self).__name__}(num_envs={self.num_envs})"


def tile_images(images: Sequence[np.ndarray]) -> np.ndarray:
    """Tile ``N`` ``(H, W, C)`` frames into a near-square grid, as SB3 does."""
    frames = np.asarray(images)
    n, h, w, c = frames.shape
    rows = int(np.ceil(np.sqrt(n)))
    cols = int(np.ceil(n / rows))
    padded = np.concatenate([frames, np.zeros((rows * cols - n, h, w, c), frames.dtype)])
    grid = padded.reshape(rows, cols, h, w, c).transpose(0, 2, 1, 3, 4)
    return grid.reshape(rows * h, cols * w, c)


class VecEnvWrapper(VecEnv):
    """Base of SB3-style vector wrappers; every call goes to ``self.venv`` unless overridden.

    Attributes of inner layers are reached through ``venv`` or ``unwrapped``, not forwarded.
    """

    def __init__(
        self,
        venv: VecEnv,
        observation_space: Space[Any] | None = None,
        action_space: Space[Any] | None = None,
    ) -> None:
        if not isinstance(venv, VecEnv):
            raise error.NotAVecEnv(
                f"{type(self).__name__} expects a palaestra.vec_env.VecEnv to wrap, got "
                f"{venv!r:.200} ({type(venv)})"
            )
        self.venv = venv
        super().__init__(
            venv.num_envs,
            observation_space or venv.observation_space,
            action_space or venv.action_space,
        )
        self.render_mode = venv.render_mode
        self.metadata = venv.metadata

    def reset(self) -> Any:
        """Reset the inner vector env."""
        return self.venv.reset()

    def step_async(self, actions: np.ndarray) -> None:
        """Start a step of the inner vector env."""
        self.venv.step_async(actions)

    def step_wait(self) -> StepReturn:
        """Finish the inner step."""
        return self.venv.step_wait()

    def close(self) -> None:
        """Close the inner vector env."""
        self.venv.close()

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed the inner vector env."""
        return self.venv.seed(seed)

    def set_options(self, options: list[dict[str, Any]] | dict[str, Any] | None = None) -> None:
        """Set the inner vector env's reset options."""
        self.venv.set_options(options)

    def render(self, mode: str | None = None) -> np.ndarray | None:
        """Render the inner vector env."""
        return self.venv.render(mode=mode)

    def get_images(self) -> Sequence[np.ndarray | None]:
        """The inner vector env's frames."""
        return self.venv.get_images()

    def get_attr(self, attr_name: str, indices: Indices = None) -> list[Any]:
        """Attribute of the inner envs."""
        return self.venv.get_attr(attr_name, indices)

    def set_attr(self, attr_name: str, value: Any, indices: Indices = None) -> None:
        """Set an attribute of the inner envs."""
        self.venv.set_attr(attr_name, value, indices)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Indices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Call a method of the inner envs."""
        return self.venv.env_method(method_name, *method_args, indices=indices, **method_kwargs)

    def env_is_wrapped(self, wrapper_class: type, indices: Indices = None) -> list[bool]:
        """Whether the inner envs are wrapped with ``wrapper_class``."""
        return self.venv.env_is_wrapped(wrapper_class, indices)

    @property
    def reset_infos(self) -> list[dict[str, Any]]:
        """The inner vector env's reset infos."""
        return self.venv.reset_infos

    @reset_infos.setter
    def reset_infos(self, value: list[dict[str, Any]]) -> None:
        pass  # set by VecEnv.__init__; the inner env owns them

    @property
    def unwrapped(self) -> VecEnv:
        """The innermost vector env."""
        return self.venv.unwrapped

    def __repr__(self) -> str:
        return f"<{type(self).__name__}, {self.venv!r}>"
