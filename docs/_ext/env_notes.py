"""The gallery's prose: each family's introduction, and per env what it is, its rewards, when an
episode ends and its version history. Spaces, limits and thresholds are not written here: the
gallery reads them from the live environment when the site is built.
"""

from __future__ import annotations

import re

FAMILIES: dict[str, dict[str, str]] = {
    "classic_control": {
        "title": "Classic control",
        "intro": """
The five classic-control problems, with Gymnasium 1.4's dynamics, bit for bit for the same
seed and actions. They need nothing beyond numpy, and `palaestra.make_vec(id, num_envs=N)`
steps N of them as one numpy batch (the native batch, see {doc}`/guides/vector-envs`).
""",
    },
    "toy_text": {
        "title": "Toy text",
        "intro": """
Small grid and card games with discrete observations, Gymnasium 1.4's rules and transition
tables `P` (`env.unwrapped.P`), drawn with palaestra's numpy rasterizer (no pygame). They batch
natively as the classic-control envs do.
""",
    },
    "box2d": {
        "title": "Box2D",
        "intro": """
Three physics tasks on the Box2D engine: `pip install "palaestra[box2d]"`. palaestra's code
makes the same Box2D calls as Gymnasium 1.4's, so the same seed and actions give the same
states, rewards and flags. See {doc}`/guides/box2d`.
""",
    },
    "mujoco": {
        "title": "MuJoCo",
        "intro": """
Gymnasium's eleven v5 robots on the MuJoCo physics engine: `pip install "palaestra[mujoco]"`.
The models are palaestra's own MJCF files that compile to the same `MjModel` as Gymnasium's.
Rendering uses MuJoCo's OpenGL renderer; headless, set `MUJOCO_GL=egl` (these animations were
rendered that way). The v2, v3 and v4 ids raise `palaestra.error.DeprecatedEnv` naming v5. See
{doc}`/guides/mujoco`.
""",
    },
    "goal": {
        "title": "Goal environments",
        "intro": """
Stable-Baselines3's bit-flipping environment: Dict observations with `observation`,
`achieved_goal` and `desired_goal`, and a `compute_reward(achieved_goal, desired_goal, info)`
method, which is what Hindsight Experience Replay (`HerReplayBuffer`) needs.
""",
    },
    "atari": {
        "title": "Atari",
        "intro": """
Every Atari 2600 game that ale-py ships, under two ids each: `ALE/<Game>-v5` and
`<Game>NoFrameskip-v4`. `pip install "palaestra[atari]"` installs ale-py, whose wheel carries
the ROMs; no other step is needed. Observations are the 210x160 RGB screen. See
{doc}`/guides/atari`.

**Rewards** are the change in the game's score. **An episode ends** when the game is over
(terminated) or after `max_num_frames_per_episode=108000` emulator frames (truncated).
`ALE/<Game>-v5` repeats each action for 4 frames (`frameskip=4`) and repeats the previous action
with probability 0.25 (sticky actions, `repeat_action_probability=0.25`); `<Game>NoFrameskip-v4`
steps one frame at a time with no sticky actions, the setting DQN-era papers and Stable-Baselines3's
`AtariWrapper` start from. Both use the game's minimal action set (`full_action_space=False`).
""",
    },
}

_CARTPOLE = {
    "summary": "A pole is hinged to a cart on a frictionless track; push the cart left or right to keep "
    "the pole upright. Observation: cart position, cart velocity, pole angle, pole angular velocity. "
    "Actions: 0 push left, 1 push right.",
    "rewards": "+1 for every step, the last one included.",
    "end": "Terminated when the pole leans more than 12 degrees or the cart leaves [-2.4, 2.4]; "
    "truncated at the time limit.",
    "versions": "v1: the time limit rose from 200 to 500 steps and the reward threshold from 195 to 475. "
    "v0: the first version; both are registered.",
}

_FROZEN = {
    "summary": "Cross a frozen lake from the start (top left) to the goal (bottom right) without "
    "falling into a hole. The observation is the cell, `row * ncol + col`. Actions: 0 left, 1 down, "
    "2 right, 3 up. The ice is slippery by default (`is_slippery=True`): the agent moves in the "
    "chosen direction with probability 1/3 and to either side with 1/3 each.",
    "rewards": "1 on reaching the goal, 0 otherwise.",
    "end": "Terminated in a hole or at the goal; truncated at the time limit.",
    "versions": "v1: reward and map fixes over v0, which is not registered (as in Gymnasium 1.4).",
}

