"""Observation and action spaces with Gymnasium 1.x semantics (reprs, seeding, sampling).

>>> from palaestra import spaces
>>> spaces.Discrete(3), spaces.Box(0, 1, shape=(2,))
(Discrete(3), Box(0.0, 1.0, (2,), float32))
"""

from palaestra.spaces.box import Box
from palaestra.spaces.dict import Dict
from palaestra.spaces.discrete import Discrete
from palaestra.spaces.graph import Graph, GraphInstance
from palaestra.spaces.multi_binary import MultiBinary
from palaestra.spaces.multi_discrete import MultiDiscrete
from palaestra.spaces.oneof import OneOf
from palaestra.spaces.sequence import Sequence
from palaestra.spaces.space import InvalidMask, InvalidProbabilityMask, Space
from palaestra.spaces.text import Text
from palaestra.spaces.tuple import Tuple
from palaestra.spaces.utils import flatdim, flatten, flatten_space, unflatten

__all__ = [
    "Box",
    "Dict",
    "Discrete",
    "Graph",
    "GraphInstance",
    "InvalidMask",
    "InvalidProbabilityMask",
    "MultiBinary",
    "MultiDiscrete",
    "OneOf",
    "Sequence",
    "Space",
    "Text",
    "Tuple",
    "flatdim",
    "flatten",
    "flatten_space",
    "unflatten",
]
