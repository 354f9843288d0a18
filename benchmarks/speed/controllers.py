"""Controller speed: FBSM and backstepping cost per control step, batched, and a 300-s episode.

    python -m benchmarks.speed.controllers [--steps 200] [--vehicles 1024]

Targets: one 300-s FBSM episode through `gym.make` in < 2 s of wall time on one core;
batched FBSM ≥ 100,000 vehicle-control-steps/s.

The controllers are timed in closed loop on the paper's scenario (±35 white noise, default
control period), so the observations, and hence how often a loop saturates and skips its
adaptation, are those of a real run; only `predict` is inside the timer. FBSM is
memory-bound when batched: each vehicle carries 2 × 3 × 3125 adaptive weights (150 kB) that are
read and written once per control step, so 1024 vehicles stream ~300 MB per step; a batch of 64
(10 MB) stays in the L3 cache and runs ~1.6× faster per vehicle on the 2-core AMD EPYC sandbox.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numba
import numpy as np

import controllers
from auv_gym.sim.config import SimConfig
from auv_gym.sim.simulator import Simulator
from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option


def closed_loop(name: str, n: int, steps: int, threads: int, warmup: int = 100) -> dict[str, float]:
    """`predict` throughput on n noisy vehicles of the default scenario, after ``warmup`` steps.

    Returns vehicle-control-steps/s of the controller alone and the fraction of saturated
    action entries in the timed steps (a saturated FBSM loop skips its adaptive update).
    """
    sim = Simulator(SimConfig.from_kwargs(disturbance="paper"), n, parallel=threads > 1)
    for i in range(n):
        sim.reset_row(i, np.random.default_rng(i))
    policy = controllers.make(name, threads="auto" if threads > 1 else "serial")
    state, start, elapsed, saturated = None, np.ones(n, dtype=bool), 0.0, 0
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        for k in range(warmup + steps):
            obs = sim.obs.astype(np.float32)
            tic = time.perf_counter()
            actions, state = policy.predict(obs, state, start)
            if k >= warmup:
                elapsed += time.perf_counter() - tic
                saturated += int((np.abs(actions) >= 1.0).sum())
            start[:] = False
            sim.step(actions)
    finally:
        numba.set_num_threads(previous)
    return {"rate": n * steps / elapsed, "saturated": saturated / (3 * n * steps)}


def episode_wall_time(name: str = "fbsm") -> float:
    """Wall time [s] of one default 300-s episode through gym.make (compiled beforehand)."""
    import gymnasium as gym

    import auv_gym  # noqa: F401

    env = gym.make("AUVPath3D-v0")
    policy = controllers.make(name)
    obs, _ = env.reset(seed=0)
    policy.predict(obs)
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        start = time.perf_counter()
        obs, _ = env.reset(seed=0)
        state, done, start_flag = None, False, np.array([True])
        while not done:
            action, state = policy.predict(obs, state, start_flag)
            start_flag = np.array([False])
            obs, _, terminated, truncated, _ = env.step(action)
            done = terminated or truncated
        return time.perf_counter() - start
    finally:
        numba.set_num_threads(previous)


@dataclass
class Options:
    """The command line of `auv-gym speed controllers`."""

    steps: int = option(200, "timed control steps")
    vehicles: int = option(1024, "batch size")


def main(argv: list[str] | None = None) -> dict[str, float]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.controllers"), __doc__
    )
    if args.steps < 1 or args.vehicles < 1:
        parser.error("--steps and --vehicles must be positive")
    results = {}
    print("\nController cost in closed loop, ±35 noise (predict only; vehicle-control-steps/s)")
    print(
        f"{'controller':<14} {'N':>6} {'threads':>8} {'steps/s':>12} {'µs/vehicle-step':>16} "
        f"{'saturated':>10}"
    )
    max_threads = numba.config.NUMBA_NUM_THREADS
    for name in ("fbsm", "backstepping", "pid_los"):
        sizes = ((1, 1), (64, 1), (args.vehicles, 1), (args.vehicles, min(2, max_threads)))
        for n, threads in sizes:
            steps = args.steps * (10 if n == 1 else 1 if n > 64 else 3)
            out = closed_loop(name, n, steps, threads)
            results[f"{name}_n{n}_t{threads}"] = out["rate"]
            print(
                f"{name:<14} {n:>6} {threads:>8} {out['rate']:>12,.0f} "
                f"{1e6 / out['rate']:>16.2f} {out['saturated']:>10.1%}"
            )
    for name in ("fbsm", "backstepping", "pid_los"):
        wall = episode_wall_time(name)
        results[f"{name}_episode_s"] = wall
        print(f"one 300-s {name} episode through gym.make (6000 steps): {wall:.2f} s wall")
    return results


if __name__ == "__main__":
    main()
