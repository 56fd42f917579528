"""The assumptions that let one ``step_state`` serve Python floats and numpy arrays exactly."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from palaestra.envs.classic_control._ops import ARRAY, SCALAR


@pytest.fixture(scope="module")
def points() -> np.ndarray:
    rng = np.random.default_rng(0)
    return np.concatenate([rng.uniform(-4, 4, 300_000), rng.uniform(-60, 60, 100_000)])


@pytest.mark.parametrize("name", ["cos", "sin"])
def test_numpy_trig_is_libm_bit_for_bit(points: np.ndarray, name: str) -> None:
    """numpy's float64 cos/sin (arrays, strided views, scalars) equal math.cos/sin here.

    If this fails on a platform, the batched engine and the numpy-scalar Gymnasium envs
    differ from the Python-float path by an ulp now and then: parity is no longer exact.
    """
    ufunc, libm = getattr(np, name), getattr(math, name)
    expected = np.array([libm(x) for x in points.tolist()])
    np.testing.assert_array_equal(ufunc(points), expected)
    np.testing.assert_array_equal(ufunc(points[::3]), expected[::3])
    assert [float(ufunc(np.float64(x))) for x in points[:2000]] == expected[:2000].tolist()


def test_pow2_is_libm_pow_not_the_square() -> None:
    """Gymnasium's ``x**2`` on numpy scalars is libm pow, which differs from x*x sometimes."""
    x = np.random.default_rng(1).uniform(-30, 30, 400_000)
    expected = np.array([v**2 for v in x.tolist()])  # Python's float pow: the same libm call
    assert (expected != x * x).sum() > 0  # the reason pow2 exists
    np.testing.assert_array_equal(ARRAY.pow2(x), expected)
    assert [SCALAR.pow2(v) for v in x[:1000].tolist()] == expected[:1000].tolist()
    assert [float(np.float64(v) ** 2) for v in x[:1000]] == expected[:1000].tolist()


def test_powf2_is_numpy_float32_scalar_power() -> None:
    u = np.random.default_rng(2).uniform(-3, 3, 200_000).astype(np.float32)
    expected = np.array([float(v**2) for v in u])
    np.testing.assert_array_equal(ARRAY.powf2(u.astype(np.float64)), expected)
    assert [SCALAR.powf2(float(v)) for v in u[:1000]] == expected[:1000].tolist()


def test_f32_rounding_agrees() -> None:
    x = np.random.default_rng(3).normal(size=10_000) * 10.0 ** np.arange(-5, 5).repeat(1000)
    expected = x.astype(np.float32).astype(np.float64)
    np.testing.assert_array_equal(ARRAY.f32(x), expected)
    assert [SCALAR.f32(v) for v in x.tolist()] == expected.tolist()
    assert SCALAR.f32(1e300) == math.inf  # numpy's overflow, not struct's OverflowError


def _f32_edge_cases() -> np.ndarray:
    """Doubles where a float32 rounding can go wrong: ties, range bounds, specials, random."""
    rng = np.random.default_rng(5)
    f = np.concatenate(
        [
            rng.uniform(-1e3, 1e3, 100_000).astype(np.float32),
            (rng.integers(2**23, 2**24, 100_000) * 2.0 ** rng.integers(-149, 105, 100_000)).astype(
                np.float32
            ),
            np.array([1, 2**-126, 2**-149, np.finfo(np.float32).max], dtype=np.float32),
        ]
    )
    f = np.concatenate([f, -f])
    with np.errstate(over="ignore"):  # float32 max's upper neighbour is inf (mid inf)
        up = np.nextafter(f, np.copysign(np.float32(np.inf), f))
    lo, hi = f.astype(np.float64), up.astype(np.float64)
    mid = lo + (hi - lo) / 2  # exact: float32 neighbours' midpoint needs <= 26 bits
    near = np.concatenate([np.nextafter(mid, -np.inf), mid, np.nextafter(mid, np.inf)])
    specials = [0.0, -0.0, np.inf, -np.inf, np.nan, 1e300, -1e300, 5e-324, -5e-324]
    bounds = [2.0**-126, 2.0**-126 - 2.0**-150, 2.0**-126 - 2.0**-151, 2.0**-150, 2.0**-151]
    bounds += [2.0**128 - 2.0**103, 2.0**128 - 2.0**103 - 2.0**75, 2.0**128, 3.4028235e38]
    bounds += [math.nextafter(b, d) for b in bounds for d in (-math.inf, math.inf)]
    random = rng.standard_normal(300_000) * 2.0 ** rng.uniform(-160, 140, 300_000)
    return np.concatenate([lo, near, specials, bounds, np.negative(bounds), random])


