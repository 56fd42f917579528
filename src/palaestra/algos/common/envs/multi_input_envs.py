"""``SimpleMultiObsEnv`` (SB3's ``multi_input_envs``): a 4x4 grid world seen through a Dict
observation, a vector for the column and an image for the row, for the ``MultiInputPolicy``.

Random draws are SB3's: the vectors and images are drawn at construction and the random start
at each reset from numpy's global generator (``np.random``), so ``np.random.seed(s)`` before
construction and before each reset gives SB3's grid and starts; ``reset(seed=s)`` reseeds
``np_random`` only. Observations are copies of the grid's arrays (SB3 returns the arrays
themselves, so changing an observation changed the grid), and an action outside the action
space raises ``InvalidAction`` (SB3 indexes with it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from palaestra import spaces
from palaestra.algos.common.envs.identity_env import checked_action
from palaestra.core import Env

__all__ = ["SimpleMultiObsEnv"]

# Cells each move is possible from on SB3's 4x4 grid (cells 5, 6, 9 and 10 are walls); the
# lists are SB3's and are kept for other grid sizes too, as SB3 keeps them.
_LEFT = (1, 2, 3, 13, 14, 15)
_DOWN = (0, 4, 8, 3, 7, 11)
_RIGHT = (0, 1, 2, 12, 13, 14)
_UP = (4, 8, 12, 7, 11, 15)


class SimpleMultiObsEnv(Env[dict[str, np.ndarray], Any]):
    """Grid world from cell 0 (or a random cell) to the last cell; actions are left, down,
    right, up. Reward -0.1 a step, 1.0 on reaching the goal (``terminated``); truncated after
    101 steps (SB3's ``count > max_count`` with ``max_count = 100``).

    .. code-block:: text

         0  1  2  3
         4 |5  6| 7
         8 |9 10|11
        12 13 14 15

    :param num_col: columns; each is a random ``(5,)`` float64 vector (``"vec"``)
    :param num_row: rows; each is a random ``64x64`` uint8 image (``"img"``)
    :param random_start: start each episode in a random cell below the goal
    :param discrete_actions: ``Discrete(4)``; else ``Box(0, 1, (4,))`` read by its argmax
    :param channel_last: images ``(64, 64, 1)``, else ``(1, 64, 64)``
    """

    def __init__(
        self,
        num_col: int = 4,
        num_row: int = 4,
        random_start: bool = True,
        discrete_actions: bool = True,
        channel_last: bool = True,
    ) -> None:
        self.vector_size = 5
        self.img_size = [64, 64, 1] if channel_last else [1, 64, 64]
        self.random_start = random_start
        self.discrete_actions = discrete_actions
        self.action_space: spaces.Space[Any] = (
            spaces.Discrete(4) if discrete_actions else spaces.Box(0, 1, (4,))
        )
        self.observation_space = spaces.Dict(
            {
                "vec": spaces.Box(0, 1, (self.vector_size,), dtype=np.float64),
                "img": spaces.Box(0, 255, tuple(self.img_size), dtype=np.uint8),
            }
        )
        self.count = 0
        self.max_count = 100
        self.log = ""
        self.state = 0
        self.action2str = ["left", "down", "right", "up"]
        self.num_col = num_col
        self.state_mapping: list[dict[str, np.ndarray]] = []
        self.init_state_mapping(num_col, num_row)
        self.max_state = len(self.state_mapping) - 1

    def init_state_mapping(self, num_col: int, num_row: int) -> None:
        """Draw each column's vector and each row's image (global ``np.random``, in SB3's
        order) and list the observation of every cell, column by column as SB3 does."""
        col_vecs = np.random.random((num_col, self.vector_size))  # noqa: NPY002 - SB3's draws
        row_imgs = np.random.randint(0, 255, (num_row, 64, 64), dtype=np.uint8)  # noqa: NPY002
        for i in range(num_col):
            for j in range(num_row):
                self.state_mapping.append(
                    {"vec": col_vecs[i], "img": row_imgs[j].reshape(self.img_size)}
                )

    def get_state_mapping(self) -> dict[str, np.ndarray]:
        """The observation of the current cell (copies)."""
        cell = self.state_mapping[self.state]
        return {"vec": cell["vec"].copy(), "img": cell["img"].copy()}

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        action = checked_action(action, self.action_space)
        move = int(action) if self.discrete_actions else int(np.argmax(action))
        self.count += 1
        before = self.state
        if move == 0 and self.state in _LEFT:
            self.state -= 1
        elif move == 1 and self.state in _DOWN:
            self.state += self.num_col
        elif move == 2 and self.state in _RIGHT:
            self.state += 1
        elif move == 3 and self.state in _UP:
            self.state -= self.num_col
        got_to_end = self.state == self.max_state
        reward = 1.0 if got_to_end else -0.1
        self.log = f"Went {self.action2str[move]} in state {before}, got to state {self.state}"
        truncated = self.count > self.max_count
        return self.get_state_mapping(), reward, got_to_end, truncated, {"got_to_end": got_to_end}

    def render(self) -> None:
        """Print the last move (SB3's ``render`` prints it)."""
        print(self.log)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        self.count = 0
        # SB3's draw: never the goal cell itself
        start = np.random.randint(0, self.max_state) if self.random_start else 0  # noqa: NPY002
        self.state = int(start)
        return self.get_state_mapping(), {}
