"""Controller speed: FBSM and backstepping cost per control step, batched, and a 300-s episode.

Targets (issue 3): one 300-s FBSM episode through `gym.make` in < 2 s of wall time on one core;
batched FBSM ≥ 100,000 vehicle-control-steps/s.
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

import controllers
from auv_gym.observation import OBS_DIM, OBS_INDEX


def _observations(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    obs = np.zeros((n, OBS_DIM), dtype=np.float32)
    for name, scale in (("y_e", 2.0), ("z_e", 2.0), ("psi_error", 0.5), ("v", 0.1), ("w", 0.1),
                        ("q", 0.1), ("r", 0.1), ("theta", 0.2)):  # fmt: skip
        obs[:, OBS_INDEX[name]] = scale * rng.standard_normal(n)
    obs[:, OBS_INDEX["u"]] = 1.0 + 0.1 * rng.standard_normal(n)
    obs[:, OBS_INDEX["u_D"]] = 1.0
    obs[:, OBS_INDEX["theta_F"]] = 0.3
    return obs


def per_step(name: str, n: int, steps: int, threads: int) -> float:
    """Vehicle-control-steps per second of `predict` on n vehicles."""
    numba.set_num_threads(threads)
    policy = controllers.make(name)
    obs = _observations(n)
    _, state = policy.predict(obs)
    start = time.perf_counter()
    for _ in range(steps):
        _, state = policy.predict(obs, state)
    return n * steps / (time.perf_counter() - start)


def episode_wall_time(name: str = "fbsm") -> float:
    """Wall time [s] of one default 300-s episode through gym.make (compiled beforehand)."""
    import gymnasium as gym

    import auv_gym  # noqa: F401

    numba.set_num_threads(1)
    env = gym.make("AUVPath3D-v0")
    policy = controllers.make(name)
    obs, _ = env.reset(seed=0)
    policy.predict(obs)
    start = time.perf_counter()
    obs, _ = env.reset(seed=0)
    state, done, start_flag = None, False, np.array([True])
    while not done:
        action, state = policy.predict(obs, state, start_flag)
        start_flag = np.array([False])
        obs, _, terminated, truncated, _ = env.step(action)
        done = terminated or truncated
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=200)
    args = parser.parse_args(argv)
    results = {}
    print("\nController cost (predict only; vehicle-control-steps/s)")
    print(f"{'controller':<14} {'N':>6} {'threads':>8} {'steps/s':>12} {'µs/vehicle-step':>16}")
    for name in ("fbsm", "backstepping"):
        for n, threads in ((1, 1), (1024, 1), (1024, 2)):
            steps = args.steps * (20 if n == 1 else 1)
            rate = per_step(name, n, steps, threads)
            results[f"{name}_n{n}_t{threads}"] = rate
            print(f"{name:<14} {n:>6} {threads:>8} {rate:>12,.0f} {1e6 / rate:>16.1f}")
    for name in ("fbsm", "backstepping"):
        wall = episode_wall_time(name)
        results[f"{name}_episode_s"] = wall
        print(f"one 300-s {name} episode through gym.make (6000 steps): {wall:.2f} s wall")
    return results


if __name__ == "__main__":
    main()
