"""``palaestra.utils.play`` (Gymnasium's ``play``/``PlayPlot``), driven by scripted pygame
events on SDL's dummy video driver: the steps it takes are the env's own steps for the keys
held, episodes restart with the seed, and pygame is imported only when a game starts."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import numpy as np
import pytest

import palaestra as gym
from palaestra.utils import play as play_module

pygame = pytest.importorskip("pygame")


@pytest.fixture
def scripted(monkeypatch: pytest.MonkeyPatch) -> Any:
    """Replace pygame's event queue with a script: frame number -> events."""
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")

    def install(script: dict[int, list[Any]]) -> None:
        frames = iter(range(10_000))

        def get() -> list[Any]:
            return script.get(next(frames), [])

        monkeypatch.setattr(pygame.event, "get", get)

    return install


def _key(kind: int, key: int) -> Any:
    return pygame.event.Event(kind, key=key)


def test_play_steps_the_env_with_the_keys_held(scripted: Any) -> None:
    right, left = 275, 276  # MountainCar's own mapping: () -> 1, right -> 2, left -> 0
    scripted(
        {
            2: [_key(pygame.KEYDOWN, right)],
            5: [_key(pygame.KEYUP, right), _key(pygame.KEYDOWN, left)],
            8: [_key(pygame.KEYDOWN, right)],
            11: [pygame.event.Event(pygame.QUIT)],
        }
    )
    steps: list[tuple[Any, ...]] = []
    env = gym.make("MountainCar-v0", render_mode="rgb_array")
    play_module.play(env, fps=1000, seed=3, callback=lambda *step: steps.append(step))
    # frame 0 resets; frames 1..11 step with the keys held after the previous frame's events
    actions = [step[2] for step in steps]
    assert actions == [1, 1, 2, 2, 2, 0, 0, 0, 1, 1, 1]
    reference = gym.make("MountainCar-v0")
    obs, _ = reference.reset(seed=3)
    for prev, nxt, action, reward, terminated, truncated, _ in steps:
        np.testing.assert_array_equal(prev, obs)
        obs, want_reward, want_term, want_trunc, _ = reference.step(action)
        np.testing.assert_array_equal(nxt, obs)
        assert (reward, terminated, truncated) == (want_reward, want_term, want_trunc)


def test_wait_on_player_and_escape(scripted: Any) -> None:
    scripted({3: [_key(pygame.KEYDOWN, ord("d"))], 6: [_key(pygame.KEYDOWN, pygame.K_ESCAPE)]})
    steps: list[Any] = []
    env = gym.make("CartPole-v1", render_mode="rgb_array")
    play_module.play(
        env,
        fps=1000,
        keys_to_action={"a": 0, "d": 1},
        wait_on_player=True,
        zoom=0.5,
        callback=lambda *step: steps.append(step[2]),
    )
    assert steps == [1, 1, 1]  # only once "d" is held (frames 4, 5, 6)


def test_bad_arguments(scripted: Any) -> None:
    scripted({})
    cartpole = gym.make("CartPole-v1", render_mode="rgb_array")
    with pytest.raises(play_module.MissingKeysToAction, match="CartPole-v1 does not have"):
        play_module.play(cartpole)
    with pytest.raises(TypeError, match="keys_to_action must be a dictionary"):
        play_module.play(cartpole, keys_to_action=[("a", 0)])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="Action 5 is not a valid action"):
        play_module.play(cartpole, keys_to_action={"a": 5})
    with pytest.raises(ValueError, match="works only with rgb_array"):
        play_module.play(gym.make("CartPole-v1"), keys_to_action={"a": 0})
    with pytest.raises(ValueError, match="Zoom must be a positive float"):
        play_module.play(cartpole, keys_to_action={"a": 0}, zoom=0)


def test_play_plot_keeps_the_horizon() -> None:
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    plot = play_module.PlayPlot(lambda *step: [step[3], float(step[2])], 3, ["reward", "action"])
    for t in range(5):
        plot.callback(None, None, t % 2, float(t), False, False, {})
    assert [list(d) for d in plot.data] == [[2.0, 3.0, 4.0], [0.0, 1.0, 0.0]]
    assert plot.ax[0].get_title() == "reward" and plot.ax[0].get_xlim() == (2.0, 5.0)


def test_importing_play_imports_neither_pygame_nor_matplotlib() -> None:
    code = (
        "import sys, palaestra.utils.play; "
        "print('pygame' in sys.modules, 'matplotlib' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
