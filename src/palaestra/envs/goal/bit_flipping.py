"""``BitFlippingEnv``: the goal env SB3's HER tests learn on (its constructor, spaces, rewards
and seeding), written for palaestra.

The state is ``n_bits`` bits drawn uniformly at reset; the desired goal is all ones. An action
flips one bit (discrete) or every bit whose action component is positive (continuous). The
reward is 0 when the state equals the goal (the episode then terminates) and -1 otherwise: the
sparse reward that plain DQN almost never sees for 15 bits, and that HER relabels. Episodes
are truncated after ``max_steps`` steps. ``reset(seed=s)`` draws the same first state as SB3's
env reset with ``seed=s``.

Observation variants (SB3's): ``MultiBinary(n_bits)`` bits (default); ``discrete_obs_space``:
each bit vector as one integer ``sum(bit_i * 2**i)`` in ``Discrete(2**n_bits)``;
``image_obs_space``: a ``uint8`` image of 36 x 36 pixels, the bits (0 or 255) first in
row-major order and zeros after, ``(1, 36, 36)`` or ``(36, 36, 1)`` as ``channel_first`` says.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.core import Env
from palaestra.envs.action_checks import check_discrete_action, invalid_action

__all__ = ["BitFlippingEnv"]

_IMAGE_SIDE = 36
_CELL = 16  # pixels per bit in rgb_array frames


class BitFlippingEnv(Env[dict[str, Any], Any]):
    """Flip bits until they are all ones; SB3's ``BitFlippingEnv`` arguments and spaces.

    >>> env = BitFlippingEnv(n_bits=4)
    >>> obs, _ = env.reset(seed=0)
    >>> obs["observation"], obs["desired_goal"]
    (array([0, 1, 1, 1], dtype=int8), array([1, 1, 1, 1], dtype=int8))
    >>> obs, reward, terminated, truncated, info = env.step(0)
    >>> reward, terminated, info
    (-0.0, True, {'is_success': True})
    >>> env.compute_reward(np.array([[1, 1, 1, 1], [0, 1, 1, 1]]), np.ones((2, 4)), None)
    array([-0., -1.], dtype=float32)
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array", "ansi"], "render_fps": 4}
    state: np.ndarray

    def __init__(
        self,
        n_bits: int = 10,
        continuous: bool = False,
        max_steps: int | None = None,
        discrete_obs_space: bool = False,
        image_obs_space: bool = False,
        channel_first: bool = True,
        render_mode: str | None = "human",
    ) -> None:
        if isinstance(n_bits, bool) or not isinstance(n_bits, (int, np.integer)) or n_bits < 1:
            raise ValueError(f"n_bits must be a positive integer, got {n_bits!r}")
        n_bits = int(n_bits)
        if max_steps is not None and (
            isinstance(max_steps, bool)
            or not isinstance(max_steps, (int, np.integer))
            or max_steps < 1
        ):
            raise ValueError(f"max_steps must be a positive integer or None, got {max_steps!r}")
        if discrete_obs_space and image_obs_space:
            raise ValueError("Cannot use both discrete and image observation spaces")
        if image_obs_space and n_bits > _IMAGE_SIDE * _IMAGE_SIDE:
            raise ValueError(
                f"image_obs_space holds at most {_IMAGE_SIDE * _IMAGE_SIDE} bits, got "
                f"n_bits={n_bits!r}"
            )
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, "
                f"got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.n_bits = n_bits
        self.continuous = bool(continuous)
        self.discrete_obs_space = bool(discrete_obs_space)
        self.image_obs_space = bool(image_obs_space)
        self.channel_first = bool(channel_first)
        self.image_shape = (
            (1, _IMAGE_SIDE, _IMAGE_SIDE) if channel_first else (_IMAGE_SIDE, _IMAGE_SIDE, 1)
        )
        self.observation_space = self._make_observation_space(
            self.discrete_obs_space, self.image_obs_space, n_bits
        )
        self.action_space: spaces.Space[Any] = (
            spaces.Box(-1, 1, shape=(n_bits,), dtype=np.float32)
            if self.continuous
            else spaces.Discrete(n_bits)
        )
        self.desired_goal = np.ones(n_bits, dtype=self.observation_space["desired_goal"].dtype)
        self.max_steps = n_bits if max_steps is None else int(max_steps)
        self.current_step = 0
        self.state = np.zeros(n_bits, dtype=np.int8)

    # -- spaces and conversions (SB3's public helpers) -------------------------------------
    def _make_observation_space(
        self, discrete_obs_space: bool, image_obs_space: bool, n_bits: int
    ) -> spaces.Dict:
        """The ``Dict`` of ``observation``, ``achieved_goal`` and ``desired_goal`` spaces."""
        if discrete_obs_space and image_obs_space:
            raise ValueError("Cannot use both discrete and image observation spaces")
        keys = ("observation", "achieved_goal", "desired_goal")
        if discrete_obs_space:
            return spaces.Dict({k: spaces.Discrete(2**n_bits) for k in keys})
        if image_obs_space:
            return spaces.Dict(
                {k: spaces.Box(0, 255, shape=self.image_shape, dtype=np.uint8) for k in keys}
            )
        return spaces.Dict({k: spaces.MultiBinary(n_bits) for k in keys})

    def convert_if_needed(self, state: np.ndarray) -> int | np.ndarray:
        """A bit vector as this env observes it: the integer ``sum(bit_i * 2**i)``
        (``discrete_obs_space``), the image (``image_obs_space``), else the vector itself."""
        if self.discrete_obs_space:
            return int(np.asarray(state, dtype=np.int64) @ (1 << np.arange(len(state))))
        if self.image_obs_space:
            image = np.zeros(int(np.prod(self.image_shape)), dtype=np.uint8)
            image[: len(state)] = np.asarray(state, dtype=np.uint8) * 255
            return image.reshape(self.image_shape)
        return state

    def convert_to_bit_vector(self, state: int | np.ndarray, batch_size: int) -> np.ndarray:
        """``batch_size`` observed goals back as bit vectors ``[batch_size, n_bits]``.

        An ``int`` (one ``discrete_obs_space`` goal) -> its bits (int64); images -> their first
        ``n_bits`` pixels over 255 (float); bit vectors -> reshaped. A batch of integer goals
        is decoded to bits too (SB3 passes such an array through unchanged: the rewards
        compare equal either way)."""
        if isinstance(state, (int, np.integer)) or (
            self.discrete_obs_space and not self.image_obs_space
        ):
            codes = np.asarray(state, dtype=np.int64).reshape(batch_size, -1)[:, :1]
            return (codes >> np.arange(self.n_bits)) & 1
        if self.image_obs_space:
            return np.asarray(state).reshape(batch_size, -1)[:, : self.n_bits] / 255
        return np.asarray(state).reshape(batch_size, -1)

    def _get_obs(self) -> dict[str, Any]:
        return {
            "observation": self.convert_if_needed(self.state.copy()),
            "achieved_goal": self.convert_if_needed(self.state.copy()),
            "desired_goal": self.convert_if_needed(self.desired_goal.copy()),
        }

    # -- the env API -----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """A uniformly drawn state (SB3's draw: ``MultiBinary(n_bits).sample()``)."""
        super().reset(seed=seed)
        self.current_step = 0
        self.state = self.np_random.integers(0, 2, size=self.n_bits, dtype=np.int8)
        return self._get_obs(), {}

    def step(self, action: Any) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Flip bit ``action`` (or the bits where ``action > 0``); reward 0 and termination
        when every bit is one, else -1; truncation after ``max_steps`` steps."""
        if self.continuous:
            flip = np.asarray(action)
            if flip.shape != (self.n_bits,) or flip.dtype.kind not in "biuf":
                raise invalid_action(action, self.action_space, f"expected {self.n_bits} numbers")
            mask = flip > 0
            self.state[mask] = 1 - self.state[mask]
        else:
            bit = check_discrete_action(action, self.action_space, self.n_bits)
            self.state[bit] = 1 - self.state[bit]
        obs = self._get_obs()
        reward = float(self.compute_reward(obs["achieved_goal"], obs["desired_goal"], None)[0])
        terminated = reward == 0
        self.current_step += 1
        truncated = self.current_step >= self.max_steps
        return obs, reward, terminated, truncated, {"is_success": terminated}

    def compute_reward(
        self, achieved_goal: Any, desired_goal: Any, _info: Any = None
    ) -> np.ndarray:
        """Rewards ``[batch]`` (float32): 0 where the goals are equal, -1 elsewhere, for one
        goal pair (a batch of one) or a batch (the leading axis), as SB3 computes them."""
        if isinstance(achieved_goal, (int, np.integer)):
            batch_size = 1
        else:
            goal_ndim = 3 if self.image_obs_space else 1
            shape = np.shape(achieved_goal)
            batch_size = shape[0] if len(shape) > goal_ndim else 1
        desired = self.convert_to_bit_vector(desired_goal, batch_size)
        achieved = self.convert_to_bit_vector(achieved_goal, batch_size)
        return -(np.any(achieved != desired, axis=-1)).astype(np.float32)

    def render(self) -> np.ndarray | str | None:
        """``human``: print the bits (as SB3); ``ansi``: them as a string; ``rgb_array``: a
        frame with the state (top row) over the desired goal, white cells for ones."""
        if self.render_mode == "rgb_array":
            rows = np.stack([self.state, self.desired_goal]).astype(np.uint8) * 255
            cells = np.kron(rows, np.ones((_CELL, _CELL), dtype=np.uint8))
            return np.repeat(cells[:, :, None], 3, axis=2)
        if self.render_mode == "ansi":
            return "".join(str(int(b)) for b in self.state)
        if self.render_mode == "human":
            print(self.state)
        return None

    def close(self) -> None:
        """Nothing to release."""
