"""SB3's ``stable_baselines3.her.goal_selection_strategy``: which achieved goal a hindsight
transition is relabelled with."""

from __future__ import annotations

from enum import Enum
from typing import Any

__all__ = ["KEY_TO_GOAL_STRATEGY", "GoalSelectionStrategy", "goal_strategy"]


class GoalSelectionStrategy(Enum):
    """``FUTURE``: a goal achieved at this step or later in the same episode; ``FINAL``: the
    goal achieved at the episode's end; ``EPISODE``: any goal achieved in the episode."""

    FUTURE = 0
    FINAL = 1
    EPISODE = 2


KEY_TO_GOAL_STRATEGY = {
    "future": GoalSelectionStrategy.FUTURE,
    "final": GoalSelectionStrategy.FINAL,
    "episode": GoalSelectionStrategy.EPISODE,
}


def goal_strategy(value: Any) -> GoalSelectionStrategy:
    """A strategy from its name (any case) or itself; ``ValueError`` naming anything else."""
    if isinstance(value, GoalSelectionStrategy):
        return value
    if isinstance(value, str) and value.lower() in KEY_TO_GOAL_STRATEGY:
        return KEY_TO_GOAL_STRATEGY[value.lower()]
    raise ValueError(
        f"goal_selection_strategy must be one of {sorted(KEY_TO_GOAL_STRATEGY)} or a "
        f"GoalSelectionStrategy, got {value!r}"
    )
