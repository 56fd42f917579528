"""The tutorial's training code blocks, verbatim except for their import lines
(``gymnasium`` -> ``palaestra``, ``stable_baselines3`` -> ``palaestra.algos`` /
``palaestra.vec_env``). ``test_tutorial.py`` runs them shortened (fast) and in full (slow)."""

TRAIN_DQN = """
import palaestra as gym
from palaestra.algos import DQN
# Create the environment
env = gym.make('MountainCar-v0')
# Create the DQN model with tuned hyperparameters
model = DQN(
"MlpPolicy",
env,
learning_rate=1e-3,
buffer_size=50000,
learning_starts=1000,
batch_size=128,
tau=1.0,
gamma=0.99,
train_freq=4,
gradient_steps=1,
target_update_interval=250,
exploration_fraction=0.2,
exploration_final_eps=0.05,
verbose=1
)
# Train - DQN typically solves MountainCar in 200k timesteps
print("Training DQN on MountainCar...")
model.learn(total_timesteps=200000)
# Save the trained model
model.save("dqn_mountaincar")
print("Training complete!")
"""

TEST_DQN = """
import palaestra as gym
from palaestra.algos import DQN
import matplotlib.pyplot as plt
from IPython import display
# Load the trained model
model = DQN.load("dqn_mountaincar")
# Create environment with rendering
env = gym.make('MountainCar-v0', render_mode='rgb_array')
obs, info = env.reset()
plt.figure(figsize=(6, 4))
for step in range(200):
    # Use the trained model to predict the action
    action, _states = model.predict(obs, deterministic=True)
    obs, reward, terminated, truncated, info = env.step(action)
    frame = env.render()
    plt.clf()
    plt.imshow(frame)
    plt.axis('off')
    plt.title(f"Step: {step}, Position: {obs[0]:.3f}")
    display.clear_output(wait=True)
    display.display(plt.gcf())
    if terminated:
        print(f"Success! Reached goal in {step} steps")
        break
env.close()
plt.close()
"""

TRAIN_PPO = """
import palaestra as gym
from palaestra.algos import PPO
env = gym.make('MountainCar-v0')
model = PPO(
"MlpPolicy",
env,
verbose=1,
learning_rate=0.001,
n_steps=2048,
batch_size=64,
n_epochs=10
)
# PPO needs significantly more training time for MountainCar
model.learn(total_timesteps=500000)
model.save("ppo_mountaincar")
"""

SHAPING_WRAPPERS = """
import palaestra as gym
class NaiveRewardShaping(gym.RewardWrapper):
    def __init__(self, env):
        super().__init__(env)
    def reward(self, reward):
        # Get current position (height on the hill)
        position = self.env.unwrapped.state[0]
        # Original reward is -1 per step
        # Add bonus for being higher up: position ranges from -1.2 to 0.6
        height_bonus = (position + 1.2) * 0.5
        return reward + height_bonus
class BetterRewardShaping(gym.RewardWrapper):
    def __init__(self, env):
        super().__init__(env)
        self.best_position = -1.2 # Track the rightmost position reached
    def reset(self, **kwargs):
        self.best_position = -1.2
        return self.env.reset(**kwargs)
    def reward(self, reward):
        position = self.env.unwrapped.state[0]
        # Only reward new rightward progress
        if position > self.best_position:
            bonus = (position - self.best_position) * 10
            self.best_position = position
            return reward + bonus
        return reward
"""

TRAIN_NAIVE = """
import palaestra as gym
from palaestra.algos import DQN
# Save baseline model first for comparison
import shutil
from pathlib import Path
Path("./models").mkdir(exist_ok=True)
shutil.copy("dqn_mountaincar.zip", "./models/dqn_mountaincar_baseline.zip")
# Create wrapped environment with naive reward shaping
env = gym.make('MountainCar-v0')
wrapped_env = NaiveRewardShaping(env)
# Train with shaped rewards
model = DQN(
"MlpPolicy",
wrapped_env,
learning_rate=1e-3,
buffer_size=50000,
learning_starts=1000,
batch_size=128,
verbose=1
)
print("Training with naive reward shaping...")
model.learn(total_timesteps=200000)
model.save("./models/dqn_mountaincar_naive_shaped")
"""

TRAIN_BETTER = """
import palaestra as gym
from palaestra.algos import DQN
env = gym.make('MountainCar-v0')
wrapped_env = BetterRewardShaping(env)
model = DQN(
"MlpPolicy",
wrapped_env,
learning_rate=1e-3,
buffer_size=50000,
learning_starts=1000,
batch_size=128,
verbose=1
)
print("Training with improved reward shaping...")
model.learn(total_timesteps=200000)
model.save("./models/dqn_mountaincar_better_shaped")
"""

COMPARE = """
from palaestra.algos import DQN
import palaestra as gym
import numpy as np
def test_model(model_path, num_episodes=10):
    model = DQN.load(model_path)
    env = gym.make('MountainCar-v0')
    episode_lengths = []
    successes = 0
    for episode in range(num_episodes):
        obs, info = env.reset()
        for step in range(200):
            action, _states = model.predict(obs, deterministic=True)
            obs, reward, terminated, truncated, info = env.step(action)
            if terminated:
                episode_lengths.append(step)
                successes += 1
                break
    env.close()
    avg_length = np.mean(episode_lengths) if episode_lengths else 200
    success_rate = (successes / num_episodes) * 100
    return avg_length, success_rate
# Compare all three models
baseline_length, baseline_success = test_model("./models/dqn_mountaincar_baseline")
naive_length, naive_success = test_model("./models/dqn_mountaincar_naive_shaped")
better_length, better_success = test_model("./models/dqn_mountaincar_better_shaped")
print("\\n--- Model Comparison ---")
print(f"Baseline - Avg steps: {baseline_length:.1f}, Success rate: {baseline_success:.0f}%")
print(f"Naive Shaped - Avg steps: {naive_length:.1f}, Success rate: {naive_success:.0f}%")
print(f"Better Shaped - Avg steps: {better_length:.1f}, Success rate: {better_success:.0f}%")
"""

TRAIN_VECTORIZED = """
from palaestra.algos import DQN
from palaestra.vec_env import make_vec_env
# Create 8 parallel environments
vec_env = make_vec_env('MountainCar-v0', n_envs=8)
# Train with vectorized environments
model = DQN("MlpPolicy", vec_env, verbose=1)
model.learn(total_timesteps=200000)
model.save("./models/dqn_mountaincar_vectorized")
print("Training complete with 8 parallel environments")
"""

ALL_TRAINING = [
    TRAIN_DQN,
    TEST_DQN,
    TRAIN_PPO,
    SHAPING_WRAPPERS,
    TRAIN_NAIVE,
    TRAIN_BETTER,
    COMPARE,
    TRAIN_VECTORIZED,
]
