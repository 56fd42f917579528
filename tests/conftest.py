"""Shared pytest configuration."""

import os

# Rendering tests must never open a window on CI machines.
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ["PYGAME_HIDE_SUPPORT_PROMPT"] = "hide"
