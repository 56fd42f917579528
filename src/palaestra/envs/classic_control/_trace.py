"""A third ``ops`` namespace: record a ``step_state`` once, replay it on buffers kept per batch.

``step_state`` functions are written once against ``ops`` (see :mod:`._ops`): :data:`~._ops.SCALAR`
runs them on Python floats for the single env, :data:`~._ops.ARRAY` on ``[N]`` arrays. On arrays
each operator allocates a fresh temporary and numpy's per-call cost repeats for every operation.
:class:`TraceOps` instead runs the same function once on placeholder values and records each
operation it meets -- the function's own code, so the recorded program is the physics as
written, not a second copy of it. :class:`Program` then replays that record with numpy ufuncs
writing into buffers allocated once (a pool reused as values die), chunk by chunk of rows.

Why the replay is bit-for-bit the array path: every recorded operation is the same IEEE
operation on the same operands in the same order (Python evaluates the expressions, so the
association is the source's; operations on constants alone are folded by Python itself, as on
the other paths). Two rewrites are made, both exact: an operation met twice with the same
operands is computed once (IEEE operations are deterministic), and ``x * 1.0``/``x / 1.0`` are
``x`` (``clip`` replays as numpy's clip ufunc computes it: max, then min). Values the caller
already has -- e.g. ``cos(theta2)`` from the last observation -- can be given as inputs
(``known``), which is the same reuse.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from palaestra.envs.classic_control._ops import (
    SCALAR,
    _libm_square,
    _near_midpoint,
    _near_midpoint32,
    wrap_into,
)

_F64, _BOOL = "f8", "?"


class Var:
    """A placeholder for one value of the recorded program (an ``[N]`` array at replay)."""

    __slots__ = ("_t", "id")

    def __init__(self, tracer: TraceOps, ident: int) -> None:
        self._t, self.id = tracer, ident

    def __add__(self, o: Any) -> Var:
        return self._t.binary("add", self, o)

    def __radd__(self, o: Any) -> Var:
        return self._t.binary("add", o, self)

    def __sub__(self, o: Any) -> Var:
        return self._t.binary("sub", self, o)

    def __rsub__(self, o: Any) -> Var:
        return self._t.binary("sub", o, self)

    def __mul__(self, o: Any) -> Var:
        return self._t.binary("mul", self, o)

    def __rmul__(self, o: Any) -> Var:
        return self._t.binary("mul", o, self)

    def __truediv__(self, o: Any) -> Var:
        return self._t.binary("div", self, o)

    def __rtruediv__(self, o: Any) -> Var:
        return self._t.binary("div", o, self)

    def __neg__(self) -> Var:
        return self._t.emit("neg", (self.id,))[0]

    def __gt__(self, o: Any) -> Var:
        return self._t.binary("gt", self, o)

    def __lt__(self, o: Any) -> Var:
        return self._t.binary("lt", self, o)

    def __bool__(self) -> bool:
        raise TypeError("a traced value has no truth value: the branch must be an ops call")

    __hash__ = None  # type: ignore[assignment]


_UFUNCS: dict[str, Callable[..., Any]] = {
    "add": np.add,
    "sub": np.subtract,
    "mul": np.multiply,
    "div": np.divide,
    "mod": np.remainder,
    "gt": np.greater,
    "lt": np.less,
    "neg": np.negative,
    "cos": np.cos,
    "sin": np.sin,
}


class TraceOps:
    """An ``ops`` namespace that records operations (see the module docstring).

    Supports what the array path of a ``step_state`` uses: ``+ - * /``, unary ``-``, ``< >``,
    ``cos``, ``sin``, ``clip``, ``wrap``, ``mod``, ``f32``, ``pow2s`` and ``powf2``; anything
    else raises, so a new operation in the physics fails loudly here instead of being
    replayed wrongly.
    """

    def __init__(self) -> None:
        # One node per operation: (op, argument ids, output ids, extra constants).
        self.nodes: list[tuple[str, tuple[int, ...], tuple[int, ...], tuple[Any, ...]]] = []
        self.kinds: list[str] = []  # value id -> "in", "const" or "node"
        self.dtypes: list[str] = []
        self.consts: dict[int, float] = {}
        self._const_ids: dict[bytes, int] = {}
        self._seen: dict[tuple[Any, ...], tuple[int, ...]] = {}
        self.inputs: list[int] = []

    def _new(self, kind: str, dtype: str = _F64) -> int:
        self.kinds.append(kind)
        self.dtypes.append(dtype)
        return len(self.kinds) - 1

    def input(self) -> Var:
        """A new input value (an ``[N]`` float64 array at replay)."""
        ident = self._new("in")
        self.inputs.append(ident)
        return Var(self, ident)

    def known(self, op: str, x: Var) -> Var:
        """An input that holds ``op(x)`` (e.g. ``cos`` of an input): the recorded ``op(x)``
        is then read from it, as any repeated operation is."""
        value = self.input()
        self._seen[(op, (x.id,), ())] = (value.id,)
        return value

    def _arg(self, x: Any) -> int:
        if isinstance(x, Var):
            if x._t is not self:
                raise ValueError("a value from another trace")
            return x.id
        if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.floating)):
            raise TypeError(f"cannot trace an operand of type {type(x).__name__}: {x!r}")
        value = float(x)
        key = struct.pack("d", value)  # -0.0 and 0.0 are different constants
        if key not in self._const_ids:
            ident = self._new("const")
            self.consts[ident] = value
            self._const_ids[key] = ident
        return self._const_ids[key]

    def emit(
        self, op: str, args: tuple[int, ...], n_out: int = 1, extra: tuple[Any, ...] = ()
    ) -> list[Var]:
        """Record ``op`` on ``args`` (value ids), or return the outputs of the same record."""
        key = (op, args, extra)
        outs = self._seen.get(key)
        if outs is None:
            dtype = _BOOL if op in ("gt", "lt") else _F64
            outs = tuple(self._new("node", dtype) for _ in range(n_out))
            self.nodes.append((op, args, outs, extra))
            self._seen[key] = outs
        return [Var(self, o) for o in outs]

    def binary(self, op: str, a: Any, b: Any) -> Var:
        """``a op b`` with ``x * 1.0``, ``1.0 * x`` and ``x / 1.0`` folded to ``x`` (exact)."""
        ia, ib = self._arg(a), self._arg(b)
        if op in ("mul", "div") and self.consts.get(ib) == 1.0:
            return Var(self, ia)
        if op == "mul" and self.consts.get(ia) == 1.0:
            return Var(self, ib)
        if self.kinds[ia] == "const" and self.kinds[ib] == "const":
            raise TypeError(f"{op} of two constants should have been folded by Python")
        return self.emit(op, (ia, ib))[0]

    # -- the ops namespace --------------------------------------------------------------
    def cos(self, x: Var) -> Var:
        """Recorded ``np.cos``."""
        return self.emit("cos", (self._arg(x),))[0]

    def sin(self, x: Var) -> Var:
        """Recorded ``np.sin``."""
        return self.emit("sin", (self._arg(x),))[0]

    def clip(self, x: Var, lo: float, hi: float) -> Var:
        """Recorded ``np.clip`` with constant bounds."""
        return self.emit("clip", (self._arg(x),), extra=(float(lo), float(hi)))[0]

    def wrap(self, x: Var, lo: float, hi: float) -> Var:
        """Recorded :meth:`~._ops.ArrayOps.wrap`."""
        return self.emit("wrap", (self._arg(x),), extra=(float(lo), float(hi)))[0]

    def mod(self, x: Var, m: float) -> Var:
        """Recorded ``np.remainder`` (Python's ``%``)."""
        return self.binary("mod", x, m)

    def f32(self, x: Any) -> Any:
        """Recorded rounding to float32 (kept as float64); a constant is rounded now, as
        Python folds the other operations on constants."""
        if not isinstance(x, Var):
            return SCALAR.f32(float(x))
        return self.emit("f32", (x.id,))[0]

    def pow2s(self, *xs: Var) -> list[Var]:
        """Recorded :meth:`~._ops.ArrayOps.pow2s` (libm ``pow(x, 2)`` of each)."""
        return self.emit("pow2s", tuple(self._arg(x) for x in xs), n_out=len(xs))

    def powf2(self, x: Var) -> Var:
        """Recorded :meth:`~._ops.ArrayOps.powf2` (libm ``powf(u, 2)`` of float32 values)."""
        return self.emit("powf2", (self._arg(x),))[0]


class _Squares:
    """libm ``pow(x, 2)`` of ``k`` ``[n]`` arrays into buffers: :meth:`ArrayOps.pow2`'s test
    (the exact square, near-midpoint rows from libm) on one stacked ``[k, n]`` block.

    ``scratch`` (three ``[k, n]`` arrays, the last boolean) may be shared by kernels that
    never run at the same time: fewer buffers stay in the cache.
    """

    def __init__(self, k: int, n: int, scratch: tuple[np.ndarray, ...] | None = None) -> None:
        self.x = np.empty((k, n))
        self.p = np.empty((k, n))
        self._scratch = _Squares.scratch(k, n) if scratch is None else scratch

    @staticmethod
    def scratch(k: int, n: int) -> tuple[np.ndarray, ...]:
        """Scratch arrays for kernels of ``k`` rows of ``n``."""
        return np.empty((k, n)), np.empty((k, n)), np.empty((k, n), dtype=bool)

    def __call__(self, *xs: np.ndarray) -> None:
        """Square ``xs`` (``k`` arrays of ``n``) into the rows of ``self.p``."""
        for row, v in zip(self.x, xs):
            if v is not row:
                np.positive(v, out=row)
        self._square(self.x, self.p)

    def _square(self, x: np.ndarray, p: np.ndarray) -> None:
        np.multiply(x, x, out=p)
        hard = _near_midpoint(x, p, self._scratch).ravel().nonzero()[0]
        if hard.size:
            p.ravel()[hard] = _libm_square(x.ravel()[hard])


class _Squares32(_Squares):
    """libm ``powf(u, 2)`` of ``k`` ``[n]`` arrays of float32 values held as float64:
    :meth:`ArrayOps.powf2`'s test (the exact square rounded to float32, near-midpoint rows
    from libm), as :class:`_Squares` does for ``pow``."""

    def __init__(self, k: int, n: int, scratch: tuple[np.ndarray, ...] | None = None) -> None:
        super().__init__(k, n, scratch)
        self._f = np.empty((k, n), dtype=np.float32)

    def _square(self, x: np.ndarray, p: np.ndarray) -> None:
        f = self._f
        np.multiply(x, x, out=p)  # exact: a float32 squared needs 48 bits
        np.positive(p, out=f)  # rounded to float32 (the cast of ``astype``)
        hard = _near_midpoint32(p, f, self._scratch).ravel().nonzero()[0]
        if hard.size:
            f.ravel()[hard] = _libm_square(x.ravel()[hard].astype(np.float32))
        np.positive(f, out=p)


_KERNELS: dict[str, type[_Squares]] = {"pow2s": _Squares, "powf2": _Squares32}


def _f32_into(x: np.ndarray, tmp: np.ndarray, out: np.ndarray) -> None:
    # float32's rounding of each element (astype's cast), back to float64 (exact).
    np.positive(x, out=tmp)
    np.positive(tmp, out=out)


def _clip(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, out: np.ndarray) -> None:
    # np.clip's ufunc for float64 is max-then-min with NaN passed through: the same bits.
    np.maximum(x, lo, out=out)
    np.minimum(out, hi, out=out)


class Program:
    """A recorded trace, replayed on ``[n]`` rows with buffers allocated once.

    ``blocks`` names groups of values (inputs or results) that live as the rows of one
    ``[k, n]`` array, :meth:`block`: the caller fills input blocks before :meth:`run` and reads
    result blocks after it (one copy for a whole group, e.g. ``state[rows] = block.T``).
    Every other value lives in a pool of buffers, each reused once its value is dead; an
    argument of one ``pow2s``/``powf2`` only is written straight into that kernel's input rows.
    :meth:`steps` gives the replay with some buffers swapped for the caller's own arrays
    (chunks of its state), so those need no copy at all.
    """

    def __init__(self, trace: TraceOps, n: int, blocks: dict[str, Sequence[Var]]) -> None:
        self.n = n
        nodes = trace.nodes
        last_use: dict[int, int] = {}
        kernel_args: dict[int, list[int]] = {}
        for i, (op, args, _, _) in enumerate(nodes):
            for a in args:
                last_use[a] = i
                if op in _KERNELS:
                    kernel_args.setdefault(a, []).append(i)
        consts = {i: np.array(v) for i, v in trace.consts.items()}
        bufs: dict[int, np.ndarray] = {}
        self._blocks: dict[str, np.ndarray] = {}
        for name, values in blocks.items():
            dtypes = {trace.dtypes[v.id] for v in values}
            if len(dtypes) != 1:
                raise ValueError(f"block {name!r} mixes dtypes {sorted(dtypes)}")
            block = np.empty((len(values), n), dtype=dtypes.pop())
            self._blocks[name] = block
            for row, v in zip(block, values):
                if v.id in bufs:
                    raise ValueError(f"value {v.id} is in two blocks or twice in {name!r}")
                bufs[v.id] = row
        kept = set(bufs)  # never given to the pool
        for ident in trace.inputs:
            if ident not in bufs:
                bufs[ident] = np.empty(n)
            kept.add(ident)
        free: dict[str, list[np.ndarray]] = {_F64: [], _BOOL: []}
        self.n_buffers = 0
        squares: dict[int, _Squares] = {}
        scratch: dict[int, tuple[np.ndarray, ...]] = {}  # one per row count, shared
        for i, (op, args, _, _) in enumerate(nodes):
            if op in _KERNELS:
                k, kind = len(args), _KERNELS[op]
                if k not in scratch:
                    scratch[k] = _Squares.scratch(k, n)
                squares[i] = kind(k, n, scratch[k])
                for a, row in zip(args, squares[i].x):
                    only_here = kernel_args[a] == [i] and args.count(a) == 1
                    if only_here and a not in kept and trace.kinds[a] == "node":
                        bufs[a] = row  # the producer writes the kernel's input directly
                        kept.add(a)

        def take(dtype: str) -> np.ndarray:
            if free[dtype]:
                return free[dtype].pop()
            self.n_buffers += 1
            return np.empty(n, dtype=dtype)

        def val(ident: int) -> np.ndarray:
            return consts[ident] if ident in consts else bufs[ident]

        steps: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
        for i, (op, args, outs, extra) in enumerate(nodes):
            # Arguments dead after this node give their buffers back first: an elementwise
            # ufunc may write over its own input.
            for a in set(args):
                if a in bufs and a not in kept and last_use[a] == i:
                    free[trace.dtypes[a]].append(bufs[a])
            if op in _KERNELS:
                kernel = squares[i]
                steps.append((kernel, tuple(val(a) for a in args)))
                for row, o in zip(kernel.p, outs):
                    if o in bufs:  # a block row: copied from the kernel's output
                        steps.append((np.positive, (row, bufs[o])))
                    else:
                        bufs[o] = row  # the kernel's own output row, never pooled
                        kept.add(o)
                continue
            (o,) = outs
            out = bufs[o] if o in bufs else bufs.setdefault(o, take(trace.dtypes[o]))
            if op in _UFUNCS:
                steps.append((_UFUNCS[op], (*(val(a) for a in args), out)))
            elif op == "clip":
                lo, hi = (np.array(v) for v in extra)
                steps.append((_clip, (val(args[0]), lo, hi, out)))
            elif op == "f32":
                tmp = np.empty(n, dtype=np.float32)
                steps.append((_f32_into, (val(args[0]), tmp, out)))
            elif op == "wrap":
                steps.append((wrap_into, (val(args[0]), *extra, out, np.empty(n, dtype=bool))))
            else:  # pragma: no cover - TraceOps records nothing else
                raise AssertionError(op)
            if o not in last_use and o not in kept:  # computed for nothing: free at once
                free[trace.dtypes[o]].append(out)
        self._steps = steps
        self._bufs = bufs

    def block(self, name: str) -> np.ndarray:
        """The ``[k, n]`` array holding the values of block ``name``."""
        return self._blocks[name]

    def steps(self, swap: dict[str, np.ndarray] | None = None) -> list[tuple[Any, tuple[Any, ...]]]:
        """The replay, with row ``i`` of block ``name`` replaced by ``swap[f"{name}.{i}"]``.

        Only rows of blocks can be swapped (their buffers are never shared with other values):
        e.g. an input read straight from the caller's array, or a result written into it.
        """
        if not swap:
            return list(self._steps)
        by_addr = {}  # block rows are new view objects each time: matched by address
        for key, arr in swap.items():
            name, _, row = key.partition(".")
            block = self._blocks[name]
            if arr.shape != (self.n,) or arr.dtype != block.dtype:
                raise ValueError(f"{key}: expected a ({self.n},) {block.dtype} array")
            by_addr[self._addr(block[int(row)])] = arr
        return [
            (
                fn,
                tuple(
                    by_addr.get(self._addr(a), a) if isinstance(a, np.ndarray) else a for a in args
                ),
            )
            for fn, args in self._steps
        ]

    @staticmethod
    def _addr(a: np.ndarray) -> tuple[int, int, tuple[int, ...]]:
        return (a.__array_interface__["data"][0], a.size, a.strides)

    def run(self, steps: list[tuple[Any, tuple[Any, ...]]] | None = None) -> None:
        """Replay every recorded operation (``steps`` from :meth:`steps`, else the blocks')."""
        for fn, args in self._steps if steps is None else steps:
            fn(*args)


def trace(fn: Callable[..., Any], n_inputs: int) -> tuple[TraceOps, list[Var], Any]:
    """Record ``fn(ops, *inputs)``; return the trace, its inputs and ``fn``'s result."""
    ops = TraceOps()
    ins = [ops.input() for _ in range(n_inputs)]
    return ops, ins, fn(ops, *ins)
