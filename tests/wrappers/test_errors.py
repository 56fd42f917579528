# ruff: noqa: E501  (one case per line reads best in these tables)
"""Bad constructor arguments raise clear errors that name the value and the expectation."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.wrappers.conftest import make_toy, pal

from palaestra.error import InvalidAction, InvalidBound, InvalidProbability

W = pal().W


def cont() -> Any:
    return make_toy(pal(), "ToyContinuous")


def chain() -> Any:
    return make_toy(pal(), "ToyChain")


def dict_env() -> Any:
    return make_toy(pal(), "ToyDict")


def tuple_env() -> Any:
    return make_toy(pal(), "ToyTuple")


CASES: list[tuple[str, Any, type[Exception], str]] = [
    # action wrappers
    ("ClipAction-discrete", lambda: W.ClipAction(chain()), TypeError, r"ClipAction requires a Box action space, got .*Discrete"),
    ("RescaleAction-discrete", lambda: W.RescaleAction(chain(), 0.0, 1.0), TypeError, "RescaleAction requires a Box"),
    ("RescaleAction-equal", lambda: W.RescaleAction(cont(), 1.0, 1.0), InvalidBound, r"Min action \(1.0\) must be strictly smaller than max action \(1.0\)"),
    ("RescaleAction-reversed", lambda: W.RescaleAction(cont(), 1.0, -1.0), ValueError, r"Min action \(1.0\) must be smaller than max action \(-1.0\)"),
    ("RescaleAction-shape", lambda: W.RescaleAction(cont(), np.zeros(3), 1.0), ValueError, r"new_min.shape to be \(2,\), got \(3,\)"),
    ("RescaleAction-type", lambda: W.RescaleAction(cont(), "0", 1.0), TypeError, "new_min to be an int, float or numpy array"),
    ("TransformAction-func", lambda: W.TransformAction(cont(), 3, None), TypeError, "`func` to be callable, got 3"),
    ("DiscretizeAction-discrete", lambda: W.DiscretizeAction(chain(), 3), TypeError, "only compatible with Box actions, got Discrete"),
    ("DiscretizeAction-bins", lambda: W.DiscretizeAction(cont(), (2, 3, 4)), ValueError, "expected 2, got 3"),
    ("DiscretizeAction-zero-bins", lambda: W.DiscretizeAction(cont(), 0), ValueError, "at least 1, got 0"),
    ("StickyAction-p1", lambda: W.StickyAction(chain(), 1.0), InvalidProbability, r"interval \[0,1\). Received 1.0"),
    ("StickyAction-negative", lambda: W.StickyAction(chain(), -0.1), InvalidProbability, "Received -0.1"),
    ("StickyAction-duration-order", lambda: W.StickyAction(chain(), 0.5, (3, 1)), InvalidBound, r"Received \(3, 1\)"),
    ("StickyAction-duration-zero", lambda: W.StickyAction(chain(), 0.5, 0), ValueError, "larger or equal than 1. Received 0"),
    ("StickyAction-duration-len", lambda: W.StickyAction(chain(), 0.5, (1, 2, 3)), ValueError, "two integers"),
    ("StickyAction-duration-type", lambda: W.StickyAction(chain(), 0.5, 1.5), ValueError, "integer or a tuple. Received 1.5"),
    ("RepeatAction-zero", lambda: W.RepeatAction(chain(), 0), ValueError, "num_repeats needs to be at least 1, actual value: 0"),
    ("RepeatAction-float", lambda: W.RepeatAction(chain(), 2.0), TypeError, "num_repeats is expected to be an integer"),
    # reward wrappers
    ("ClipReward-none", lambda: W.ClipReward(chain()), InvalidBound, "cannot be None"),
    ("ClipReward-reversed", lambda: W.ClipReward(chain(), 1.0, 0.0), InvalidBound, r"Min reward \(1.0\) must be smaller than max reward \(0.0\)"),
    ("TransformReward-func", lambda: W.TransformReward(chain(), None), TypeError, "callable, got None"),
    ("NormalizeReward-gamma", lambda: W.NormalizeReward(chain(), gamma=1.5), InvalidBound, r"\[0, 1\]. Received 1.5"),
    ("NormalizeReward-eps", lambda: W.NormalizeReward(chain(), epsilon=0), InvalidBound, "strictly positive. Received 0"),
    # observation wrappers
    ("NormalizeObservation-eps", lambda: W.NormalizeObservation(cont(), epsilon=-1.0), InvalidBound, "Received -1.0"),
    ("FrameStack-zero", lambda: W.FrameStackObservation(cont(), 0), ValueError, "stack_size needs to be at least 1, actual value: 0"),
    ("FrameStack-float", lambda: W.FrameStackObservation(cont(), 2.5), TypeError, "stack_size is expected to be an integer"),
    ("FrameStack-padding", lambda: W.FrameStackObservation(cont(), 2, padding_type="zeros"), ValueError, "expected 'reset', 'zero' or an element of the observation space .*'zeros'"),
    ("FrameStack-padding-outside", lambda: W.FrameStackObservation(cont(), 2, padding_type=np.full(3, 9.0, np.float32)), ValueError, "actual value: array"),
    ("DelayObservation-negative", lambda: W.DelayObservation(cont(), -1), ValueError, "delay needs to be at least 0, actual value: -1"),
    ("DelayObservation-float", lambda: W.DelayObservation(cont(), 1.0), TypeError, "delay is expected to be an integer"),
    ("MaxAndSkip-1", lambda: W.MaxAndSkipObservation(cont(), skip=1), ValueError, "skip needs to be at least 2"),
    ("FilterObservation-unknown", lambda: W.FilterObservation(dict_env(), ["pos", "speed"]), ValueError, r"Missing keys: \['speed'\]"),
    ("FilterObservation-empty", lambda: W.FilterObservation(dict_env(), []), ValueError, "empty"),
    ("FilterObservation-int-keys-dict", lambda: W.FilterObservation(dict_env(), [0]), TypeError, "must be strings for a Dict"),
    ("FilterObservation-tuple-range", lambda: W.FilterObservation(tuple_env(), [0, 3]), ValueError, r"missing indexes: \[3\]"),
    ("FilterObservation-tuple-dup", lambda: W.FilterObservation(tuple_env(), [1, 1]), ValueError, "Duplicate keys"),
    ("FilterObservation-str", lambda: W.FilterObservation(dict_env(), "pos"), ValueError, r"got the string 'pos'; pass \['pos'\]"),
    ("FilterObservation-box", lambda: W.FilterObservation(cont(), ["x"]), ValueError, "only usable with `Dict` and `Tuple`"),
    ("ReshapeObservation-size", lambda: W.ReshapeObservation(cont(), (2, 2)), ValueError, r"new shape \(2, 2\) to match the original shape \(3,\)"),
    ("ReshapeObservation-list", lambda: W.ReshapeObservation(cont(), [3, 1]), TypeError, "tuple, got <class 'list'>"),
    ("ReshapeObservation-discrete", lambda: W.ReshapeObservation(chain(), (1,)), TypeError, "requires a Box"),
    ("RescaleObservation-discrete", lambda: W.RescaleObservation(chain(), 0.0, 1.0), TypeError, "requires a Box"),
    ("DtypeObservation-dict", lambda: W.DtypeObservation(dict_env(), np.float32), TypeError, "requires a Box, Discrete, MultiDiscrete, or MultiBinary space"),
    ("DiscretizeObservation-discrete", lambda: W.DiscretizeObservation(chain(), 3), TypeError, "only compatible with Box observations"),
    ("DiscretizeObservation-bins-type", lambda: W.DiscretizeObservation(cont(), "3"), TypeError, "`bins` must be an int or a tuple of ints, got '3'"),
    ("GrayscaleObservation-shape", lambda: W.GrayscaleObservation(cont()), ValueError, r"3 channels, got shape \(3,\)"),
    ("TimeAware-no-limit", lambda: W.TimeAwareObservation(cont()), ValueError, "TimeLimit wrapper or the spec"),
    ("TimeAware-key-clash", lambda: W.TimeAwareObservation(_timed(dict_env()), dict_time_key="pos"), ValueError, r"\('pos'\) already exists"),
]  # fmt: skip


def _timed(env: Any) -> Any:
    from palaestra.wrappers.common import TimeLimit

    return TimeLimit(env, 10)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_arguments(case: tuple[str, Any, type[Exception], str]) -> None:
    _, build, exc, pattern = case
    with pytest.raises(exc, match=pattern):
        build()


def test_discretize_on_unbounded_box() -> None:
    from palaestra.wrappers.transform_action import ClipAction

    with pytest.raises(ValueError, match="requires action space to be finite"):
        W.DiscretizeAction(ClipAction(cont()), 3)
    with pytest.raises(ValueError, match="requires observation space to be finite"):
        W.DiscretizeObservation(W.NormalizeObservation(cont()), 3)


def test_discretize_action_rejects_out_of_range() -> None:
    env = W.DiscretizeAction(cont(), 3)
    env.reset(seed=0)
    with pytest.raises(InvalidAction, match=r"Action 9 is not in the action space Discrete\(9\)"):
        env.step(9)
    with pytest.raises(InvalidAction, match="Action -1"):
        env.step(-1)
    env = W.DiscretizeAction(cont(), 3, multidiscrete=True)
    env.reset(seed=0)
    with pytest.raises(InvalidAction, match=r"MultiDiscrete\(\[3 3\]\)"):
        env.step(np.array([0, 3]))


def test_record_episode_statistics_refuses_to_overwrite_info() -> None:
    env = W.RecordEpisodeStatistics(chain(), stats_key="pos")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="info already has the key 'pos'"):
        for _ in range(100):
            env.step(2)
