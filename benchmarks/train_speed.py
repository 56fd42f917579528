"""Training speed: env-steps/s of palaestra's DQN, PPO and A2C against Stable-Baselines3's.

Run from the repository root::

    .venv/bin/python benchmarks/train_speed.py              # full run (several minutes)
    .venv/bin/python benchmarks/train_speed.py --quick      # smoke run

Cases (one torch thread, ``torch.set_num_threads(1)``, both libraries in this process):

* ``dqn-mountaincar``: DQN on MountainCar-v0, one env, the tutorial settings
  (``learning_rate=1e-3, buffer_size=50000, learning_starts=1000, batch_size=128, tau=1.0,
  gamma=0.99, train_freq=4, gradient_steps=1, target_update_interval=250,
  exploration_fraction=0.2, exploration_final_eps=0.05``);
* ``ppo-mountaincar``: PPO on MountainCar-v0, one env, ``learning_rate=1e-3, n_steps=2048,
  batch_size=64, n_epochs=10``;
* ``dqn-cartpole-cleanrl``: DQN on CartPole-v1, one env, CleanRL's ``dqn.py`` defaults
  (``DQN_CLEANRL_KWARGS``), timed after its 10,000-step warm-up;
* ``ppo-cartpole-zoo``: PPO on CartPole-v1, 8 envs, the RL Zoo's settings (``n_steps=32``,
  ``batch_size=256``, 20 epochs, linear learning rate and clip range: ``PPO_ZOO_KWARGS``);
* ``ppo-cartpole-8``: PPO on CartPole-v1, 8 envs x 128 steps, 4 epochs, 4 minibatches
  (``batch_size=256``);
* ``a2c-cartpole-8``: A2C on CartPole-v1, 8 envs, SB3's defaults (``n_steps=5``, RMSprop, one
  update per 40 env steps);
* ``sac-pendulum``, ``td3-pendulum``: SAC and TD3 on Pendulum-v1, one env, SB3's defaults
  (256x256 nets for SAC, 400x300 for TD3, batch 256, one gradient step per env step) with
  ``learning_rate=1e-3``; 3,000 steps timed after 1,000 (past ``learning_starts``).

Acting latency (``--acting``, also after the cases of a full run): microseconds per
``model.predict`` of one vector step's observations (stochastic, as in collection) on each
case's model, fresh from construction, median of repeats of 5,000 calls.

SB3 gets ``gymnasium.make`` (single env) or SB3's ``make_vec_env``; palaestra gets
``palaestra.make`` or ``palaestra.vec_env.make_vec_env``. Each measurement is one
``learn(warmup + steps)`` call: a callback notes the process CPU time (and wall time) when
``num_timesteps`` first reaches ``warmup`` and at the end, so the timed part is ``steps`` env
steps of steady-state training (DQN's warm-up passes ``learning_starts``; PPO's is one rollout
+ update; A2C's, 50 rollouts). Model construction is not timed. Repeats interleave the
libraries (the starting one alternates); the figure is the median env-steps per CPU second,
and the ratio is palaestra / SB3 of the medians.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import torch
from tutorial_settings import DQN_KWARGS  # benchmarks/ is on sys.path when run as a script

PPO_MC_KWARGS: dict[str, Any] = dict(learning_rate=1e-3, n_steps=2048, batch_size=64, n_epochs=10)
PPO_CP_KWARGS: dict[str, Any] = dict(n_steps=128, batch_size=256, n_epochs=4)


def linear(start: float) -> Callable[[float], float]:
    """The RL Zoo's ``lin_`` schedules: ``progress_remaining * start``."""

    def schedule(progress_remaining: float) -> float:
        return progress_remaining * start

    return schedule


