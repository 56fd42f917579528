"""Moved to :mod:`palaestra.utils.stacked_infos` (toy text's batches use it too, and the env
packages sit above ``vector``); this path re-exports it."""

from palaestra.utils.stacked_infos import StackedInfos

__all__ = ["StackedInfos"]
