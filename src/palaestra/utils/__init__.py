"""Small utilities shared across palaestra (seeding, colours, constructor records, video)."""

import importlib
from typing import Any

from palaestra.utils.colorize import colorize
from palaestra.utils.ezpickle import EzPickle
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["EzPickle", "RecordConstructorArgs", "colorize", "save_video"]


def __getattr__(name: str) -> Any:
    # save_video's module is loaded on first use, keeping `import palaestra` lean. It is
    # Gymnasium's module path (palaestra.utils.save_video.save_video) and, called, palaestra's
    # save_video(frames, path, fps) of palaestra.utils.video.
    if name == "save_video":
        return importlib.import_module(  # lazy: import-time — utils.video
            "palaestra.utils.save_video"
        )
    raise AttributeError(f"module 'palaestra.utils' has no attribute {name!r}")
