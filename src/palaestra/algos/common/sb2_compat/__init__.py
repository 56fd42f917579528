"""What SB3 keeps for reproducing Stable-Baselines (SB2) results: ``RMSpropTFLike``."""

from palaestra.algos.common.sb2_compat.rmsprop_tf_like import RMSpropTFLike

__all__ = ["RMSpropTFLike"]