# RL Zoo 2.x ``hyperparams/ppo.yml`` CartPole-v1 (8 envs; ``n_timesteps`` aside).
PPO_ZOO_KWARGS: dict[str, Any] = dict(
    n_steps=32,
    batch_size=256,
    gae_lambda=0.8,
    gamma=0.98,
    n_epochs=20,
    ent_coef=0.0,
    learning_rate=linear(1e-3),
    clip_range=linear(0.2),
)
# CleanRL's ``dqn.py`` defaults (CartPole-v1) in SB3's terms: 120-84 ReLU Q-net, Adam 2.5e-4,
# 10k buffer and warm-up, a gradient step every 10 env steps, target copied every 500.
DQN_CLEANRL_KWARGS: dict[str, Any] = dict(
    learning_rate=2.5e-4,
    buffer_size=10_000,
    learning_starts=10_000,
    batch_size=128,
    tau=1.0,
    gamma=0.99,
    train_freq=10,
    gradient_steps=1,
    target_update_interval=500,
    exploration_initial_eps=1.0,
    exploration_final_eps=0.05,
    exploration_fraction=0.5,
    policy_kwargs=dict(net_arch=[120, 84]),
)


@dataclass(frozen=True)
class Case:
    name: str
    algo: str
    env_id: str
    n_envs: int  # 0: a single env passed directly
    kwargs: dict[str, Any]
    warmup: int
    steps: int
    target: float


CASES = [
    Case("dqn-mountaincar", "dqn", "MountainCar-v0", 0, DQN_KWARGS, 2_000, 20_000, 6.0),
    Case("dqn-cartpole-cleanrl", "dqn", "CartPole-v1", 0, DQN_CLEANRL_KWARGS, 10_000, 40_000, 6.0),
    Case("ppo-mountaincar", "ppo", "MountainCar-v0", 0, PPO_MC_KWARGS, 2_048, 20_480, 3.0),
    Case("ppo-cartpole-8", "ppo", "CartPole-v1", 8, PPO_CP_KWARGS, 1_024, 30_720, 5.0),
    Case("ppo-cartpole-zoo", "ppo", "CartPole-v1", 8, PPO_ZOO_KWARGS, 256, 25_600, 15.0),
    Case("a2c-cartpole-8", "a2c", "CartPole-v1", 8, {}, 2_000, 40_000, 5.0),
    Case("sac-pendulum", "sac", "Pendulum-v1", 0, {"learning_rate": 1e-3}, 1_000, 3_000, 2.0),
    Case("td3-pendulum", "td3", "Pendulum-v1", 0, {"learning_rate": 1e-3}, 1_000, 3_000, 2.0),
]


def make_env(lib: str, case: Case) -> Any:
    if case.n_envs:
        if lib == "sb3":
            from stable_baselines3.common.env_util import make_vec_env
        else:
            from palaestra.vec_env import make_vec_env
        return make_vec_env(case.env_id, n_envs=case.n_envs, seed=0)
    if lib == "sb3":
        import gymnasium

        return gymnasium.make(case.env_id)
    import palaestra

    return palaestra.make(case.env_id)


def make_model(lib: str, case: Case) -> Any:
    if lib == "sb3":
        import stable_baselines3 as algos
    else:
        import palaestra.algos as algos  # type: ignore[no-redef]
    cls = getattr(algos, case.algo.upper())
    return cls("MlpPolicy", make_env(lib, case), seed=0, **case.kwargs)


def timer_callback(lib: str, warmup: int) -> Any:
    """A callback of ``lib``'s own class that notes (cpu, wall, num_timesteps) at warm-up end."""
    if lib == "sb3":
        from stable_baselines3.common.callbacks import BaseCallback
    else:
        from palaestra.algos.callbacks import BaseCallback

    class Timer(BaseCallback):  # type: ignore[misc, valid-type]
        def __init__(self) -> None:
            super().__init__()
            self.mark: tuple[float, float, int] | None = None

        def _on_step(self) -> bool:
            if self.mark is None and self.num_timesteps >= warmup:
                self.mark = (time.process_time(), time.perf_counter(), self.num_timesteps)
            return True

    return Timer()


def measure(lib: str, case: Case) -> tuple[float, float]:
    """(env-steps per CPU second, per wall second) after the warm-up."""
    model = make_model(lib, case)
    timer = timer_callback(lib, case.warmup)
    model.learn(total_timesteps=case.warmup + case.steps, callback=timer)
    cpu_end, wall_end = time.process_time(), time.perf_counter()
    assert timer.mark is not None
    cpu0, wall0, steps0 = timer.mark
    steps = model.num_timesteps - steps0
    return steps / (cpu_end - cpu0), steps / (wall_end - wall0)


