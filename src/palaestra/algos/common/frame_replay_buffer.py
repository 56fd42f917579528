"""DQN's memory-lean replay buffer (``optimize_memory_usage=True``): each frame stored once.

With stacked frames (``VecFrameStack``, ``FrameStackObservation``) consecutive observations
share all but one frame, and a transition's next observation shares all but one frame with
its observation. Storing ``obs`` and ``next_obs`` whole (the plain buffer) keeps every Atari
frame 8 times; SB3's ``optimize_memory_usage`` keeps it 4 times and returns the reset
observation instead of the terminal one as ``next_obs`` at episode ends (so SB3 refuses it
together with ``handle_timeout_termination``).

Here observations are split into frames along the stacking axis; every cell of the
``[rows, n_envs]`` ring holds ``n_frames`` frame references for ``obs`` and for ``next_obs``
into one pool of frames (reference 0 is the all-zero frame). A frame is reused only when it
is bit-for-bit equal to the frame it stands for: ``obs`` against the previous ``next_obs`` of
the same env, ``next_obs[k]`` against ``obs[k + 1]`` (the shift of a frame stack), padding
against zeros or the next-newer frame (``VecFrameStack`` pads with zeros, Gymnasium's
``FrameStackObservation`` repeats the first frame). Sampling rebuilds exactly what a plain
buffer would return, episode boundaries, padding and terminal observations included, for any
observations; stacking only decides how much is saved. Frames are reference-counted and
recycled when the cells using them are overwritten; the pool starts at one frame per cell
plus ``frame_margin`` for episode starts and grows by 10% if short episodes need more.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.spaces_util import (
    allocate,
    is_image_space,
    is_image_space_channels_first,
)

__all__ = ["FrameReplayBuffer", "frame_layout"]


def frame_layout(space: spaces.Space[Any], venv: Any = None) -> tuple[int | None, int]:
    """``(axis, channels per frame)`` along which observations are split into frames.

    A ``VecFrameStack`` in ``venv``'s wrapper chain decides; otherwise images split per
    channel (HWC or CHW by SB3's smallest-axis rule), rank-4+ boxes (stacks of images) along
    their first axis, and anything else is one frame (``axis`` None).
    """
    from palaestra.vec_env import VecFrameStack  # lazy: import-time — cloudpickle

    if not isinstance(space, spaces.Box):
        raise ValueError(
            f"optimize_memory_usage=True needs a Box observation space, got {space}; "
            "use optimize_memory_usage=False for Dict and other observations"
        )
    shape = space.shape
    while venv is not None:
        if isinstance(venv, VecFrameStack):
            return venv.axis % len(shape), int(venv.channels)
        venv = getattr(venv, "venv", None)
    if is_image_space(space):
        return (0 if is_image_space_channels_first(space) else 2), 1
    if len(shape) >= 4:
        return 0, 1
    return None, 0


def _words(a: np.ndarray, lead: int) -> np.ndarray:
    """C-contiguous ``a`` as ``[*a.shape[:lead], words]`` in the widest unsigned type dividing
    its rows: equal words mean equal bits (-0.0 is not 0.0, NaN equals itself), and comparing
    7056-byte frames as 882 words is what keeps ``add`` cheap."""
    row = a.reshape(*a.shape[:lead], -1).view(np.uint8)
    for word in (np.uint64, np.uint32, np.uint16):
        if row.shape[-1] % np.dtype(word).itemsize == 0:
            return row.view(word)
    return row


class FrameReplayBuffer:
    """``TransitionRing``'s interface over a pool of deduplicated frames (see module doc)."""

    def __init__(
        self,
        buffer_size: int,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        n_envs: int = 1,
        device: torch.device | str = "cpu",
        handle_timeout_termination: bool = True,
        layout: tuple[int | None, int] | None = None,
        frame_margin: float = 0.05,
    ) -> None:
        axis, channels = layout if layout is not None else frame_layout(observation_space)
        assert isinstance(observation_space, spaces.Box)  # frame_layout checked it
        shape = tuple(observation_space.shape)
        if axis is not None and (channels < 1 or shape[axis] % channels):
            raise ValueError(
                f"cannot split observations of shape {shape} into frames of {channels} "
                f"channel(s) along axis {axis}"
            )
        self.buffer_size = max(int(buffer_size) // n_envs, 1)  # rows, as TransitionRing
        self.n_envs, self.device = n_envs, torch.device(device)
        self.handle_timeout_termination = handle_timeout_termination
        self.observation_space, self.action_space = observation_space, action_space
        self.layout, self.obs_shape = (axis, channels), shape
        self.n_frames = 1 if axis is None else shape[axis] // channels
        self.frame_shape = shape if axis is None else (*shape[:axis], channels, *shape[axis + 1 :])
        lead = (self.buffer_size, n_envs)
        self.obs_refs = np.zeros((*lead, self.n_frames), dtype=np.int32)
        self.next_refs = np.zeros((*lead, self.n_frames), dtype=np.int32)
        self.actions = allocate(action_space, lead)
        self.rewards = np.zeros(lead, dtype=np.float32)
        self.terminated = np.zeros(lead, dtype=np.float32)
        self.pos, self.full = 0, False
        # One frame per cell, the frames of the oldest stacks, one add's new frames, margin.
        cells = self.buffer_size * n_envs
        self._reserve = (self.n_frames + 2) * n_envs
        capacity = 1 + cells + self._reserve + int(frame_margin * cells)
        self._frames = np.zeros((capacity, *self.frame_shape), dtype=observation_space.dtype)
        self._refcount = np.zeros(capacity, dtype=np.int32)
        self._free = np.arange(capacity - 1, 0, -1, dtype=np.int32)  # a stack: pops low slots
        self._n_free = capacity - 1
        self._last_next = np.zeros((n_envs, *shape), dtype=observation_space.dtype)
        self._last_frames = np.zeros((n_envs, self.n_frames, *self.frame_shape), self._frames.dtype)
        self._last_refs = np.zeros((n_envs, self.n_frames), dtype=np.int32)
        self._has_last = np.zeros(n_envs, dtype=bool)

    def size(self) -> int:
        """Number of stored rows (each row holds one transition per env)."""
        return self.buffer_size if self.full else self.pos

    def nbytes(self) -> int:
        """Bytes of every array this buffer holds."""
        arrays = [
            self._frames,
            self._refcount,
            self._free,
            self.obs_refs,
            self.next_refs,
            self.actions,
            self.rewards,
            self.terminated,
            self._last_next,
            self._last_frames,
            self._last_refs,
            self._has_last,
        ]
        return int(sum(a.nbytes for a in arrays))

    def stored_frames(self) -> int:
        """Frames in use (the zero frame not counted)."""
        return int(self._frames.shape[0] - 1 - self._n_free)

    # -- frames <-> observations ------------------------------------------------------------
    def _split(self, obs: np.ndarray) -> np.ndarray:
        """``[B, *obs_shape]`` -> view ``[B, n_frames, *frame_shape]``."""
        axis, channels = self.layout
        if axis is None:
            return obs[:, None]
        s = self.obs_shape
        split = obs.reshape(obs.shape[0], *s[:axis], self.n_frames, channels, *s[axis + 1 :])
        return np.moveaxis(split, 1 + axis, 1)

    def _frame_major(self, obs: np.ndarray) -> np.ndarray:
        """``[B, *obs_shape]`` -> C-contiguous ``[B, n_frames, *frame_shape]`` (a copy only
        when frames are interleaved, as channel-last stacks are)."""
        return np.ascontiguousarray(self._split(obs))

    def _gather(self, refs: np.ndarray) -> np.ndarray:
        """``[B, n_frames]`` references -> observations ``[B, *obs_shape]``."""
        frames = self._frames[refs]  # [B, n_frames, *frame_shape]
        axis = self.layout[0]
        if axis is not None and axis > 0:
            frames = np.moveaxis(frames, 1, 1 + axis)
        return frames.reshape(refs.shape[0], *self.obs_shape)

    # -- adding --------------------------------------------------------------------------------
    def add(
        self,
        obs: np.ndarray,
        next_obs: np.ndarray,
        actions: np.ndarray,
        rewards: np.ndarray,
        dones: np.ndarray,
        timeouts: np.ndarray,
    ) -> None:
        """Store one step of every env (arrays ``[n_envs, ...]``); new frames are copied."""
        expected = (self.n_envs, *self.obs_shape)
        for name, value in (("obs", obs), ("next_obs", next_obs)):
            if not isinstance(value, np.ndarray) or value.shape != expected:
                raise ValueError(
                    f"{name} must be an array of shape {expected}, got "
                    f"{getattr(value, 'shape', type(value).__name__)}"
                )
        # Compared bit for bit below, so both must be in the stored dtype first.
        obs = np.ascontiguousarray(obs, dtype=self._frames.dtype)
        next_obs = np.ascontiguousarray(next_obs, dtype=self._frames.dtype)
        new: list[np.ndarray] = []  # frames to store; refs -(i + 1) point at new[i] until then
        same = self._has_last & (_words(obs, 1) == _words(self._last_next, 1)).all(axis=1)
        nf = self._frame_major(next_obs)  # [E, n_frames, *frame_shape]
        nw = _words(nf, 2)  # [E, n_frames, words]
        if same.all():  # mid-episode: obs is the last next_obs, already split
            of, ow = self._last_frames, _words(self._last_frames, 2)
        else:
            of = self._frame_major(obs)
            ow = _words(of, 2)
        obs_refs = self._last_refs.astype(np.int64)
        for e in np.flatnonzero(~same):  # an episode start (or a first add): padding or new
            obs_refs[e] = self._fresh_refs(of[e], ow[e], new)
        next_refs = np.zeros((self.n_envs, self.n_frames), dtype=np.int64)
        shifted = np.zeros((self.n_envs, self.n_frames), dtype=bool)
        if self.n_frames > 1:  # a frame stack's shift: next_obs[k] is obs[k + 1]
            shifted[:, :-1] = (nw[:, :-1] == ow[:, 1:]).all(axis=2)
            next_refs[:, :-1] = obs_refs[:, 1:]
        for e, k in zip(*np.nonzero(~shifted)):
            if nw[e, k].any():
                new.append(nf[e, k])
                next_refs[e, k] = -len(new)
        if new:
            slots = self._alloc(len(new))
            for slot, frame in zip(slots.tolist(), new):
                self._frames[slot] = frame
            for refs in (obs_refs, next_refs):
                pending = refs < 0
                refs[pending] = slots[-refs[pending] - 1]
        row = self.pos
        counted = np.concatenate([obs_refs.ravel(), next_refs.ravel()])
        np.add.at(self._refcount, counted[counted > 0], 1)
        if self.full:  # release the overwritten cells after counting the new ones
            self._release(np.concatenate([self.obs_refs[row].ravel(), self.next_refs[row].ravel()]))
        self.obs_refs[row], self.next_refs[row] = obs_refs, next_refs
        self._last_next[...] = next_obs
        self._last_frames[...] = nf
        self._last_refs[...] = next_refs
        self._has_last[:] = True
        self.actions[row] = actions
        self.rewards[row] = rewards
        ended = np.asarray(dones, dtype=bool)
        if self.handle_timeout_termination:
            ended = np.logical_and(ended, np.logical_not(timeouts))
        self.terminated[row] = ended
        self.pos += 1
        if self.pos == self.buffer_size:
            self.full, self.pos = True, 0

    @staticmethod
    def _fresh_refs(frames: np.ndarray, words: np.ndarray, new: list[np.ndarray]) -> np.ndarray:
        """References for a stack not continuing the last one: the zero frame, the newer frame
        it repeats (padding), or a new frame."""
        refs = np.zeros(len(frames), dtype=np.int64)
        for k in range(len(frames) - 1, -1, -1):
            if not words[k].any():
                continue
            if k + 1 < len(frames) and (words[k] == words[k + 1]).all():
                refs[k] = refs[k + 1]
            else:
                new.append(frames[k])
                refs[k] = -len(new)
        return refs

    def _alloc(self, k: int) -> np.ndarray:
        if k > self._n_free:
            self._grow(k)
        self._n_free -= k
        return self._free[self._n_free : self._n_free + k][::-1].copy()

    def _release(self, refs: np.ndarray) -> None:
        refs = refs[refs > 0]
        np.subtract.at(self._refcount, refs, 1)
        freed = np.unique(refs[self._refcount[refs] == 0])
        self._free[self._n_free : self._n_free + freed.size] = freed
        self._n_free += freed.size

    def _grow(self, k: int) -> None:
        """10% more frames (short episodes start stacks more often than the margin allows)."""
        old = self._frames.shape[0]
        capacity = max(old + k + self._reserve, old + old // 10)
        frames = np.zeros((capacity, *self.frame_shape), dtype=self._frames.dtype)
        frames[:old] = self._frames
        self._frames = frames
        self._refcount = np.concatenate([self._refcount, np.zeros(capacity - old, np.int32)])
        free = np.empty(capacity, dtype=np.int32)
        added = np.arange(capacity - 1, old - 1, -1, dtype=np.int32)
        free[: added.size] = added
        free[added.size : added.size + self._n_free] = self._free[: self._n_free]
        self._free, self._n_free = free, self._n_free + added.size

    # -- sampling ------------------------------------------------------------------------------
    def _cells(self, batch_size: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        rows = rng.integers(0, self.size(), size=batch_size)  # the plain buffer's draws
        cols = rng.integers(0, self.n_envs, size=batch_size)
        return rows, cols

    def sample_arrays(self, batch_size: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        """``(obs, actions, next_obs, rewards, terminated)`` as numpy arrays."""
        rows, cols = self._cells(batch_size, rng)
        return self.get(rows, cols)

    def get(self, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, ...]:
        """Transitions at ``(rows, cols)``: ``(obs, actions, next_obs, rewards, terminated)``."""
        return (
            self._gather(self.obs_refs[rows, cols]),
            self.actions[rows, cols],
            self._gather(self.next_refs[rows, cols]),
            self.rewards[rows, cols],
            self.terminated[rows, cols],
        )

    # -- persistence (the frames in use, renumbered 1..K; see model_io.save_arrays) -------------
    def state(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """JSON metadata and arrays: live frames and each cell's references to them."""
        n = self.size()
        live = np.unique(np.concatenate([self.obs_refs[:n].ravel(), self.next_refs[:n].ravel()]))
        live = live[live > 0]
        renumber = np.zeros(self._frames.shape[0], dtype=np.int32)
        renumber[live] = np.arange(1, live.size + 1, dtype=np.int32)
        arrays = {
            "frames": self._frames[live],
            "obs_refs": renumber[self.obs_refs[:n]],
            "next_refs": renumber[self.next_refs[:n]],
            "actions": self.actions[:n],
            "rewards": self.rewards[:n],
            "terminated": self.terminated[:n],
        }
        meta = {
            "kind": "frames",
            "buffer_size": self.buffer_size,
            "n_envs": self.n_envs,
            "pos": self.pos,
            "full": self.full,
            "handle_timeout_termination": self.handle_timeout_termination,
            "layout": list(self.layout),
        }
        return meta, arrays

    def load_state(self, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
        """Restore from ``state()`` output; ``ValueError`` if it does not fit this buffer."""
        if meta.get("kind") != "frames":
            raise ValueError(
                "the file holds a plain replay buffer (optimize_memory_usage=False); "
                "this model uses optimize_memory_usage=True"
            )
        if int(meta["n_envs"]) != self.n_envs:
            raise ValueError(
                f"replay buffer was saved with n_envs={meta['n_envs']}, "
                f"this model has n_envs={self.n_envs}"
            )
        if tuple(meta["layout"]) != self.layout:
            raise ValueError(f"replay buffer frame layout {meta['layout']} is not {self.layout}")
        n = arrays["rewards"].shape[0]
        if n > self.buffer_size:
            raise ValueError(f"saved replay buffer holds {n} rows, capacity is {self.buffer_size}")
        frames = arrays["frames"]
        refs_shape = (n, self.n_envs, self.n_frames)
        expected = {
            "frames": (frames.shape[0], *self.frame_shape),
            "obs_refs": refs_shape,
            "next_refs": refs_shape,
            "actions": self.actions[:n].shape,
            "rewards": (n, self.n_envs),
            "terminated": (n, self.n_envs),
        }
        if set(arrays) != set(expected):
            raise ValueError(
                f"replay buffer arrays {sorted(arrays)} do not match {sorted(expected)}"
            )
        for key, shape in expected.items():
            if arrays[key].shape != shape:
                raise ValueError(
                    f"replay buffer {key!r} has shape {arrays[key].shape}, expected {shape}"
                )
        for key in ("obs_refs", "next_refs"):
            refs = arrays[key]
            if refs.size and (refs.min() < 0 or refs.max() > frames.shape[0]):
                raise ValueError(
                    f"replay buffer {key!r} points outside its {frames.shape[0]} frames"
                )
        k = frames.shape[0]
        capacity = self._frames.shape[0]
        if 1 + k + self._reserve > capacity:
            self._grow(1 + k + self._reserve - capacity)
        self._frames[1 : 1 + k] = frames
        self.obs_refs[:n], self.next_refs[:n] = arrays["obs_refs"], arrays["next_refs"]
        self.obs_refs[n:], self.next_refs[n:] = 0, 0
        self.actions[:n] = arrays["actions"]
        self.rewards[:n], self.terminated[:n] = arrays["rewards"], arrays["terminated"]
        counted = np.concatenate([self.obs_refs[:n].ravel(), self.next_refs[:n].ravel()])
        self._refcount[...] = np.bincount(counted, minlength=self._frames.shape[0])
        self._refcount[0] = 0
        free = np.flatnonzero(self._refcount[1:] == 0)[::-1] + 1
        self._free[: free.size], self._n_free = free, free.size
        self._has_last[:] = False
        full = bool(meta["full"]) and n == self.buffer_size
        self.full, self.pos = full, int(meta["pos"]) % self.buffer_size if full else n
