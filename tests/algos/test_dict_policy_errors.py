"""Dict observations meet SB3's construction-time errors (issue 16, item 15): ``MlpPolicy`` or
``CnnPolicy`` on a Dict space is a ``ValueError`` naming ``MultiInputPolicy``, and a nested
Dict/Tuple space is SB3's ``NotImplementedError``, both side by side with the installed SB3."""

from __future__ import annotations

from typing import Any

import pytest

from palaestra import algos, spaces
from palaestra.core import Env

from .toys import Toy

sb3 = pytest.importorskip("stable_baselines3")
compat = pytest.importorskip("palaestra.compat")

ALGOS = {"DQN": "discrete", "PPO": "discrete", "A2C": "discrete"}
ALGOS.update(SAC="box", TD3="box", DDPG="box")
SMALL = {"buffer_size": 100}


class Nested(Env[Any, Any]):
    """A Dict observation holding a Dict (SB3 and palaestra refuse it at construction)."""

    def __init__(self, action: str = "discrete") -> None:
        inner = spaces.Dict({"pos": spaces.Box(-1, 1, (2,))})
        self.observation_space = spaces.Dict({"inner": inner, "vec": spaces.Box(-1, 1, (2,))})
        self.action_space = Toy(action=action).action_space

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> Any:
        return self.observation_space.sample(), 0.0, False, False, {}


def _kwargs(name: str) -> dict[str, Any]:
    return SMALL if name not in ("PPO", "A2C") else {}


@pytest.mark.parametrize("name", sorted(ALGOS))
@pytest.mark.parametrize("policy", ["MlpPolicy", "CnnPolicy"])
def test_mlp_or_cnn_policy_on_dict_is_refused_as_sb3(name: str, policy: str) -> None:
    action = ALGOS[name]
    message = (
        f"You must use `MultiInputPolicy` when working with dict observation space, not {policy}"
    )
    with pytest.raises(ValueError) as ours:
        getattr(algos, name)(policy, Toy("dict", action), **_kwargs(name))
    with pytest.raises(ValueError) as theirs:
        getattr(sb3, name)(policy, compat.to_gymnasium(Toy("dict", action)), **_kwargs(name))
    assert str(ours.value) == str(theirs.value) == message
    # the right policy builds
    getattr(algos, name)("MultiInputPolicy", Toy("dict", action), **_kwargs(name))


@pytest.mark.parametrize("name", sorted(ALGOS))
def test_nested_dict_is_refused_at_construction_as_sb3(name: str) -> None:
    action = ALGOS[name]
    with pytest.raises(NotImplementedError, match="Nested observation spaces are not supported"):
        getattr(algos, name)("MultiInputPolicy", Nested(action), **_kwargs(name))
    with pytest.raises(NotImplementedError, match="Nested observation spaces are not supported"):
        getattr(sb3, name)("MultiInputPolicy", compat.to_gymnasium(Nested(action)), **_kwargs(name))
