"""What every toy-text env shares: render modes (ansi, rgb_array, human) and the batch base.

The batch base owns the rows' generators, their pre-drawn streams (:mod:`._streams`), the
never-reset check and seeding; a subclass says how rows reset and how the batch steps. Row
``i`` reset with ``seed=s`` uses ``np.random.default_rng(s + i)``, so it draws exactly what a
single env reset with ``seed=s + i`` draws.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from palaestra import error
from palaestra.envs.action_checks import check_discrete_batch
from palaestra.envs.batch_args import row_mask, row_seeds
from palaestra.envs.rendered import RenderedEnv
from palaestra.envs.toy_text._streams import RowStreams
from palaestra.spaces import Discrete, Space
from palaestra.utils.seeding import np_random


class ToyTextEnv(RenderedEnv[Any, Any]):
    """The single toy-text envs' base: :class:`~palaestra.envs.rendered.RenderedEnv` plus the
    ``ansi`` mode.

    Subclasses implement ``_frame()`` (an ``rgb_array`` picture) and, where Gymnasium has
    one, ``_text()`` (the ``ansi`` string).
    """

    def _text(self) -> str:
        raise NotImplementedError

    def render(self) -> Any:
        """The frame (``rgb_array``), the text (``ansi``), or show the frame (``human``)."""
        if self.render_mode == "ansi":
            return self._text()
        return super().render()


class ToyTextBatch:
    """``num_envs`` toy-text envs of one kind as arrays; subclasses fill in the parts.

    ``_obs`` is the batched observation (rewritten in place); ``last_infos()`` gives the infos
    of the last reset or step, one array per key (or None when every info is empty).
    """

    # A registry entry's vector_entry_point may name the class: make_vec runs it natively.
    is_native_batch: ClassVar[bool] = True
    single_observation_space: Space[Any]
    single_action_space: Discrete
    streams_class: ClassVar[type[RowStreams]] = RowStreams
    # Everything a step or reset changes (utils.run_state); subclasses extend it.
    RUN_STATE: ClassVar[tuple[str, ...]] = (
        "_rngs",
        "seeds",
        "_streams",
        "_needs_reset",
        "_all_reset",
    )

    def __init__(self, num_envs: int) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)):
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        n = self.num_envs = int(num_envs)
        self._rngs: list[np.random.Generator | None] = [None] * n
        self.seeds: list[int | None] = [None] * n
        self._streams = self.streams_class(self._rngs)
        self._needs_reset = np.ones(n, dtype=bool)  # [N]
        self._all_reset = False
        self._all = np.arange(n)  # [N] every row, for the streams' gathers
        self._infos: Any = None

    def frame(self, row: int, action: Any = None) -> np.ndarray:
        """Row ``row``'s ``rgb_array`` picture, as the single env in that state draws it;
        ``action``: the row's last action (None since its reset)."""
        raise NotImplementedError(f"{type(self).__name__} draws no frames")

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
        mask: np.ndarray | None = None,
    ) -> Any:
        """Re-sample the rows selected by ``mask`` (all by default); return the observations.

        ``seed`` is an int (row i gets ``seed + i``) or one seed per row; rows whose seed is
        None keep their generator. Toy-text envs take no reset options (Gymnasium ignores
        them). The returned arrays are reused by the next call: copy them to keep them.
        """
        if mask is None:
            rows = self._all
        else:
            mask = row_mask(mask, self.num_envs, "mask")
            rows = mask.nonzero()[0]
        seeds = row_seeds(seed, self.num_envs)
        fresh = [
            i for i in rows.tolist() if seeds[i] is not None or self._rngs[i] is None
        ]  # rows that get a new generator
        for i in fresh:
            self._rngs[i], self.seeds[i] = np_random(seeds[i])
        if fresh:
            self._streams.restart(np.array(fresh, dtype=np.intp))
        self._needs_reset[rows] = False
        self._all_reset = not self._needs_reset.any()  # only ever turns True
        self._infos = self._reset_rows(rows, None if mask is None else mask)
        return self._obs

    def step(self, actions: Any, reset_mask: np.ndarray | None = None) -> tuple[Any, Any, Any]:
        """Step every row: ``(obs, reward [N] float64, terminated [N] bool)``.

        Rows in ``reset_mask`` are reset instead of stepped (they draw what a reset draws,
        nothing for a step); their reward is 0 and terminated False. The returned arrays are
        reused by the next call: copy them to keep them.
        """
        if not self._all_reset and self._needs_reset.any():
            rows = np.flatnonzero(self._needs_reset)[:10].tolist()
            raise error.ResetNeeded(f"Rows {rows} were never reset; call reset() before step().")
        act = check_discrete_batch(actions, self.single_action_space, self.num_envs)
        if reset_mask is None:
            stepping, resetting = self._all, None
        else:
            mask = row_mask(reset_mask, self.num_envs, "reset_mask")
            resetting = mask
        fused = self._step_all(act, resetting)
        if fused is not None:
            self._infos = None
            return self._obs, *fused
        if resetting is not None:
            stepping = (~resetting).nonzero()[0]
        reward, terminated = self._step_rows(stepping, act[stepping])
        step_infos = self._infos = self._step_infos(stepping)
        if resetting is not None:
            rows = resetting.nonzero()[0]
            reward[rows] = 0.0
            terminated[rows] = False
            reset_infos = self._reset_rows(rows, resetting)
            self._infos = self._merge_infos(step_infos, reset_infos, resetting)
        return self._obs, reward, terminated

    def last_infos(self) -> Any:
        """The infos of the last reset or step (a ``StackedInfos``), or None if all empty."""
        return self._infos

    # -- per-env parts ----------------------------------------------------------------------
    _obs: Any

    def _reset_rows(self, rows: np.ndarray, mask: np.ndarray | None) -> Any:
        """Draw initial states for ``rows``; write their obs; return the reset infos."""
        raise NotImplementedError

    def _step_rows(self, rows: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step ``rows`` with their actions; write their obs; return ``(reward, terminated)``
        as ``[N]`` arrays (entries of other rows are overwritten by the caller)."""
        raise NotImplementedError

    def _step_all(
        self, actions: np.ndarray, resetting: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Step and reset every row in one pass, or None to take the two-part path
        (:meth:`_step_rows`, then :meth:`_reset_rows`). Only for batches whose infos are
        all empty: a fused step reports none."""
        return None

    def _step_infos(self, rows: np.ndarray) -> Any:
        """The step infos of ``rows`` (every row, or all but the ones being reset)."""
        return None

    def _merge_infos(self, step_infos: Any, reset_infos: Any, resetting: np.ndarray) -> Any:
        """One info per row: reset infos for the rows in ``resetting``, step infos elsewhere."""
        return None

    def __repr__(self) -> str:
        return f"{type(self).__name__}(num_envs={self.num_envs})"
