"""SB3's ``stable_baselines3.common.utils`` helpers that user code calls.

Seeding every generator at once, schedules as functions of ``progress_remaining``, the Polyak
(soft) target update, device choice, parameter lookup by name and a system report for bug
reports. The schedules are palaestra's own classes, so a model saved with one stores it exactly.
"""

from __future__ import annotations

import os
import platform
import random
import re
from collections.abc import Iterable
from typing import Any

import numpy as np
import torch

from palaestra.algos.common.schedules import (
    ConstantSchedule,
    FloatSchedule,
    LinearSchedule,
    Schedule,
    as_schedule,
)
from palaestra.algos.learners.losses import explained_variance, polyak

__all__ = [
    "ConstantSchedule",
    "FloatSchedule",
    "LinearSchedule",
    "constant_fn",
    "explained_variance",
    "get_device",
    "get_linear_fn",
    "get_parameters_by_name",
    "get_schedule_fn",
    "get_system_info",
    "polyak_update",
    "set_random_seed",
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
