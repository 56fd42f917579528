"""The stdout table is byte-identical to SB3's; CSV rows; callbacks conversion."""

import csv
import io
from pathlib import Path

import pytest

from palaestra.algos import callbacks as cb
from palaestra.algos.logger import CSVOutputFormat, HumanOutputFormat, Logger, configure

ROWS = [
    ("rollout/ep_len_mean", 200.0),
    ("rollout/ep_rew_mean", -200.0),
    ("rollout/exploration_rate", 0.05),
    ("time/episodes", 4),
    ("time/fps", 1523),
    ("time/time_elapsed", 3),
    ("time/total_timesteps", 800),
    ("train/learning_rate", 0.001),
    ("train/loss", 0.0012345),
    ("train/n_updates", 123),
    ("train/approx_kl", 0.0123456789),
]


def test_table_identical_to_sb3() -> None:
    from stable_baselines3.common import logger as sb3

    theirs, ours = io.StringIO(), io.StringIO()
    a, b = (
        sb3.Logger(None, [sb3.HumanOutputFormat(theirs)]),
        Logger(None, [HumanOutputFormat(ours)]),
    )
    for key, value in ROWS:
        a.record(key, value)
        b.record(key, value)
    a.dump(1)
    b.dump(1)
    assert ours.getvalue() == theirs.getvalue()


def test_csv_header_grows_and_exclusions(tmp_path: Path) -> None:
    log = Logger(str(tmp_path), [CSVOutputFormat(str(tmp_path / "progress.csv"))])
    log.record("a", 1)
    log.dump()
    log.record("a", 2)
    log.record("b", "x,y")
    log.record("hidden", 3, exclude="csv")
    log.record_mean("m", 1.0)
    log.record_mean("m", 2.0)
    log.dump()
    log.close()
    with open(tmp_path / "progress.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows == [{"a": "1", "b": "", "m": ""}, {"a": "2", "b": "x,y", "m": "1.5"}]


def test_configure(tmp_path: Path) -> None:
    log = configure(str(tmp_path), ["csv", "log"])
    log.record("x", 1.0)
    log.dump()
    log.close()
    assert (tmp_path / "progress.csv").exists() and "x" in (tmp_path / "log.txt").read_text()
    with pytest.raises(ValueError, match="Unknown format"):
        configure(str(tmp_path), ["html"])


def test_function_callbacks_and_lists() -> None:
    calls = []
    fn = cb.convert_callback(lambda locals_, globals_: calls.append(locals_["dones"]))
    fn.locals = {"dones": [False]}
    assert fn._on_step() is True  # None from a function keeps training (SB3 would stop)
    stop = cb.convert_callback(lambda locals_, globals_: False)
    assert stop._on_step() is False
    both = cb.convert_callback([fn, stop])
    assert isinstance(both, cb.CallbackList)
    with pytest.raises(TypeError):
        cb.convert_callback(42)
