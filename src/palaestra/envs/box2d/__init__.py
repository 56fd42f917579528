"""The Box2D environments (LunarLander, BipedalWalker, CarRacing), on the ``box2d`` package.

Each env builds its world with the same Box2D calls, in the same order, as Gymnasium 1.4.0's,
and draws its random numbers from ``np_random`` in the same order, so the same seed and
actions give the same states and rewards bit for bit. CarRacing's observation is a drawn
frame (:mod:`palaestra.rendering.car_racing`), ~99.5% of whose pixels equal Gymnasium's.
``Box2D`` is imported when an env is constructed, never by ``import palaestra``; without it
the constructor raises ``DependencyNotInstalled`` naming ``pip install "palaestra[box2d]"``.
Each env pickles and deep-copies to an env that continues the same trajectory
(:class:`~palaestra.envs.box2d._common.ReplayCopies`). The classes are exported here under
Gymnasium's names (``from palaestra.envs.box2d import LunarLander``).
"""

from palaestra.envs.box2d.bipedal_walker import BipedalWalker, BipedalWalkerHardcore
from palaestra.envs.box2d.car_racing import CarRacing
from palaestra.envs.box2d.lunar_lander import LunarLander, LunarLanderContinuous

__all__ = [
    "BipedalWalker",
    "BipedalWalkerHardcore",
    "CarRacing",
    "LunarLander",
    "LunarLanderContinuous",
]
