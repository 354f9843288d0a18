"""An episode as an MCAP file of ROS 2 messages, for Foxglove and ``ros2 bag`` (mcap extra).

    auv-gym record --policy fbsm --scenario paper --seed 0 --duration 300 --out out/run.mcap

The policy (`benchmarks.catalog.policies` spec) flies one seeded episode of a scenario of
`benchmarks/scenarios.toml` (`auv_gym.rollout.rollout`, as `auv-gym compare` runs it: the same
seed gives the same episode) and `benchmarks.reports.mcap_export` writes it: odometry, tf, the
path, the virtual point, the path-following errors, the commands, the disturbance and the reward,
in ENU/FLU frames (REP-103) stamped with the sim time that /clock publishes (docs/usage.md,
"Episodes for ROS tools"). The file appears atomically when complete.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym import VARIANTS
from auv_gym.sim.config import MAX_EPISODE_TIME, SimConfig
from benchmarks.arguments import ArgumentParser, finite_number, parse_checked, program_name
from benchmarks.cli import HelpFormatter
from benchmarks.options import add_options, option
from benchmarks.reports.one_episode import OneEpisodeOptions, resolve_episode

__all__ = ["RecordEpisodeOptions", "check_output", "episode_path", "main", "record"]


@dataclass
class RecordEpisodeOptions(OneEpisodeOptions):
    """The options of `auv-gym record`: the episode's (`OneEpisodeOptions`), then the file."""

    out: Path = option(Path("run.mcap"), "MCAP file (.mcap) in an existing folder")  # noqa: RUF009


def build_parser() -> argparse.ArgumentParser:
    """The parser of `RecordEpisodeOptions` (each option's default and help from its field)."""
    parser = ArgumentParser(
        prog=program_name("benchmarks.reports.record"),
        description=__doc__,
        formatter_class=HelpFormatter,
    )
    add_options(parser, RecordEpisodeOptions)
    return parser


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The arguments, every one checked before the episode runs (a bad one exits with code 2
    and a one-line message): ranges, the output file, the scenario, the policy."""
    return parse_checked(build_parser(), argv, check_args)


def check_output(out: Path) -> Path:
    """``out`` if an .mcap file can be written there: its folder exists and is writable, and
    it is not a folder; else ValueError / OSError naming the path."""
    if out.suffix.lower() != ".mcap":
        raise ValueError(f"--out must name an .mcap file, got {str(out)!r}")
    folder = out.parent
    if out.is_dir():
        problem = "it is a folder"
    elif not folder.exists():
        problem = f"its folder {str(folder)!r} does not exist"
    elif not folder.is_dir():
        problem = f"{str(folder)!r} is a file, not a folder"
    else:
        problem = None
        try:
            with tempfile.NamedTemporaryFile(dir=folder, prefix=".write-test-", suffix=".tmp"):
                pass
        except OSError as error:
            problem = f"its folder {str(folder)!r} is not writable ({error.strerror or error})"
    if problem is not None:
        raise OSError(f"--out {str(out)!r} cannot be written: {problem}")
    return out


def check_args(args: argparse.Namespace) -> None:
    """Validate ``args``; adds ``env_kwargs``, ``env_id``, ``config`` and ``policy_object``
    (built for the scenario). ValueError / OSError naming the argument; ModuleNotFoundError
    without the mcap extra (`auv-gym` names the extra), before any episode."""
    import mcap_ros2.writer  # noqa: F401

    finite_number("--duration", args.duration, 0.0, MAX_EPISODE_TIME, low_open=True, unit="s")
    check_output(args.out)
    added = resolve_episode(args)  # sets args.env_id
    args.env_kwargs = {**VARIANTS[args.env_id], **added}


def episode_path(env_kwargs: dict[str, Any], seed: int) -> Any:
    """The path (`auv_gym.paths.Path`) of the episode of ``seed``: drawn by the same reset as
    `auv_gym.rollout.rollouts` (a fixed path for a fixed task, a drawn one for a drawn task)."""
    from gymnasium.utils import seeding

    from auv_gym.sim.simulator import Simulator

    sim = Simulator(SimConfig.from_kwargs(**env_kwargs), 1)
    sim.reset_row(0, seeding.np_random(seed)[0])
    return sim.paths[0]


def record(
    policy: Any,
    env_kwargs: dict[str, Any],
    out: Path,
    seed: int = 0,
    facts: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Fly ``policy`` on the episode of ``seed`` and write it to ``out`` (`write_episode_mcap`).

    ``facts`` (policy spec, scenario, env id…) go into the file's metadata. Returns the
    samples, episode time [s], its end, the file size [bytes] and the wall time [s]. An episode
    that cannot be built or run raises RuntimeError naming ``out`` (nothing is written); so does
    a write that fails (no partial file is left).
    """
    from auv_gym.rollout import rollout
    from benchmarks.reports.mcap_export import path_points, write_episode_mcap

    began = time.perf_counter()
    carried = getattr(policy, "env_kwargs", None)  # as `rollouts` merges an agent's env
    env = {**carried, **env_kwargs} if isinstance(carried, dict) else dict(env_kwargs)
    try:
        trajectory = rollout(policy, seed, **env)
        points = path_points(episode_path(env, seed), trajectory)
    except Exception as error:  # a policy's or env's own error, said in one line
        raise RuntimeError(
            f"{str(out)!r} not written: the episode failed to build or run "
            f"({type(error).__name__}: {error})"
        ) from error
    try:
        write_episode_mcap(trajectory, out, path=points, facts={"seed": seed, **(facts or {})})
    except OSError as error:
        raise RuntimeError(f"{str(out)!r} not written: {error.strerror or error}") from error
    return {
        "samples": trajectory.steps + 1,
        "episode_s": trajectory.duration,
        "end": trajectory.termination_reason,
        "bytes": os.path.getsize(out),
        "wall_s": time.perf_counter() - began,
    }


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    prog = build_parser().prog
    try:
        result = record(
            args.policy_object,
            args.env_kwargs,
            args.out,
            args.seed,
            {
                "policy": args.policy,
                "scenario": args.scenario,
                "env_id": args.env_id,
                "duration": args.duration,
            },
        )
    except RuntimeError as error:
        print(f"{prog}: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 1
    print(
        f"wrote {args.out}: {result['samples']} samples of a {result['episode_s']:g}-s episode "
        f"({result['end']}), {result['bytes'] / 1e6:.2f} MB, in {result['wall_s']:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
