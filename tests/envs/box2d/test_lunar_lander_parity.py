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


def test_parity_with_rendering() -> None:
    """Exhaust particles are Box2D bodies while rendering; they must not move the lander."""
    ours = palaestra.make("LunarLander-v3", render_mode="rgb_array")
    ref = gymnasium.make("LunarLander-v3", render_mode="rgb_array")
    obs, _ = ours.reset(seed=3)
    ref.reset(seed=3)
    rng = np.random.default_rng(3)
    for t in range(120):
        action = int(rng.integers(4))
        obs, reward, term, _, _ = ours.step(action)
        ref_obs, ref_reward, ref_term, _, _ = ref.step(action)
        assert obs.tobytes() == ref_obs.tobytes(), t
        assert reward == float(ref_reward) and term == ref_term
        if t % 5 == 0:
            ours.render()
            ref.render()
        if term:
            break
    assert len(ours.unwrapped.particles) == len(ref.unwrapped.particles) > 0
