"""The recorded replay of a ``step_state`` (``_trace``): bit for bit the array path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from palaestra.envs.classic_control._ops import ARRAY, SCALAR
from palaestra.envs.classic_control._trace import Program, TraceOps, trace
from palaestra.envs.classic_control.acrobot import AcrobotParams, observation, step_state


def _hard_states(n: int) -> np.ndarray:
    """``[4, n]`` Acrobot states: random, past the velocity bounds, angles several periods
    out, and velocities whose squares are libm's near-midpoint cases."""
    rng = np.random.default_rng(11)
    s = np.stack(
        [
            rng.uniform(-4 * math.pi, 4 * math.pi, n),
            rng.uniform(-9.0, 9.0, n),
            rng.uniform(-16.0, 16.0, n),
            rng.uniform(-35.0, 35.0, n),
        ]
    )
    x = rng.uniform(-30, 30, 200_000)
    hard = x[np.array([v**2 for v in x.tolist()]) != x * x]  # pow and x*x differ here
    s[2, : n // 4] = np.resize(hard[np.abs(hard) < 12], n // 4)
    s[3, n // 4 : n // 2] = np.resize(hard, n // 2 - n // 4)
    s[:, -3:] = [[0.0, -0.0, 1e-300], [-0.0, 0.0, -1e-300], [0.0, 40.0, -0.0], [-0.0, -40.0, 0.0]]
    return s


@pytest.mark.parametrize("params", [AcrobotParams(), AcrobotParams(LINK_MASS_2=1.5, dt=0.05)])
def test_replayed_acrobot_step_equals_the_array_path_and_single_env(params: AcrobotParams) -> None:
    n = 4000
    s = _hard_states(n)
    torque = np.random.default_rng(12).integers(0, 3, n) - 1.0
    *expected, term = step_state(ARRAY, params, *s, torque)
    expected_obs = observation(ARRAY, *expected)

    def fn(ops: TraceOps, s0: object, s1: object, s2: object, s3: object, a: object) -> object:
        *new, terminated = step_state(ops, params, s0, s1, s2, s3, a)
        return (s0, s1, s2, s3, a), new, terminated, observation(ops, *new)[:4]

    ops, _, (ins, new, terminated, trig) = trace(fn, 5)
    blocks = {"in": ins, "new": new, "trig": trig, "term": [terminated]}
    for size in (n, 1000):  # the whole batch, and chunks of it through the same record
        prog = Program(ops, size, blocks)
        for c0 in range(0, n, size):
            prog.block("in")[:4] = s[:, c0 : c0 + size]
            prog.block("in")[4] = torque[c0 : c0 + size]
            prog.run()
            for j in range(4):
                got = prog.block("new")[j]
                assert got.tobytes() == expected[j][c0 : c0 + size].tobytes(), (size, j)
                got = prog.block("trig")[j]
                assert got.tobytes() == expected_obs[j][c0 : c0 + size].tobytes(), (size, j)
            assert np.array_equal(prog.block("term")[0], term[c0 : c0 + size])
    for i in range(0, n, 397):  # and the single env's Python floats
        *row, t = step_state(SCALAR, params, *s[:, i].tolist(), float(torque[i]))
        assert row == [float(e[i]) for e in expected] and t == term[i]


def test_repeats_are_computed_once_and_products_by_one_dropped() -> None:
    def fn(ops: TraceOps, x: object, y: object) -> object:
        a = ops.cos(x) * 1.0 + y
        b = 1.0 * ops.cos(x) + y  # the same cos, the same sum
        return a, b, ops.cos(x) / 1.0, 2.0 * x, 2 * x

    ops, ins, (a, b, c, d, e) = trace(fn, 2)
    assert [node[0] for node in ops.nodes] == ["cos", "add", "mul"]
    assert a.id == b.id and d.id == e.id
    prog = Program(ops, 3, {"in": ins, "out": [a, c, d]})
    prog.block("in")[:] = [[0.5, 1.0, -2.0], [1.0, 2.0, 3.0]]
    prog.run()
    x = np.array([0.5, 1.0, -2.0])
    np.testing.assert_array_equal(
        prog.block("out"), [np.cos(x) + np.array([1.0, 2.0, 3.0]), np.cos(x), 2.0 * x]
    )


def test_known_values_replace_the_operation() -> None:
    def fn(ops: TraceOps, x: object) -> object:
        known = ops.known("cos", x)
        return x, known, ops.cos(x) + ops.sin(x)

    ops, _, (x, known, total) = trace(fn, 1)
    assert [node[0] for node in ops.nodes] == ["sin", "add"]
    prog = Program(ops, 4, {"x": [x], "k": [known], "t": [total]})
    prog.block("x")[0] = [0.1, 0.2, 0.3, 0.4]
    prog.block("k")[0] = 100.0  # read in place of cos(x): the caller's promise
    prog.run()
    np.testing.assert_array_equal(prog.block("t")[0], 100.0 + np.sin([0.1, 0.2, 0.3, 0.4]))


def test_swapped_rows_read_and_write_the_callers_arrays() -> None:
    def fn(ops: TraceOps, x: object, y: object) -> object:
        return x, y, x * y - 1.0

    ops, _, (x, y, z) = trace(fn, 2)
    prog = Program(ops, 3, {"in": [x, y], "out": [z]})
    mine_x, mine_z = np.array([1.0, 2.0, 3.0]), np.zeros(3)
    steps = prog.steps({"in.0": mine_x, "out.0": mine_z})
    prog.block("in")[1] = 2.0
    prog.run(steps)
    np.testing.assert_array_equal(mine_z, [1.0, 3.0, 5.0])
    assert not np.array_equal(prog.block("out")[0], mine_z)  # the block row was not written
    with pytest.raises(ValueError, match=r"in\.0: expected a \(3,\) float64 array"):
        prog.steps({"in.0": np.zeros(4)})


def test_untraceable_uses_fail_loudly() -> None:
    ops = TraceOps()
    x = ops.input()
    with pytest.raises(TypeError, match="no truth value"):
        if x > 1.0:
            pass
    with pytest.raises(TypeError, match="operand of type str: 'a'"):
        x + "a"
    with pytest.raises(TypeError, match="operand of type bool: True"):
        x * True
    with pytest.raises(ValueError, match="from another trace"):
        x + TraceOps().input()
    with pytest.raises(ValueError, match=r"block 'b' mixes dtypes \['\?', 'f8'\]"):
        Program(ops, 2, {"b": [x, x > 1.0]})
    with pytest.raises(ValueError, match="value 0 is in two blocks or twice in 'b'"):
        Program(ops, 2, {"a": [x], "b": [x]})


def test_wrap_scalar_and_array_agree_one_period_at_a_time() -> None:
    x = np.array([-20.0, -3.2, -math.pi, 0.0, -0.0, math.pi, 3.2, 7.0, 25.0, np.nan])
    got = ARRAY.wrap(x, -math.pi, math.pi)
    expected = [SCALAR.wrap(v, -math.pi, math.pi) for v in x.tolist()]
    assert got.tobytes() == np.array(expected).tobytes()
    d = 2 * math.pi
    assert SCALAR.wrap(25.0, -math.pi, math.pi) == 25.0 - d - d - d - d


def test_replayed_pendulum_step_equals_the_array_path_and_single_env() -> None:
    """``mod``, ``f32`` and ``powf2`` replay as the array path computes them: angles many
    periods out, squares at libm's near-midpoint cases (``pow`` and ``powf``), torques past
    the bounds, zeros of both signs."""
    from palaestra.envs.classic_control.pendulum import PendulumParams
    from palaestra.envs.classic_control.pendulum import step_state as pendulum_step

    n, rng = 6000, np.random.default_rng(21)
    th = rng.uniform(-40.0, 40.0, n)
    thdot = rng.uniform(-8.0, 8.0, n)
    u = rng.uniform(-3.0, 3.0, n).astype(np.float32)
    x = rng.uniform(-8, 8, 200_000)
    hard = x[np.array([v**2 for v in x.tolist()]) != x * x]
    thdot[: n // 4] = np.resize(hard, n // 4)
    f = rng.uniform(-2.0, 2.0, 60_000).astype(np.float32)
    powf = np.array([v**2 for v in f])  # numpy float32 scalars: libm powf
    hard32 = f[powf != (f.astype(np.float64) ** 2).astype(np.float32)]  # powf != rounded x*x
    assert hard32.size > 10
    u[n // 4 : n // 2] = np.resize(hard32, n // 2 - n // 4)
    th[-3:], thdot[-3:], u[-3:] = [0.0, -0.0, 1e-300], [-0.0, 0.0, 8.0], [0.0, -0.0, -2.0]
    u64 = u.astype(np.float64)
    for params in (PendulumParams(), PendulumParams(m=1.5, l=0.75, g=9.81)):
        expected = pendulum_step(ARRAY, params, th, thdot, u64)

        def fn(ops: TraceOps, a: object, b: object, c: object) -> object:
            return (a, b, c), pendulum_step(ops, params, a, b, c)  # noqa: B023

        ops, _, (ins, outs) = trace(fn, 3)
        assert {"mod", "f32", "powf2", "pow2s"} <= {node[0] for node in ops.nodes}
        prog = Program(ops, n, {"in": ins, "out": outs})
        prog.block("in")[:] = [th, thdot, u64]
        prog.run()
        for j in range(4):
            assert prog.block("out")[j].tobytes() == expected[j].tobytes(), j
        for i in range(0, n, 293):
            row = pendulum_step(SCALAR, params, float(th[i]), float(thdot[i]), float(u[i]))
            assert list(row) == [float(e[i]) for e in expected], i