def test_scalar_f32_is_numpy_rounding_on_edge_cases() -> None:
    """The Veltkamp fast path and its struct fallback round exactly like ``np.float32``."""
    x = _f32_edge_cases()
    with np.errstate(over="ignore"):
        expected = x.astype(np.float32).astype(np.float64)
    got = np.array([SCALAR.f32(v) for v in x.tolist()])
    same = (got == expected) | (np.isnan(got) & np.isnan(expected))
    assert same.all(), x[~same][:10]
    assert np.array_equal(np.signbit(got), np.signbit(expected))  # -0.0 stays -0.0


def test_f32_where_rounds_only_where_asked() -> None:
    """Scalar and array ``f32_where`` equal ``f32`` where the condition holds, else the input."""
    x = _f32_edge_cases()
    cond = np.random.default_rng(6).random(x.size) < 0.5
    with np.errstate(over="ignore"):
        expected = np.where(cond, x.astype(np.float32).astype(np.float64), x)
    got = np.array([SCALAR.f32_where(c, v) for c, v in zip(cond.tolist(), x.tolist())])
    with np.errstate(over="ignore"):
        arr = ARRAY.f32_where(cond, x)
    for values in (got, arr):
        same = (values == expected) | (np.isnan(values) & np.isnan(expected))
        assert same.all(), x[~same][:10]
        assert np.array_equal(np.signbit(values), np.signbit(expected))


def test_remainder_and_clip_agree() -> None:
    x = np.random.default_rng(4).uniform(-50, 50, 100_000)
    ops: Any = ARRAY  # numpy ufuncs as staticmethods: their stubs confuse mypy
    np.testing.assert_array_equal(
        ops.mod(x + math.pi, 2 * math.pi), [SCALAR.mod(v + math.pi, 2 * math.pi) for v in x]
    )
    np.testing.assert_array_equal(ops.clip(x, -8, 8), [SCALAR.clip(v, -8, 8) for v in x])


def test_pick_selects_like_the_scalar_path() -> None:
    values = (np.array(-10.0), np.array(10.0))  # 0-d constants, as the array step passes them
    index = np.array([1, 0, 0, 1, 1])
    picked = ARRAY.pick(index, *values)
    assert picked.dtype == np.float64
    assert picked.tolist() == [SCALAR.pick(i, -10.0, 10.0) for i in index.tolist()]
    with pytest.raises(IndexError):  # a table lookup: nothing out of range slips through
        ARRAY.pick(np.array([0, 2]), *values)


def test_constants_are_0d_arrays_of_the_same_values() -> None:
    from palaestra.envs.classic_control.cartpole import CartPoleParams

    p = CartPoleParams()
    c = ARRAY.constants(p)
    assert isinstance(c.tau, np.ndarray) and c.tau.shape == () and c.tau == p.tau
    assert c.kinematics_integrator == p.kinematics_integrator  # non-floats kept as they are


