"""Built-in environments, registered under Gymnasium's ids."""

from palaestra.envs.atari.games import atari_specs
from palaestra.envs.registration import make, pprint_registry, register, registry, spec

__all__ = ["make", "pprint_registry", "register", "registry", "spec"]

# Classic control: Gymnasium 1.x's ids, entry-point class names, limits and thresholds. The
# modules are imported only when make() loads an entry point. Each id's vector entry point is
# its native batch (``classic_control.*Batch``): make_vec runs it behind the vector API
# (palaestra.vector.native), which adds autoreset and time limits on top of it.
_CC = "palaestra.envs.classic_control"
_CLASSIC_CONTROL: dict[str, dict] = {
    "CartPole-v0": dict(
        vector_entry_point=f"{_CC}.cartpole:CartPoleBatch",
        entry_point=f"{_CC}.cartpole:CartPoleEnv",
        max_episode_steps=200,
        reward_threshold=195.0,
    ),
    "CartPole-v1": dict(
        vector_entry_point=f"{_CC}.cartpole:CartPoleBatch",
        entry_point=f"{_CC}.cartpole:CartPoleEnv",
        max_episode_steps=500,
        reward_threshold=475.0,
    ),
    "MountainCar-v0": dict(
        vector_entry_point=f"{_CC}.mountain_car:MountainCarBatch",
        entry_point=f"{_CC}.mountain_car:MountainCarEnv",
        max_episode_steps=200,
        reward_threshold=-110.0,
    ),
    "MountainCarContinuous-v0": dict(
        vector_entry_point=f"{_CC}.continuous_mountain_car:ContinuousMountainCarBatch",
        entry_point=f"{_CC}.continuous_mountain_car:Continuous_MountainCarEnv",
        max_episode_steps=999,
        reward_threshold=90.0,
    ),
    "Pendulum-v1": dict(
        vector_entry_point=f"{_CC}.pendulum:PendulumBatch",
        entry_point=f"{_CC}.pendulum:PendulumEnv",
        max_episode_steps=200,
    ),
    "Acrobot-v1": dict(
        vector_entry_point=f"{_CC}.acrobot:AcrobotBatch",
        entry_point=f"{_CC}.acrobot:AcrobotEnv",
        max_episode_steps=500,
        reward_threshold=-100.0,
    ),
}
for _id, _kwargs in _CLASSIC_CONTROL.items():
    if _id not in registry:  # importing this module twice (pytest's importlib mode) is harmless
        register(id=_id, **_kwargs)

# Box2D (on the optional box2d package, imported when one of these envs is made): Gymnasium
# 1.4.0's ids, kwargs, limits and thresholds.
_B2 = "palaestra.envs.box2d"
_BOX2D: dict[str, dict] = {
    "LunarLander-v3": dict(
        entry_point=f"{_B2}.lunar_lander:LunarLander",
        max_episode_steps=1000,
        reward_threshold=200,
    ),
    "LunarLanderContinuous-v3": dict(
        entry_point=f"{_B2}.lunar_lander:LunarLander",
        kwargs={"continuous": True},
        max_episode_steps=1000,
        reward_threshold=200,
    ),
    "BipedalWalker-v3": dict(
        entry_point=f"{_B2}.bipedal_walker:BipedalWalker",
        max_episode_steps=1600,
        reward_threshold=300,
    ),
    "BipedalWalkerHardcore-v3": dict(
        entry_point=f"{_B2}.bipedal_walker:BipedalWalker",
        kwargs={"hardcore": True},
        max_episode_steps=2000,
        reward_threshold=300,
    ),
    "CarRacing-v3": dict(
        entry_point=f"{_B2}.car_racing:CarRacing",
        max_episode_steps=1000,
        reward_threshold=900,
    ),
}
for _id, _kwargs in _BOX2D.items():
    if _id not in registry:
        register(id=_id, **_kwargs)

