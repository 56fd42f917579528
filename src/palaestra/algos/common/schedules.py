"""Schedules: functions of ``progress_remaining`` (1.0 at the start of training, 0.0 at the end).

SB3 passes every schedulable hyperparameter (learning rate, clip range, epsilon) through a
callable of progress remaining; a plain number means a constant. The two classes here are the
only schedules palaestra can store in a model file exactly; any other callable is tabulated on
save (see ``model_io``).

>>> eps = LinearSchedule(1.0, 0.05, 0.1)
>>> eps(1.0), round(eps(0.95), 6), eps(0.5)
(1.0, 0.525, 0.05)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

Schedule = Callable[[float], float]

__all__ = [
    "ConstantSchedule",
    "FloatSchedule",
    "LinearSchedule",
    "Schedule",
    "TabulatedSchedule",
    "as_schedule",
    "schedule_from_json",
    "schedule_to_json",
]


@dataclass(frozen=True)
class ConstantSchedule:
    """The same value at every point of training."""

    value: float

    def __call__(self, progress_remaining: float) -> float:
        return float(self.value)


@dataclass(frozen=True)
class LinearSchedule:
    """Interpolate from ``start`` (progress 1) to ``end``, reached after ``end_fraction`` of
    training, then stay at ``end``; SB3's ``LinearSchedule`` / ``get_linear_fn``."""

    start: float
    end: float
    end_fraction: float = 1.0

    def __call__(self, progress_remaining: float) -> float:
        elapsed = 1.0 - progress_remaining
        if self.end_fraction <= 0 or elapsed > self.end_fraction:
            return float(self.end)
        return float(self.start + elapsed * (self.end - self.start) / self.end_fraction)


@dataclass(frozen=True)
class TabulatedSchedule:
    """A schedule sampled at evenly spaced progress points (index 0 is progress 0) and
    interpolated linearly; how an arbitrary user callable is stored without pickle."""

    values: tuple[float, ...]

    def __call__(self, progress_remaining: float) -> float:
        grid = np.linspace(0.0, 1.0, len(self.values))
        return float(np.interp(progress_remaining, grid, self.values))


@dataclass(frozen=True)
class FloatSchedule:
    """A user's schedule whose values are returned as Python floats (SB3's ``FloatSchedule``):
    a callable returning numpy scalars or ints still gives ``float``."""

    value_schedule: Schedule

    def __call__(self, progress_remaining: float) -> float:
        return float(self.value_schedule(progress_remaining))


def as_schedule(value: float | Schedule) -> Schedule:
    """A number becomes a ``ConstantSchedule``; a callable returns Python floats (SB3's
    ``get_schedule_fn``: other callables are wrapped in ``FloatSchedule``).

    >>> as_schedule(3e-4)(0.5)
    0.0003
    >>> type(as_schedule(lambda p: np.float32(p))(0.5)).__name__
    'float'
    """
    if isinstance(value, (ConstantSchedule, LinearSchedule, TabulatedSchedule, FloatSchedule)):
        return value  # these return floats already (and save exactly)
    if callable(value):
        return FloatSchedule(value)
    if isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool):
        return ConstantSchedule(float(value))
    raise TypeError(f"expected a number or a callable of progress_remaining, got {value!r}")


TABLE_POINTS = 1001


def schedule_to_json(schedule: Schedule) -> dict[str, Any]:
    """Describe a schedule as JSON; unknown callables are sampled at 1001 progress points."""
    if isinstance(schedule, ConstantSchedule):
        return {"type": "constant", "value": schedule.value}
    if isinstance(schedule, LinearSchedule):
        return {
            "type": "linear",
            "start": schedule.start,
            "end": schedule.end,
            "end_fraction": schedule.end_fraction,
        }
    if isinstance(schedule, TabulatedSchedule):
        return {"type": "table", "values": list(schedule.values)}
    grid = np.linspace(0.0, 1.0, TABLE_POINTS)
    return {"type": "table", "values": [float(schedule(float(p))) for p in grid]}


def schedule_from_json(data: Any) -> Schedule:
    """Inverse of ``schedule_to_json``; raises ``ValueError`` on anything else."""
    kind = data.get("type") if isinstance(data, dict) else None
    try:
        if kind == "constant":
            return ConstantSchedule(float(data["value"]))
        if kind == "linear":
            return LinearSchedule(
                float(data["start"]), float(data["end"]), float(data["end_fraction"])
            )
        if kind == "table" and len(data["values"]) >= 2:
            return TabulatedSchedule(tuple(float(v) for v in data["values"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"malformed schedule {data!r}") from exc
    raise ValueError(f"unknown schedule {data!r}")
