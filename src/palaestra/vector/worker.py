"""The worker process of :class:`~.process_engine.ProcessEngine`: one env, commands on a pipe.

Observations, rewards, dones and array actions travel through shared memory. The pipe carries
raw bytes: a step is the one byte ``STEP`` and, when the env's info is empty (the usual case),
the answer is zero bytes, so nothing is pickled per step. Other commands and answers are pickled
``(command, data)`` / ``(ok, payload)`` tuples. An env exception is sent back with its traceback
text and the worker keeps serving; the parent re-raises it.
"""

from __future__ import annotations

import pickle
import traceback
from typing import Any

import cloudpickle
import numpy as np

from palaestra.vector.engine import call_env, is_wrapped
from palaestra.vector.shared_memory import shared_views, write_row

STEP = b"s"  # step with the action in shared memory
EMPTY_OK = b""  # (True, {}) without pickling


class Payload:
    """A callable pickled with cloudpickle, so lambdas, closures and local classes reach the
    worker under every start method ("fork" would inherit them; "spawn" and "forkserver" do
    not). Module-level functions still travel by name."""

    def __init__(self, fn: Any) -> None:
        self.fn = fn

    def __getstate__(self) -> bytes:
        try:
            return bytes(cloudpickle.dumps(self.fn))
        except Exception as e:  # e.g. it captured a lock, an open file or a live env
            raise TypeError(
                f"cannot send the env function {self.fn!r} to a worker process: {e} (it, or "
                "something it refers to, cannot be pickled; build that inside the function)"
            ) from e

    def __setstate__(self, state: bytes) -> None:
        self.fn = pickle.loads(state)

    def __call__(self) -> Any:
        """``fn()`` (Gymnasium's ``CloudpickleWrapper`` is called to make the env)."""
        return self.fn()


def dumps(obj: Any) -> bytes:
    """``obj`` pickled; with cloudpickle (by value) where plain pickle cannot name a class.

    That happens to the classes of the parent's own script under "spawn" and "forkserver": the
    env function reached the worker by value (see :class:`Payload`), so its classes are rebuilt
    copies that the worker's re-imported ``__main__`` does not hold under their names. Sent
    back by value, cloudpickle's class tracking turns each into the parent's original class, so
    ``except BoomError`` in the parent's script matches, as under "fork". Plain pickle first:
    it is faster for the usual answers (arrays, dicts of numbers).
    """
    try:
        return pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:
        return bytes(cloudpickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


def encode_error(exc: BaseException) -> bytes:
    """A failed answer: the exception and its traceback text, or, if the exception cannot be
    rebuilt from its pickle, a ``RuntimeError`` stand-in with its type name and message."""
    text = traceback.format_exc()
    try:
        message = dumps((False, (exc, text)))
        pickle.loads(message)  # an __init__ that does not take its own args fails here, not there
        return message
    except Exception:
        return dumps((False, (RuntimeError(f"{type(exc).__name__}: {exc}"), text)))


def encode(ok: bool, payload: Any) -> bytes:
    """An answer as bytes: empty for ``(True, {})``, else a pickled ``(ok, payload)``."""
    if ok and type(payload) is dict and not payload:
        return EMPTY_OK
    return dumps((ok, payload))


def decode(message: bytes) -> tuple[bool, Any]:
    """Inverse of :func:`encode`."""
    return (True, {}) if not message else pickle.loads(message)


class _Shared:
    """The worker's views onto the shared buffers (row ``index`` is its own)."""

    def __init__(self, buffers: dict[str, Any], spaces: tuple[Any, Any], n: int) -> None:
        self.obs_space, act_space = spaces
        self.obs = shared_views(self.obs_space, buffers["obs"], n=n)
        self.actions = None
        if buffers.get("actions") is not None:
            self.actions = shared_views(act_space, buffers["actions"], n=n)
        self.rewards = np.frombuffer(buffers["rewards"], dtype=np.float64, count=n)
        self.terminated = np.frombuffer(buffers["terminated"], dtype=np.bool_, count=n)
        self.truncated = np.frombuffer(buffers["truncated"], dtype=np.bool_, count=n)


def _serve(env: Any, command: str, data: Any, index: int, shared: _Shared | None) -> Any:
    """Run one command on ``env``; its answer's payload."""
    if command == "step":
        if shared is None:
            return env.step(data)
        action = shared.actions[index] if data is None else data  # type: ignore[index]
        obs, reward, term, trunc, info = env.step(action)
        write_row(shared.obs_space, shared.obs, index, obs)
        shared.rewards[index], shared.terminated[index], shared.truncated[index] = (
            reward,
            term,
            trunc,
        )
        return info
    if command == "reset":
        seed, options = data
        extra = {} if options is None else {"options": options}  # as LoopEngine.reset
        obs, info = env.reset(seed=seed, **extra)
        if shared is None:
            return obs, info
        write_row(shared.obs_space, shared.obs, index, obs)
        return info
    if command == "call":
        return call_env(env, *data)
    if command == "is_wrapped":
        return is_wrapped(env, data)
    if command == "set_attr":
        env.set_wrapper_attr(*data)
        return None
    if command == "spaces":
        return env.observation_space, env.action_space, env.metadata, env.render_mode
    raise RuntimeError(f"Unknown worker command {command!r}")


def run_worker(
    index: int,
    env_fn: Payload,
    conn: Any,
    parent_conn: Any,
    buffers: dict[str, Any] | None,
    num_envs: int,
    spaces: tuple[Any, Any],
) -> None:
    """Serve commands until "close" or until the parent goes away."""
    if parent_conn is not None:
        parent_conn.close()  # forked copy of the parent's end: keep only ours
    env = None
    try:
        env = env_fn.fn()
        shared = None if buffers is None else _Shared(buffers, spaces, num_envs)
        conn.send_bytes(encode(True, None))
    except Exception as e:
        conn.send_bytes(encode_error(e))
        return
    try:
        while True:
            try:
                message = conn.recv_bytes()
            except (EOFError, OSError, KeyboardInterrupt):
                return  # parent gone: nothing left to serve
            if message == STEP:
                command, data = "step", None
            else:
                command, data = pickle.loads(message)
            if command == "close":
                conn.send_bytes(encode(True, None))
                return
            try:
                answer = encode(True, _serve(env, command, data, index, shared))
            except Exception as e:
                answer = encode_error(e)
            conn.send_bytes(answer)
    finally:
        if env is not None:
            try:
                env.close()
            except Exception:
                pass
        conn.close()
