"""LunarLander against the installed Gymnasium 1.4: identical observation bytes, rewards, flags.

Both envs are made through ``make`` with the same kwargs, reset with the same seeds and
stepped with the same actions; every step's observation must have the same bytes and the
reward the same float (no tolerance: the Box2D calls and the float operations are the same).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.envs.box2d.cases import LUNAR_VARIANTS, policy_for

import palaestra

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("Box2D")


def run_both(
    env_id: str, kwargs: dict[str, Any], seed: int, steps: int, explore: float = 0.15
) -> dict[str, int]:
    """Step both libraries in lockstep for ``steps``; count how episodes ended.

    Actions come from the landing controller, replaced by random ones with probability
    ``explore`` (1.0: random play, which mostly crashes).
    """
    ours = palaestra.make(env_id, **kwargs)
    ref = gymnasium.make(env_id, **kwargs)
    obs, info = ours.reset(seed=seed)
    ref_obs, ref_info = ref.reset(seed=seed)
    assert obs.dtype == np.float32 and obs.tobytes() == ref_obs.tobytes()
    assert info == ref_info == {}
    rng = np.random.default_rng(seed + 1000)
    policy = policy_for(ours)
    endings = {"crash": 0, "rest": 0, "truncated": 0, "contacts": 0}
    for t in range(steps):
        action = policy(rng, obs, explore)
        obs, reward, term, trunc, info = ours.step(action)
        ref_obs, ref_reward, ref_term, ref_trunc, ref_info = ref.step(action)
        where = f"{env_id} {kwargs} seed {seed} step {t}"
        assert obs.tobytes() == ref_obs.tobytes(), f"{where}: {obs} != {ref_obs}"
        assert reward == float(ref_reward), f"{where}: {reward!r} != {ref_reward!r}"
        assert type(reward) is float
        assert (term, trunc) == (ref_term, ref_trunc), where
        assert info == ref_info == {}
        endings["contacts"] += bool(obs[6] or obs[7])
        if term or trunc:
            if term:
                endings["rest" if reward == 100 else "crash"] += 1
            else:
                endings["truncated"] += 1
            # Alternate continuing the generator and reseeding.
            kw: dict[str, Any] = {} if t % 2 else {"seed": seed + t}
            obs, _ = ours.reset(**kw)
            ref_obs, _ = ref.reset(**kw)
            assert obs.tobytes() == ref_obs.tobytes(), f"{where}: reset {kw}"
    ours.close()
    ref.close()
    return endings


@pytest.mark.parametrize("env_id, kwargs", LUNAR_VARIANTS)
def test_short_parity(env_id: str, kwargs: dict[str, Any]) -> None:
    run_both(env_id, kwargs, seed=5, steps=150)


@pytest.mark.slow
@pytest.mark.parametrize("env_id, kwargs", LUNAR_VARIANTS)
def test_long_parity(env_id: str, kwargs: dict[str, Any]) -> None:
    """1500 steps from each of 3 seeds, resets included; the runs must land and crash."""
    total: dict[str, int] = {}
    for seed, explore in ((0, 0.1), (1, 0.3), (2, 1.0)):
        for key, n in run_both(env_id, kwargs, seed, 1500, explore).items():
            total[key] = total.get(key, 0) + n
    assert total["crash"] > 0 and total["contacts"] > 0, total
    if kwargs.get("gravity", -10.0) < -5:  # weak gravity floats too long to settle
        assert total["rest"] > 0, total


def test_parity_with_rendering_every_step() -> None:
    """Rendered at every step (a video, a window) the exhaust is Gymnasium's, puff for puff."""
    ours = palaestra.make("LunarLander-v3", render_mode="rgb_array")
    ref = gymnasium.make("LunarLander-v3", render_mode="rgb_array")
    obs, _ = ours.reset(seed=3)
    ref.reset(seed=3)
    rng = np.random.default_rng(3)
    policy = policy_for(ours)
    most = 0
    for t in range(150):
        action = policy(rng, obs, 0.3)
        obs, reward, term, _, _ = ours.step(action)
        ref_obs, ref_reward, ref_term, _, _ = ref.step(action)
        assert obs.tobytes() == ref_obs.tobytes(), t
        assert reward == float(ref_reward) and term == ref_term
        ours.render()
        ref.render()
        sparks = [(p.position.x, p.position.y, p.ttl) for p in ours.unwrapped.particles]
        ref_sparks = [(p.position.x, p.position.y, p.ttl) for p in ref.unwrapped.particles]
        assert sparks == ref_sparks, t
        most = max(most, len(sparks))
        if term:
            break
    assert most > 3


def test_unrendered_exhaust_does_not_pile_up() -> None:
    """An rgb_array env that is never rendered (SB3's make_vec_env asks for rgb_array) ages its
    exhaust per step: a long controlled flight keeps a few puffs where Gymnasium keeps every
    puff of the episode as a Box2D body, and the lander moves bit for bit the same."""
    ours = palaestra.make("LunarLander-v3", render_mode="rgb_array")
    ref = gymnasium.make("LunarLander-v3", render_mode="rgb_array")
    obs, _ = ours.reset(seed=1)
    ref.reset(seed=1)
    rng = np.random.default_rng(1)
    policy = policy_for(ours)
    ours_most = ref_most = 0
    for t in range(400):
        action = policy(rng, obs, 0.1)
        obs, reward, term, trunc, _ = ours.step(action)
        ref_obs, ref_reward, ref_term, ref_trunc, _ = ref.step(action)
        assert obs.tobytes() == ref_obs.tobytes(), t
        assert reward == float(ref_reward) and (term, trunc) == (ref_term, ref_trunc)
        ours_most = max(ours_most, len(ours.unwrapped.particles))
        ref_most = max(ref_most, len(ref.unwrapped.particles))
        if term or trunc:
            break
    # A puff lives at most 1.0 / 0.15 steps and each step makes at most two.
    assert 0 < ours_most <= 14 and ref_most > 50, (ours_most, ref_most, t)