def run_case(case: Case, repeats: int, log: Callable[[str], None]) -> dict[str, list[float]]:
    rates: dict[str, list[float]] = {
        "palaestra": [],
        "sb3": [],
        "palaestra_wall": [],
        "sb3_wall": [],
    }
    for i in range(repeats):
        order = ["palaestra", "sb3"] if i % 2 == 0 else ["sb3", "palaestra"]
        for lib in order:
            cpu_rate, wall_rate = measure(lib, case)
            rates[lib].append(cpu_rate)
            rates[f"{lib}_wall"].append(wall_rate)
            log(
                f"  {case.name} repeat {i} {lib:9s} {cpu_rate:9,.0f} steps/cpu-s"
                f" {wall_rate:9,.0f} steps/wall-s"
            )
    return rates


def report(case: Case, rates: dict[str, list[float]]) -> str:
    pal, sb3 = statistics.median(rates["palaestra"]), statistics.median(rates["sb3"])
    ratio = pal / sb3
    verdict = "met" if ratio >= case.target else "MISSED"
    per_repeat = ", ".join(f"{p / s:.2f}" for p, s in zip(rates["palaestra"], rates["sb3"]))
    return (
        f"| {case.name} | {pal:,.0f} | {sb3:,.0f} | {ratio:.2f}x | >= {case.target:g}x: {verdict} "
        f"| {per_repeat} |"
    )


def acting_latency(lib: str, case: Case, calls: int = 5_000) -> float:
    """Microseconds per ``predict`` of one vector step (``n_envs`` rows, 1 for a single env)."""
    model = make_model(lib, case)
    obs = model.get_env().reset()  # [n_envs, *obs_shape], as collection sees them
    for _ in range(200):  # warm-up: first-call allocations, caches
        model.predict(obs)
    start = time.process_time()
    for _ in range(calls):
        model.predict(obs)
    return (time.process_time() - start) / calls * 1e6


def run_acting(cases: list[Case], repeats: int, log: Callable[[str], None]) -> list[str]:
    lines = []
    for case in cases:
        times: dict[str, list[float]] = {"palaestra": [], "sb3": []}
        for i in range(repeats):
            for lib in ["palaestra", "sb3"] if i % 2 == 0 else ["sb3", "palaestra"]:
                times[lib].append(acting_latency(lib, case))
                log(f"  acting {case.name} repeat {i} {lib:9s} {times[lib][-1]:8.1f} us/step")
        pal, sb3 = statistics.median(times["palaestra"]), statistics.median(times["sb3"])
        lines.append(f"| {case.name} | {pal:.1f} | {sb3:.1f} | {sb3 / pal:.2f}x |")
    return lines


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    names = [c.name for c in CASES]
    parser.add_argument("--cases", nargs="+", default=names, choices=names)
    parser.add_argument("--quick", action="store_true", help="1 repeat, a tenth of the steps")
    parser.add_argument("--acting", action="store_true", help="only the acting latencies")
    return parser.parse_args()


def main() -> None:
    args = parse_args()
    torch.set_num_threads(1)
    cases = [c for c in CASES if c.name in args.cases]
    repeats = 1 if args.quick else args.repeats
    if args.quick:
        cases = [
            Case(c.name, c.algo, c.env_id, c.n_envs, c.kwargs, c.warmup, c.steps // 10, c.target)
            for c in cases
        ]
    lines = []
    for case in [] if args.acting else cases:
        rates = run_case(case, repeats, lambda s: print(s, flush=True))
        lines.append(report(case, rates))
        print(lines[-1], flush=True)
    acting = run_acting(cases, repeats, lambda s: print(s, flush=True))
    if lines:
        print(
            "\n| case | palaestra steps/cpu-s | SB3 steps/cpu-s | ratio | target "
            "| per-repeat ratios |"
        )
        print("|---|---:|---:|---:|---|---|")
        print("\n".join(lines))
    print("\n| acting | palaestra µs/step | SB3 µs/step | palaestra speed-up |")
    print("|---|---:|---:|---:|")
    print("\n".join(acting))


if __name__ == "__main__":
    main()
