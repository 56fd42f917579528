"""SB3's ``stable_baselines3.common.utils`` helpers that user code calls.

Seeding every generator at once, schedules as functions of ``progress_remaining``, the Polyak
(soft) target update, device choice, parameter lookup by name and a system report for bug
reports. The schedules are palaestra's own classes, so a model saved with one stores it exactly.
"""

from __future__ import annotations

import glob
import os
import platform
import random
import re
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from palaestra import spaces
from palaestra.algos.common.logger import Logger, configure
from palaestra.algos.common.schedules import (
    ConstantSchedule,
    FloatSchedule,
    LinearSchedule,
    Schedule,
    as_schedule,
)
from palaestra.algos.common.spaces_util import (
    is_vectorized_box_observation,
    is_vectorized_dict_observation,
    is_vectorized_discrete_observation,
    is_vectorized_multibinary_observation,
    is_vectorized_multidiscrete_observation,
    is_vectorized_observation,
)
from palaestra.algos.learners.losses import explained_variance, polyak
from palaestra.error import InvalidObservation

if TYPE_CHECKING:  # type_aliases imports buffers, which imports this module
    from palaestra.algos.common.type_aliases import TrainFreq

__all__ = [
    "ConstantSchedule",
    "FloatSchedule",
    "LinearSchedule",
    "check_for_correct_spaces",
    "check_shape_equal",
    "configure_logger",
    "constant_fn",
    "explained_variance",
    "get_device",
    "get_latest_run_id",
    "get_linear_fn",
    "get_parameters_by_name",
    "get_schedule_fn",
    "get_system_info",
    "is_vectorized_box_observation",
    "is_vectorized_dict_observation",
    "is_vectorized_discrete_observation",
    "is_vectorized_multibinary_observation",
    "is_vectorized_multidiscrete_observation",
    "is_vectorized_observation",
    "obs_as_tensor",
    "polyak_update",
    "safe_mean",
    "set_random_seed",
    "should_collect_more_steps",
    "update_learning_rate",
    "zip_strict",
]


def set_random_seed(seed: int, using_cuda: bool = False) -> None:
    """Seed Python's ``random``, numpy's global generator and torch (CUDA: deterministic
    cuDNN too)."""
    random.seed(seed)
    np.random.seed(seed)  # noqa: NPY002 - the legacy global generator is what SB3 seeds
    torch.manual_seed(seed)
    if using_cuda:  # cuDNN's fast kernels are not deterministic
        torch.backends.cudnn.deterministic = True
        torch.backends.cudnn.benchmark = False


def get_schedule_fn(value_schedule: Schedule | float) -> Schedule:
    """A number or a callable of ``progress_remaining`` as a schedule returning floats.

    >>> get_schedule_fn(0.1)(0.5)
    0.1
    """
    return as_schedule(value_schedule)


def get_linear_fn(start: float, end: float, end_fraction: float) -> Schedule:
    """From ``start`` (progress 1) to ``end``, reached after ``end_fraction`` of training.

    >>> get_linear_fn(1.0, 0.0, 0.5)(0.75)
    0.5
    """
    return LinearSchedule(start, end, end_fraction)


def constant_fn(val: float) -> Schedule:
    """The schedule that is always ``val``."""
    return ConstantSchedule(val)


def get_device(device: torch.device | str = "auto") -> torch.device:
    """``"auto"`` means CUDA when available; a CUDA device without CUDA falls back to CPU."""
    resolved = torch.device("cuda" if device == "auto" else device)
    if resolved.type == "cuda" and not torch.cuda.is_available():
        return torch.device("cpu")
    return resolved


def polyak_update(
    params: Iterable[torch.Tensor], target_params: Iterable[torch.Tensor], tau: float
) -> None:
    """``target = (1 - tau) * target + tau * param`` in place, without a graph (tau=1 copies):
    the learners' ``polyak``, for torch tensors."""
    with torch.no_grad():
        polyak(list(params), list(target_params), tau)


def get_parameters_by_name(model: torch.nn.Module, included_names: Iterable[str]) -> list[Any]:
    """The ``state_dict`` entries whose name contains one of ``included_names`` (SB3 uses it
    for batch-norm running statistics)."""
    names = list(included_names)
    return [value for name, value in model.state_dict().items() if any(k in name for k in names)]


def zip_strict(*iterables: Iterable[Any]) -> Iterable[Any]:
    """``zip`` that raises ``ValueError`` when the iterables' lengths differ."""
    return zip(*iterables, strict=True)


def update_learning_rate(optimizer: torch.optim.Optimizer, learning_rate: float) -> None:
    """Set the learning rate of every parameter group of ``optimizer``."""
    for param_group in optimizer.param_groups:
        param_group["lr"] = learning_rate


def safe_mean(arr: Any) -> float:
    """The mean of ``arr``, NaN when it is empty (for logging)."""
    return float("nan") if len(arr) == 0 else float(np.mean(arr))


def get_latest_run_id(log_path: str = "", log_name: str = "") -> int:
    """The largest ``N`` among the folders ``{log_name}_{N}`` in ``log_path``; 0 if none
    (``log_name`` is matched literally, glob characters included)."""
    latest = 0
    for path in glob.glob(os.path.join(log_path, f"{glob.escape(log_name)}_[0-9]*")):
        name = os.path.basename(path)
        stem, _, ext = name.rpartition("_")
        if stem == log_name and ext.isdigit():
            latest = max(latest, int(ext))
    return latest


