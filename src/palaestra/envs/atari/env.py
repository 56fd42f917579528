"""``AtariEnv``: one Atari 2600 game, emulated by ale-py's ``ALEInterface``.

The semantics are ale-py's ``AtariEnv`` (the one behind Gymnasium's ``ALE/<Game>-v5`` ids):
the same constructor arguments and defaults, the same seeding (a seed is split by a
``SeedSequence`` into one seed for ``np_random`` and one for the emulator, and the ROM is
reloaded), the same order of emulator calls, so that equal seeds and actions give equal frames,
rewards and infos. Only ``ALEInterface`` is used, never ale-py's own Python env class.

Observations are fresh arrays on every step: a shared buffer would silently change
observations that a caller (a replay buffer, a frame stack) still holds.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_discrete_action, invalid_action
from palaestra.envs.atari.actions import direction_table, keys_for
from palaestra.envs.atari.checks import (
    RENDER_MODES,
    check_choice,
    check_frameskip,
    check_options,
    import_ale_py,
)
from palaestra.envs.atari.games import check_game
from palaestra.envs.rendered import RenderedEnv
from palaestra.spaces import Box, Dict, Discrete
from palaestra.utils.seeding import np_random as make_rng

EMULATOR_FPS = 60  # the 2600's NTSC frame rate: human mode plays at 60 / frameskip steps/s


class AtariEnv(RenderedEnv[Any, Any]):
    """An Atari 2600 game (``ALE/<Game>-v5``); arguments and defaults are ale-py's.

    ``game`` is the snake_case ROM id (``"breakout"``); ``obs_type`` ``"rgb"`` gives
    ``(210, 160, 3)`` frames, ``"grayscale"`` ``(210, 160)``, ``"ram"`` the 128 bytes of RAM.
    ``frameskip`` is an int or a ``(low, high)`` range sampled per step; sticky actions repeat
    the previous action with ``repeat_action_probability`` per frame (Machado et al., 2018).
    ``info`` holds ``lives``, ``episode_frame_number`` and ``frame_number`` (and ``seeds``
    after a seeded reset). ``env.unwrapped.ale`` is the emulator, for preprocessing wrappers.
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 30}

    def __init__(
        self,
        game: str,
        mode: int | None = None,
        difficulty: int | None = None,
        obs_type: str = "rgb",
        frameskip: int | tuple[int, int] = 4,
        repeat_action_probability: float = 0.25,
        full_action_space: bool = False,
        continuous: bool = False,
        continuous_action_threshold: float = 0.5,
        max_num_frames_per_episode: int | None = None,
        render_mode: str | None = None,
        sound_obs: bool = False,
    ) -> None:
        check_options(obs_type, render_mode, repeat_action_probability)
        self._frameskip = check_frameskip(frameskip)
        self.game = check_game(game)
        ale_py = import_ale_py()
        # Kept for copies: an ALEInterface cannot be copied, so a copy is rebuilt from these.
        self._init_kwargs = dict(
            game=game,
            mode=mode,
            difficulty=difficulty,
            obs_type=obs_type,
            frameskip=frameskip,
            repeat_action_probability=repeat_action_probability,
            full_action_space=full_action_space,
            continuous=continuous,
            continuous_action_threshold=continuous_action_threshold,
            max_num_frames_per_episode=max_num_frames_per_episode,
            render_mode=render_mode,
            sound_obs=sound_obs,
        )
        self.obs_type = obs_type
        self.render_mode = render_mode
        self.sound_obs = sound_obs
        self._mode, self._difficulty = mode, difficulty

        # Same settings, same order as ale-py (the emulator reads them at loadROM).
        ale_py.ALEInterface.setLoggerMode(ale_py.LoggerMode.Error)  # before: no banner
        self.ale = ale_py.ALEInterface()
        self.ale.setFloat("repeat_action_probability", float(repeat_action_probability))
        if max_num_frames_per_episode is not None:
            self.ale.setInt("max_num_frames_per_episode", int(max_num_frames_per_episode))
        self.ale.setBool("sound_obs", bool(sound_obs))
        self.seed_game()
        self._np_random_seed = -1  # derived from fresh entropy, not from a seed the user gave
        self.load_game()

        self.continuous = continuous
        self.continuous_action_threshold = continuous_action_threshold
        if full_action_space or continuous:
            self._action_set = tuple(self.ale.getLegalActionSet())
        else:
            self._action_set = tuple(self.ale.getMinimalActionSet())
        self._num_actions = len(self._action_set)
        if continuous:
            # (radius, angle, fire): polar joystick coordinates, as in ale-py.
            self._directions = direction_table(ale_py.Action)
            self.action_space: Box | Discrete = Box(
                np.array([0.0, -np.pi, 0.0], np.float32), np.array([1.0, np.pi, 1.0], np.float32)
            )
        else:
            self.action_space = Discrete(self._num_actions)

        height, width = self.ale.getScreenDims()
        shape = {"rgb": (height, width, 3), "grayscale": (height, width)}.get(
            obs_type, (self.ale.getRAMSize(),)
        )
        self._observe = {
            "rgb": self.ale.getScreenRGB,
            "grayscale": self.ale.getScreenGrayscale,
            "ram": self.ale.getRAM,
        }[obs_type]
        image_space = Box(0, 255, shape, np.uint8)
        if sound_obs:
            sound_space = Box(0, 255, (self.ale.getAudioSize(),), np.uint8)
            self.observation_space: Box | Dict = Dict(image=image_space, sound=sound_space)
        else:
            self.observation_space = image_space
        self._window: Any = None
        self._image_shape = shape
        self._skip_screen = False  # set by skip_screen_observations()

    # --- seeding and loading (ale-py's public methods, same names) -------------------------

    def seed_game(self, seed: int | None = None) -> tuple[np.uint32, np.uint32]:
        """Split ``seed`` into ``np_random``'s seed and the emulator's, as ale-py does."""
        np_seed, ale_seed = np.random.SeedSequence(seed).generate_state(n_words=2)
        self._np_random, _ = make_rng(int(np_seed))
        # ale-py passes np.int32(ale_seed): the uint32 wraps to a signed int.
        self.ale.setInt("random_seed", int(ale_seed) - (1 << 32) * (int(ale_seed) >= 1 << 31))
        return np_seed, ale_seed

    def load_game(self) -> None:
        """Load the ROM (this applies the seed) and set the mode and difficulty."""
        from ale_py import roms

        rom_path = roms.get_rom_path(self.game)
        if rom_path is None:  # a game newer than the installed ale-py
            raise error.Error(
                f"The installed ale-py does not ship the ROM of {self.game!r}; "
                'upgrade it with `pip install -U "palaestra[atari]"`'
            )
        self.ale.loadROM(rom_path)
        check_choice("mode", self._mode, self.ale.getAvailableModes(), self.game)
        check_choice("difficulty", self._difficulty, self.ale.getAvailableDifficulties(), self.game)
        if self._mode is not None:
            self.ale.setMode(self._mode)
        if self._difficulty is not None:
            self.ale.setDifficulty(self._difficulty)

    # --- the env API -------------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new game; a seed reseeds both RNGs and reloads the ROM (ale-py's behaviour)."""
        super().reset(seed=seed)
        seeds = None
        if seed is not None:
            seeds = self.seed_game(seed)
            self.load_game()
        self.ale.reset_game()
        info = self._info()
        if seeds is not None:
            info["seeds"] = seeds
        if self.render_mode == "human":
            self.render()
        return self._obs(), info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Repeat ``action`` for ``frameskip`` frames; the reward is their sum."""
        strength = 1.0
        if self.continuous:
            ale_action, strength = self._continuous_action(action)
        elif (type(action) is int or type(action) is np.int64) and 0 <= action < self._num_actions:
            ale_action = self._action_set[action]
        else:
            n = self._num_actions
            ale_action = self._action_set[check_discrete_action(action, self.action_space, n)]
        frameskip: Any = self._frameskip
        if type(frameskip) is tuple:
            frameskip = self.np_random.integers(*frameskip)
        act = self.ale.act
        reward = 0.0
        for _ in range(frameskip):
            reward += act(ale_action, strength)
        terminated = self.ale.game_over(with_truncation=False)
        truncated = self.ale.game_truncated()
        if self.render_mode == "human":
            self.render()
        return self._obs(), reward, terminated, truncated, self._info()

    def skip_screen_observations(self, skip: bool = True) -> None:
        """Return a fresh all-zero frame instead of reading the screen at every step and
        reset (``skip=False`` undoes it).

        For wrappers that read the screen from ``ale`` themselves and discard the env's
        observation (``AtariPreprocessing`` does, at ``frameskip=1``): an RGB screen read
        costs about a quarter of an emulated frame, and would be paid on every frame.
        """
        # The frame's shape is the image space's: no screen read needed to build the blank,
        # so a frame-skip wrapper can switch reads off and on around each skipped frame (a
        # flag: nothing is allocated per switch). The blank stays fresh per frame: a shared one
        # would trip the passive checker's "observations share an object" warning.
        self._skip_screen = bool(skip)

    @property
    def screen_observations_skipped(self) -> bool:
        """Whether :meth:`skip_screen_observations` is in effect."""
        return self._skip_screen

    def _obs(self) -> Any:
        image = np.zeros(self._image_shape, np.uint8) if self._skip_screen else self._observe()
        if self.sound_obs:
            return {"image": image, "sound": self.ale.getAudio()}
        return image

    def _info(self) -> dict[str, Any]:
        ale = self.ale
        return {
            "lives": ale.lives(),
            "episode_frame_number": ale.getEpisodeFrameNumber(),
            "frame_number": ale.getFrameNumber(),
        }

    def _continuous_action(self, action: Any) -> tuple[Any, float]:
        """``(radius, angle, fire)`` -> the joystick direction it points to, and its strength."""
        arr = np.asarray(action)
        if arr.shape != (3,) or arr.dtype != np.float32 or not np.isfinite(arr).all():
            raise invalid_action(action, self.action_space, "expected 3 finite float32 values")
        x, y = arr[0] * np.cos(arr[1]), arr[0] * np.sin(arr[1])
        threshold = self.continuous_action_threshold
        horizontal = int(x > threshold) - int(x < -threshold)
        vertical = int(y > threshold) - int(y < -threshold)
        return self._directions[horizontal, vertical, bool(arr[2] > threshold)], arr[0]

    def _frame(self) -> np.ndarray:
        """The screen as ``(210, 160, 3) uint8``."""
        return self.ale.getScreenRGB()

    def _window_settings(self) -> tuple[str, int]:
        title = self.spec.id if self.spec is not None else f"Atari {self.game}"
        skip = self._frameskip
        mean_skip = skip if isinstance(skip, int) else (skip[0] + skip[1] - 1) / 2
        return title, max(1, math.floor(EMULATOR_FPS / mean_skip))

    # --- ale-py's extras ---------------------------------------------------------------------

    @property
    def frameskip(self) -> int | tuple[int, int]:
        """Frames per step: an int, or the ``(low, high)`` range sampled each step."""
        return self._frameskip

    def get_action_meanings(self) -> list[str]:
        """The name of each action index, e.g. ``['NOOP', 'FIRE', 'RIGHT', 'LEFT']``."""
        return [action.name for action in self._action_set]

    def get_keys_to_action(self) -> dict[tuple[str, ...], int]:
        """Keyboard map for ``play``: w/a/s/d move, space fires, e is NOOP (ale-py's keys)."""
        if self.continuous:
            raise AttributeError(
                "`get_keys_to_action` can't be provided for this Atari environment as "
                "`continuous=True`."
            )
        return {keys_for(action.name): i for i, action in enumerate(self._action_set)}

    def clone_state(self, include_rng: bool = False) -> Any:
        """The emulator state (``ale_py.ALEState``); ``include_rng`` to replay sticky actions."""
        return self.ale.cloneState(include_rng=include_rng)

    def restore_state(self, state: Any) -> None:
        """Return the emulator to a state from :meth:`clone_state`."""
        self.ale.restoreState(state)

    # --- copies (copy.deepcopy, pickle): same game, same emulator state, same RNG -------------

    def __getstate__(self) -> dict[str, Any]:
        return {
            "kwargs": self._init_kwargs,
            "ale_state": self.ale.cloneState(include_rng=True).serialize(),
            "np_random": self.np_random.bit_generator.state,
            "np_random_seed": self._np_random_seed,
            "spec": self.spec,
            "skip_screen": self._skip_screen,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        import ale_py

        self.__init__(**state["kwargs"])  # type: ignore[misc]
        self.ale.restoreState(ale_py.ALEState(state["ale_state"]))
        self.np_random.bit_generator.state = state["np_random"]
        self._np_random_seed = state["np_random_seed"]
        self.spec = state["spec"]
        self.skip_screen_observations(state.get("skip_screen", False))
