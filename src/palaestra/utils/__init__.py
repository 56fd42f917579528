"""Small utilities shared across palaestra (seeding, colours, constructor records, video)."""

from typing import Any

from palaestra.utils.colorize import colorize
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["RecordConstructorArgs", "colorize", "save_video"]


def __getattr__(name: str) -> Any:
    # save_video's module is loaded on first use, keeping `import palaestra` lean.
    if name == "save_video":
        from palaestra.utils.video import save_video  # lazy: import-time — utils.video

        return save_video
    raise AttributeError(f"module 'palaestra.utils' has no attribute {name!r}")
