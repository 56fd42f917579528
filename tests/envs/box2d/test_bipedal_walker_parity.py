"""BipedalWalker against the installed Gymnasium 1.4: identical bytes, rewards and flags.

Gymnasium keeps one Box2D world for the env's life, so these runs reset many times in one env
(the destroy/create order across episodes is part of what must match). Random and striding
actions fall within a few metres; to reach the hardcore obstacles, one test moves both walkers
(the same Box2D call on both) to just before the first obstacle and walks into it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.envs.box2d.cases import walker_action

import palaestra

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("Box2D")

WALKER_IDS = ["BipedalWalker-v3", "BipedalWalkerHardcore-v3"]


def _check_step(ours: Any, ref: Any, action: Any, where: str) -> tuple[np.ndarray, float, bool]:
    obs, reward, term, trunc, info = ours.step(action)
    ref_obs, ref_reward, ref_term, ref_trunc, ref_info = ref.step(action)
    assert obs.tobytes() == ref_obs.tobytes(), f"{where}: {obs} != {ref_obs}"
    assert type(reward) is float and reward == float(ref_reward), f"{where}: {reward!r}"
    assert (term, trunc) == (ref_term, ref_trunc), where
    assert info == ref_info == {}
    return obs, reward, term or trunc


def run_both(env_id: str, seed: int, steps: int, dtype: Any = np.float32) -> int:
    """Lockstep run with resets (alternately reseeded); returns the number of episodes."""
    ours, ref = palaestra.make(env_id), gymnasium.make(env_id)
    obs, _ = ours.reset(seed=seed)
    ref_obs, _ = ref.reset(seed=seed)
    assert obs.tobytes() == ref_obs.tobytes()
    rng = np.random.default_rng(seed + 1000)
    episodes, t0 = 0, 0
    for t in range(steps):
        where = f"{env_id} seed {seed} step {t}"
        _, _, done = _check_step(ours, ref, walker_action(rng, t - t0, dtype), where)
        if done:
            episodes, t0 = episodes + 1, t + 1
            kw: dict[str, Any] = {} if episodes % 2 else {"seed": seed + t}
            obs, _ = ours.reset(**kw)
            ref_obs, _ = ref.reset(**kw)
            assert obs.tobytes() == ref_obs.tobytes(), f"{where}: reset {kw}"
    return episodes


@pytest.mark.parametrize("env_id", WALKER_IDS)
def test_short_parity(env_id: str) -> None:
    assert run_both(env_id, seed=4, steps=250) >= 1


def test_float64_actions_keep_their_precision_as_in_gymnasium() -> None:
    run_both("BipedalWalker-v3", seed=6, steps=120, dtype=np.float64)


@pytest.mark.slow
@pytest.mark.parametrize("env_id", WALKER_IDS)
def test_long_parity(env_id: str) -> None:
    episodes = sum(run_both(env_id, seed, steps=1200) for seed in (0, 1, 2))
    assert episodes >= 6


@pytest.mark.parametrize("hardcore", [False, True])
def test_terrain_and_clouds_match_over_many_seeds(hardcore: bool) -> None:
    ours = palaestra.make("BipedalWalker-v3", hardcore=hardcore).unwrapped
    ref = gymnasium.make("BipedalWalker-v3", hardcore=hardcore).unwrapped
    kinds = set()
    for seed in range(25):
        obs, _ = ours.reset(seed=seed)
        ref_obs, _ = ref.reset(seed=seed)
        assert obs.tobytes() == ref_obs.tobytes(), seed
        assert ours.terrain_y == [float(y) for y in ref.terrain_y], seed
        assert ours.terrain_x == ref.terrain_x
        assert [c[0] for c in ours.cloud_poly] == [c[0] for c in ref.cloud_poly]
        assert len(ours.terrain) == len(ref.terrain)
        kinds.add(len(ours.obstacles) > 0)
    assert kinds == ({True} if hardcore else {False})


def _move_walker(env: Any, dx: float, dy: float) -> None:
    for body in [env.hull, *env.legs]:
        body.position = (body.position.x + dx, body.position.y + dy)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_parity_at_the_hardcore_obstacles(seed: int) -> None:
    ours = palaestra.make("BipedalWalkerHardcore-v3")
    ref = gymnasium.make("BipedalWalkerHardcore-v3")
    ours.reset(seed=seed)
    ref.reset(seed=seed)
    env = ours.unwrapped
    first_x = min(p[0] for p in env.obstacles[0])
    i = int(first_x / (14 / 30.0))
    dx = first_x - 1.2 - env.hull.position.x
    dy = env.terrain_y[i - 3] - env.terrain_y[0] + 0.05
    _move_walker(env, dx, dy)
    _move_walker(ref.unwrapped, dx, dy)
    rng = np.random.default_rng(seed)
    for t in range(200):
        _, _, done = _check_step(ours, ref, walker_action(rng, t), f"seed {seed} step {t}")
        if done:
            break
