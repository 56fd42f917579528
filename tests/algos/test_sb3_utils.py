"""``palaestra.algos.utils`` and ``palaestra.algos.results_plotter`` against SB3's functions
(``stable_baselines3.common.utils`` side by side; SB3's results_plotter needs pandas, so the
plotter is checked against monitor files with known contents)."""

from __future__ import annotations

import platform
import random
import sys

import numpy as np
import pytest
import torch
from stable_baselines3 import __version__ as sb3_version
from stable_baselines3.common import utils as sb3_utils

import palaestra as gym
from palaestra.algos import results_plotter, utils
from palaestra.wrappers.monitor import Monitor

# SB3 2.x marks its schedule functions deprecated; palaestra keeps them quiet.
pytestmark = pytest.mark.filterwarnings("ignore:.* is deprecated, please use:UserWarning")


def _draws():
    return random.random(), float(np.random.rand())  # noqa: NPY002, float(torch.rand(1))


def test_set_random_seed_seeds_what_sb3_seeds():
    sb3_utils.set_random_seed(7)
    theirs = _draws()
    utils.set_random_seed(7)
    assert _draws() == theirs


@pytest.mark.parametrize("progress", [1.0, 0.9, 0.5, 0.2, 0.0])
def test_schedules_match_sb3(progress):
    assert utils.get_linear_fn(1.0, 0.1, 0.3)(progress) == pytest.approx(
        sb3_utils.get_linear_fn(1.0, 0.1, 0.3)(progress), abs=1e-15
    )
    assert utils.get_schedule_fn(3)(progress) == sb3_utils.get_schedule_fn(3)(progress) == 3.0
    fn = lambda p: np.float32(p) * 2  # noqa: E731
    ours, theirs = utils.get_schedule_fn(fn)(progress), sb3_utils.get_schedule_fn(fn)(progress)
    assert type(ours) is type(theirs) is float and ours == theirs
    assert utils.constant_fn(0.5)(progress) == sb3_utils.constant_fn(0.5)(progress)


def test_polyak_update_matches_sb3():
    torch.manual_seed(0)
    source = torch.nn.Linear(3, 2)
    ours_target, theirs_target = torch.nn.Linear(3, 2), torch.nn.Linear(3, 2)
    theirs_target.load_state_dict(ours_target.state_dict())
    utils.polyak_update(source.parameters(), ours_target.parameters(), 0.3)
    sb3_utils.polyak_update(source.parameters(), theirs_target.parameters(), 0.3)
    for a, b in zip(ours_target.parameters(), theirs_target.parameters()):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
    with pytest.raises(ValueError):  # strict zip, as SB3
        utils.polyak_update(source.parameters(), [ours_target.weight], 0.5)


def test_device_parameters_zip_and_system_info(capsys):
    assert utils.get_device("auto") == sb3_utils.get_device("auto")
    assert utils.get_device("cuda:0") == sb3_utils.get_device("cuda:0")
    net = torch.nn.Sequential(torch.nn.Linear(2, 2), torch.nn.BatchNorm1d(2))
    names = ["running_"]
    ours = utils.get_parameters_by_name(net, names)
    theirs = sb3_utils.get_parameters_by_name(net, names)
    assert len(ours) == len(theirs) == 2
    assert [a.data_ptr() for a in ours] == [b.data_ptr() for b in theirs]  # the same storage
    assert list(utils.zip_strict([1, 2], "ab")) == [(1, "a"), (2, "b")]
    with pytest.raises(ValueError):
        list(utils.zip_strict([1, 2], "a"))
    info, text = utils.get_system_info()
    assert {"OS", "Python", "PyTorch", "Numpy"} <= set(info)
    assert capsys.readouterr().out.strip() == text.strip()
    assert text.startswith("- OS: ")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux's shortcut")
def test_system_info_names_the_os_as_platform_does_without_its_subprocess(monkeypatch):
    """``save`` records the OS as ``platform.platform()`` names it, less the processor that
    ``uname -p`` (a subprocess) may add; ``platform.processor`` is never asked."""
    processor = platform.processor()
    expected = platform.platform().replace(f"-{processor}", "", 1) if processor else None

    def no_subprocess() -> str:
        raise AssertionError("platform.processor() runs uname -p")

    monkeypatch.setattr(platform, "processor", no_subprocess)
    info, _ = utils.get_system_info(print_info=False)
    assert info["OS"].startswith(expected or platform.platform())
    assert info["Numpy"] == np.__version__ and info["PyTorch"] == torch.__version__
    assert info["Stable-Baselines3"] == sb3_version  # read from its metadata's Version line


def _monitor_logs(tmp_path, ranks):
    """One monitor per rank in one folder; returns every finished episode's (r, l)."""
    episodes = []
    for rank in ranks:
        env = Monitor(gym.make("CartPole-v1"), str(tmp_path / str(rank)))
        env.reset(seed=rank)
        for _ in range(3):
            done = False
            while not done:
                _, _, terminated, truncated, info = env.step(rank % 2)
                done = terminated or truncated
            episodes.append((info["episode"]["r"], info["episode"]["l"]))
            env.reset()
        env.close()
    return episodes


def test_load_columns_and_ts2xy(tmp_path):
    episodes = _monitor_logs(tmp_path, [0, 1])
    data = results_plotter.load_columns(str(tmp_path))
    assert sorted(data["l"].tolist()) == sorted(length for _, length in episodes)
    assert np.all(np.diff(data["t"]) >= 0) and data["t"][0] >= 0
    x, y = results_plotter.ts2xy(data, results_plotter.X_TIMESTEPS)
    np.testing.assert_array_equal(x, np.cumsum(data["l"]))
    np.testing.assert_array_equal(y, data["r"])
    x, _ = results_plotter.ts2xy(data, results_plotter.X_EPISODES)
    assert x.tolist() == list(range(6))
    x, _ = results_plotter.ts2xy(data, results_plotter.X_WALLTIME)
    np.testing.assert_allclose(x, data["t"] / 3600)
    with pytest.raises(NotImplementedError, match="Unsupported x_axis='steps'"):
        results_plotter.ts2xy(data, "steps")


def test_window_func_matches_a_loop():
    rng = np.random.default_rng(0)
    y = rng.random(120)
    x, means = results_plotter.window_func(np.arange(120), y, 100, np.mean)
    assert x.tolist() == list(range(99, 120))
    np.testing.assert_allclose(means, [y[i - 99 : i + 1].mean() for i in range(99, 120)])


def test_plot_results_draws_each_folder(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    _monitor_logs(tmp_path / "a", [0])
    _monitor_logs(tmp_path / "b", [1])
    figure = results_plotter.plot_results(
        [str(tmp_path / "a"), str(tmp_path / "b")], 10_000, results_plotter.X_TIMESTEPS, "CartPole"
    )
    axes = figure.axes[0]
    assert axes.get_title() == "CartPole" and axes.get_ylabel() == "Episode Rewards"
    assert len(axes.collections) == 2  # one scatter per folder
    from matplotlib import pyplot as plt

    plt.close(figure)
