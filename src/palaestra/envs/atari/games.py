"""The Atari game list and the ids registered for it, as pure data (no ale-py import).

``import palaestra`` registers every ``ALE/<Game>-v5`` id from these lists, so it must not load
ale-py (~100 ms and a GPL C++ extension most users never need). A test checks the lists
against the ROMs that the installed ale-py ships.
"""

from __future__ import annotations

from typing import Any

from palaestra import error

# ale-py 0.12's ROM ids (``ale_py.roms.get_all_rom_ids()``), sorted.
ROM_IDS: tuple[str, ...] = tuple(
    sorted(
        """
        adventure air_raid alien amidar assault asterix asteroids atlantis atlantis2 backgammon
        bank_heist basic_math battle_zone beam_rider berzerk blackjack bowling boxing breakout
        carnival casino centipede chopper_command combat crazy_climber crossbow darkchambers
        defender demon_attack donkey_kong double_dunk earthworld elevator_action enduro entombed
        et fishing_derby flag_capture freeway frogger frostbite galaxian gopher gravitar hangman
        haunted_house hero human_cannonball ice_hockey jamesbond journey_escape joust kaboom
        kangaroo keystone_kapers king_kong klax koolaid krull kung_fu_master laser_gates
        lost_luggage mario_bros maze_craze miniature_golf montezuma_revenge mr_do ms_pacman
        name_this_game othello pacman phoenix pitfall pitfall2 pong pooyan private_eye qbert
        riverraid road_runner robotank seaquest sir_lancelot skiing solaris space_invaders
        space_war star_gunner superman surround tennis tetris tic_tac_toe_3d time_pilot trondead
        turmoil tutankham up_n_down venture video_checkers video_chess video_cube video_pinball
        warlords wizard_of_wor word_zapper yars_revenge zaxxon
        """.split()
    )
)

# Multi-player-only ROMs: ale-py registers no single-agent v5 id for them.
MULTIPLAYER_ONLY = frozenset({"combat", "joust", "maze_craze", "warlords"})

# The games of the original ALE benchmark, the only ones with v0/v4 ids in ale-py.
LEGACY_GAMES: tuple[str, ...] = tuple(
    """
    adventure air_raid alien amidar assault asterix asteroids atlantis bank_heist battle_zone
    beam_rider berzerk bowling boxing breakout carnival centipede chopper_command crazy_climber
    defender demon_attack double_dunk elevator_action enduro fishing_derby freeway frostbite
    gopher gravitar hero ice_hockey jamesbond journey_escape kangaroo krull kung_fu_master
    montezuma_revenge ms_pacman name_this_game phoenix pitfall pong pooyan private_eye qbert
    riverraid road_runner robotank seaquest skiing solaris space_invaders star_gunner tennis
    time_pilot tutankham up_n_down venture video_pinball wizard_of_wor yars_revenge zaxxon
    """.split()
)

# 108k frames = 30 minutes of play at 60 Hz, ale-py's episode cap (Machado et al., 2018).
MAX_FRAMES_PER_EPISODE = 108_000

ENTRY_POINT = "palaestra.envs.atari.env:AtariEnv"
VECTOR_ENTRY_POINT = "palaestra.envs.atari.vector:AtariVectorEnv"


def rom_id_to_name(rom: str) -> str:
    """``"space_invaders"`` -> ``"SpaceInvaders"`` (the id's name, as ale-py spells it).

    >>> rom_id_to_name("tic_tac_toe_3d")
    'TicTacToe3D'
    """
    return rom.title().replace("_", "")


def check_game(game: str) -> str:
    """``game`` if it is a known ROM id, else ``palaestra.error.Error`` naming the closest."""
    if game in ROM_IDS:
        return game
    import difflib  # only on this error path: keeps `import palaestra` lean

    snake = "".join(f"_{c.lower()}" if c.isupper() else c for c in str(game)).lstrip("_")
    close = difflib.get_close_matches(snake, ROM_IDS, n=3) or difflib.get_close_matches(
        str(game).lower(), ROM_IDS, n=3
    )
    hint = f" Did you mean: {', '.join(map(repr, close))}?" if close else ""
    raise error.Error(
        f"Unknown Atari game {game!r}: expected a snake_case ROM id of ale-py such as "
        f"'breakout' or 'space_invaders'.{hint}"
    )


def atari_specs() -> dict[str, dict[str, Any]]:
    """``id -> register() kwargs`` for every Atari id palaestra registers.

    ``ALE/<Game>-v5``: ale-py's v5 settings (sticky actions 0.25, frameskip 4, minimal action
    set). ``<Game>NoFrameskip-v4``: the v4 settings SB3 / RL-Zoo Atari pipelines expect (no
    sticky actions, frameskip 1; the wrappers skip frames).
    """
    specs: dict[str, dict[str, Any]] = {}
    for rom in ROM_IDS:
        if rom in MULTIPLAYER_ONLY:
            continue
        specs[f"ALE/{rom_id_to_name(rom)}-v5"] = dict(
            entry_point=ENTRY_POINT,
            vector_entry_point=VECTOR_ENTRY_POINT,
            kwargs=dict(
                game=rom,
                repeat_action_probability=0.25,
                full_action_space=False,
                frameskip=4,
                max_num_frames_per_episode=MAX_FRAMES_PER_EPISODE,
            ),
        )
    for rom in LEGACY_GAMES:
        specs[f"{rom_id_to_name(rom)}NoFrameskip-v4"] = dict(
            entry_point=ENTRY_POINT,
            kwargs=dict(
                game=rom,
                repeat_action_probability=0.0,
                full_action_space=False,
                frameskip=1,
                max_num_frames_per_episode=MAX_FRAMES_PER_EPISODE,
            ),
        )
    return specs
