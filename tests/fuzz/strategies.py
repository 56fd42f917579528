"""What the property-based tests share: junk values, the budgets, and the one check.

The check (:func:`clear`) runs a call and lets it succeed or fail in only one way: a palaestra
error, ``ValueError`` or ``TypeError`` whose message names one of the offending values (its
repr, its str, or its type's name). Anything else (AttributeError, IndexError, KeyError,
ZeroDivisionError, OverflowError, ...) escapes and fails the example; a segfault or a hang
fails the run (each test has a timeout).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from palaestra import error

# Each property runs FAST examples in the default suite and SLOW under the slow marker; the
# slow budgets add up to more than 10,000 examples (tests/fuzz/test_budget.py checks).
BUDGETS = pytest.mark.parametrize(
    "budget",
    [pytest.param("fast", id="fast"), pytest.param("slow", id="slow", marks=pytest.mark.slow)],
)


def fuzz_settings(budget: str, fast: int, slow: int) -> settings:
    """Hypothesis settings for one property: no example database written, no deadline (the
    machines are shared and noisy), derandomised in the fast run so CI is reproducible."""
    return settings(
        max_examples=fast if budget == "fast" else slow,
        deadline=None,
        database=None,
        derandomize=budget == "fast",
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    )


ALLOWED = (error.Error, ValueError, TypeError, error.ClosedEnvironmentError)

DTYPES = [
    np.bool_, np.int8, np.uint8, np.int32, np.int64, np.uint64, np.float16, np.float32,
    np.float64, np.complex64, np.complex128,
]  # fmt: skip

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    st.integers(-3, 6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.complex_numbers(allow_nan=True, allow_infinity=True),
    st.text(max_size=4),
    st.binary(max_size=3),
)

arrays = st.one_of(
    hnp.arrays(
        st.sampled_from(DTYPES),
        hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=4),
    ),
    hnp.arrays(st.just(np.dtype("U3")), hnp.array_shapes(min_dims=0, max_dims=2, max_side=3)),
    hnp.arrays(
        st.just(np.dtype(object)),
        hnp.array_shapes(min_dims=1, max_dims=2, max_side=3),
        elements=scalars,
    ),
)

# Any value a user might pass by mistake: scalars, numpy values and arrays, nested containers.
junk = st.recursive(
    st.one_of(scalars, arrays),
    lambda children: st.one_of(
        st.lists(children, max_size=4),
        st.tuples(children, children),
        st.dictionaries(st.text(max_size=3), children, max_size=3),
    ),
    max_leaves=6,
)

dtypes_junk = st.one_of(
    st.sampled_from(DTYPES),
    st.sampled_from([object, str, "float32", "int64", "nonsense", None, 3, float, int, bool]),
)

# Small sizes and the classic mistakes around them (0, negatives, floats, strings, too large
# for an int64). Not 2**31: a space of that size is valid, and numpy's MemoryError says so.
sizes = st.one_of(
    st.integers(-3, 6),
    st.sampled_from([2**64, -(2**63), 1.0, 2.5, float("nan"), "3", None, True]),
    st.floats(allow_nan=True, allow_infinity=True),
)
# Counts that size nothing up front (Discrete's n, a time limit): huge values are fair.
counts = st.one_of(sizes, st.sampled_from([2**31, 2**62, 2**63 - 1]))


def _candidates(value: Any) -> list[str]:
    """The ways a message may name ``value``."""
    names = [type(value).__name__]
    for text in (repr(value), str(value)):
        if len(text) <= 300:
            names.append(text)
    if isinstance(value, np.ndarray):
        names += [str(value.dtype), str(value.shape), np.array2string(value)[:40]]
        if value.dtype.kind in "iuf":  # as a float32 Box prints its bounds
            names.append(str(value.astype(np.float32)))
    elif isinstance(value, (list, tuple)):
        try:
            names.append(str(np.shape(value)))  # "should have the same shape, got (0,) ..."
        except ValueError:
            pass
    if isinstance(value, float) and math.isfinite(value) and value == int(value):
        names.append(str(int(value)))
    real = (int, float, np.integer, np.floating)
    if isinstance(value, real) and not isinstance(value, bool):
        names.append(str(bool(value)))  # as a bool Box prints its bounds
        for dtype in (np.float32, np.float64):  # as numpy prints it inside an array
            with np.errstate(over="ignore"):
                names.append(str(np.array([value], dtype=dtype))[1:-1].strip())
    if isinstance(value, (list, tuple, dict, str, bytes)) and len(value) == 0:
        names += ["empty", "Empty", "at least one", "non-empty"]
    return [n for n in names if n]


def _parts(value: Any, depth: int = 3) -> list[Any]:
    """``value`` and what it holds (a few levels down): the offending part may be nested."""
    parts = [value]
    if depth and isinstance(value, (list, tuple, dict)):
        items = value.items() if isinstance(value, dict) else value
        for item in items:
            parts += _parts(item, depth - 1)
    return parts


def names(message: str, *values: Any) -> bool:
    """Whether ``message`` names one of ``values``, a part of one, or one of their types."""
    return any(c in message for v in values for p in _parts(v) for c in _candidates(p))


def clear(call: Callable[[], Any], *offending: Any) -> Any:
    """``call()``; None if it raised an allowed error whose message names an offending value."""
    try:
        return call()
    except ALLOWED as e:
        message = str(e)
        assert names(message, *offending), (
            f"{type(e).__name__}({message!r}) names none of {offending!r}"
        )
        return None
