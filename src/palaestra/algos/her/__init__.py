"""Hindsight Experience Replay (Andrychowicz et al. 2017) as SB3 offers it: a replay buffer
for goal-conditioned Dict envs that relabels sampled transitions with goals achieved later,
for DQN, SAC, TD3 and DDPG::

    from palaestra.algos import DQN
    from palaestra.algos.her import HerReplayBuffer

    model = DQN("MultiInputPolicy", "BitFlipping15-v0", replay_buffer_class=HerReplayBuffer,
                replay_buffer_kwargs=dict(n_sampled_goal=4, goal_selection_strategy="future"))
"""

from palaestra.algos.her.goal_selection_strategy import KEY_TO_GOAL_STRATEGY, GoalSelectionStrategy
from palaestra.algos.her.her_replay_buffer import HerReplayBuffer

__all__ = ["KEY_TO_GOAL_STRATEGY", "GoalSelectionStrategy", "HerReplayBuffer"]
