"""Small utilities shared across palaestra (seeding, colours, constructor records)."""

from palaestra.utils.colorize import colorize
from palaestra.utils.record_constructor import RecordConstructorArgs

__all__ = ["RecordConstructorArgs", "colorize"]
