"""The logger's output formats take SB3's ``write(key_values, key_excluded, step)`` (issue 26):
TensorBoard events written at that step and read back with TensorBoard's own event reader,
side by side with SB3's format; the text formats filter exclusions themselves; keys that
collide once truncated are refused with SB3's error."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from palaestra.algos import logger as ours

sb3_logger = pytest.importorskip("stable_baselines3.common.logger")
event_accumulator = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")
mpl_figure = pytest.importorskip("matplotlib.figure")


def _events(folder: Path) -> Any:
    acc = event_accumulator.EventAccumulator(str(folder), size_guidance={"scalars": 0})
    acc.Reload()
    return acc


def _values(lib: Any) -> tuple[dict[str, Any], dict[str, tuple[str, ...]]]:
    values = {
        "train/loss": 0.25,
        "train/count": np.int64(3),
        "train/flag": True,
        "note": "hello",
        "weights": np.arange(4.0),
        "figure": lib.Figure(mpl_figure.Figure(figsize=(1, 1)), close=True),
        "image": lib.Image(np.zeros((4, 6, 3), np.uint8), "HWC"),
        "hparam": lib.HParam({"lr": 0.1, "algo": "PPO"}, {"train/loss": 0}),
        "skipped": 7.0,
    }
    excluded = {key: ("stdout",) for key in values}
    excluded["skipped"] = ("tensorboard",)
    return values, excluded


def test_tensorboard_write_takes_excluded_then_step_and_events_read_back(tmp_path: Path) -> None:
    tags = []
    for lib, name in ((ours, "pal"), (sb3_logger, "sb3")):
        folder = tmp_path / name
        fmt = lib.TensorBoardOutputFormat(str(folder))
        values, excluded = _values(lib)
        fmt.write(values, excluded, 7)  # SB3's positional order: values, excluded, step
        fmt.write({"train/loss": 0.5}, {"train/loss": None}, step=9)
        fmt.close()
        acc = _events(folder)
        loss = [(e.step, e.value) for e in acc.Scalars("train/loss")]
        assert loss == [(7, 0.25), (9, 0.5)]
        assert [(e.step, e.value) for e in acc.Scalars("train/count")] == [(7, 3.0)]
        assert [(e.step, e.value) for e in acc.Scalars("train/flag")] == [(7, 1.0)]
        assert [e.step for e in acc.Histograms("weights")] == [7]
        assert [e.step for e in acc.Images("image")] == [7]
        assert acc.Images("image")[0].width == 6 and acc.Images("image")[0].height == 4
        assert [e.step for e in acc.Images("figure")] == [7]
        all_tags = acc.Tags()
        assert "skipped" not in str(all_tags)
        tags.append({k: sorted(v) for k, v in all_tags.items() if isinstance(v, list)})
        tags[-1]["hparams"] = sorted(acc.PluginTagToContent("hparams").items())
    assert tags[0] == tags[1]
    assert [tag for tag, _ in tags[0]["hparams"]] == [
        "_hparams_/experiment",
        "_hparams_/session_end_info",
        "_hparams_/session_start_info",
    ]
    assert tags[0]["tensors"] == ["note/text_summary"]


def test_logger_dump_writes_tensorboard_events_at_the_step(tmp_path: Path) -> None:
    log = ours.configure(str(tmp_path), ["tensorboard"])
    log.record("rollout/ep_rew_mean", 12.5)
    log.record("time/total_timesteps", 100, exclude="tensorboard")
    log.dump(step=2048)
    log.close()
    acc = _events(tmp_path)
    assert [(e.step, e.value) for e in acc.Scalars("rollout/ep_rew_mean")] == [(2048, 12.5)]
    assert acc.Tags()["scalars"] == ["rollout/ep_rew_mean"]


@pytest.mark.parametrize("fmt", ["stdout", "csv", "json", "log"])
def test_text_formats_filter_exclusions_in_write_as_sb3(tmp_path: Path, fmt: str) -> None:
    texts = []
    for lib, name in ((ours, "pal"), (sb3_logger, "sb3")):
        out = io.StringIO()
        folder = tmp_path / name
        writer = (
            lib.HumanOutputFormat(out)
            if fmt == "stdout"
            else lib.make_output_format(fmt, str(folder))
        )
        values = {"a/x": 1.5, "a/y": 2, "b": "text", "hidden": 3.0, "only_tb": torch.zeros(1)}
        excluded = {
            "a/x": None,
            "a/y": (),
            "b": ("tensorboard",),
            "hidden": (fmt,),
            "only_tb": ("stdout", "log", "json", "csv"),
        }
        writer.write(values, excluded, 4)
        writer.write({"a/x": 2.5}, {"a/x": None})  # step defaults to 0
        writer.close()
        if fmt == "stdout":
            texts.append(out.getvalue())
        elif fmt == "csv":  # SB3 orders new columns as a set does: compare the rows by name
            rows = list(csv.DictReader(io.StringIO(next(folder.iterdir()).read_text())))
            texts.append(str(sorted(sorted(row.items()) for row in rows)))
        else:
            texts.append(next(folder.iterdir()).read_text())
    assert texts[0] == texts[1]
    assert "hidden" not in texts[0] and "1.5" in texts[0]


def test_write_with_a_step_in_the_place_of_excluded_is_a_type_error() -> None:
    writer = ours.HumanOutputFormat(io.StringIO())
    with pytest.raises(
        TypeError, match=r"key_excluded must map keys .* got 100; pass the step as step="
    ):
        writer.write({"a": 1.0}, 100)  # type: ignore[arg-type]


def test_keys_colliding_after_truncation_are_refused_as_sb3() -> None:
    values = {"train/" + "x" * 40 + "1": 1.0, "train/" + "x" * 40 + "2": 2.0}
    excluded: dict[str, tuple[str, ...]] = {k: () for k in values}
    messages = []
    for lib in (ours, sb3_logger):
        with pytest.raises(ValueError, match="truncated to") as caught:
            lib.HumanOutputFormat(io.StringIO(), max_length=20).write(values, excluded, 0)
        messages.append(str(caught.value))
    assert messages[0] == messages[1]
    # a longer max_length takes both
    out = io.StringIO()
    ours.HumanOutputFormat(out, max_length=60).write(values, excluded, 0)
    assert "x1 " in out.getvalue() and "x2 " in out.getvalue()


def test_users_kvwriter_gets_sb3s_arguments() -> None:
    got = []

    class Mine(ours.KVWriter):
        def write(self, key_values: Any, key_excluded: Any = None, step: int = 0) -> None:
            got.append((dict(key_values), dict(key_excluded), step))

        def close(self) -> None:
            pass

    log = ours.Logger(None, [Mine()])
    log.record("a", 1.0, exclude="csv")
    log.record("b", 2)
    log.dump(step=3)
    assert got == [({"a": 1.0, "b": 2}, {"a": ("csv",), "b": ()}, 3)]
    assert ours.filter_excluded_keys({"a": 1, "b": 2}, {"a": ("csv",)}, "csv") == {"b": 2}
    assert sb3_logger.filter_excluded_keys(
        {"a": 1, "b": 2}, {"a": ("csv",), "b": ("",)}, "csv"
    ) == {"b": 2}


def test_tensorboard_log_of_a_model_writes_events_at_its_step_counts(tmp_path: Path) -> None:
    from palaestra.algos import PPO

    model = PPO(
        "MlpPolicy",
        "CartPole-v1",
        n_steps=32,
        batch_size=32,
        n_epochs=1,
        tensorboard_log=str(tmp_path),
    )
    model.learn(64, tb_log_name="run")
    acc = _events(tmp_path / "run_1")
    assert [e.step for e in acc.Scalars("time/fps")] == [32, 64]
    assert [e.step for e in acc.Scalars("train/loss")] == [64]  # logged with the next dump