def test_hard_squares_come_from_numpy_power_loop_not_python(monkeypatch: Any) -> None:
    """Near-midpoint rows take libm's answer through numpy's array-exponent power loop, in C.

    Rows where pow and ``x*x`` differ are found and fixed there; where numpy's loop is not
    libm (an AVX-512 build's SVML pow), the per-row Python path gives the same bits.
    """
    from palaestra.envs.classic_control import _ops

    # x86-64 without AVX-512, numpy 2.4 (this machine): numpy's loop calls libm's pow
    libm_loop = _ops.numpy_power_is_libm()
    x = np.random.default_rng(7).uniform(-30, 30, 50_000)
    expected = np.array([v**2 for v in x.tolist()])
    assert (expected != x * x).sum() > 10
    power, calls = np.power, []

    def spy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        calls.append(a.size)
        return power(a, b)

    monkeypatch.setattr(_ops.np, "power", spy)
    np.testing.assert_array_equal(ARRAY.pow2(x), expected)
    if libm_loop:
        assert calls and 0 < calls[0] < 0.06 * x.size  # only the hard rows, all at once
    else:  # another pow in numpy's loop: the hard rows went the per-row Python way
        assert calls == []
    monkeypatch.setattr(_ops, "numpy_power_is_libm", lambda: False)
    calls.clear()
    np.testing.assert_array_equal(ARRAY.pow2(x), expected)
    assert calls == []
    u = np.random.default_rng(8).uniform(-3, 3, 50_000).astype(np.float32)
    np.testing.assert_array_equal(ARRAY.powf2(u.astype(np.float64)), [float(v**2) for v in u])


def test_near_midpoint_mask_is_the_exact_squares_distance_from_a_midpoint() -> None:
    """The integer test flags exactly the rows whose exact square (Python's big integers) lies
    within ``0.5 - _POW_HARD`` ulp of the rounding midpoint, for 105- and 106-bit squares,
    the fraction where one turns into the other, wide exponents and subnormals."""
    import struct

    from palaestra.envs.classic_control import _ops

    rng = np.random.default_rng(31)
    x = rng.uniform(1.0, 2.0, 30_000) * 2.0 ** rng.integers(-400, 400, 30_000)
    x[::2] *= -1
    edge = int(_ops._SQ_105)
    frac = np.array([edge - 2, edge - 1, edge, edge + 1, 0, 2**52 - 1], dtype=np.uint64)
    x[:6] = (frac | np.uint64(1023 << 52)).view(np.float64)
    x[6:12] = [0.0, -0.0, 5e-324, -1e-310, 1e-160, 2.0**-520]
    near = _ops._near_midpoint(x)
    tol = _ops._NEAR_ULPS  # (0.5 - _POW_HARD) ulp, in the last of 53 dropped bits
    assert abs(tol - (0.5 - _ops._POW_HARD) * 2**53) < 1
    for i, v in enumerate(x.tolist()):
        if v == 0.0 or abs(v) < 2.0**-511:  # zeros exact; tiny squares always flagged
            assert near[i] == (v != 0.0), v
            continue
        bits = struct.unpack("<Q", struct.pack("<d", v))[0]
        m = (bits & (2**52 - 1)) | 2**52
        sq = m * m
        dropped = 53 if sq >= 2**105 else 52
        rest = (sq % 2**dropped) << (53 - dropped)  # as a 53-bit remainder
        assert near[i] == (2**52 - tol <= rest < 2**52 + tol), (v, rest)
    assert 0.03 < near.mean() < 0.05


def test_pow2s_equals_pow2_of_each() -> None:
    a, b, c = np.random.default_rng(9).uniform(-30, 30, (3, 20_000))
    for got, x in zip(ARRAY.pow2s(a, b[::-1], c), (a, b[::-1], c)):
        np.testing.assert_array_equal(got, [v**2 for v in x.tolist()])
    assert SCALAR.pow2s(1.5, -3.0) == [2.25, 9.0]


def test_squares_that_underflow_dekker_or_overflow_match_numpy_scalars() -> None:
    x = np.array([0.0, -0.0, 1e-160, -3e-170, 1e-200, 2.0**-600, 1.0, np.inf, np.nan, 1e200])
    with np.errstate(all="ignore"):
        got = ARRAY.pow2(x)
        expected = np.array([float(np.float64(v) ** 2) for v in x.tolist()])  # Gymnasium's
    np.testing.assert_array_equal(got, expected)
