"""Built-in environments, registered under Gymnasium's ids."""

from palaestra.envs.registration import make, pprint_registry, register, registry, spec

__all__ = ["make", "pprint_registry", "register", "registry", "spec"]

# Classic control: Gymnasium 1.x's ids, entry-point class names, limits and thresholds. The
# modules are imported only when make() loads an entry point. The native batched engines
# (``*Batch``) get their vector entry points with the vector API, which adds autoreset and
# time limits on top of them.
_CLASSIC = "palaestra.envs.classic_control"
register(
    id="CartPole-v0",
    entry_point=f"{_CLASSIC}.cartpole:CartPoleEnv",
    max_episode_steps=200,
    reward_threshold=195.0,
)
register(
    id="CartPole-v1",
    entry_point=f"{_CLASSIC}.cartpole:CartPoleEnv",
    max_episode_steps=500,
    reward_threshold=475.0,
)
register(
    id="MountainCar-v0",
    entry_point=f"{_CLASSIC}.mountain_car:MountainCarEnv",
    max_episode_steps=200,
    reward_threshold=-110.0,
)
register(
    id="MountainCarContinuous-v0",
    entry_point=f"{_CLASSIC}.continuous_mountain_car:Continuous_MountainCarEnv",
    max_episode_steps=999,
    reward_threshold=90.0,
)
register(
    id="Pendulum-v1",
    entry_point=f"{_CLASSIC}.pendulum:PendulumEnv",
    max_episode_steps=200,
)
register(
    id="Acrobot-v1",
    entry_point=f"{_CLASSIC}.acrobot:AcrobotEnv",
    reward_threshold=-100.0,
    max_episode_steps=500,
)