# MuJoCo (on the optional mujoco package, imported when one of these envs is made): Gymnasium
# 1.4.0's v5 ids, limits and thresholds. Only v5 is registered: making a v2-v4 id raises
# DeprecatedEnv naming v5 (their models and rewards differ; they are not aliases of v5).
_MJ = "palaestra.envs.mujoco"
_MUJOCO: dict[str, dict] = {
    "Reacher-v5": dict(
        entry_point=f"{_MJ}.fixed_base:ReacherEnv", max_episode_steps=50, reward_threshold=-3.75
    ),
    "Pusher-v5": dict(
        entry_point=f"{_MJ}.fixed_base:PusherEnv", max_episode_steps=100, reward_threshold=0.0
    ),
    "InvertedPendulum-v5": dict(
        entry_point=f"{_MJ}.fixed_base:InvertedPendulumEnv",
        max_episode_steps=1000,
        reward_threshold=950.0,
    ),
    "InvertedDoublePendulum-v5": dict(
        entry_point=f"{_MJ}.fixed_base:InvertedDoublePendulumEnv",
        max_episode_steps=1000,
        reward_threshold=9100.0,
    ),
    "HalfCheetah-v5": dict(
        entry_point=f"{_MJ}.locomotion:HalfCheetahEnv",
        max_episode_steps=1000,
        reward_threshold=4800.0,
    ),
    "Hopper-v5": dict(
        entry_point=f"{_MJ}.locomotion:HopperEnv", max_episode_steps=1000, reward_threshold=3800.0
    ),
    "Swimmer-v5": dict(
        entry_point=f"{_MJ}.locomotion:SwimmerEnv", max_episode_steps=1000, reward_threshold=360.0
    ),
    "Walker2d-v5": dict(entry_point=f"{_MJ}.locomotion:Walker2dEnv", max_episode_steps=1000),
    "Ant-v5": dict(
        entry_point=f"{_MJ}.locomotion:AntEnv", max_episode_steps=1000, reward_threshold=6000.0
    ),
    "Humanoid-v5": dict(entry_point=f"{_MJ}.locomotion:HumanoidEnv", max_episode_steps=1000),
    "HumanoidStandup-v5": dict(
        entry_point=f"{_MJ}.locomotion:HumanoidStandupEnv", max_episode_steps=1000
    ),
}
for _id, _kwargs in _MUJOCO.items():
    if _id not in registry:
        # each v5 env's native batch is its class's name with Batch for Env (mujoco/batch.py)
        _batch = _kwargs["entry_point"].rsplit(":", 1)[1].removesuffix("Env") + "Batch"
        register(id=_id, vector_entry_point=f"{_MJ}.batch:{_batch}", **_kwargs)

# Toy text: Gymnasium 1.4's ids, kwargs, limits and thresholds. Older versions (Taxi-v3,
# CliffWalking-v0, FrozenLake-v0, Blackjack-v0) are not registered, as in Gymnasium: making one
# raises DeprecatedEnv naming the current version.
_TT = "palaestra.envs.toy_text"
_TOY_TEXT: dict[str, dict] = {
    "Blackjack-v1": dict(
        vector_entry_point=f"{_TT}.blackjack:BlackjackBatch",
        entry_point=f"{_TT}.blackjack:BlackjackEnv",
        kwargs={"sab": True, "natural": False},
    ),
    "FrozenLake-v1": dict(
        vector_entry_point=f"{_TT}.frozen_lake:FrozenLakeBatch",
        entry_point=f"{_TT}.frozen_lake:FrozenLakeEnv",
        kwargs={"map_name": "4x4"},
        max_episode_steps=100,
        reward_threshold=0.70,  # optimum 0.74
    ),
    "FrozenLake8x8-v1": dict(
        vector_entry_point=f"{_TT}.frozen_lake:FrozenLakeBatch",
        entry_point=f"{_TT}.frozen_lake:FrozenLakeEnv",
        kwargs={"map_name": "8x8"},
        max_episode_steps=200,
        reward_threshold=0.85,  # optimum 0.91
    ),
    "CliffWalking-v1": dict(
        vector_entry_point=f"{_TT}.cliffwalking:CliffWalkingBatch",
        entry_point=f"{_TT}.cliffwalking:CliffWalkingEnv",
    ),
    "CliffWalkingSlippery-v1": dict(
        vector_entry_point=f"{_TT}.cliffwalking:CliffWalkingBatch",
        entry_point=f"{_TT}.cliffwalking:CliffWalkingEnv",
        kwargs={"is_slippery": True},
    ),
    "Taxi-v4": dict(
        vector_entry_point=f"{_TT}.taxi:TaxiBatch",
        entry_point=f"{_TT}.taxi:TaxiEnv",
        max_episode_steps=200,
        reward_threshold=8,  # optimum 8.46
    ),
}
for _id, _kwargs in _TOY_TEXT.items():
    if _id not in registry:
        register(id=_id, **_kwargs)

# Goal envs (palaestra's own ids; SB3's test env, which HER learns on): see envs.goal.
_GOAL = "palaestra.envs.goal.bit_flipping:BitFlippingEnv"
_GOAL_ENVS: dict[str, dict] = {
    "BitFlipping-v0": dict(entry_point=_GOAL, kwargs={"render_mode": None}),
    "BitFlippingContinuous-v0": dict(
        entry_point=_GOAL, kwargs={"continuous": True, "render_mode": None}
    ),
    "BitFlipping15-v0": dict(entry_point=_GOAL, kwargs={"n_bits": 15, "render_mode": None}),
}
for _id, _kwargs in _GOAL_ENVS.items():
    if _id not in registry:
        register(id=_id, **_kwargs)

# Atari: every id ale-py registers for v5, plus the NoFrameskip-v4 ids of SB3/RL-Zoo pipelines,
# from a static game list so that this import does not load ale-py.
for _id, _kwargs in atari_specs().items():
    if _id not in registry:
        register(id=_id, **_kwargs)
