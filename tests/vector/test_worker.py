"""The worker's answers as bytes: exceptions keep their class, or fall back to a stand-in."""

from __future__ import annotations

import pytest

from palaestra.vector.worker import EMPTY_OK, decode, encode, encode_error


def _raised(exc: BaseException) -> bytes:
    try:
        raise exc
    except BaseException as e:
        return encode_error(e)


def test_plain_exception_round_trips_with_its_traceback_text():
    ok, (exc, text) = decode(_raised(KeyError("k")))
    assert ok is False and type(exc) is KeyError and exc.args == ("k",)
    assert text.startswith("Traceback") and "KeyError: 'k'" in text


def test_class_pickle_cannot_name_comes_back_as_the_same_class():
    # A local class stands for a script's class rebuilt by value in a spawn worker: plain pickle
    # cannot find it by name, cloudpickle sends it by value and its tracking maps it back.

    class LocalError(Exception):
        pass

    _, (exc, _) = decode(_raised(LocalError("boom")))
    assert type(exc) is LocalError and str(exc) == "boom"


def test_exception_that_cannot_be_rebuilt_becomes_a_runtime_error_naming_it():
    class TwoArgs(Exception):
        def __init__(self, a, b):  # pickle rebuilds it as TwoArgs(message): a TypeError there
            super().__init__(f"{a} and {b}")

    _, (exc, text) = decode(_raised(TwoArgs(1, 2)))
    assert type(exc) is RuntimeError and str(exc) == "TwoArgs: 1 and 2"
    assert "TwoArgs" in text


def test_local_env_functions_travel_by_value_and_module_ones_by_name():
    import pickle

    from palaestra.vector.worker import Payload

    scale = 3

    class Local:
        def __init__(self) -> None:
            self.scale = scale

    assert encode(True, {}) == EMPTY_OK and decode(EMPTY_OK) == (True, {})
    assert pickle.loads(pickle.dumps(Payload(lambda: scale * 2))).fn() == 6
    assert pickle.loads(pickle.dumps(Payload(Local))).fn().scale == 3
    assert pickle.loads(pickle.dumps(Payload(sorted))).fn is sorted
    ok, answer = decode(encode(True, Local()))
    assert ok is True and type(answer) is Local and answer.scale == 3


def test_env_function_that_cannot_be_pickled_names_itself_and_the_cause():
    import pickle
    import threading

    from palaestra.vector.worker import Payload

    lock = threading.Lock()

    def make_env():
        return lock

    expected = (
        r"cannot send the env function <function .*make_env.*> to a worker process: cannot "
        r"pickle '_thread.lock' object \(it, or something it refers to, cannot be pickled; "
        r"build that inside the function\)"
    )
    with pytest.raises(TypeError, match=expected):
        pickle.dumps(Payload(make_env))
