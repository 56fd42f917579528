"""Autoreset, written once: the three modes, ``reset_mask`` and per-row seeding over any engine.

:class:`Autoresetter` turns an engine's raw "step these rows, reset those" into a
:class:`Transition`; the Gymnasium face stacks its infos into a dict with ``_key`` masks, the
SB3 face turns it into ``(obs, rewards, dones, infos)`` with ``terminal_observation``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from palaestra import error
from palaestra.spaces import Box
from palaestra.spaces.batched_samples import iterate
from palaestra.utils.seeding import row_seeds
from palaestra.vector.engine import Engine, Infos, copy_obs
from palaestra.vector.vector_env import AutoresetMode


class Transition(NamedTuple):
    """One vector step as the engine saw it (arrays owned by the engine: copy to keep)."""

    obs: Any  # batched observations after any autoreset
    rewards: np.ndarray  # [N] float64
    terminated: np.ndarray  # [N] bool
    truncated: np.ndarray  # [N] bool
    infos: Infos  # per-row step infos (reset infos for rows reset in this call)
    final_rows: np.ndarray | None  # SAME_STEP: rows that ended (reset, unless `continuing`)
    final_obs: list[Any] | None  # their last observations, in final_rows order
    final_infos: list[dict[str, Any]] | None  # their last step infos


def parse_reset_mask(options: dict[str, Any] | None, num_envs: int) -> np.ndarray | None:
    """Check ``options["reset_mask"]`` (Gymnasium's rules); None when absent."""
    if options is not None and not isinstance(options, Mapping):
        raise error.InvalidOptions(  # Gymnasium: "argument of type 'int' is not iterable"
            f"Reset options must be None or a dict (of the sub-envs' options and "
            f"'reset_mask'), got {options!r:.200}"
        )
    if options is None or "reset_mask" not in options:
        return None
    mask = options["reset_mask"]
    if not isinstance(mask, np.ndarray):
        raise TypeError(f"`options['reset_mask']` must be a numpy array, got {type(mask)}")
    if mask.shape != (num_envs,):
        raise ValueError(
            f"`options['reset_mask']` must have shape `({num_envs},)`, got {mask.shape}"
        )
    if mask.dtype != np.bool_:
        raise TypeError(f"`options['reset_mask']` must have `dtype=np.bool_`, got {mask.dtype}")
    if not mask.any():
        raise ValueError(
            "`options['reset_mask']` must contain a boolean array with at least one True value, "
            f"got reset_mask={mask}"
        )
    return mask


def take_rows(space: Any, obs: Any, rows: np.ndarray) -> list[Any]:
    """Copies of the single observations in ``rows`` of a batch (loops over those rows only).

    ``space`` is the *batched* observation space: only it knows how to split ``obs`` into rows
    (a batched ``Discrete`` is a ``MultiDiscrete``, a batched ``Text`` a tuple of strings).
    """
    if isinstance(space, Box) and isinstance(obs, np.ndarray):
        return list(obs[rows])  # fancy indexing copies: [R, *shape] -> R row arrays
    wanted = set(rows.tolist())
    return [
        copy_obs(item)
        for i, item in enumerate(iterate(space, obs))
        if i in wanted  # iterate walks every row; only non-Box spaces take this path
    ]


class Autoresetter:
    """Drives an engine in one autoreset mode; remembers which rows have finished."""

    RUN_STATE = ("engine", "_ended")  # for exact resume (utils.run_state)

    def __init__(self, engine: Engine, mode: AutoresetMode | str) -> None:
        self.engine = engine
        self.mode = mode if isinstance(mode, AutoresetMode) else AutoresetMode(mode)
        n = engine.num_envs
        self._ended = np.zeros(n, dtype=bool)  # [N] finished on the last step, not yet reset
        self._done = np.zeros(n, dtype=bool)  # [N] scratch for SAME_STEP
        self._no_seeds: list[int | None] = [None] * n
        self._pending: np.ndarray | None = None  # NEXT_STEP rows reset by the step in flight

    def reset(self, seed: Any, options: dict[str, Any] | None) -> tuple[Any, Infos]:
        """Reset all rows, or those in ``options["reset_mask"]``; ``seed`` is int/list/None."""
        mask, seeds, options = self._reset_args(seed, options)
        infos = self.engine.reset(mask, seeds, options)
        self._reset_done(mask)
        return self.engine.obs, infos

    def begin_reset(self, seed: Any, options: dict[str, Any] | None) -> np.ndarray | None:
        """Start a reset on an engine that splits it (``reset_send``/``reset_recv``: the
        process engine); finish with :meth:`finish_reset` and the mask returned here."""
        mask, seeds, options = self._reset_args(seed, options)
        self.engine.reset_send(mask, seeds, options)  # type: ignore[attr-defined]
        return mask

    def finish_reset(self, mask: np.ndarray | None, timeout: float | None) -> tuple[Any, Infos]:
        """Collect the reset started by :meth:`begin_reset`."""
        infos = self.engine.reset_recv(timeout)  # type: ignore[attr-defined]
        self._reset_done(mask)
        return self.engine.obs, infos

    def _reset_args(
        self, seed: Any, options: dict[str, Any] | None
    ) -> tuple[np.ndarray | None, list[int | None], dict[str, Any] | None]:
        n = self.engine.num_envs
        seeds = row_seeds(seed, n)
        mask = parse_reset_mask(options, n)
        if mask is not None:
            # The sub-envs never see the mask (Gymnasium pops it; we leave the caller's dict).
            options = {k: v for k, v in options.items() if k != "reset_mask"}  # type: ignore[union-attr]
        return mask, seeds, options

    def _reset_done(self, mask: np.ndarray | None) -> None:
        if mask is None:
            self._ended[:] = False
        else:
            self._ended[mask] = False

    def step(self, actions: Any) -> Transition:
        """One vector step in this mode."""
        self.begin_step(actions)
        return self.finish_step()

    def begin_step(self, actions: Any) -> None:
        """Send the actions (rows that ended last step are reset instead under NEXT_STEP)."""
        if self.mode is AutoresetMode.DISABLED and self._ended.any():
            rows = np.flatnonzero(self._ended)[:10].tolist()
            raise error.ResetNeeded(
                f"Sub-environments {rows} have finished and autoreset_mode is DISABLED: "
                "reset them with reset(options={'reset_mask': mask}) before stepping."
            )
        pending = None
        # count_nonzero: ~0.5 us less than ndarray.any() (a Python-level wrapper) per step.
        if self.mode is AutoresetMode.NEXT_STEP and np.count_nonzero(self._ended):
            pending = self._ended.copy()
        self.engine.step_send(actions, pending)
        self._pending = pending

    def finish_step(self, timeout: float | None = None) -> Transition:
        """Collect the step and apply the mode's autoreset."""
        engine = self.engine
        rewards, terminated, truncated, infos = engine.step_recv(timeout)
        # Rows whose `terminated` marks a lost life while the game goes on (ale-py's
        # life_loss_info): reported as terminated, never reset. Only some engines have them.
        continuing: np.ndarray | None = getattr(engine, "continuing", None)
        if self.mode is not AutoresetMode.SAME_STEP:
            pending = self._pending
            if pending is not None:
                # A row reset in place of a step reports reward 0 and not done (Gymnasium).
                # Few rows: integer indices are ~3x cheaper than the [N] mask, three times.
                reset_rows = pending.nonzero()[0]
                rewards[reset_rows] = 0.0
                terminated[reset_rows] = False
                truncated[reset_rows] = False
            np.logical_or(terminated, truncated, out=self._ended)
            if continuing is not None:
                self._ended &= ~continuing
            return Transition(engine.obs, rewards, terminated, truncated, infos, None, None, None)

        done = np.logical_or(terminated, truncated, out=self._done)
        if not np.count_nonzero(done):  # ndarray.any() costs ~0.5 us more per step
            return Transition(engine.obs, rewards, terminated, truncated, infos, None, None, None)
        final_rows = np.flatnonzero(done)
        # The env's own objects where the engine kept them (as Gymnasium hands on what the
        # sub-env returned: a GraphInstance, a Python int), rows of the batch otherwise.
        own: Any = getattr(engine, "final_observations", None)
        final_obs = own(final_rows) if own is not None else None
        if final_obs is None:
            final_obs = take_rows(engine.observation_space, engine.obs, final_rows)
        final_infos = (
            [{} for _ in final_rows] if infos is None else [infos[i] for i in final_rows.tolist()]
        )
        if continuing is not None:
            done &= ~continuing  # their final obs is also their next one: nothing to reset
        rows = np.flatnonzero(done).tolist()
        if rows:
            reset_infos = engine.reset(done, self._no_seeds, None)
            if reset_infos is not None:
                infos = [{} for _ in range(engine.num_envs)] if infos is None else list(infos)
                for i in rows:
                    infos[i] = reset_infos[i]
            elif infos is not None:
                infos = list(infos)
                for i in rows:
                    infos[i] = {}
        return Transition(
            engine.obs, rewards, terminated, truncated, infos, final_rows, final_obs, final_infos
        )