_CLIFF = {
    "summary": "A 4x12 grid: walk from the bottom-left start to the bottom-right goal along a cliff. "
    "The observation is the cell, `row * 12 + col`. Actions: 0 up, 1 right, 2 down, 3 left.",
    "rewards": "-1 per step; -100 for stepping into the cliff, which sends the agent back to the start.",
    "end": "Terminated at the goal.",
    "versions": "v1: adds the slippery variant (`is_slippery=True`, registered as "
    "`CliffWalkingSlippery-v1`). v0 is not registered, as in Gymnasium 1.4.",
}

_LUNAR = {
    "summary": "Land a lander on the pad between the flags. Observation: position, velocity, angle, "
    "angular velocity and one contact flag per leg (8 numbers).",
    "rewards": "Shaped by distance to the pad, speed and tilt; +10 for each leg touching the ground; "
    "-0.3 per frame the main engine fires and -0.03 per side-engine frame; +100 for coming to rest, "
    "-100 for crashing.",
    "end": "Terminated when the lander crashes, leaves the screen horizontally or comes to rest; "
    "truncated at the time limit.",
    "versions": "v3: Gymnasium 1.0's fixes (wind and turbulence seeded from the reset, deterministic "
    "with a seed). v2 is not registered.",
}

_BIPEDAL = {
    "summary": "Walk a two-legged robot to the far end of rough terrain. Observation: hull angle and "
    "angular velocity, velocities, joint positions and speeds, leg contacts and 10 lidar readings "
    "(24 numbers). Actions: speeds of the four hip and knee motors in [-1, 1].",
    "rewards": "Forward progress (over 300 in all for reaching the end), minus a small cost for motor "
    "torque; -100 for falling.",
    "end": "Terminated when the hull touches the ground or the walker reaches the end; truncated at "
    "the time limit.",
    "versions": "v3: the lidar returns the nearest hit. v2 is not registered.",
}

_BITFLIP = {
    "summary": "Flip bits until the observation equals a goal bit string. Stable-Baselines3's "
    "`BitFlippingEnv`; Dict observation with `observation`, `achieved_goal` (the same bits) and "
    "`desired_goal`.",
    "rewards": "-1 per step, 0 when the bits equal the goal (`compute_reward` gives the same for any "
    "goal, which HER uses).",
    "end": "Terminated when the bits equal the goal; truncated after as many steps as there are bits.",
    "versions": "v0: the first version.",
}


def _mujoco(summary: str, rewards: str, end: str) -> dict[str, str]:
    return {
        "summary": summary,
        "rewards": rewards,
        "end": end,
        "versions": "v5 (Gymnasium 1.0's): constructor arguments for the reward weights, healthy ranges, "
        "`reset_noise_scale` and `xml_file`, and `default_camera_config`. v2 to v4 raise "
        "`DeprecatedEnv` naming v5.",
    }


_HEALTHY = "Terminated when the robot is no longer healthy (see `healthy_*` arguments); truncated at the time limit."

