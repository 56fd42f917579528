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
doubles ``pow(x, 2) != x*x`` about 900 times (powf: ~700 per million), while numpy's array
``x**2`` is the exact square and its general ``np.power`` loop is SIMD and differs more often.
So :meth:`ArrayOps.pow2` takes the exact square ``x*x``, finds the rows whose square lies
within 0.02 ulp of a rounding midpoint (the only ones where a pow with glibc's documented
< 0.52 ulp error can round the other way; measured: none beyond 0.007 ulp in 10^7 draws) and
recomputes just those with Python's ``**`` (the same libm call), a few percent of rows.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from typing import Any

import numpy as np

_f32 = np.float32
_pack_f32, _unpack_f32 = struct.Struct("f").pack, struct.Struct("f").unpack
_SPLIT = 134217729.0  # 2**27 + 1: Veltkamp's splitter for the exact error of x*x
_POW_HARD = 0.48  # ulps from the exact square beyond which libm pow may round differently
_POWF_HARD = 0.45  # the same for powf (measured mismatches all beyond 0.498)


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
    def pow2(x: float) -> float:
        """``x**2`` as numpy computes it on a float64 scalar (libm ``pow``)."""
        return x**2

    @staticmethod
    def powf2(x: float) -> float:
        """``u**2`` of a float32 scalar (libm ``powf``), as a Python float."""
        return float(_f32(x) ** 2)


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
        """Elementwise libm ``pow(x, 2)``: the exact square, near-midpoint rows redone by pow."""
        p = x * x
        c = x * _SPLIT
        hi = c - (c - x)
        lo = x - hi
        err = ((hi * hi - p) + 2 * hi * lo) + lo * lo  # exact rounding error of x*x (Dekker)
        hard = np.flatnonzero(np.abs(err) > _POW_HARD * np.spacing(p))
        if hard.size:
            p[hard] = [v**2 for v in x[hard].tolist()]
        return p

    @staticmethod
    def powf2(x: np.ndarray) -> np.ndarray:
        """Elementwise ``np.float32(u)**2`` (libm ``powf``) of float32 values held as float64."""
        d = x * x  # exact: a float32 squared needs 48 bits
        f = d.astype(np.float32)
        hard = np.flatnonzero(np.abs(d - f) > _POWF_HARD * np.spacing(f).astype(np.float64))
        if hard.size:
            f[hard] = [_f32(v) ** 2 for v in x[hard].tolist()]
        return f.astype(np.float64)


SCALAR = ScalarOps()
ARRAY = ArrayOps()
