"""The matrix-product bound of PPO's training loop, and how close palaestra comes to it.

Run from the repository root::

    .venv/bin/python benchmarks/gemm_bound.py            # bound and 3 training runs, interleaved
    .venv/bin/python benchmarks/gemm_bound.py --quick    # 1 run, a tenth of the steps

The case is ``ppo-cartpole-zoo`` of ``benchmarks/train_speed.py`` (the RL Zoo's CartPole
settings: 8 envs x 32 steps, one minibatch of 256 per epoch, 20 epochs, 64-64 tanh actor and
critic). Each env step is trained on ``n_epochs`` times; each time, every linear layer costs
one product forward (``x @ W.T``), one for its weight gradient (``g.T @ x``) and, except the
first, one for its input gradient (``g @ W``): ``2 * in * out`` FLOPs each per sample. The
bound is the env-steps per second a loop doing nothing but those products would reach:
``1 / (n_epochs * seconds of the products of one minibatch / batch_size)``, with each product
timed at its own shapes and memory layout (numpy's OpenBLAS on one thread, as the numpy learner
runs them; median of many calls). Env stepping, acting, the loss, activations and the
optimizer are all outside it, so a real loop reaches a fraction of it.

The training runs (``train_speed.measure``: env-steps per CPU second after a one-rollout
warm-up) alternate with the product timings, so both see the same machine load.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import os
import statistics
import time

import numpy as np
import torch
import train_speed  # benchmarks/ is on sys.path when run as a script

from palaestra.algos.learners.adam import one_blas_thread

OBS, HIDDEN, N_ACTIONS, BATCH, EPOCHS = 4, (64, 64), 2, 256, 20


def products(batch: int) -> list[tuple[tuple[int, int], tuple[int, int], bool]]:
    """``(a shape, b shape, b transposed)`` of each product one minibatch update runs: per
    layer of the actor and the critic, forward, weight gradient, input gradient."""
    shapes: list[tuple[tuple[int, int], tuple[int, int], bool]] = []
    for out_dim in (N_ACTIONS, 1):  # actor, critic
        dims = [OBS, *HIDDEN, out_dim]
        for layer, (fan_in, fan_out) in enumerate(itertools.pairwise(dims)):
            shapes.append(((batch, fan_in), (fan_out, fan_in), True))  # x @ W.T
            shapes.append(((fan_out, batch), (batch, fan_in), False))  # g.T @ x
            if layer:
                shapes.append(((batch, fan_out), (fan_out, fan_in), False))  # g @ W
    return shapes


def flops_per_sample() -> int:
    """Forward and backward multiply-adds, times 2, of one sample through both nets (each
    product ``[M, K] @ [K, N]`` costs ``2 M K N``; a minibatch's total over its size)."""
    total = sum(2 * a[0] * a[1] * (b[0] if t else b[1]) for a, b, t in products(BATCH))
    return total // BATCH


def time_products(calls: int = 2000) -> float:
    """Seconds for the products of one minibatch update (sum of each product's median)."""
    rng = np.random.default_rng(0)
    total = 0.0
    with one_blas_thread():
        for a_shape, b_shape, transposed in products(BATCH):
            if a_shape[0] != BATCH:  # g.T: a transposed view of a [batch, out] array
                a = rng.standard_normal(a_shape[::-1], dtype=np.float32).T
            else:
                a = rng.standard_normal(a_shape, dtype=np.float32)
            b = rng.standard_normal(b_shape, dtype=np.float32)
            b = b.T if transposed else b
            out = np.empty((a.shape[0], b.shape[1]), dtype=np.float32)
            samples = []
            for _ in range(5):
                start = time.perf_counter()
                for _ in range(calls // 5):
                    np.matmul(a, b, out=out)
                samples.append((time.perf_counter() - start) / (calls // 5))
            total += statistics.median(samples)
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="1 run, a tenth of the steps")
    args = parser.parse_args()
    torch.set_num_threads(1)
    case = next(c for c in train_speed.CASES if c.name == "ppo-cartpole-zoo")
    assert case.kwargs["batch_size"] == BATCH and case.kwargs["n_epochs"] == EPOCHS
    repeats = 1 if args.quick else args.repeats
    if args.quick:
        case = dataclasses.replace(case, steps=case.steps // 10)
    flops = flops_per_sample()
    bounds, rates = [], []
    for i in range(repeats):
        seconds = time_products()
        bounds.append(BATCH / (EPOCHS * seconds))
        rates.append(train_speed.measure("palaestra", case)[0])
        gflops = flops * BATCH / seconds / 1e9
        print(
            f"run {i}: products {seconds * 1e6:.0f} us per minibatch ({gflops:.1f} GFLOP/s), "
            f"bound {bounds[-1]:,.0f} steps/s; palaestra {rates[-1]:,.0f} steps/cpu-s "
            f"({rates[-1] / bounds[-1]:.0%}); load {os.getloadavg()[0]:.2f}",
            flush=True,
        )
    bound, rate = statistics.median(bounds), statistics.median(rates)
    print(f"\nFLOPs per env step: {flops * EPOCHS / 1e6:.2f} M ({flops:,} per sample and epoch)")
    print("| bound steps/s (median, range) | palaestra steps/cpu-s | fraction | target |")
    print("|---:|---:|---:|---|")
    verdict = "met" if rate >= 0.5 * bound else "MISSED"
    print(
        f"| {bound:,.0f} ({min(bounds):,.0f}-{max(bounds):,.0f}) | {rate:,.0f} "
        f"| {rate / bound:.0%} | >= 50%: {verdict} |"
    )


if __name__ == "__main__":
    main()