NOTES: dict[str, dict[str, str]] = {
    "CartPole-v0": _CARTPOLE,
    "CartPole-v1": _CARTPOLE,
    "MountainCar-v0": {
        "summary": "A car between two hills must reach the flag on the right, but its engine is too weak "
        "to climb directly: it has to rock back and forth. Observation: position in [-1.2, 0.6] and "
        "velocity in [-0.07, 0.07]. Actions: 0 push left, 1 no push, 2 push right.",
        "rewards": "-1 per step.",
        "end": "Terminated when the position reaches 0.5 (the flag); truncated at the time limit.",
        "versions": "v0: the first and only version.",
    },
    "MountainCarContinuous-v0": {
        "summary": "MountainCar with a continuous engine: the action is a force in [-1, 1].",
        "rewards": "-0.1 times the squared action per step; +100 on reaching the flag.",
        "end": "Terminated when the position reaches 0.45; truncated at the time limit.",
        "versions": "v0: the first and only version.",
    },
    "Pendulum-v1": {
        "summary": "Swing a pendulum up and hold it upright. Observation: cos and sin of the angle and "
        "the angular velocity. Action: a torque in [-2, 2].",
        "rewards": "-(angle² + 0.1 angular velocity² + 0.001 torque²), the angle normalised to [-pi, pi].",
        "end": "Never terminates; truncated at the time limit.",
        "versions": "v1: simpler equations, the same behaviour as v0, which is not registered.",
    },
    "Acrobot-v1": {
        "summary": "A two-link chain hangs from a joint; torque on the middle joint must swing the tip "
        "above a line. Observation: cos and sin of both angles and both angular velocities. Actions: "
        "torque -1, 0 or +1.",
        "rewards": "-1 per step, 0 on the step that reaches the line.",
        "end": "Terminated when `-cos(theta1) - cos(theta1 + theta2) > 1`; truncated at the time limit.",
        "versions": "v1: 500 steps instead of 200, and sines and cosines of the angles instead of the "
        "angles. v0 is not registered.",
    },
    "FrozenLake-v1": _FROZEN,
    "FrozenLake8x8-v1": _FROZEN,
    "CliffWalking-v1": _CLIFF,
    "CliffWalkingSlippery-v1": _CLIFF,
    "Taxi-v4": {
        "summary": "Pick a passenger up at one of four marked squares and drop them at another. The "
        "observation encodes taxi row and column, passenger location and destination (500 states). "
        "Actions: 0 south, 1 north, 2 east, 3 west, 4 pick up, 5 drop off.",
        "rewards": "-1 per step; +20 for delivering the passenger; -10 for an illegal pick-up or drop-off.",
        "end": "Terminated when the passenger is delivered; truncated at the time limit.",
        "versions": "v4: the version Gymnasium 1.4 registers; Taxi-v3 is not registered.",
    },
    "Blackjack-v1": {
        "summary": "Beat the dealer at blackjack. Observation: the player's sum, the dealer's showing "
        "card and whether the player holds a usable ace. Actions: 0 stick, 1 hit.",
        "rewards": "+1 for a win, -1 for a loss, 0 for a draw; with `natural=True`, +1.5 for a natural "
        "blackjack. Registered with `sab=True` (Sutton and Barto's rules).",
        "end": "Terminated when the player sticks or goes over 21.",
        "versions": "v1: fixes how a natural is scored. v0 is not registered.",
    },
    "LunarLander-v3": {
        **_LUNAR,
        "summary": _LUNAR["summary"] + " Actions: 0 nothing, 1 left engine, "
        "2 main engine, 3 right engine.",
    },
    "LunarLanderContinuous-v3": {
        **_LUNAR,
        "summary": _LUNAR["summary"] + " Actions (`continuous=True`): "
        "main and lateral engine throttles in [-1, 1].",
    },
    "BipedalWalker-v3": _BIPEDAL,
    "BipedalWalkerHardcore-v3": {
        **_BIPEDAL,
        "summary": _BIPEDAL["summary"] + " Hardcore "
        "(`hardcore=True`) adds ladders, stumps and pitfalls.",
    },
    "CarRacing-v3": {
        "summary": "Drive a car round a randomly generated track from a top-down 96x96 image. Actions: "
        "steering in [-1, 1], gas and brake in [0, 1] (`continuous=False`: 5 discrete actions).",
        "rewards": "-0.1 per frame and +1000/N for each of the track's N tiles visited.",
        "end": "Terminated when the lap is complete (`lap_complete_percent` of the tiles) or the car "
        "leaves the playfield (-100); truncated at the time limit.",
        "versions": "v3: `domain_randomize`, `lap_complete_percent` and `continuous` options, and "
        "Gymnasium 1.0's fixes. v2 is not registered.",
    },
    "Ant-v5": _mujoco(
        "A four-legged robot (a torso and four two-joint legs) learns to walk forward. Actions: torques "
        "on its 8 joints.",
        "`healthy_reward` while healthy + forward velocity - control cost - contact cost.",
        _HEALTHY,
    ),
    "HalfCheetah-v5": _mujoco(
        "A two-dimensional cat-like robot runs forward. Actions: torques on its 6 joints.",
        "Forward velocity - control cost.",
        "Never terminates; truncated at the time limit.",
    ),
    "Hopper-v5": _mujoco(
        "A one-legged two-dimensional robot hops forward. Actions: torques on its 3 joints.",
        "`healthy_reward` while healthy + forward velocity - control cost.",
        _HEALTHY,
    ),
    "Humanoid-v5": _mujoco(
        "A three-dimensional humanoid learns to walk forward without falling. Actions: torques on its "
        "17 joints.",
        "`healthy_reward` while healthy + forward velocity - control cost - contact cost.",
        "Terminated when the torso's height leaves `healthy_z_range`; truncated at the time limit.",
    ),
    "HumanoidStandup-v5": _mujoco(
        "The humanoid starts lying down and learns to stand up. Actions: torques on its 17 joints.",
        "Height of the torso (`uph_cost`) + 1 - control cost - impact cost.",
        "Never terminates; truncated at the time limit.",
    ),
    "InvertedDoublePendulum-v5": _mujoco(
        "Balance two poles stacked on a cart. Action: the force on the cart.",
        "`healthy_reward` (alive bonus) - distance of the tip from upright - velocity penalty.",
        "Terminated when the tip falls below height 1; truncated at the time limit.",
    ),
    "InvertedPendulum-v5": _mujoco(
        "Balance a pole on a cart. Action: the force on the cart.",
        "+1 per step while the pole is upright.",
        "Terminated when the pole leans more than 0.2 rad; truncated at the time limit.",
    ),
    "Pusher-v5": _mujoco(
        "A seven-joint arm pushes an object to a target. Actions: torques on its 7 joints.",
        "-(distance of the fingertip to the object) - (distance of the object to the goal) - control cost, "
        "with the weights `reward_near_weight`, `reward_dist_weight`, `reward_control_weight`.",
        "Never terminates; truncated at the time limit.",
    ),
    "Reacher-v5": _mujoco(
        "A two-joint arm moves its fingertip to a random target. Actions: torques on its 2 joints.",
        "-(distance of the fingertip to the target) - control cost.",
        "Never terminates; truncated at the time limit.",
    ),
    "Swimmer-v5": _mujoco(
        "A three-segment swimmer moves forward through a viscous fluid. Actions: torques on its 2 joints.",
        "Forward velocity - control cost.",
        "Never terminates; truncated at the time limit.",
    ),
    "Walker2d-v5": _mujoco(
        "A two-legged two-dimensional robot walks forward. Actions: torques on its 6 joints.",
        "`healthy_reward` while healthy + forward velocity - control cost.",
        _HEALTHY,
    ),
    "BitFlipping-v0": {
        **_BITFLIP,
        "summary": _BITFLIP["summary"] + " 10 bits; action: the bit to flip.",
    },
    "BitFlippingContinuous-v0": {
        **_BITFLIP,
        "summary": _BITFLIP["summary"] + " 10 bits; continuous "
        "action (`continuous=True`): a Box of 10, each positive entry flips its bit.",
    },
    "BitFlipping15-v0": {
        **_BITFLIP,
        "summary": _BITFLIP["summary"] + " 15 bits (`n_bits=15`), the "
        "setting where DQN fails without HER.",
    },
}

_ATARI = re.compile(r"^(?:ALE/(?P<v5>\w+)-v5|(?P<v4>\w+)NoFrameskip-v4)$")


def notes_for(env_id: str) -> dict[str, str] | None:
    """The prose for ``env_id``; Atari ids share the family's text (the intro says it once)."""
    if env_id in NOTES:
        return NOTES[env_id]
    match = _ATARI.match(env_id)
    if match is None:
        return None
    game = match.group("v5") or match.group("v4")
    v5 = match.group("v5") is not None
    return {
        "summary": f"The Atari 2600 game {game}, emulated by ale-py.",
        "rewards": "The change in the game's score.",
        "end": "Terminated at game over; truncated after 108,000 emulator frames.",
        "versions": (
            "v5: 4 frames per step and sticky actions (probability 0.25), ale-py's current setting."
            if v5
            else "v4, NoFrameskip: one frame per step, no sticky actions (use it with `AtariWrapper` or "
            "`AtariPreprocessing`, which skip frames themselves)."
        ),
    }
