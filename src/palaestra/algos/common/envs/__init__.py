"""SB3's test environments (``stable_baselines3.common.envs``): tiny envs with a known answer,
for checking that an algorithm learns at all and that every space type goes through it.
Same constructors, spaces, rewards, episode lengths and random draws as SB3's."""

from palaestra.algos.common.envs.bit_flipping_env import BitFlippingEnv
from palaestra.algos.common.envs.identity_env import (
    FakeImageEnv,
    IdentityEnv,
    IdentityEnvBox,
    IdentityEnvMultiBinary,
    IdentityEnvMultiDiscrete,
)
from palaestra.algos.common.envs.multi_input_envs import SimpleMultiObsEnv

__all__ = [
    "BitFlippingEnv",
    "FakeImageEnv",
    "IdentityEnv",
    "IdentityEnvBox",
    "IdentityEnvMultiBinary",
    "IdentityEnvMultiDiscrete",
    "SimpleMultiObsEnv",
]
