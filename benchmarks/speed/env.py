"""Single-environment speed: `gym.make("AUVPath3D-v0")` steps per second and real-time factor.

The reference runs the very same step with numba's JIT disabled (NUMBA_DISABLE_JIT=1), i.e. the
identical equations as plain Python/numpy, in a subprocess of the same run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass

import numpy as np

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option


def measure(steps: int, seed: int = 0) -> dict[str, float]:
    """Time `steps` env.step calls through gym.make with pre-drawn actions (default settings)."""
    import gymnasium as gym

    import auv_gym  # noqa: F401  (registers the env)

    env = gym.make("AUVPath3D-v0")
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, size=(steps, 3)).astype(np.float32)
    actions[:, 0] = 0.1 * np.abs(actions[:, 0])
    actions[:, 1:] *= 0.2
    env.reset(seed=seed)
    env.step(actions[0])  # compile outside the timed loop
    env.reset(seed=seed)
    resets = 0
    start = time.perf_counter()
    for a in actions:
        _, _, terminated, truncated, _ = env.step(a)
        if terminated or truncated:
            env.reset()
            resets += 1
    wall = time.perf_counter() - start
    cfg = env.unwrapped.config
    return {
        "env_steps_per_s": steps / wall,
        "physics_steps_per_s": steps * cfg.substeps / wall,
        "real_time_factor": steps * cfg.control_dt / wall,
        "resets": resets,
    }


def measure_reference(steps: int) -> dict[str, float]:
    """The same loop with the JIT disabled, in a subprocess."""
    code = (
        "import json, warnings; warnings.simplefilter('ignore');"
        f"from benchmarks.speed.env import measure; print(json.dumps(measure({steps})))"
    )
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


@dataclass
class Options:
    """The command line of `auv-gym speed env`."""

    steps: int = option(60_000, "control steps to time")
    reference_steps: int = option(400, "control steps of the JIT-off (plain Python) reference")


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    args, parser = parse_options(Options, argv, program_name("benchmarks.speed.env"), __doc__)
    if args.steps < 1 or args.reference_steps < 1:  # a rate of no steps is no figure
        parser.error("--steps and --reference-steps must be >= 1")
    results = {
        "numba (gym.make)": measure(args.steps),
        "plain Python/numpy (JIT off)": measure_reference(args.reference_steps),
    }
    print("\nSingle env, default settings (helix, white noise ±35, control 0.05 s, RK4 0.01 s)")
    print(f"{'implementation':<30} {'env steps/s':>12} {'RK4 steps/s':>12} {'real-time ×':>12}")
    for name, r in results.items():
        print(
            f"{name:<30} {r['env_steps_per_s']:>12,.0f} {r['physics_steps_per_s']:>12,.0f} "
            f"{r['real_time_factor']:>12,.0f}"
        )
    fast, ref = results["numba (gym.make)"], results["plain Python/numpy (JIT off)"]
    ratio = fast["real_time_factor"] / ref["real_time_factor"]
    print(f"numba / plain reference in this run: {ratio:,.0f}×; target ≥ 3,000× real time")
    return results


if __name__ == "__main__":
    main()
