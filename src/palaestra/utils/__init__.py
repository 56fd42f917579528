"""Small utilities shared across palaestra (seeding, colours, constructor records, video)."""

from palaestra.utils.colorize import colorize
from palaestra.utils.record_constructor import RecordConstructorArgs
from palaestra.utils.video import save_video

__all__ = ["RecordConstructorArgs", "colorize", "save_video"]
