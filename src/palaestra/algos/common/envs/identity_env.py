"""Identity envs (SB3's ``identity_env``): the observation is a sample of the action space and
the reward is 1 for acting it back, so a policy that learns anything learns the identity.
``FakeImageEnv`` returns random Atari-sized frames for exercising the ``CnnPolicy``.

Random draws are SB3's: each state is ``action_space.sample()`` (``FakeImageEnv``:
``observation_space.sample()``), so ``env.action_space.seed(s)`` fixes the states, as in SB3
(``make_vec_env(..., seed=s)`` does it); ``reset(seed=s)`` reseeds ``np_random`` only, which
these envs do not draw from. Episodes end by truncation only, after ``ep_length`` steps.
Unlike SB3's, an action outside the space raises ``InvalidAction`` naming it.
"""

from __future__ import annotations

from typing import Any, Generic, TypeVar, cast

import numpy as np

from palaestra import spaces
from palaestra.core import Env
from palaestra.envs.action_checks import check_discrete_action, invalid_action

__all__ = [
    "FakeImageEnv",
    "IdentityEnv",
    "IdentityEnvBox",
    "IdentityEnvMultiBinary",
    "IdentityEnvMultiDiscrete",
]

T = TypeVar("T", int, np.ndarray)


def checked_action(action: Any, space: spaces.Space[Any]) -> Any:
    """``action`` if it belongs to ``space`` (a Box action: the right shape, real and finite,
    bounds not enforced, as the classic-control envs), else ``InvalidAction`` naming both."""
    if isinstance(space, spaces.Discrete) and int(space.start) == 0:
        # the fast check counts from 0; another start goes through space.contains below
        return check_discrete_action(action, space, int(space.n))
    if isinstance(space, spaces.Box):
        try:
            array = np.asarray(action)
        except (TypeError, ValueError) as exc:
            raise invalid_action(action, space, "not a numeric array") from exc
        if array.dtype.kind not in "biuf":
            raise invalid_action(action, space, f"expected real values, got dtype {array.dtype}")
        if array.shape != space.shape:
            raise invalid_action(action, space, f"expected shape {space.shape}, got {array.shape}")
        if not np.all(np.isfinite(array)):
            raise invalid_action(action, space, "actions must be finite (no NaN or inf)")
        return array
    if not space.contains(action):
        raise invalid_action(action, space)
    return action


class IdentityEnv(Env[T, T], Generic[T]):
    """Observation = action space sample; reward 1.0 when the action equals it, else 0.0.

    :param dim: ``Discrete(dim)`` spaces (default 1); give at most one of ``dim`` and ``space``
    :param space: the action and observation space
    :param ep_length: steps per episode (then ``truncated``)
    """

    def __init__(
        self, dim: int | None = None, space: spaces.Space[Any] | None = None, ep_length: int = 100
    ) -> None:
        if space is None:
            space = spaces.Discrete(1 if dim is None else dim)
        elif dim is not None:
            raise ValueError(
                f"arguments for both 'dim' ({dim!r}) and 'space' ({space}) provided: at most "
                "one allowed"
            )
        self.action_space = self.observation_space = cast("spaces.Space[T]", space)
        self.ep_length = ep_length
        self.current_step = 0
        self.num_resets = -1  # the reset below makes it 0, as SB3's
        self.state: Any = None
        self.reset()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[T, dict[str, Any]]:
        super().reset(seed=seed)
        self.current_step = 0
        self.num_resets += 1
        self._choose_next_state()
        return self.state, {}

    def step(self, action: T) -> tuple[T, float, bool, bool, dict[str, Any]]:
        reward = self._get_reward(checked_action(action, self.action_space))
        self._choose_next_state()
        self.current_step += 1
        return self.state, reward, False, self.current_step >= self.ep_length, {}

    def _choose_next_state(self) -> None:
        self.state = self.action_space.sample()

    def _get_reward(self, action: Any) -> float:
        return 1.0 if np.all(self.state == action) else 0.0

    def render(self) -> None:
        """Nothing to draw (SB3's renders nothing either)."""


class IdentityEnvBox(IdentityEnv[np.ndarray]):
    """A ``Box(low, high, (1,), float32)`` identity: reward 1.0 when the action is within
    ``eps`` of the observation."""

    def __init__(
        self, low: float = -1.0, high: float = 1.0, eps: float = 0.05, ep_length: int = 100
    ) -> None:
        space = spaces.Box(low=low, high=high, shape=(1,), dtype=np.float32)
        super().__init__(ep_length=ep_length, space=space)
        self.eps = eps

    def _get_reward(self, action: Any) -> float:
        # SB3's arithmetic: float32 state +- eps, compared with the action as given
        low, high = self.state - self.eps, self.state + self.eps
        return 1.0 if bool(np.all((low <= action) & (action <= high))) else 0.0


class IdentityEnvMultiDiscrete(IdentityEnv[np.ndarray]):
    """A ``MultiDiscrete([dim, dim])`` identity."""

    def __init__(self, dim: int = 1, ep_length: int = 100) -> None:
        super().__init__(ep_length=ep_length, space=spaces.MultiDiscrete([dim, dim]))


class IdentityEnvMultiBinary(IdentityEnv[np.ndarray]):
    """A ``MultiBinary(dim)`` identity."""

    def __init__(self, dim: int = 1, ep_length: int = 100) -> None:
        super().__init__(ep_length=ep_length, space=spaces.MultiBinary(dim))


class FakeImageEnv(Env[np.ndarray, Any]):
    """Random ``uint8`` frames of Atari's size, reward 0, episodes of 10 steps.

    :param action_dim: ``Discrete(action_dim)`` actions (``discrete=True``)
    :param screen_height, screen_width, n_channels: the frame's shape
    :param discrete: ``False``: ``Box(-1, 1, (5,), float32)`` actions
    :param channel_first: frames ``(n_channels, H, W)`` instead of ``(H, W, n_channels)``
    """

    def __init__(
        self,
        action_dim: int = 6,
        screen_height: int = 84,
        screen_width: int = 84,
        n_channels: int = 1,
        discrete: bool = True,
        channel_first: bool = False,
    ) -> None:
        if channel_first:
            self.observation_shape = (n_channels, screen_height, screen_width)
        else:
            self.observation_shape = (screen_height, screen_width, n_channels)
        self.observation_space = spaces.Box(0, 255, self.observation_shape, np.uint8)
        self.action_space: spaces.Space[Any] = (
            spaces.Discrete(action_dim)
            if discrete
            else spaces.Box(-1, 1, shape=(5,), dtype=np.float32)
        )
        self.ep_length = 10
        self.current_step = 0

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.current_step = 0
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        checked_action(action, self.action_space)
        self.current_step += 1
        truncated = self.current_step >= self.ep_length
        return self.observation_space.sample(), 0.0, False, truncated, {}

    def render(self) -> None:
        """Nothing to draw (SB3's renders nothing either)."""
