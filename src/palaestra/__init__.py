"""palaestra: Gymnasium's environment API, classic-control and Atari envs, and SB3-style agents."""

from palaestra.core import ActionWrapper, Env, ObservationWrapper, RewardWrapper, Wrapper

__version__ = "0.1.0"
__all__ = ["ActionWrapper", "Env", "ObservationWrapper", "RewardWrapper", "Wrapper"]
