"""The tutorial's environment, space and wrapper blocks, with only the import lines changed.

Each block is run verbatim (import lines swapped) under palaestra and, where it prints, under
gymnasium too: the printed lines must be identical. Blocks are kept as the tutorial writes
them, so a behaviour change that breaks the tutorial breaks this file.
"""

from __future__ import annotations

import contextlib
import io
import textwrap

import numpy as np
import pytest

PALAESTRA = {"import gymnasium as gym": "import palaestra as gym",
             "from gymnasium import spaces": "from palaestra import spaces"}  # fmt: skip


def run_block(code: str, library: str, namespace: dict | None = None) -> tuple[str, dict]:
    """Exec a tutorial block under ``library`` ("palaestra" or "gymnasium"); return stdout."""
    code = textwrap.dedent(code)
    if library == "palaestra":
        for ref, ours in PALAESTRA.items():
            code = code.replace(ref, ours)
    ns: dict = {} if namespace is None else namespace
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, f"<tutorial:{library}>", "exec"), ns)
    return out.getvalue(), ns


SPACES_BLOCK = """
import gymnasium as gym
env = gym.make('MountainCar-v0')
obs_space = env.observation_space
action_space = env.action_space
print("The observation space: {}".format(obs_space))
print("The action space: {}".format(action_space))
"""

BOUNDS_BLOCK = """
import gymnasium as gym
env = gym.make('MountainCar-v0')
print("Upper Bound for Env Observation:", env.observation_space.high)
print("Lower Bound for Env Observation:", env.observation_space.low)
"""

STEP_BLOCK = """
import gymnasium as gym
env = gym.make('MountainCar-v0')
# (seeded here, and the action space below, so both libraries print the same numbers)
env.action_space.seed(0)
# Reset the environment and see the initial observation
obs, info = env.reset(seed=0)
print("The initial observation is {}".format(obs))
# Sample a random action from the entire action space
random_action = env.action_space.sample()
# Take the action and get the new observation
new_obs, reward, terminated, truncated, info = env.step(random_action)
print("The new observation is {}".format(new_obs))
"""

ROBOT_ARM_BLOCK = """
from gymnasium import spaces
import numpy as np
# 3 joints, each can rotate from -180 to 180 degrees
action_space = spaces.Box(
    low=np.array([-180, -180, -180]),
    high=np.array([180, 180, 180]),
    dtype=np.float32
)
print(action_space)
"""

WRAPPER_CLASSES = """
import gymnasium as gym
import numpy as np

class SimplifiedActionWrapper(gym.ActionWrapper):
    def __init__(self, env):
        super().__init__(env)
        self.action_space = gym.spaces.Discrete(2)

    def action(self, action):
        if action == 0:
            return 0  # Push left
        else:
            return 2  # Push right

class NaiveRewardShaping(gym.RewardWrapper):
    def __init__(self, env):
        super().__init__(env)

    def reward(self, reward):
        position = self.env.unwrapped.state[0]
        height_bonus = (position + 1.2) * 0.5
        return reward + height_bonus

class BetterRewardShaping(gym.RewardWrapper):
    def __init__(self, env):
        super().__init__(env)
        self.best_position = -1.2  # Track the rightmost position reached

    def reset(self, **kwargs):
        self.best_position = -1.2
        return self.env.reset(**kwargs)

    def reward(self, reward):
        position = self.env.unwrapped.state[0]
        if position > self.best_position:
            bonus = (position - self.best_position) * 10
            self.best_position = position
            return reward + bonus
        return reward
"""

WRAPPER_TEST_BLOCK = """
env = gym.make('MountainCar-v0')
wrapped_env = SimplifiedActionWrapper(env)
print("Original action space:", env.action_space)
print("Wrapped action space:", wrapped_env.action_space)
obs, info = wrapped_env.reset()
obs, reward, terminated, truncated, info = wrapped_env.step(0)
print("Action 0 (left) executed successfully")
"""

STACKED_BLOCK = """
import gymnasium as gym
env = gym.make('MountainCar-v0')
wrapped_env = SimplifiedActionWrapper(env)
wrapped_env = BetterRewardShaping(wrapped_env)
print("Final action space:", wrapped_env.action_space)
print("Original environment preserved:", wrapped_env.unwrapped)
"""


@pytest.mark.parametrize("block", [SPACES_BLOCK, BOUNDS_BLOCK, STEP_BLOCK, ROBOT_ARM_BLOCK])
def test_block_prints_what_gymnasium_prints(block: str) -> None:
    ours, _ = run_block(block, "palaestra")
    ref, _ = run_block(block, "gymnasium")
    assert ours == ref


def test_spaces_block_prints_the_tutorials_text() -> None:
    ours, _ = run_block(SPACES_BLOCK, "palaestra")
    assert ours.splitlines() == [
        "The observation space: Box([-1.2  -0.07], [0.6  0.07], (2,), float32)",
        "The action space: Discrete(3)",
    ]


def test_space_type_is_palaestras_box() -> None:
    _, ns = run_block("import gymnasium as gym\nenv = gym.make('MountainCar-v0')", "palaestra")
    space = ns["env"].observation_space
    assert type(space).__module__ == "palaestra.spaces.box" and type(space).__name__ == "Box"


def test_step_2_works_and_step_4_raises_naming_action_and_space() -> None:
    import palaestra as gym

    env = gym.make("MountainCar-v0")
    env.reset(seed=0)
    env.step(2)  # Works fine
    with pytest.raises(gym.error.InvalidAction) as excinfo:
        env.step(4)  # Raises an error - 4 is not in [0, 1, 2]
    assert "4" in str(excinfo.value) and "Discrete(3)" in str(excinfo.value)


@pytest.mark.parametrize("library", ["palaestra", "gymnasium"])
def test_wrapper_blocks(library: str) -> None:
    _, ns = run_block(WRAPPER_CLASSES, library)
    out, _ = run_block(WRAPPER_TEST_BLOCK, library, ns)
    assert out.splitlines() == [
        "Original action space: Discrete(3)",
        "Wrapped action space: Discrete(2)",
        "Action 0 (left) executed successfully",
    ]
    out, _ = run_block(STACKED_BLOCK, library, ns)
    assert out.splitlines() == [
        "Final action space: Discrete(2)",
        "Original environment preserved: <MountainCarEnv<MountainCar-v0>>",
    ]


def test_reward_shaping_wrappers_give_gymnasiums_rewards() -> None:
    """Same seed and actions: the tutorial's shaped rewards agree with Gymnasium's exactly."""
    rewards = {}
    for library in ["palaestra", "gymnasium"]:
        _, ns = run_block(WRAPPER_CLASSES, library)
        gym = ns["gym"]
        actions = np.random.default_rng(0).integers(0, 2, 400)
        for shaping in ["NaiveRewardShaping", "BetterRewardShaping"]:
            env = ns[shaping](ns["SimplifiedActionWrapper"](gym.make("MountainCar-v0")))
            env.reset(seed=3)
            seq = []
            for a in actions:
                _, r, terminated, truncated, _ = env.step(int(a))
                seq.append(r)
                if terminated or truncated:
                    env.reset()
            rewards[library, shaping] = seq
    for shaping in ["NaiveRewardShaping", "BetterRewardShaping"]:
        assert rewards["palaestra", shaping] == rewards["gymnasium", shaping]
    assert max(rewards["palaestra", "BetterRewardShaping"]) > -1.0  # the bonus did fire
