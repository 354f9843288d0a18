"""Rendering speed: `render_mode="rgb_array"` frames per second, fast path and full redraw.

    auv-gym speed render [--frames 300] [--every 1]

FBSM follows the paper's helix under ±35 white noise through `gym.make(..., render_mode=
"rgb_array")`; a frame is taken every ``--every`` control steps and only `env.render()` is timed
(the default 960 × 320 px frame). The full-redraw reference (`EpisodeRenderer(fast=False)`) is
timed on the same episode for comparison. Target: ≥ 50 frames/s on the fast path.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option


def measure(frames: int, every: int, fast: bool) -> dict[str, float]:
    """Frames/s of `frames` renders, one every `every` control steps of an FBSM episode."""
    import gymnasium as gym

    import auv_gym  # noqa: F401  (registers the env)
    import controllers
    from auv_gym.envs.rendering import EpisodeRenderer

    max_time = (frames * every + 1) * 0.05
    env = gym.make("AUVPath3D-v0", render_mode="rgb_array", max_time=max_time).unwrapped
    if not fast:
        env._renderer = EpisodeRenderer(env.config.path, max_time, fast=False)
    policy = controllers.make("fbsm")
    obs, _ = env.reset(seed=0)
    env.render()  # builds the figure: not part of the steady rate
    state, start = None, np.ones(1, dtype=bool)
    spent, drawn = 0.0, 0
    for k in range(1, frames * every + 1):
        action, state = policy.predict(obs[None], state, start)
        start[:] = False
        obs, *_ = env.step(action[0])
        if k % every == 0:
            began = time.perf_counter()
            env.render()
            spent += time.perf_counter() - began
            drawn += 1
    return {"frames": drawn, "frames_per_s": drawn / spent, "ms_per_frame": 1e3 * spent / drawn}


@dataclass
class Options:
    """The command line of `auv-gym speed render`."""

    frames: int = option(300, "timed frames of the fast path")
    every: int = option(1, "control steps between frames")
    reference_frames: int = option(20, "timed frames of the full-redraw reference; 0 skips it")


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    args, parser = parse_options(Options, argv, program_name("benchmarks.speed.render"), __doc__)
    if args.frames < 1 or args.every < 1 or args.reference_frames < 0:
        parser.error("--frames and --every must be >= 1, --reference-frames >= 0")
    results = {"fast": measure(args.frames, args.every, fast=True)}
    if args.reference_frames:
        results["full redraw"] = measure(args.reference_frames, args.every, fast=False)
    print("\nrgb_array frames (960 × 320 px), FBSM on the paper scenario")
    print(f"{'path':<12} {'frames':>7} {'frames/s':>9} {'ms/frame':>9}")
    for name, r in results.items():
        print(f"{name:<12} {r['frames']:>7} {r['frames_per_s']:>9.1f} {r['ms_per_frame']:>9.2f}")
    return results


if __name__ == "__main__":
    main()
