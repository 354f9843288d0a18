"""Train N seeds of one RL configuration: local parallel processes by default, or a Ray cluster.

Examples (see `benchmarks.training.seeds` for the layout, resuming and the agent selection)::

    python -m benchmarks.training.seeds_cli --algo ppo --env-id AUVPath3D-v0 \\
        --config benchmarks/hyperparams/ppo_helix.yml --seeds 0-4 --workers 2 \\
        --out runs/ppo_helix --export runs/ppo_helix/agent
    python -m benchmarks.training.seeds_cli ... --resume          # continue a killed run
    python -m benchmarks.training.seeds_cli ... --backend ray --address HOST:6379

``--seeds`` is a count N (seeds 0..N-1), a range a-b or a list a,b,c. Bad input is refused
before any training starts with a one-line error and exit code 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from benchmarks.arguments import ArgumentParser
from benchmarks.options import add_options, from_args
from benchmarks.training.schedule import SCHEDULE_FILE, read_schedule, train_schedule
from benchmarks.training.seeds import SUMMARY_FILE, SeedsOptions, train_seeds
from benchmarks.training.train import TrainOptions, default_config

# The options of each dataclass, in the order --help lists them.
TRAIN_FIRST = ("algo", "config", "env_id", "init_from")
SEEDS_FIRST = ("seeds", "workers", "backend", "address", "out", "resume")
TRAIN_BUDGET = (
    "n_timesteps",
    "stop_at",
    "eval_seeds",
    "eval_duration",
    "eval_freq",
    "checkpoint_freq",
    "keep_checkpoints",
)
SEEDS_EVALUATION = ("task_set", "eval_episodes")
TRAIN_ENVS = ("vec_env", "threads")
SEEDS_OUTPUTS = ("export", "results", "progress")


def build_parser() -> argparse.ArgumentParser:
    from benchmarks.arguments import program_name
    from benchmarks.cli import HelpFormatter

    p = ArgumentParser(
        prog=program_name("benchmarks.training.seeds_cli"),
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    for cls, names in (
        (TrainOptions, TRAIN_FIRST),
        (SeedsOptions, SEEDS_FIRST),
        (TrainOptions, TRAIN_BUDGET),
        (SeedsOptions, SEEDS_EVALUATION),
        (TrainOptions, TRAIN_ENVS),
        (SeedsOptions, SEEDS_OUTPUTS),
    ):
        add_options(p, cls, names, negatable=False)
    return p


def parse_args(argv: Sequence[str] | None = None) -> SeedsOptions:
    """SeedsOptions from the command line; bad input exits with code 2 and one line. A
    schedule file's ``options`` (`benchmarks.training.schedule`) are the defaults of the options
    it names, and its env section the default env id: the command line wins."""
    parser = build_parser()
    ns = parser.parse_args(argv)
    if ns.config is not None:
        try:
            schedule = read_schedule(ns.config)
        except ValueError as error:
            parser.error(str(error))
        if schedule is not None:
            parser.set_defaults(**schedule.options, env_id=schedule.env_id)
            ns = parser.parse_args(argv)
    if ns.config is None:
        try:
            ns.config = default_config(ns.algo)
        except ValueError as error:
            build_parser().error(str(error))
    train_names = TRAIN_FIRST + TRAIN_BUDGET + TRAIN_ENVS
    train = from_args(TrainOptions, ns, train_names, progress_bar=False)
    return from_args(SeedsOptions, ns, SEEDS_FIRST + SEEDS_EVALUATION + SEEDS_OUTPUTS, train=train)


def main(argv: Sequence[str] | None = None) -> int:
    from benchmarks.arguments import program_name

    opts = parse_args(argv)
    prog = program_name("benchmarks.training.seeds_cli")  # auv-gym train-seeds when installed
    summary_file = Path(opts.out) / SUMMARY_FILE
    try:
        schedule = read_schedule(opts.train.config)
        how = "validation"
        if schedule is not None:
            record = train_schedule(opts, schedule)
            summary = {**record["phases"][-1]["summary"], "selected_seed": record["selected_seed"]}
            if "shipped_selection" in record:
                how = "validation, as shipped"
            summary_file = Path(opts.out) / SCHEDULE_FILE  # each phase's summary, the selection
        else:
            summary = train_seeds(opts)
    except (ValueError, FileNotFoundError) as exc:  # refused before any training started
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except RuntimeError as exc:  # a seed failed; the others are finished
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    best = next(e for e in summary["seeds"] if e["seed"] == summary["selected_seed"])
    for entry in summary["seeds"]:
        test = entry["test_summary"]
        print(
            f"seed {entry['seed']}: {entry['num_timesteps']} steps, {entry['wall_time_s']:.0f} s;"
            f" test rms distance {test['rms_distance_mean']:.4g} m, {test['n_terminated']} "
            f"terminated, max surge {test['max_surge_max']:.3g} m/s"
        )
    print(f"selected seed {best['seed']} ({how}); summary: {summary_file}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
