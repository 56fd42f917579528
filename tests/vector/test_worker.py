"""The worker's answers as bytes: exceptions keep their class, or fall back to a stand-in."""

from __future__ import annotations

import sys

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
    pytest.importorskip("cloudpickle")

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


def test_answers_by_value_without_cloudpickle_raise_the_pickling_error(monkeypatch):
    class Local:
        pass

    assert encode(True, {}) == EMPTY_OK and decode(EMPTY_OK) == (True, {})
    monkeypatch.setitem(sys.modules, "cloudpickle", None)
    with pytest.raises(AttributeError, match="Can't pickle local object"):
        encode(True, Local())


def test_local_env_function_without_cloudpickle_says_what_to_do(monkeypatch):
    import pickle

    from palaestra.vector.worker import Payload

    monkeypatch.setitem(sys.modules, "cloudpickle", None)
    with pytest.raises(TypeError, match=r"cannot send the env function <function .*<lambda>.* "
                       r"pass a module-level function, or `pip install cloudpickle`"):  # fmt: skip
        pickle.dumps(Payload(lambda: None))
    assert pickle.loads(pickle.dumps(Payload(sorted))).fn is sorted
