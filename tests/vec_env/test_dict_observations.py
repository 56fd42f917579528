"""Episode ends with Dict observations holding non-Box parts (regression: a Discrete inside a
Dict could not be split into rows at autoreset)."""

import numpy as np

import palaestra as gym
from palaestra import spaces
from palaestra.vec_env import DummyVecEnv


class TwoStepDict(gym.Env):
    def __init__(self) -> None:
        self.observation_space = spaces.Dict(
            {"a": spaces.Discrete(3), "b": spaces.Box(-1, 1, (2,)), "c": spaces.Text(4)}
        )
        self.action_space = spaces.Discrete(2)
        self.t = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return {"a": 0, "b": np.zeros(2, np.float32), "c": "r"}, {}

    def step(self, action):
        self.t += 1
        obs = {"a": 2, "b": np.full(2, 0.5 * self.t, np.float32), "c": f"t{self.t}"}
        return obs, 1.0, self.t >= 2, False, {}


def test_terminal_observation_is_the_single_dict_observation() -> None:
    envs = DummyVecEnv([TwoStepDict, TwoStepDict])
    envs.reset()
    envs.step(np.array([0, 1]))
    obs, _, dones, infos = envs.step(np.array([0, 1]))
    assert dones.tolist() == [True, True]
    final = infos[1]["terminal_observation"]
    assert final["a"] == 2 and final["c"] == "t2"
    np.testing.assert_array_equal(final["b"], [1.0, 1.0])
    assert obs["a"].tolist() == [0, 0] and obs["c"] == ("r", "r")


def test_same_step_final_obs_on_the_gymnasium_face() -> None:
    envs = gym.vector.SyncVectorEnv(
        [TwoStepDict, TwoStepDict], autoreset_mode=gym.vector.AutoresetMode.SAME_STEP
    )
    envs.reset(seed=0)
    envs.step(np.array([0, 1]))
    _, _, terminated, _, infos = envs.step(np.array([0, 1]))
    assert terminated.tolist() == [True, True]
    assert [o["a"] for o in infos["final_obs"]] == [2, 2]
    assert [o["c"] for o in infos["final_obs"]] == ["t2", "t2"]
