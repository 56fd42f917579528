"""The ALE engine: ale-py's ``ALEVectorInterface`` steps N preprocessed games on C++ threads.
It is the Atari family's native batch, so it lives with the Atari envs (``vector`` never
imports the env packages).

The interface does the Atari preprocessing itself (frame skip with max-pooling, grayscale,
area resize, frame stack, no-op and FIRE resets, reward clipping, episode frame limit) and
returns batched arrays. This engine adds what the :class:`~palaestra.vector.engine.Engine`
protocol asks for: batch-level checks (an out-of-range action would hang ALE's worker thread
for good), infos kept as arrays (:class:`~palaestra.utils.stacked_infos.StackedInfos`) and
seeds checked against ALE's range.

The interface always runs in ALE's own NEXT_STEP mode, which resets exactly the rows the
:class:`~palaestra.vector.autoreset.Autoresetter` resets in that mode. SAME_STEP is the
autoresetter's explicit reset of the finished rows right after the step; it draws what ALE's
SAME_STEP draws, so both give the same observations (tests/vector/test_atari_vector.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.atari.actions import direction_table
from palaestra.envs.atari.checks import import_ale_py
from palaestra.envs.atari.games import check_game
from palaestra.spaces import Box, Discrete, Space
from palaestra.spaces.batching import batch_space
from palaestra.utils.stacked_infos import StackedInfos
from palaestra.vector.engine import Rows, StepResult

MAX_SEED = 2**31 - 1  # ALE takes C ints; negative means "keep the current seed"


@dataclass(frozen=True)
class ALESettings:
    """ale-py's ``AtariVectorEnv`` keyword arguments, with its defaults, checked."""

    batch_size: int = 0  # 0 or num_envs: every step returns every env
    num_threads: int = 0  # 0: one per core
    thread_affinity_offset: int = -1  # -1: no thread pinning
    max_num_frames_per_episode: int = 108_000  # truncation after this many frames
    repeat_action_probability: float = 0.0  # sticky actions, per frame
    full_action_space: bool = False  # all 18 actions instead of the game's minimal set
    continuous: bool = False  # (radius, angle, fire) actions
    continuous_action_threshold: float = 0.5  # where a continuous action presses a direction
    img_height: int = 84
    img_width: int = 84
    grayscale: bool = True  # else RGB frames [H, W, 3]
    stack_num: int = 4  # frames per observation, oldest first
    frameskip: int = 4  # frames per step
    maxpool: bool = True  # max over the last two frames of a step
    noop_max: int = 30  # up to this many no-op frames after a reset
    episodic_life: bool = False  # a lost life ends the episode (and the game restarts)
    life_loss_info: bool = False  # a lost life reports terminated=True; the game goes on
    reward_clipping: bool = True  # rewards clipped to [-1, 1]
    use_fire_reset: bool = True  # press FIRE after a reset in games that have it

    def __post_init__(self) -> None:
        if type(self.frameskip) is not int or self.frameskip <= 0:
            raise error.Error(
                f"Invalid frameskip {self.frameskip!r}: expected a positive int (frames per step)"
            )
        for name, low in (
            ("num_threads", 0),
            ("max_num_frames_per_episode", 1),
            ("img_height", 1),
            ("img_width", 1),
            ("stack_num", 1),
            ("noop_max", 0),
            ("batch_size", 0),
            ("thread_affinity_offset", -1),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
                raise ValueError(f"Invalid {name} {value!r}: expected an int >= {low}")
        p = self.repeat_action_probability
        if isinstance(p, bool) or not isinstance(p, (int, float, np.number)) or not 0 <= p <= 1:
            raise ValueError(
                f"Invalid repeat_action_probability {p!r}: expected a probability in [0, 1]"
            )


def vector_interface_available() -> bool:
    """Whether the installed ale-py has ``ALEVectorInterface`` (ale-py >= 0.11)."""
    return hasattr(import_ale_py(), "ALEVectorInterface")


def ale_seed(seed: Any) -> int:
    """ALE's seed for a row: -1 (keep its generator) for None, else an int in [0, 2**31 - 1]."""
    if seed is None:
        return -1
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise error.Error(f"Seed must be a python integer, actual type: {type(seed)}")
    if not 0 <= seed <= MAX_SEED:
        raise error.Error(
            f"Seed must be an int in [0, {MAX_SEED}] (ALE's seed range), actual value: {seed}"
        )
    return int(seed)


class ALEVectorEngine:
    """Engine over one ``ale_py.ALEVectorInterface`` running ``num_envs`` copies of ``game``.

    ``frames_last=True`` (with ``stack_num=1``) gives each observation as one ``(H, W, C)``
    image, the layout of SB3's ``AtariWrapper``, instead of ale-py's ``(stack, H, W)``.
    """

    def __init__(
        self, game: str, num_envs: int, settings: ALESettings, frames_last: bool = False
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)):
            raise TypeError(f"num_envs must be an int >= 1, got {num_envs!r}")
        if num_envs < 1:
            raise ValueError(f"num_envs must be an int >= 1, got {num_envs}")
        if settings.batch_size not in (0, num_envs):
            raise ValueError(
                f"batch_size={settings.batch_size} is not supported: every step returns all "
                f"{num_envs} envs (use batch_size=0)"
            )
        if frames_last and settings.stack_num != 1:
            raise ValueError(f"frames_last needs stack_num=1, got {settings.stack_num}")
        self.game = check_game(game)
        self.settings = settings
        ale_py = import_ale_py()
        kwargs = asdict(settings)
        self.ale: Any = ale_py.ALEVectorInterface(
            rom_path=ale_py.roms.get_rom_path(self.game),
            num_envs=num_envs,
            frame_skip=settings.frameskip,
            max_episode_steps=kwargs.pop("max_num_frames_per_episode"),
            full_action_space=settings.full_action_space or settings.continuous,
            # A lost life is added to `terminated` here (see step_recv), so that ALE's
            # terminated/truncated say exactly which rows it will reset.
            life_loss_info=False,
            # Clipped here instead (see step_recv), so that the game's score stays readable.
            reward_clipping=False,
            autoreset_mode="NextStep",
            **{k: v for k, v in kwargs.items() if k in _PASSED_AS_IS},
        )
        self.closed = False
        self.num_envs = n = int(num_envs)
        self.metadata: dict[str, Any] = {}
        self.render_mode: str | None = None
        action_set = self.ale.get_action_set()
        self.action_meanings = [action.name for action in action_set]
        frame = (settings.img_height, settings.img_width)
        if frames_last:
            shape: tuple[int, ...] = (*frame, 1 if settings.grayscale else 3)
        else:
            shape = (settings.stack_num, *frame) + (() if settings.grayscale else (3,))
        self.single_observation_space: Space[Any] = Box(0, 255, shape, np.uint8)
        self.single_action_space: Space[Any]
        if settings.continuous:
            self.single_action_space = Box(
                np.array([0.0, -np.pi, 0.0], np.float32), np.array([1.0, np.pi, 1.0], np.float32)
            )
            table = direction_table(ale_py.Action)
            self._directions = np.zeros((3, 3, 2), dtype=np.int64)  # [h + 1, v + 1, fire]
            for (h, v, fire), action in table.items():
                self._directions[h + 1, v + 1, int(fire)] = int(action.value)
        else:
            self.single_action_space = Discrete(len(action_set))
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._obs_shape = (n, *shape)
        self.obs = np.zeros(self._obs_shape, np.uint8)  # [N, stack, H, W(, 3)] or [N, H, W, C]
        self._all_rows = list(range(n))
        self._paddle = np.ones(n, dtype=np.float32)  # [N] full strength for discrete actions
        self._rewards = np.zeros(n)  # [N] float64, clipped if reward_clipping
        self.raw_rewards = np.zeros(n)  # [N] float64, the game's score change in the last step
        self._terminated = np.zeros(n, dtype=bool)  # [N]
        self._truncated = np.zeros(n, dtype=bool)  # [N]
        self._lives = np.zeros(n, dtype=np.int32)  # [N] lives after the last step or reset
        # Rows whose termination is a lost life in a game that goes on (life_loss_info).
        self.continuing: np.ndarray | None = None
        if settings.life_loss_info and not settings.episodic_life:
            self.continuing = np.zeros(n, dtype=bool)
        self._started = False  # ALE needs one full reset before anything else

    def _check_open(self) -> None:
        if self.closed:
            raise error.ClosedEnvironmentError("The Atari vector engine has been closed.")

    def reset(self, mask: np.ndarray | None, seeds: list[int | None], options: Any) -> StackedInfos:
        """Reset the masked rows (all if None); ``seeds[i]`` seeds row i (None keeps its RNG)."""
        self._check_open()
        if options:
            raise ValueError(
                f"The Atari vector env takes no reset options but 'reset_mask', got {options!r}"
            )
        rows = self._all_rows if mask is None else np.flatnonzero(mask).tolist()
        if not self._started and len(rows) != self.num_envs:
            raise error.ResetNeeded(
                "The first reset of an Atari vector env must reset every sub-environment "
                f"(got a reset_mask selecting {len(rows)} of {self.num_envs})"
            )
        row_seeds = [ale_seed(seeds[i]) for i in rows]
        obs, info = self.ale.reset(rows, row_seeds)  # every row's obs and info
        self.obs = obs.reshape(self._obs_shape)  # a view: only frames_last changes the shape
        self._started = True
        np.copyto(self._lives, info["lives"])
        return StackedInfos(info, self.num_envs, mask)

    def step_send(self, actions: Any, reset_mask: np.ndarray | None) -> None:
        """Check the actions and hand them to ALE's threads (which reset ``reset_mask``'s rows
        themselves: those are exactly the rows that ended)."""
        self._check_open()
        if not self._started:
            raise error.ResetNeeded("Cannot call `step` before calling `reset` on the vector env")
        if self.settings.continuous:
            ids, paddle = self._continuous_actions(actions)
            self.ale.send(ids, paddle)
        else:
            self.ale.send(self._discrete_actions(actions), self._paddle)

    def _discrete_actions(self, actions: Any) -> np.ndarray:
        arr = actions if isinstance(actions, np.ndarray) else np.asarray(actions)
        n, space = self.num_envs, self.action_space
        if arr.shape != (n,):
            raise error.InvalidAction(
                f"Expected a batch of {n} actions (shape ({n},)) for action space {space}, got "
                f"shape {arr.shape}: {actions!r}"
            )
        if arr.dtype.kind not in "iu":
            raise error.InvalidAction(
                f"Expected integer actions for action space {space}, got dtype {arr.dtype}: "
                f"{actions!r}"
            )
        if arr.min() < 0 or arr.max() >= len(self.action_meanings):
            rows = np.flatnonzero((arr < 0) | (arr >= len(self.action_meanings))).tolist()
            raise error.InvalidAction(
                f"Actions {arr[rows].tolist()} of sub-environments {rows} are not in "
                f"{self.single_action_space} (the game's actions: {self.action_meanings})"
            )
        return arr

    def _continuous_actions(self, actions: Any) -> tuple[np.ndarray, np.ndarray]:
        arr = actions if isinstance(actions, np.ndarray) else np.asarray(actions)
        n = self.num_envs
        if arr.shape != (n, 3) or arr.dtype.kind != "f" or not np.isfinite(arr).all():
            raise error.InvalidAction(
                f"Expected a batch of {n} actions of 3 finite floats (radius, angle, fire), "
                f"shape ({n}, 3), each in {self.single_action_space}; got {arr.dtype} "
                f"{arr.shape}: {actions!r}"
            )
        arr = arr.astype(np.float32, copy=False)  # ale-py maps float32 actions
        threshold = self.settings.continuous_action_threshold
        x = arr[:, 0] * np.cos(arr[:, 1])
        y = arr[:, 0] * np.sin(arr[:, 1])
        horizontal = (x > threshold).astype(np.int64) - (x < -threshold) + 1
        vertical = (y > threshold).astype(np.int64) - (y < -threshold) + 1
        fire = (arr[:, 2] > threshold).astype(np.int64)
        return self._directions[horizontal, vertical, fire], np.ascontiguousarray(arr[:, 0])

    def step_recv(self, timeout: float | None = None) -> StepResult:
        """Collect ALE's step: ``obs`` is a new array, rewards/flags are copied into ours."""
        self._check_open()
        obs, rewards, terminated, truncated, info = self.ale.recv()
        self.obs = obs.reshape(self._obs_shape)
        np.copyto(self.raw_rewards, rewards)  # int32 -> float64, as Gymnasium's vector envs
        if self.settings.reward_clipping:
            np.clip(self.raw_rewards, -1.0, 1.0, out=self._rewards)  # ALE's std::clamp
        else:
            np.copyto(self._rewards, self.raw_rewards)
        np.copyto(self._terminated, terminated)
        np.copyto(self._truncated, truncated)
        lives = info["lives"]
        if self.settings.life_loss_info:
            # ale-py's life_loss_info: a life lost in this step (ALE's own test, against the
            # lives at the end of the previous step) reports terminated, never truncated.
            lost = (lives < self._lives) & (lives > 0)
            if self.continuing is not None:
                np.logical_and(lost, ~(self._terminated | self._truncated), out=self.continuing)
            self._terminated |= lost
            self._truncated &= ~lost
        np.copyto(self._lives, lives)
        return self._rewards, self._terminated, self._truncated, StackedInfos(info, self.num_envs)

    def call(
        self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any], rows: Rows = None
    ) -> tuple[Any, ...]:
        """The few per-env attributes a native Atari batch has (it holds no env objects)."""
        self._check_open()
        values: dict[str, Any] = {
            "get_action_meanings": lambda: list(self.action_meanings),
            "game": self.game,
            "render_mode": None,
        }
        if name not in values:
            raise AttributeError(
                f"The native Atari vector env has no sub-env objects, so no {name!r} (it has "
                f"{sorted(values)}); use vectorization_mode='async' for per-env calls"
            )
        value = values[name]
        result = value(*args, **kwargs) if callable(value) else value
        return tuple(result for _ in (self._all_rows if rows is None else rows))

    def set_attr(self, name: str, values: Sequence[Any], rows: Rows = None) -> None:
        """A native Atari batch has no sub-env attributes to set."""
        raise AttributeError(
            f"Cannot set {name!r}: the native Atari vector env has no sub-env objects (use "
            "vectorization_mode='async' for per-env attributes)"
        )

    def is_wrapped(self, wrapper_class: type, rows: Rows = None) -> list[bool]:
        """A native batch has no wrappers."""
        return [False for _ in (self._all_rows if rows is None else rows)]

    def render(self) -> tuple[Any, ...]:
        """ALE's vector interface does not render (use a single env for frames)."""
        return tuple(None for _ in self._all_rows)

    def close(self) -> None:
        """Stop ALE's threads (dropping the interface joins them); idempotent."""
        self.closed = True
        self.ale = None


# Settings whose names are the same in ALEVectorInterface's signature.
_PASSED_AS_IS = frozenset(
    {
        "batch_size",
        "num_threads",
        "thread_affinity_offset",
        "repeat_action_probability",
        "img_height",
        "img_width",
        "grayscale",
        "stack_num",
        "maxpool",
        "noop_max",
        "episodic_life",
        "use_fire_reset",
    }
)
