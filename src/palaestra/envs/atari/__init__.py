"""Atari 2600 games through ale-py: ``ALE/<Game>-v5`` and ``<Game>NoFrameskip-v4``.

``import palaestra`` registers the ids from :mod:`.games` (pure data); ale-py loads only when an
env is made, and a missing ale-py raises ``DependencyNotInstalled`` naming
``pip install "palaestra[atari]"``.
"""

from typing import Any

from palaestra.envs.atari.games import ROM_IDS, atari_specs, rom_id_to_name

__all__ = ["ROM_IDS", "AtariEnv", "atari_specs", "rom_id_to_name"]


def __getattr__(name: str) -> Any:
    # The env module is imported on first use: `import palaestra` registers the ids only.
    if name == "AtariEnv":
        from palaestra.envs.atari.env import AtariEnv  # lazy: import-time — the ALE env module

        return AtariEnv
    raise AttributeError(f"module 'palaestra.envs.atari' has no attribute {name!r}")
