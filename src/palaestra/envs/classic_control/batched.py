"""The batched engine: N copies of one classic-control env stepped with array ops, in place.

A subclass names its state components, its spaces, how reset uniforms become initial states
(its module's ``reset_state``) and how the whole batch steps (its module's ``step_state`` with
:data:`~palaestra.envs.classic_control._ops.ARRAY`). The base owns the buffers, the per-row
generators and seeding. There is no autoreset, time limit or info here: the vector layer adds
those on top.

Row ``i`` reset with ``seed=s`` uses ``np.random.default_rng(s + i)`` and draws exactly what a
single env reset with ``seed=s + i`` draws, so the two stay identical step by step. Each row's
generator draws the uniforms of many resets ahead (:mod:`._draws`), so resetting the rows that
ended is a vectorised gather; the per-row Python loop runs only when rows are seeded and in
occasional top-ups.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from palaestra.envs.action_checks import check_box_batch, check_discrete_batch
from palaestra.envs.batch_args import row_mask, row_seeds
from palaestra.envs.classic_control._draws import PreDrawn
from palaestra.envs.classic_control._ops import ARRAY
from palaestra.envs.classic_control._trace import Program, TraceOps, Var
from palaestra.error import ResetNeeded
from palaestra.spaces import Box, Discrete, Space
from palaestra.utils.seeding import np_random


def copy_to_columns(rows: np.ndarray, out: np.ndarray) -> None:
    """Row ``j`` of ``rows`` (``[k, n]``) into column ``j`` of ``out`` (``[n, k]``, any
    dtype it casts to): one strided copy per column, ~3x cheaper at 8192 rows than one
    transposed copy, whose inner loop would run over only ``k`` elements."""
    for j, row in enumerate(rows):
        np.positive(row, out=out[:, j])


class BatchedEnv:
    """``num_envs`` envs of one kind, as arrays. Subclasses fill in the class variables."""

    # A registry entry's vector_entry_point may name the class: make_vec runs it natively.
    is_native_batch: ClassVar[bool] = True
    state_dim: ClassVar[int]
    reset_draws: ClassVar[int]  # uniform doubles one reset consumes
    # Whether ``_step`` writes every row's observation itself (from values the step computed
    # anyway): then ``_observe`` runs only for rows reset after a step, never for all rows.
    step_writes_obs: ClassVar[bool] = False
    single_observation_space: Space[Any]
    single_action_space: Space[Any]
    params: Any  # the env's frozen params dataclass (Gymnasium's constants)
    # Everything a step or reset changes, for exact resume (utils.run_state); subclasses
    # with more per-row state extend it. ``params`` is construction, not run state.
    RUN_STATE: ClassVar[tuple[str, ...]] = (
        "_state",
        "_obs",
        "_rngs",
        "seeds",
        "_draws",
        "_seeded",
        "_needs_reset",
        "_all_seeded",
        "_all_reset",
    )

    def __init__(self, num_envs: int) -> None:
        if not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        self.num_envs = int(num_envs)
        n, k = self.num_envs, self.state_dim
        obs_dim = self.single_observation_space.shape[0]  # type: ignore[index]
        # Row i is env i (Gymnasium's layout): observations are then one contiguous cast of
        # the state, and a reset writes whole rows. Physics reads the columns as strided views
        # (~0.2 us more per op than contiguous [k, N] rows at 1024 envs, less than what the
        # transposes of that layout cost for observations and resets).
        self._state = np.zeros((n, k))  # [N, k] float64
        self._make_views()
        self._obs = np.zeros((n, obs_dim), dtype=np.float32)  # [N, obs_dim]
        self._rngs: list[np.random.Generator | None] = [None] * n
        self.seeds: list[int | None] = [None] * n
        self._draws = PreDrawn(self._rngs, self.reset_draws)  # reset uniforms drawn ahead
        self._seeded = np.zeros(n, dtype=bool)  # [N] has a generator
        self._needs_reset = np.ones(n, dtype=bool)  # [N]
        self._params_for: Any = None  # the params _params_arrays was built from
        self._params_arrays: Any = None
        # Both arrays only ever turn False/True: once every row is done, skip the checks.
        self._all_seeded = False
        self._all_reset = False

    def _make_views(self) -> None:
        """The views the physics and resets write the state through."""
        k = self.state_dim
        self._cols = tuple(self._state[:, j] for j in range(k))  # k views of [N]
        # Whole rows as opaque records: gathering or scattering R rows by index is then 1-D
        # fancy indexing, ~7x faster than 2-D ``a[rows]`` (numpy's multi-dimensional indexing
        # has a large fixed cost, and a step resets a few rows). Bytes: copied bit for bit.
        self._row = np.dtype((np.void, 8 * k))
        self._state_rows = self._state.view(self._row)[:, 0]  # [N] records of k float64

    # pickle and deepcopy copy each array on its own: copied views would no longer write into
    # the copied state, so they are left out and made again.
    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for view in ("_cols", "_state_rows"):
            state.pop(view, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._make_views()

    @property
    def state(self) -> np.ndarray:
        """The float64 state as a writable ``[N, k]`` array (row i is env i's Gymnasium state)."""
        return self._state

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture, as the single env in that state draws it;
        ``action``: what the row did at its last step (None since its reset), for the envs
        whose picture shows it (Pendulum's torque)."""
        raise NotImplementedError(f"{type(self).__name__} draws no frames")

    @property
    def observation_space(self) -> Box:
        """The batched observation space ``[N, obs_dim]``."""
        space = self.single_observation_space
        assert isinstance(space, Box)
        reps = (self.num_envs, 1)
        return Box(np.tile(space.low, reps), np.tile(space.high, reps), dtype=space.dtype)

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
        mask: np.ndarray | None = None,
    ) -> np.ndarray:
        """Re-sample the rows selected by ``mask`` (all by default); return obs ``[N, obs_dim]``.

        ``seed`` is an int (row i gets ``seed + i``) or one seed per row; rows whose seed is
        None keep their generator. The returned array is reused by the next call: copy it to
        keep it.
        """
        if mask is None:
            rows = np.arange(self.num_envs)
        else:
            mask = row_mask(mask, self.num_envs, "mask")
            rows = mask.nonzero()[0]  # [R] (np.flatnonzero, without its wrappers)
        bounds = self._parse_options(options)  # once for all rows, so bad options fail early
        self._reset_rows(rows, seed, bounds)
        self._observe(rows)
        return self._obs

    def _reset_rows(self, rows: np.ndarray, seed: Any, bounds: Any) -> None:
        """Re-sample the state of ``rows`` (sorted indices); observations are left to the caller."""
        if seed is not None or not self._all_seeded:
            self._seed_rows(rows, row_seeds(seed, self.num_envs))
        fresh = self._reset_state(self._draws.take(rows), bounds)  # [R, k]
        self._state_rows[rows] = np.ascontiguousarray(fresh, dtype=np.float64).view(self._row)[:, 0]
        if not self._all_reset:
            self._needs_reset[rows] = False
            self._all_reset = not self._needs_reset.any()
        self._after_reset(rows)

    def _seed_rows(self, rows: np.ndarray, seeds: list[int | None]) -> None:
        """New generators for rows given a seed (or never seeded); their draws start over."""
        fresh = []
        for i in rows.tolist():
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i], self.seeds[i] = np_random(seeds[i])
                fresh.append(i)
        self._draws.restart(np.array(fresh, dtype=np.intp))
        self._seeded[rows] = True
        self._all_seeded = bool(self._seeded.all())

    def step(
        self, actions: Any, reset_mask: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Step every row: ``(obs [N, obs_dim] float32, reward [N] float64, terminated [N])``.

        Actions are validated for the whole batch first (InvalidAction names the bad rows).
        Rows in ``reset_mask`` (bool ``[N]``) are re-sampled after the step, as ``reset(mask=)``
        with their own generators would, and the observations show their fresh state (their
        reward and terminated are those of the discarded step). One pass writes every
        observation: this is the autoreset fast path. The returned arrays may be reused by the
        next call: copy them to keep them.
        """
        if not self._all_reset:
            rows = np.flatnonzero(self._needs_reset)[:10].tolist()
            raise ResetNeeded(f"Rows {rows} were never reset; call reset() before step().")
        act = self.check_actions(actions)
        reward, terminated = self._step(act)
        if reset_mask is None:
            if not self.step_writes_obs:
                self._observe(None)
            return self._obs, reward, terminated
        mask = row_mask(reset_mask, self.num_envs, "reset_mask")
        rows = mask.nonzero()[0]
        self._reset_rows(rows, None, self._parse_options(None))
        # One pass over all rows also observes the reset ones, unless the step wrote the rest.
        self._observe(rows if self.step_writes_obs else None)
        return self._obs, reward, terminated

    def check_actions(self, actions: Any) -> np.ndarray:
        """Validate a batch of actions; return them as an ``[N]`` array ready for ``_step``."""
        space = self.single_action_space
        if isinstance(space, Discrete):
            return check_discrete_batch(actions, space, self.num_envs)
        assert isinstance(space, Box)
        return check_box_batch(actions, space, self.num_envs)

    def _array_params(self) -> Any:
        """``self.params`` with 0-d array floats for the array step, rebuilt when replaced."""
        if self._params_for is not self.params:
            self._params_for = self.params
            self._params_arrays = ARRAY.constants(self.params)
        return self._params_arrays

    # -- per-env parts ------------------------------------------------------------------
    def _parse_options(self, options: dict[str, Any] | None) -> Any:
        """Reset options checked once (Gymnasium's ``options={"low", "high"}`` by default)."""
        raise NotImplementedError

    def _reset_state(self, uniforms: np.ndarray, bounds: Any) -> np.ndarray:
        """Initial states ``[R, k]`` from ``[R, reset_draws]`` uniforms (the module's math)."""
        raise NotImplementedError

    def _after_reset(self, rows: np.ndarray) -> None:
        """Reset any per-row bookkeeping besides the state (nothing by default)."""

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Advance ``self._state`` in place; return ``(reward [N], terminated [N])``."""
        raise NotImplementedError

    def _observe(self, rows: np.ndarray | None) -> None:
        """Write observations of ``rows`` (all if None) into ``self._obs``."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}(num_envs={self.num_envs})"


class ReplayedBatch(BatchedEnv):
    """A batch whose step is its env's ``step_state`` recorded once on :class:`~._trace.TraceOps`
    (:meth:`_record`) and replayed by :class:`~._trace.Program` over chunks of :attr:`chunk`
    rows: the same float operations per row as the single env, on buffers allocated once. The
    record is made again when ``params``, the state or the observations array is replaced.
    The step writes every observation itself (from the values it computed).
    """

    step_writes_obs = True
    # Rows per replay: 2048 and 4096 measured slower at 16384 envs (per-call cost over cache).
    chunk = 8192

    def __init__(self, num_envs: int) -> None:
        super().__init__(num_envs)
        self._compiled: Any = None

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        state["_compiled"] = None  # recorded again on the next step
        return state

    def _record(self) -> tuple[TraceOps, dict[str, Sequence[Var]]]:
        """The recorded step and its named blocks (see :class:`~._trace.Program`)."""
        raise NotImplementedError

    def _swaps(self, rows: slice) -> dict[str, np.ndarray]:
        """Block rows the replay of ``rows`` reads from or writes to the batch's own arrays."""
        return {}

    def _replays(self) -> list[tuple[slice, Program, list[tuple[Any, tuple[Any, ...]]]]]:
        """``[(rows, program, steps)]``: one replay per chunk of rows (one program per size)."""
        compiled = self._compiled
        if (
            compiled is None
            or compiled[0] is not self.params
            or compiled[1] is not self._state
            or compiled[2] is not self._obs
        ):
            ops, blocks = self._record()
            programs: dict[int, Program] = {}
            chunks = []
            for c0 in range(0, self.num_envs, self.chunk):
                rows = slice(c0, min(c0 + self.chunk, self.num_envs))
                size = rows.stop - c0
                if size not in programs:
                    programs[size] = Program(ops, size, blocks)
                chunks.append((rows, programs[size], programs[size].steps(self._swaps(rows))))
            compiled = self._compiled = (self.params, self._state, self._obs, chunks)
        return compiled[3]

    @staticmethod
    def refresh_kept(
        values: np.ndarray, of: np.ndarray, kept: Sequence[np.ndarray], fns: Sequence[Any]
    ) -> None:
        """``kept[j][i] = fns[j](values[i])`` for the rows whose ``values`` no longer have the
        bits ``of`` holds (reset or written since the step that kept them)."""
        stale = values.view(np.uint64) != of.view(np.uint64)
        if stale.any():
            rows = stale.nonzero()[0]
            v = values[rows]
            for out, fn in zip(kept, fns):
                out[rows] = fn(v)
