"""The Box2D environments (LunarLander, BipedalWalker, CarRacing), on the ``box2d`` package.

Each env builds its world with the same Box2D calls, in the same order, as Gymnasium 1.4.0's,
and draws its random numbers from ``np_random`` in the same order, so the same seed and
actions give the same states and rewards bit for bit. CarRacing's observation is a drawn
frame (:mod:`palaestra.rendering.car_racing`), ~99.5% of whose pixels equal Gymnasium's.
``Box2D`` is imported when an env is constructed, never by ``import palaestra``; without it
the constructor raises ``DependencyNotInstalled`` naming ``pip install "palaestra[box2d]"``.
"""
