"""Observation and action spaces with Gymnasium 1.x semantics (reprs, seeding, sampling).

>>> from palaestra import spaces
>>> spaces.Discrete(3), spaces.Box(0, 1, shape=(2,))
(Discrete(3), Box(0.0, 1.0, (2,), float32))
"""

from palaestra.spaces.box import Box
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space

__all__ = ["Box", "Discrete", "InvalidMask", "InvalidProbabilityMask", "Space"]
