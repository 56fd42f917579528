"""SB3's ``Figure``/``Image``/``Video``/``HParam`` logger values (issue 16): TensorBoard gets
them, stdout/log/CSV/JSON refuse them with SB3's ``FormatUnsupportedError`` unless excluded,
as SB3 does. TensorBoard itself is not installed here: both libraries write to the same
recording stand-in for ``SummaryWriter``, and their calls are compared (ported in spirit from
SB3's ``tests/test_logger.py``)."""

from __future__ import annotations

import io
import json
import sys
import types
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos import logger as ours

sb3_logger = pytest.importorskip("stable_baselines3.common.logger")
mpl_figure = pytest.importorskip("matplotlib.figure")

TEXT_FORMATS = {"stdout": None, "log": "log.txt", "csv": "progress.csv", "json": "progress.json"}


def _rich_values(lib: Any) -> dict[str, Any]:
    figure = mpl_figure.Figure()  # not pyplot's: nothing to close, no display
    return {
        "video": lib.Video(torch.zeros(1, 2, 3, 8, 8), fps=30),
        "figure": lib.Figure(figure, close=True),
        "image": lib.Image(np.zeros((8, 8, 3), np.uint8), "HWC"),
        "hparam": lib.HParam({"lr": 0.1, "algo": "PPO"}, {"rollout/ep_rew_mean": 0}),
    }


def _writer(lib: Any, fmt: str, folder: Path) -> Any:
    if fmt == "stdout":
        return lib.HumanOutputFormat(io.StringIO())
    return lib.make_output_format(fmt, str(folder))


@pytest.mark.parametrize("fmt", sorted(TEXT_FORMATS))
@pytest.mark.parametrize("kind", ["video", "figure", "image", "hparam"])
def test_text_outputs_refuse_rich_values_as_sb3(tmp_path: Path, fmt: str, kind: str) -> None:
    messages = []
    for lib, name in ((ours, "pal"), (sb3_logger, "sb3")):
        log = lib.Logger(str(tmp_path / name), [_writer(lib, fmt, tmp_path / name)])
        log.record(kind, _rich_values(lib)[kind])
        with pytest.raises(lib.FormatUnsupportedError) as caught:
            log.dump(1)
        messages.append(str(caught.value))
        assert isinstance(caught.value, NotImplementedError)
        log.close()
        # excluded from the text outputs, it is left out of them
        log = lib.Logger(str(tmp_path / name), [_writer(lib, fmt, tmp_path / f"{name}_ok")])
        log.record(kind, _rich_values(lib)[kind], exclude=("stdout", "log", "json", "csv"))
        log.record("x", 1.0)
        log.dump(2)
        log.close()
    assert messages[0] == messages[1]
    if TEXT_FORMATS[fmt] is not None:
        ours_text = (tmp_path / "pal_ok" / TEXT_FORMATS[fmt]).read_text()
        assert ours_text == (tmp_path / "sb3_ok" / TEXT_FORMATS[fmt]).read_text()
        assert kind not in ours_text and "x" in ours_text


class _Recorder:
    """A SummaryWriter stand-in: every call, with its arguments in comparable form."""

    calls: list[tuple[Any, ...]] = []

    def __init__(self, log_dir: str) -> None:
        self.file_writer = types.SimpleNamespace(
            add_summary=lambda summary: _Recorder.calls.append(("add_summary", summary))
        )

    def __getattr__(self, name: str) -> Any:
        def record(*args: Any, **kwargs: Any) -> None:
            plain = [a.tolist() if isinstance(a, (np.ndarray, torch.Tensor)) else a for a in args]
            _Recorder.calls.append((name, *map(_comparable, plain), sorted(kwargs.items())))

        return record


def _comparable(value: Any) -> Any:
    if isinstance(value, mpl_figure.Figure):
        return "figure"
    return value


def _hparams(hparam_dict: Any, metric_dict: Any) -> tuple[Any, ...]:
    return ("experiment", sorted(hparam_dict.items()), sorted(metric_dict.items()))


def test_tensorboard_gets_what_sb3_writes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # palaestra imports torch.utils.tensorboard when the output is made: a stand-in module
    stub = types.ModuleType("torch.utils.tensorboard")
    stub.SummaryWriter = _Recorder  # type: ignore[attr-defined]
    summary = types.ModuleType("torch.utils.tensorboard.summary")
    summary.hparams = _hparams  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard", stub)
    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard.summary", summary)
    monkeypatch.setattr(sb3_logger, "SummaryWriter", _Recorder)
    monkeypatch.setattr(sb3_logger, "hparams", _hparams, raising=False)  # None without TB
    recorded = []
    for lib in (ours, sb3_logger):
        _Recorder.calls = []
        log = lib.Logger(str(tmp_path), [lib.make_output_format("tensorboard", str(tmp_path))])
        values = {
            **_rich_values(lib),
            "scalar": 1.5,
            "count": np.int64(3),
            "flag": True,
            "note": "hello",
            "weights": np.arange(4.0),
            "skipped": 7.0,
        }
        for key, value in values.items():
            excluded = ("tensorboard",) if key == "skipped" else ("stdout", "log", "json", "csv")
            log.record(key, value, exclude=excluded)
        log.dump(5)
        recorded.append(list(_Recorder.calls))
    assert recorded[0] == recorded[1]
    assert {call[0] for call in recorded[0]} >= {
        "add_video",
        "add_figure",
        "add_image",
        "add_summary",
        "add_scalar",
        "add_text",
        "add_histogram",
    }
    assert not any("skipped" in call for call in recorded[0])


def test_json_and_output_names_as_sb3(tmp_path: Path) -> None:
    rows = []
    for lib, name in ((ours, "pal"), (sb3_logger, "sb3")):
        folder = tmp_path / name
        log = lib.Logger(str(folder), [lib.make_output_format("json", str(folder), "_a")])
        log.record("a", np.float32(0.5))
        log.record("b", np.array([1, 2]))
        log.record("c", np.array([3.0]))
        log.record("d", "text")
        log.dump(1)
        log.close()
        rows.append(
            [json.loads(line) for line in (folder / "progress_a.json").read_text().splitlines()]
        )
        lib.make_output_format("log", str(folder), "_b").close()
        lib.make_output_format("csv", str(folder), "_b").close()
        assert {p.name for p in folder.iterdir()} == {
            "progress_a.json",
            "log_b.txt",
            "progress_b.csv",
        }
    assert rows[0] == rows[1] == [{"a": 0.5, "b": [1, 2], "c": 3.0, "d": "text"}]
    with pytest.raises(ValueError, match="Unknown format specified: 'html'"):
        ours.make_output_format("html", str(tmp_path))


def test_hparam_needs_metrics() -> None:
    for lib in (ours, sb3_logger):
        with pytest.raises(Exception, match="`metric_dict` must not be empty"):
            lib.HParam({"lr": 0.1}, {})
