"""Two interchangeable math namespaces so each env's physics is written once.

``step_state`` functions take ``ops`` as their first argument and only use the operations
below plus ``+ - * / < > == & |`` and builtin ``abs``. With :data:`SCALAR` they run on Python
floats (the single env's fast path); with :data:`ARRAY` they run on float64 arrays of N envs
(the batched engine).

Why this is exact: on the machines we measured (x86-64, numpy 2.4), numpy's float64
``np.cos``/``np.sin`` give bit-identical results to ``math.cos``/``math.sin`` (glibc libm) for
scalars, contiguous arrays and strided arrays alike -- ``tests/envs/test_ops.py`` checks this on
a million points, so a platform where numpy vectorises float64 trig differently fails loudly
instead of drifting silently. Gymnasium itself mixes ``math.cos`` (MountainCar) and ``np.cos``
on numpy scalars (CartPole, Pendulum, Acrobot); both are the same function here.

Squares are the exception. Gymnasium writes ``x**2`` on numpy scalars, which calls libm
``pow`` (``powf`` for float32), and glibc's pow is not correctly rounded: on a million random
doubles ``pow(x, 2) != x*x`` about 900 times (powf: ~700 per million). numpy's array ``x**2``
and ``np.power(x, 2.0)`` (a scalar exponent) are the exact square ``x*x`` (numpy's fast path
for power 2), while ``np.power(x, y)`` with an *array* exponent runs numpy's general power
loop, which on x86-64 without AVX-512 (numpy 2.4) calls libm ``pow``/``powf`` element by
element -- on AVX-512 machines it is SVML's vector pow instead, which differs from libm.

So :meth:`ArrayOps.pow2` takes the exact square ``x*x``, finds the rows whose exact square
lies within 0.02 ulp of a rounding midpoint -- the only ones where a pow with glibc's
documented < 0.52 ulp error can round the other way (measured: none beyond 0.007 ulp) -- from
the bits the square's rounding drops (integer arithmetic on the significand), and gives just
those rows libm's own
answer through numpy's general power loop: a few percent of rows, in C. Whether that loop is
libm here is checked once per process on points where pow and ``x*x`` differ
(:func:`numpy_power_is_libm`); where it is not, those rows take Python's ``**`` (the same libm
call) one by one, slower and as exact.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import struct
from typing import Any

import numpy as np

_f32 = np.float32
_pack_f32, _unpack_f32 = struct.Struct("f").pack, struct.Struct("f").unpack
_POW_HARD = 0.48  # ulps from the exact square beyond which libm pow may round differently
_POWF_HARD = 0.45  # the same for powf (measured mismatches all beyond 0.498)
_EXP_BITS = np.uint64(0x7FF0_0000_0000_0000)  # a double's exponent: 2**floor(log2|x|)
_FRACTION = np.uint64(2**52 - 1)  # its 52 stored fraction bits
_LOW_53 = np.uint64(2**53 - 1)
_SQ_105 = np.uint64(math.isqrt(2**105 - 1) + 1 - 2**52)  # fractions whose m*m has 106 bits
_NEAR_ULPS = int((0.5 - _POW_HARD) * 2**53)  # the tolerance, in the last of 53 dropped bits
_NEAR_FROM = np.uint64((_NEAR_ULPS - 2**52) % 2**64)
_NEAR_WIDTH = np.uint64(2 * _NEAR_ULPS)
_POWF_ULPS = _POWF_HARD * 2.0**-23  # _POWF_HARD ulps of a float32 in [1, 2)
_TINY = 2.0**-900  # below this the square's error underflows: libm decides those rows


@functools.cache
def numpy_power_is_libm() -> bool:
    """Whether ``np.power`` with an array exponent is libm ``pow``/``powf`` here, bit for bit.

    Checked on squares near rounding midpoints, where pow and ``x*x`` (and a vector pow with
    another error) part ways: about 1,200 float64 and 1,200 float32 points, a few ms once.
    """
    rng = np.random.default_rng(12345)
    x = rng.uniform(-30.0, 30.0, 30_000)
    x = x[_near_midpoint(x)]
    u = rng.uniform(-3.0, 3.0, 12_000).astype(np.float32)
    d = u.astype(np.float64) ** 2
    u = u[_near_midpoint32(d, d.astype(np.float32))]
    with np.errstate(all="ignore"):
        got = np.power(x, np.full_like(x, 2.0))
        got32 = np.power(u, np.full_like(u, 2.0))
    return got.tolist() == [v**2 for v in x.tolist()] and got32.tolist() == [float(v**2) for v in u]


def _near_midpoint(
    x: np.ndarray, p: np.ndarray | None = None, scratch: tuple[np.ndarray, ...] | None = None
) -> np.ndarray:
    """Rows whose exact square lies near a rounding midpoint of ``x*x``, as a boolean mask.

    In integers: a normal ``x`` has the significand ``m = 2**52 + f`` (``f``: its 52 stored
    fraction bits), and ``m*m = 2**104 + 2**53*f + f*f``, so the low 53 bits of the exact
    square are those of ``f*f`` -- which uint64 arithmetic gives, wrapping past 64 bits. A
    square of 106 bits rounds its low 53 bits away (the midpoint is 2**52); one of 105 bits
    (``f`` below ``_SQ_105``) its low 52, so those are shifted left once to be compared the
    same way. "Near" is within ``0.5 - _POW_HARD`` ulp of the midpoint. Squares below
    ``_TINY`` (subnormal ``x`` or an underflowing square, where this does not hold) count as
    near unless ``x`` is zero. ``p``: ``x*x`` when the caller has it; ``scratch``: two float64
    arrays and one boolean array shaped like ``x``, written over (the mask is the last), for
    callers that keep buffers (``_trace``); else fresh ones.
    """
    if p is None:
        p = x * x
    if scratch is None:
        scratch = (np.empty_like(x), np.empty_like(x), np.empty(x.shape, dtype=bool))
    f, low, near = scratch[0].view(np.uint64), scratch[1].view(np.uint64), scratch[-1]
    np.bitwise_and(x.view(np.uint64), _FRACTION, out=f)
    np.less(f, _SQ_105, out=near)  # 105-bit squares: shift by one
    np.multiply(f, f, out=low)  # the low 64 bits of f*f
    np.left_shift(low, near, out=low, casting="unsafe")
    np.add(low, _NEAR_FROM, out=low)  # midpoint - tolerance -> 0 (mod 2**64)
    np.bitwise_and(low, _LOW_53, out=low)
    np.less(low, _NEAR_WIDTH, out=near)
    if p.min() < _TINY:  # rare: subnormal x or squares that underflow (x = 0 is exact)
        near |= (p < _TINY) & (x != 0)
    return near


def _near_midpoint32(
    d: np.ndarray, f: np.ndarray, scratch: tuple[np.ndarray, ...] | None = None
) -> np.ndarray:
    """Rows whose exact square ``d`` (float64) lies near a midpoint of its float32 rounding
    ``f``, as a boolean mask (``d - f`` is exact: both are multiples of d's last bit).
    ``scratch``: two float64 arrays and one boolean array shaped like ``d``, written over
    (the mask is the last), for callers that keep buffers (``_trace``); else fresh ones."""
    if scratch is None:
        scratch = (np.empty_like(d), np.empty_like(d), np.empty(d.shape, dtype=bool))
    err, ulp, near = scratch
    np.subtract(d, f, out=err)
    np.abs(err, out=err)
    # d's binade (where it rounds), by a bit mask
    np.bitwise_and(d.view(np.uint64), _EXP_BITS, out=ulp.view(np.uint64))
    ulp *= _POWF_ULPS
    return np.greater(err, ulp, out=near)


class ScalarOps:
    """Operations on Python floats and bools."""

    cos = staticmethod(math.cos)
    sin = staticmethod(math.sin)

    @staticmethod
    def clip(x: float, lo: float, hi: float) -> float:
        """``np.clip`` for one float (equal to it for every non-NaN value)."""
        return lo if x < lo else (hi if x > hi else x)

    @staticmethod
    def where(cond: bool, a: Any, b: Any) -> Any:
        """``a if cond else b`` (both already evaluated, as with ``np.where``)."""
        return a if cond else b

    @staticmethod
    def pick(index: int, *values: float) -> float:
        """``values[index]``: the value a discrete action selects."""
        return values[index]

    @staticmethod
    def f32(x: float) -> float:
        """Round to the nearest float32 (ties to even, as numpy), kept as a Python float.

        Veltkamp's split ``c - (c - x)`` with ``c = x * (2**29 + 1)`` rounds a double to its
        nearest 24-bit value, ties to even: three float operations, ~1.6x cheaper than a
        struct round trip. It is float32's rounding only where the result is a normal float32,
        which ``h * h`` checks in one comparison (squaring is monotonic and no double lies
        close enough to either bound to round across it); zeros, subnormals, overflow to inf,
        inf and NaN take the struct path. ``tests/envs/test_ops.py`` compares it with
        ``np.float32`` on ties, both range bounds and random doubles.
        """
        # The constants are written out (folded at compile time): cheaper than global reads.
        c = x * (2.0**29 + 1)  # Veltkamp's splitter: keeps a double's leading 53 - 29 = 24 bits
        h = c - (c - x)
        if 2.0**-252 <= h * h < 2.0**256:  # |h| in [smallest normal float32, 2**128 (inf))
            return h
        try:
            return _unpack_f32(_pack_f32(x))[0]  # 3x np.float32
        except OverflowError:  # beyond float32's range: numpy gives inf
            return float(_f32(x))

    @staticmethod
    def f32_where(cond: bool, x: float) -> float:
        """``f32(x)`` if ``cond`` else ``x``: one call where a rounding depends on a condition.

        The fast path of :meth:`f32` is repeated here rather than called: a Python call costs
        about as much as the rounding itself.
        """
        if not cond:
            return x
        c = x * (2.0**29 + 1)
        h = c - (c - x)
        if 2.0**-252 <= h * h < 2.0**256:
            return h
        return ScalarOps.f32(x)

    @staticmethod
    def mod(x: float, m: float) -> float:
        """Python's ``%``, which equals ``np.remainder`` on float64 (same fmod + sign fix)."""
        return x % m

    @staticmethod
    def any(cond: bool) -> bool:
        """Whether the condition holds (for loops that must run until no row needs them)."""
        return bool(cond)

    @staticmethod
    def wrap(x: float, lo: float, hi: float) -> float:
        """Shift ``x`` by whole periods ``hi - lo`` into [lo, hi], one period at a time."""
        diff = hi - lo
        while x > hi:
            x = x - diff
        while x < lo:
            x = x + diff
        return x

    @staticmethod
    def pow2(x: float) -> float:
        """``x**2`` as numpy computes it on a float64 scalar (libm ``pow``)."""
        return x**2

    @staticmethod
    def powf2(x: float) -> float:
        """``u**2`` of a float32 scalar (libm ``powf``), as a Python float."""
        return float(_f32(x) ** 2)

    @staticmethod
    def pow2s(*xs: float) -> list[float]:
        """``pow2`` of each argument."""
        return [x**2 for x in xs]


class ArrayOps:
    """The same operations on numpy float64/bool arrays of shape ``[N]``."""

    @staticmethod
    def constants(params: Any) -> Any:
        """A copy of a params dataclass with its floats as 0-d float64 arrays.

        ``array * 0.02`` costs ~0.15 us more than ``array * np.array(0.02)`` (numpy converts
        the Python float on every call), and a step has ~20 such products; the values and
        results are the same float64 bits.
        """
        floats = {
            f.name: np.array(getattr(params, f.name))
            for f in dataclasses.fields(params)
            if type(getattr(params, f.name)) is float
        }
        return dataclasses.replace(params, **floats)

    cos = staticmethod(np.cos)
    sin = staticmethod(np.sin)
    clip = staticmethod(np.clip)
    where = staticmethod(np.where)
    mod = staticmethod(np.remainder)
    any = staticmethod(np.any)

    @staticmethod
    def wrap(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
        """:meth:`ScalarOps.wrap` of each element (see :func:`wrap_into`)."""
        out = np.empty_like(x)
        wrap_into(x, lo, hi, out, np.empty(x.shape, dtype=bool))
        return out

    @staticmethod
    def pick(index: np.ndarray, *values: Any) -> np.ndarray:
        """``values[index]`` for each element of an integer array (``values`` are scalars).

        A lookup table: ~4x cheaper than ``np.where(index == 1, b, a)`` (3.8 us at 1024 rows,
        np.where on scalars is slow), and an index outside ``values`` raises.
        """
        return np.array(values, dtype=np.float64).take(index)

    @staticmethod
    def f32(x: np.ndarray) -> np.ndarray:
        """Round each element to the nearest float32, kept as float64."""
        return np.asarray(x, dtype=np.float32).astype(np.float64)

    @staticmethod
    def f32_where(cond: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Each element rounded to float32 where ``cond`` holds, else kept as it is."""
        return np.where(cond, ArrayOps.f32(x), x)

    @staticmethod
    def pow2(x: np.ndarray) -> np.ndarray:
        """Elementwise libm ``pow(x, 2)``: the exact square, near-midpoint rows from libm."""
        p = x * x
        hard = np.flatnonzero(_near_midpoint(x, p))
        if hard.size:
            p[hard] = _libm_square(x[hard])
        return p

    @staticmethod
    def pow2s(*xs: np.ndarray) -> tuple[np.ndarray, ...]:
        """``pow2`` of each ``[N]`` array, in one pass over them stacked.

        The near-midpoint search is ~15 numpy calls whatever the length: at 1024 rows their
        fixed cost dominates, so three squares cost little more than one.
        """
        if xs[0].size > 4096:  # past 32 KiB a stacked copy costs more than the calls save
            return tuple(ArrayOps.pow2(x) for x in xs)
        return tuple(ArrayOps.pow2(np.concatenate(xs)).reshape(len(xs), -1))

    @staticmethod
    def powf2(x: np.ndarray) -> np.ndarray:
        """Elementwise ``np.float32(u)**2`` (libm ``powf``) of float32 values held as float64."""
        d = x * x  # exact: a float32 squared needs 48 bits
        f = d.astype(np.float32)
        hard = np.flatnonzero(_near_midpoint32(d, f))
        if hard.size:
            f[hard] = _libm_square(x[hard].astype(np.float32))
        return f.astype(np.float64)


def wrap_into(x: np.ndarray, lo: float, hi: float, out: np.ndarray, mask: np.ndarray) -> None:
    """:meth:`ScalarOps.wrap` of each element of ``x`` into ``out`` (``mask``: a boolean
    scratch array): rows above ``hi`` lose a period while any is, then rows below ``lo``
    gain one, the same subtractions per element."""
    diff = hi - lo
    if out is not x:
        np.positive(x, out=out)
    np.greater(out, hi, out=mask)
    while mask.any():
        np.subtract(out, diff, out=out, where=mask)
        np.greater(out, hi, out=mask)
    np.less(out, lo, out=mask)
    while mask.any():
        np.add(out, diff, out=out, where=mask)
        np.less(out, lo, out=mask)


def _libm_square(x: np.ndarray) -> np.ndarray:
    """libm ``pow(x, 2)`` (``powf`` for float32) of each element of a 1-d array."""
    if numpy_power_is_libm():
        # An exponent *array*: numpy squares with x*x when the exponent is a scalar 2.
        return np.power(x, np.full_like(x, 2.0))
    return np.array([v**2 for v in x.tolist()] if x.dtype == np.float64 else [v**2 for v in x])


SCALAR = ScalarOps()
ARRAY = ArrayOps()