def configure_logger(
    verbose: int = 0,
    tensorboard_log: str | None = None,
    tb_log_name: str = "",
    reset_num_timesteps: bool = True,
) -> Logger:
    """SB3's logger for a ``learn`` call: stdout when ``verbose >= 1``; with
    ``tensorboard_log``, TensorBoard in ``{tensorboard_log}/{tb_log_name}_{N}``, ``N`` the
    next run id (the latest one when ``reset_num_timesteps=False``: training goes on there)."""
    folder, formats = None, ["stdout"]
    if tensorboard_log is not None:
        run_id = get_latest_run_id(tensorboard_log, tb_log_name)
        if not reset_num_timesteps:
            run_id -= 1
        folder = os.path.join(tensorboard_log, f"{tb_log_name}_{run_id + 1}")
        formats = ["stdout", "tensorboard"] if verbose >= 1 else ["tensorboard"]
    elif verbose == 0:
        formats = [""]
    return configure(folder, format_strings=formats)


def check_for_correct_spaces(
    env: Any, observation_space: spaces.Space[Any], action_space: spaces.Space[Any]
) -> None:
    """``ValueError`` unless ``env`` has exactly these observation and action spaces."""
    if observation_space != env.observation_space:
        raise ValueError(
            f"Observation spaces do not match: {observation_space} != {env.observation_space}"
        )
    if action_space != env.action_space:
        raise ValueError(f"Action spaces do not match: {action_space} != {env.action_space}")


def check_shape_equal(space1: spaces.Space[Any], space2: spaces.Space[Any]) -> None:
    """Box spaces (and Dict spaces key by key) of the same shapes; otherwise
    ``InvalidObservation`` naming the difference (SB3's words): a ``ValueError``, and an
    ``AssertionError`` as SB3 raises."""
    if isinstance(space1, spaces.Dict):
        if not isinstance(space2, spaces.Dict):
            raise InvalidObservation(
                f"spaces must be of the same type: {type(space1)} != {type(space2)}"
            )
        if space1.spaces.keys() != space2.spaces.keys():
            raise InvalidObservation(
                f"spaces must have the same keys: {list(space1.spaces.keys())} != "
                f"{list(space2.spaces.keys())}"
            )
        for key in space1.spaces:
            check_shape_equal(space1.spaces[key], space2.spaces[key])
    elif isinstance(space1, spaces.Box) and space1.shape != space2.shape:
        raise InvalidObservation(
            f"spaces must have the same shape: {space1.shape} != {space2.shape}"
        )


def obs_as_tensor(obs: Any, device: torch.device | str) -> Any:
    """An observation array (or a dict of them) as tensors on ``device``."""
    if isinstance(obs, np.ndarray):
        return torch.as_tensor(obs, device=device)
    if isinstance(obs, dict):
        return {key: torch.as_tensor(value, device=device) for key, value in obs.items()}
    raise TypeError(f"Unrecognized type of observation {type(obs)}")


def should_collect_more_steps(
    train_freq: TrainFreq, num_collected_steps: int, num_collected_episodes: int
) -> bool:
    """Whether an off-policy collection of ``train_freq`` (steps or episodes) goes on."""
    # TrainFrequencyUnit is a str enum: its members equal these strings
    if train_freq.unit == "step":
        return num_collected_steps < train_freq.frequency
    if train_freq.unit == "episode":
        return num_collected_episodes < train_freq.frequency
    raise ValueError(
        "The unit of the `train_freq` must be either TrainFrequencyUnit.STEP or "
        f"TrainFrequencyUnit.EPISODE not '{train_freq.unit}'!"
    )


def get_system_info(print_info: bool = True) -> tuple[dict[str, str], str]:
    """Versions of the OS, Python, palaestra and its dependencies, as a dict and as the
    Markdown list a bug report wants. Every ``save`` records them, so they are looked up
    without ``platform.platform()``'s ``uname -p`` subprocess and scan of the Python
    executable, and without parsing whole package metadata (together 10-25 ms, as long as
    saving a small model takes)."""
    from importlib import metadata

    def version(package: str) -> str | None:
        try:
            dist = metadata.distribution(package)
        except metadata.PackageNotFoundError:
            return None
        for line in (dist.read_text("METADATA") or "").splitlines():
            if not line:  # the end of the headers
                break
            if line.startswith("Version:"):
                return line[len("Version:") :].strip()
        return dist.version

    info = {
        # "#42" would link to an issue on GitHub: "# 42" does not.
        "OS": re.sub(r"#(\d)", r"# \1", f"{_platform_name()} {platform.version()}"),
        "Python": platform.python_version(),
        "palaestra": version("palaestra") or "(source tree)",
        "PyTorch": torch.__version__,
        "GPU Enabled": str(torch.cuda.is_available()),
        "Numpy": np.__version__,
    }
    for name, package in (("Gymnasium", "gymnasium"), ("Stable-Baselines3", "stable-baselines3")):
        found = version(package)
        if found is not None:
            info[name] = found
    text = "".join(f"- {key}: {value}\n" for key, value in info.items())
    if print_info:
        print(text)
    return info, text


def _platform_name() -> str:
    """``platform.platform()``'s ``Linux-6.1.0-x86_64-with-glibc2.36`` on Linux with glibc,
    from ``os.uname`` and ``confstr`` (no subprocess, no file read), less the processor that
    ``uname -p`` may add after the machine; elsewhere ``platform.platform()`` itself."""
    libc = os.confstr("CS_GNU_LIBC_VERSION") if "CS_GNU_LIBC_VERSION" in os.confstr_names else None
    uname = os.uname()
    if uname.sysname != "Linux" or not libc or not libc.startswith("glibc "):
        return platform.platform()
    parts = (uname.sysname, uname.release, uname.machine, "with", "glibc" + libc.split()[1])
    return "-".join(part.strip().replace(" ", "_") for part in parts if part)
