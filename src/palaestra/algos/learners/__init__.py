"""Learners: each network, action head and loss written once (over an array namespace) and run
by torch with autograd or by numpy with hand-written vector-Jacobian products.

- ``xp``: the numpy and torch namespaces the functions are written in;
- ``mlp``: the one reader of torch module trees, ``mlp_forward`` and its VJP;
- ``heads``: action distributions (log-prob, entropy, sampling) and their VJPs;
- ``losses``: the DQN and PPO losses and their VJPs, GAE, explained variance, polyak;
- ``adam``: Adam on a flat numpy buffer;
- ``objectives``: each algorithm's update in the learners' terms;
- ``learner``: the two learners and ``build_learner``, which picks one and says why.
"""

from palaestra.algos.learners.learner import (
    BACKENDS,
    Group,
    Learner,
    Net,
    NumpyLearner,
    TorchLearner,
    build_learner,
)

__all__ = ["BACKENDS", "Group", "Learner", "Net", "NumpyLearner", "TorchLearner", "build_learner"]
