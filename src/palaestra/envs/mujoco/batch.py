"""Native batches of the MuJoCo envs: N ``MjData`` stepped together, maths on ``[N, ...]`` arrays.

``make_vec("HalfCheetah-v5", n)`` (and ``make_vec_env``) build one for each of the eleven v5
envs: each row owns a single env (its model, ``MjData`` and generator, so resets are the single
env's own code and draws), the physics of all rows runs as bare ``mj_step`` calls, spread over
``num_threads`` threads (MuJoCo releases the GIL while it steps), and the observations,
rewards, terminations and infos are computed once for all rows by the env's own row maths
(``rows_before``/``rows_step`` of :class:`~palaestra.envs.mujoco._base.MujocoEnv`, which the
single env calls with its one row) on the stacked arrays. Row i reset with seed ``s`` gives
what the single env reset with ``s + i`` gives, bit for bit (tests/envs/mujoco/test_batch.py).

``mj_rnePostConstraint`` (which only fills ``cacc``, ``cfrc_int`` and ``cfrc_ext``; nothing in
the next ``mj_step`` reads them) runs only for the envs whose maths reads ``cfrc_ext`` (Ant,
Humanoid, HumanoidStandup); the other rows' ``MjData`` keep stale values in those three arrays.

Why not ``mujoco.rollout``: it restarts every trajectory from a ``mjSTATE_FULLPHYSICS`` state
and does not hand back the solver's warm start (``qacc_warmstart``) nor the derived quantities
the observations read (``xpos``, ``cfrc_ext``), so its rows drift from the single env in the
last bits after one step.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any, ClassVar

import numpy as np

from palaestra import error
from palaestra.envs.batch_args import row_mask, row_seeds
from palaestra.envs.mujoco._base import MujocoEnv, warn_unstable, warning_names
from palaestra.envs.mujoco.fixed_base import (
    InvertedDoublePendulumEnv,
    InvertedPendulumEnv,
    PusherEnv,
    ReacherEnv,
)
from palaestra.envs.mujoco.locomotion import (
    AntEnv,
    HalfCheetahEnv,
    HopperEnv,
    HumanoidEnv,
    HumanoidStandupEnv,
    SwimmerEnv,
    Walker2dEnv,
)
from palaestra.spaces import Box
from palaestra.utils.stacked_infos import StackedInfos

__all__ = [
    "AntBatch",
    "HalfCheetahBatch",
    "HopperBatch",
    "HumanoidBatch",
    "HumanoidStandupBatch",
    "InvertedDoublePendulumBatch",
    "InvertedPendulumBatch",
    "MujocoBatch",
    "PusherBatch",
    "ReacherBatch",
    "SwimmerBatch",
    "Walker2dBatch",
]

# What mj_rnePostConstraint computes: rows run it only when their maths reads one of these.
_POST_CONSTRAINT = {"cacc", "cfrc_int", "cfrc_ext"}

_REAL_KINDS = "biuf"


class _MergedInfos(Sequence[dict[str, Any]]):
    """Step infos for most rows; other infos for some (reset in the same call, or flagged by
    MuJoCo)."""

    def __init__(self, step: StackedInfos, reset: dict[int, dict[str, Any]]) -> None:
        self.step, self.reset = step, reset

    def __len__(self) -> int:
        return len(self.step)

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[j] for j in range(len(self))[i]]
        found = self.reset.get(i)
        return self.step[i] if found is None else found


class MujocoBatch:
    """``num_envs`` MuJoCo envs of one kind (``env_class``), their maths done on all rows.

    ``kwargs`` are the single env's constructor arguments; ``num_threads`` (default 1) threads
    step the physics (each takes a contiguous block of rows).
    """

    is_native_batch: ClassVar[bool] = True
    env_class: ClassVar[type[MujocoEnv]]

    def __init__(self, num_envs: int, num_threads: int = 1, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)):
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if isinstance(num_threads, bool) or not isinstance(num_threads, (int, np.integer)):
            raise TypeError(f"num_threads must be an int, got {num_threads!r}")
        if num_threads < 1:
            raise ValueError(f"num_threads must be >= 1, got {num_threads!r}")
        if kwargs.get("render_mode") is not None:
            raise ValueError(
                f"native batches do not render (render_mode={kwargs['render_mode']!r})"
            )
        self.num_envs = n = int(num_envs)
        self.envs = [self.env_class(**kwargs) for _ in range(n)]
        first: Any = self.envs[0]
        self._share_model(first)
        self.single_observation_space: Box = first.observation_space
        self.single_action_space: Box = first.action_space
        self.metadata = first.metadata
        self._mujoco = first._mujoco
        self.frame_skip = first.frame_skip
        self.dt = first.dt
        self._maths = first  # every row has the same arguments: the first env's maths serve all
        self._post = bool(_POST_CONSTRAINT.intersection(first.row_fields))
        self._bind_views()
        self._obs = np.zeros((n, *first.observation_space.shape))  # [N, obs_dim] float64
        self._reward = np.zeros(n)
        self._terminated = np.zeros(n, dtype=bool)
        self._needs_reset = np.ones(n, dtype=bool)
        self._all = np.arange(n)
        self._infos: Any = None
        self.num_threads = min(int(num_threads), n)
        blocks = np.array_split(np.arange(n), self.num_threads)
        self._blocks = [b for b in blocks if b.size]
        self._pool = ThreadPoolExecutor(self.num_threads) if self.num_threads > 1 else None

    # -- what the native engine reads ----------------------------------------------------------
    @property
    def seeds(self) -> list[int | None]:
        """Each row's seed (None for a row never seeded)."""
        return [
            None if getattr(env, "_np_random", None) is None else env._np_random_seed
            for env in self.envs
        ]

    @property
    def _rngs(self) -> list[np.random.Generator | None]:
        return [getattr(env, "_np_random", None) for env in self.envs]

    def last_infos(self) -> Any:
        """The infos of the last reset or step."""
        return self._infos

    def close(self) -> None:
        """Stop the stepping threads."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    _VIEWS = ("_mujoco", "_datas", "_models", "_ctrl", "_warnings", "_views")

    def _share_model(self, first: Any) -> None:
        # Every row compiled the same file with the same arguments: one MjModel serves all
        # rows' MjData (the physics only reads it), which keeps it in cache across rows
        # (HalfCheetah's step is ~7% cheaper at 64 envs than with a model per row).
        model = first.model
        for env in self.envs[1:]:
            env.model = model
            env.data = first._mujoco.MjData(model)
            env._bind_views()

    def _bind_views(self) -> None:
        # MjData's arrays live as long as the MjData: views made once are gathered each step.
        first = self._maths
        self._mujoco = first._mujoco
        self._datas = [env.data for env in self.envs]
        self._models = [env.model for env in self.envs]
        self._ctrl = [d.ctrl for d in self._datas]
        self._warnings = [d.warning.number for d in self._datas]  # views of the counters
        names = dict.fromkeys(first.before_fields + first.row_fields)
        self._views = {name: [getattr(d, name) for d in self._datas] for name in names}

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_pool"] = None
        for name in self._VIEWS:
            del state[name]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind_views()
        if self.num_threads > 1:
            self._pool = ThreadPoolExecutor(self.num_threads)

    # -- reset and step ------------------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
        mask: np.ndarray | None = None,
    ) -> np.ndarray:
        """Reset the rows in ``mask`` (all by default) with their single env's own reset: row i
        gets ``seed + i`` (or ``seed[i]``); returns the observations ``[N, obs_dim]``."""
        if mask is None:
            rows = self._all
        else:
            mask = row_mask(mask, self.num_envs, "mask")
            rows = mask.nonzero()[0]
        seeds = row_seeds(seed, self.num_envs)
        infos = self._reset_rows(rows, seeds, options)
        self._infos = [infos.get(i, {}) for i in range(self.num_envs)]
        return self._obs

    def _reset_rows(
        self, rows: np.ndarray, seeds: list[int | None], options: Any = None
    ) -> dict[int, dict[str, Any]]:
        infos = {}
        for i in rows.tolist():
            obs, info = self.envs[i].reset(seed=seeds[i], options=options)
            self._obs[i] = obs
            infos[i] = info
        self._needs_reset[rows] = False
        return infos

    def check_actions(self, actions: Any) -> np.ndarray:
        """``[N, *action_shape]`` real actions (a float array keeps its dtype, as the single
        env's), else ``InvalidAction`` naming the actions, the bad rows and the space."""
        space = self.single_action_space
        try:
            raw = np.asarray(actions)
        except (TypeError, ValueError) as e:
            raise error.InvalidAction(
                f"Invalid actions {actions!r}: not a numeric array for {self.num_envs} envs of "
                f"action space {space}"
            ) from e
        if raw.dtype.kind not in _REAL_KINDS:
            raise error.InvalidAction(
                f"Invalid actions {actions!r}: expected real values for action space {space}, "
                f"got dtype {raw.dtype}"
            )
        expected = (self.num_envs, *space.shape)
        if raw.shape != expected:
            raise error.InvalidAction(
                f"Invalid actions {actions!r}: expected shape {expected} for {self.num_envs} "
                f"envs of action space {space}, got {raw.shape}"
            )
        arr = raw if raw.dtype.kind == "f" else raw.astype(np.float64)
        finite = np.isfinite(arr).all(axis=1)
        if not finite.all():
            bad = np.flatnonzero(~finite)[:10].tolist()
            raise error.InvalidAction(
                f"Invalid actions at rows {bad}: {arr[bad].tolist()} are not finite (NaN/inf) "
                f"for action space {space}"
            )
        return arr

    def step(
        self, actions: Any, reset_mask: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Step every row: ``(obs [N, obs_dim], reward [N], terminated [N])``.

        Rows in ``reset_mask`` are reset instead of stepped (reward 0, not terminated, the
        reset's info). The returned arrays are reused by the next call: copy them to keep them.
        """
        if self._needs_reset.any():
            rows = np.flatnonzero(self._needs_reset)[:10].tolist()
            raise error.ResetNeeded(f"Rows {rows} were never reset; call reset() before step().")
        act = self.check_actions(actions)
        if reset_mask is None:
            stepping = self._all
            resetting = None
        else:
            resetting = row_mask(reset_mask, self.num_envs, "reset_mask")
            stepping = (~resetting).nonzero()[0]
        if stepping.size:
            maths = self._maths
            before = maths.rows_before(self._fields(maths.before_fields, stepping))
            flagged = self._simulate(stepping, act)
            acted = act if stepping.size == self.num_envs else act[stepping]
            obs, reward, terminated, info = maths.rows_step(
                self._fields(maths.row_fields, stepping), before, acted
            )
            self._obs[stepping] = obs
            self._reward[stepping] = reward
            self._terminated[stepping] = terminated
            step_infos = self._stacked(stepping, info)
            special = self._warn(flagged, step_infos) if flagged else {}
        else:  # every row resets
            step_infos = StackedInfos({}, self.num_envs, np.zeros(self.num_envs, dtype=bool))
            special = {}
        if resetting is not None:
            rows = resetting.nonzero()[0]
            self._reward[rows] = 0.0
            self._terminated[rows] = False
            special.update(self._reset_rows(rows, [None] * self.num_envs))
        self._infos = _MergedInfos(step_infos, special) if special else step_infos
        return self._obs, self._reward, self._terminated

    def _simulate(self, rows: np.ndarray, actions: np.ndarray) -> dict[int, list[str]]:
        """Advance ``rows`` by ``frame_skip`` MuJoCo steps; MuJoCo's warnings per row."""
        counts = self._gather(self._warnings, rows)  # [R, nwarning] MuJoCo's counters
        if self._pool is None or rows.size < 2 * len(self._blocks):
            self._simulate_block(rows, actions)
        else:
            blocks = [b for b in np.array_split(rows, len(self._blocks)) if b.size]
            for _ in self._pool.map(lambda b: self._simulate_block(b, actions), blocks):
                pass
        after = self._gather(self._warnings, rows)
        raised = after > counts
        if not raised.any():
            return {}
        return {
            int(rows[r]): warning_names(after[r], counts[r])
            for r in np.flatnonzero(raised.any(axis=1)).tolist()
        }

    def _simulate_block(self, rows: np.ndarray, actions: np.ndarray) -> None:
        mujoco, nstep = self._mujoco, self.frame_skip
        step, post = mujoco.mj_step, mujoco.mj_rnePostConstraint
        models, datas, ctrls = self._models, self._datas, self._ctrl
        if self._post:
            for i in rows.tolist():
                ctrls[i][:] = actions[i]
                step(models[i], datas[i], nstep=nstep)
                post(models[i], datas[i])
        else:
            for i in rows.tolist():
                ctrls[i][:] = actions[i]
                step(models[i], datas[i], nstep=nstep)

    def _warn(
        self, flagged: dict[int, list[str]], infos: StackedInfos
    ) -> dict[int, dict[str, Any]]:
        """As the single env: a ``MujocoWarning`` per flagged row, and that row's info with
        ``"mujoco_warnings"`` (the other rows' infos have no such key)."""
        out = {}
        for i, names in flagged.items():
            who = f"{self.env_class.__name__} (row {i})"
            warn_unstable(who, names, self._datas[i].time, stacklevel=5)
            out[i] = {**infos[i], "mujoco_warnings": list(names)}
        return out

    def _fields(self, names: tuple[str, ...], rows: np.ndarray) -> dict[str, np.ndarray]:
        """The rows' MjData arrays ``names``, each stacked ``[R, ...]``."""
        return {name: self._gather(self._views[name], rows) for name in names}

    def _gather(self, views: list[np.ndarray], rows: np.ndarray) -> np.ndarray:
        shape = views[0].shape
        if rows.size == self.num_envs:
            picked = views
        elif rows.size == 0:
            return np.zeros((0, *shape), dtype=views[0].dtype)
        else:
            picked = [views[i] for i in rows.tolist()]
        # concatenate then reshape: a fifth of np.stack's cost on 64 small views
        return np.concatenate(picked).reshape(len(picked), *shape)

    def _stacked(self, rows: np.ndarray, arrays: dict[str, np.ndarray]) -> StackedInfos:
        if rows.size == self.num_envs:
            return StackedInfos(arrays, self.num_envs)
        full = {}
        for key, values in arrays.items():
            column = np.zeros((self.num_envs, *values.shape[1:]), dtype=values.dtype)
            column[rows] = values
            full[key] = column
        present = np.zeros(self.num_envs, dtype=bool)
        present[rows] = True
        return StackedInfos(full, self.num_envs, present)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(num_envs={self.num_envs}, num_threads={self.num_threads})"


class AntBatch(MujocoBatch):
    """Ant-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.AntEnv`)."""

    env_class = AntEnv


class HalfCheetahBatch(MujocoBatch):
    """HalfCheetah-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.HalfCheetahEnv`)."""

    env_class = HalfCheetahEnv


class HopperBatch(MujocoBatch):
    """Hopper-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.HopperEnv`)."""

    env_class = HopperEnv


class HumanoidBatch(MujocoBatch):
    """Humanoid-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.HumanoidEnv`)."""

    env_class = HumanoidEnv


class HumanoidStandupBatch(MujocoBatch):
    """HumanoidStandup-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.HumanoidStandupEnv`)."""

    env_class = HumanoidStandupEnv


class InvertedDoublePendulumBatch(MujocoBatch):
    """InvertedDoublePendulum-v5's rows (``fixed_base.InvertedDoublePendulumEnv``)."""

    env_class = InvertedDoublePendulumEnv


class InvertedPendulumBatch(MujocoBatch):
    """InvertedPendulum-v5's rows (``fixed_base.InvertedPendulumEnv``)."""

    env_class = InvertedPendulumEnv


class PusherBatch(MujocoBatch):
    """Pusher-v5's rows (:class:`~palaestra.envs.mujoco.fixed_base.PusherEnv`)."""

    env_class = PusherEnv


class ReacherBatch(MujocoBatch):
    """Reacher-v5's rows (:class:`~palaestra.envs.mujoco.fixed_base.ReacherEnv`)."""

    env_class = ReacherEnv


class SwimmerBatch(MujocoBatch):
    """Swimmer-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.SwimmerEnv`)."""

    env_class = SwimmerEnv


class Walker2dBatch(MujocoBatch):
    """Walker2d-v5's rows (:class:`~palaestra.envs.mujoco.locomotion.Walker2dEnv`)."""

    env_class = Walker2dEnv
