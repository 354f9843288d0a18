"""An episode's video: the 3-D track and the path-following errors over time (MP4, H.264).

    auv-gym video --policy fbsm --scenario paper --out out/run.mp4 [--duration 300] [--every 5]

The policy (`benchmarks.catalog.policies` spec) runs one seeded episode of a scenario of
`benchmarks/scenarios.toml` through `gym.make(..., render_mode="rgb_array")`; a frame
(`auv_gym.envs.rendering`) is taken every ``--every`` control steps and played at ``--fps``, so the
video runs ``every · control_dt · fps`` times faster than the episode (default 5 × 0.05 s × 20
fps = 5×: a 300-s episode becomes a 60-s video of 1200 frames). Frames stream to the ffmpeg
binary of imageio-ffmpeg (the video extra) and the file appears atomically when complete.
`gymnasium.wrappers.RecordVideo` works on the same env (it needs moviepy, also in the extra).
"""

from __future__ import annotations

import argparse
import glob
import os
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from auv_gym.support.files import process_alive
from benchmarks.arguments import (
    ArgumentParser,
    parse_checked,
    program_name,
    writable_location,
)
from benchmarks.cli import HelpFormatter
from benchmarks.options import add_options, option
from benchmarks.reports.one_episode import OneEpisodeOptions, resolve_episode


@dataclass
class VideoOptions(OneEpisodeOptions):
    """The options of `auv-gym video`: the episode's (`OneEpisodeOptions`), then the video's."""

    every: int = option(5, "control steps between frames")
    fps: int = option(20, "frames per second of the video")
    out: Path = option(Path("out/run.mp4"), "video file (.mp4); its folder is created")  # noqa: RUF009
    progress: bool = option(True, "no progress bar", flag="--quiet", invert=True)


def build_parser() -> argparse.ArgumentParser:
    """The parser of `VideoOptions` (each option's default and help from its field)."""
    parser = ArgumentParser(
        prog=program_name("benchmarks.reports.video"),
        description=__doc__,
        formatter_class=HelpFormatter,
    )
    add_options(parser, VideoOptions)
    return parser


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The arguments, every one checked before the episode runs (a bad one exits with code 2
    and a one-line message): ranges, the scenario, the policy, the video file's folder."""
    return parse_checked(build_parser(), argv, check_args)


def check_args(args: argparse.Namespace) -> None:
    """Validate ``args``; adds ``env_kwargs``, ``control_dt`` and ``policy_object`` (built for
    the scenario). ValueError / OSError naming the argument."""
    if not (0 < args.duration <= 1e5):
        raise ValueError(f"--duration must be in (0, 1e5] s, got {args.duration}")
    if not (1 <= args.every <= 10_000 and 1 <= args.fps <= 240):
        raise ValueError(
            f"--every must be in [1, 10000] and --fps in [1, 240], got {args.every} and {args.fps}"
        )
    if args.out.suffix.lower() != ".mp4":
        raise ValueError(f"--out must name an .mp4 file, got {args.out}")
    args.env_kwargs = resolve_episode(args)  # gym.make adds the env id's fixed arguments
    args.control_dt = args.config.control_dt
    writable_location(args.out, "--out", folder=False)


def remove_stale_videos(out: Path) -> list[Path]:
    """Remove the temporary videos (``.NAME.<pid>.tmp.mp4``) beside ``out`` that runs killed
    mid-recording left; a live recorder's file (its pid still runs) is kept."""
    removed = []
    pattern = re.compile(re.escape(f".{out.name}.") + r"(\d+)\.tmp\.mp4")
    for file in out.parent.glob(f".{glob.escape(out.name)}.*.tmp.mp4"):
        match = pattern.fullmatch(file.name)
        if match and not process_alive(int(match.group(1))):
            file.unlink(missing_ok=True)
            removed.append(file)
    return removed

    return True


def record(
    policy: object,
    env_kwargs: dict,
    out: Path,
    seed: int = 0,
    every: int = 5,
    fps: int = 20,
    progress: bool = True,
    env_id: str = "AUVPath3D-v0",
) -> dict[str, float]:
    """Run one episode of ``policy`` under ``env_id`` and write its video to ``out`` atomically.

    Returns frames, episode time [s], wall time [s] and the reason the episode ended.
    """
    import gymnasium as gym
    import imageio_ffmpeg
    from tqdm.auto import tqdm

    import auv_gym  # noqa: F401  (registers the env)

    env = gym.make(env_id, render_mode="rgb_array", **env_kwargs).unwrapped
    steps = env.spec.max_episode_steps if env.spec else env.config.max_steps
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp.mp4")
    began = time.perf_counter()
    obs, _ = env.reset(seed=seed)
    first = env.render()
    height, width = first.shape[:2]
    writer = imageio_ffmpeg.write_frames(
        str(tmp),
        (width, height),
        fps=fps,
        codec="libx264",
        pix_fmt_out="yuv420p",
        macro_block_size=16,
        quality=6,
        ffmpeg_log_level="error",
    )
    frames, end = 0, "time_limit"
    try:
        writer.send(None)
        writer.send(np.ascontiguousarray(first))
        frames += 1
        state, start = None, np.ones(1, dtype=bool)
        bar = tqdm(total=steps, desc="control steps", unit="step", disable=not progress)
        for k in range(1, steps + 1):
            action, state = policy.predict(obs[None], state, start)
            start[:] = False
            obs, _, terminated, truncated, info = env.step(np.asarray(action)[0])
            bar.update(1)
            done = terminated or truncated
            if k % every == 0 or done:
                writer.send(np.ascontiguousarray(env.render()))
                frames += 1
            if done:
                end = info.get("termination_reason", "time_limit")
                break
        bar.close()
        writer.close()
        os.replace(tmp, out)
    finally:
        writer.close()
        tmp.unlink(missing_ok=True)
    return {
        "frames": frames,
        "episode_s": float(info["t"]),
        "wall_s": time.perf_counter() - began,
        "end": end,
    }


def main(argv: Sequence[str] | None = None) -> dict[str, float]:
    args = parse_args(argv)
    remove_stale_videos(args.out)
    result = record(
        args.policy_object,
        args.env_kwargs,
        args.out,
        args.seed,
        args.every,
        args.fps,
        progress=not args.quiet,
        env_id=args.env_id,
    )
    speedup = args.every * args.control_dt * args.fps
    print(
        f"wrote {args.out}: {result['frames']} frames at {args.fps} fps "
        f"({result['frames'] / args.fps:.1f} s of video, {speedup:g}× the episode's pace) "
        f"of a {result['episode_s']:g}-s episode ({result['end']}) "
        f"in {result['wall_s']:.1f} s"
    )
    return result


if __name__ == "__main__":
    main()
