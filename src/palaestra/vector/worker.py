"""The worker process of :class:`~.process_engine.ProcessEngine`: one env, commands on a pipe.

Observations (and rewards/dones, and array actions) travel through shared memory; the pipe
carries a short command and the info dict. An exception in the env is sent back with its
traceback text and the worker keeps serving; the parent re-raises it.
"""

from __future__ import annotations

import pickle
import traceback
from typing import Any

import numpy as np

from palaestra.vector.shared_memory import read_from_shared_memory, write_row


class Payload:
    """Pickles a callable with cloudpickle when available, so lambdas survive spawn."""

    def __init__(self, fn: Any) -> None:
        self.fn = fn

    def __getstate__(self) -> bytes:
        try:
            import cloudpickle  # optional: plain pickle handles module-level functions

            return bytes(cloudpickle.dumps(self.fn))
        except ImportError:
            return pickle.dumps(self.fn)

    def __setstate__(self, state: bytes) -> None:
        self.fn = pickle.loads(state)


def pack_exception(exc: BaseException) -> tuple[BaseException, str]:
    """The exception (or a stand-in if it cannot be pickled) and its traceback text."""
    text = traceback.format_exc()
    try:
        pickle.loads(pickle.dumps(exc))
        return exc, text
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}"), text


def run_worker(
    index: int,
    env_fn: Payload,
    conn: Any,
    parent_conn: Any,
    buffers: dict[str, Any] | None,
    num_envs: int,
    spaces: tuple[Any, Any] | None,
) -> None:
    """Serve commands until "close" or until the parent goes away."""
    if parent_conn is not None:
        parent_conn.close()  # forked copy of the parent's end: keep only ours
    env = None
    try:
        env = env_fn.fn()
        obs_views = act_views = None
        if buffers is not None and spaces is not None:
            obs_space, act_space = spaces
            obs_views = read_from_shared_memory(obs_space, buffers["obs"], n=num_envs)
            if buffers.get("actions") is not None:
                act_views = read_from_shared_memory(act_space, buffers["actions"], n=num_envs)
            rewards = np.frombuffer(buffers["rewards"], dtype=np.float64, count=num_envs)
            terminated = np.frombuffer(buffers["terminated"], dtype=np.bool_, count=num_envs)
            truncated = np.frombuffer(buffers["truncated"], dtype=np.bool_, count=num_envs)
        conn.send((True, None))
    except Exception as e:
        conn.send((False, pack_exception(e)))
        return
    try:
        while True:
            try:
                command, data = conn.recv()
            except (EOFError, OSError, KeyboardInterrupt):
                return  # parent gone: nothing left to serve
            try:
                if command == "step":
                    action = act_views[index] if data is None else data  # type: ignore[index]
                    obs, reward, term, trunc, info = env.step(action)
                    if obs_views is None:
                        conn.send((True, (obs, reward, term, trunc, info)))
                        continue
                    write_row(obs_space, obs_views, index, obs)
                    rewards[index], terminated[index], truncated[index] = reward, term, trunc
                    conn.send((True, info))
                elif command == "reset":
                    seed, options = data
                    obs, info = env.reset(seed=seed, options=options)
                    if obs_views is None:
                        conn.send((True, (obs, info)))
                        continue
                    write_row(obs_space, obs_views, index, obs)
                    conn.send((True, info))
                elif command == "call":
                    name, args, kwargs = data
                    attr = env.get_wrapper_attr(name)
                    conn.send((True, attr(*args, **kwargs) if callable(attr) else attr))
                elif command == "set_attr":
                    name, value = data
                    env.set_wrapper_attr(name, value)
                    conn.send((True, None))
                elif command == "spaces":
                    conn.send(
                        (
                            True,
                            (
                                env.observation_space,
                                env.action_space,
                                env.metadata,
                                env.render_mode,
                            ),
                        )
                    )
                elif command == "close":
                    conn.send((True, None))
                    return
                else:
                    raise RuntimeError(f"Unknown worker command {command!r}")
            except Exception as e:
                conn.send((False, pack_exception(e)))
    finally:
        if env is not None:
            try:
                env.close()
            except Exception:
                pass
        conn.close()
