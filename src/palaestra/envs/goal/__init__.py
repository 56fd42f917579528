"""Goal-conditioned environments: observations are dicts of ``observation``, ``achieved_goal``
and ``desired_goal``, and the env's ``compute_reward(achieved_goal, desired_goal, info)``
recomputes rewards for any goal, batched (what Hindsight Experience Replay relabels with:
``palaestra.algos.her``).

Registered ids (``palaestra.make(id, n_bits=..., ...)`` overrides any keyword):

- ``BitFlipping-v0``: :class:`BitFlippingEnv` with discrete actions (flip bit ``a``) and
  ``MultiBinary`` observations, ``n_bits=10``;
- ``BitFlippingContinuous-v0``: the same with ``Box(-1, 1, (n_bits,))`` actions (bit ``i``
  flips where ``action[i] > 0``);
- ``BitFlipping15-v0``: ``BitFlipping-v0`` with ``n_bits=15`` (the size on which HER+DQN
  learns and plain DQN does not: the ``her`` preset of ``palaestra train dqn``).

Each episode lasts at most ``max_steps`` (default ``n_bits``) steps: the env truncates
itself, as SB3's does, so no ``TimeLimit`` is added.
"""

from palaestra.envs.goal.bit_flipping import BitFlippingEnv

__all__ = ["BitFlippingEnv"]
