"""Train N seeds of one RL configuration: local parallel processes by default, or a Ray cluster.

Examples (see `benchmarks.training.seeds` for the layout, resuming and the agent selection)::

    python -m benchmarks.train_seeds --algo ppo --env-id AUVPath3DSpeedLimit-v0 \\
        --config benchmarks/hyperparams/ppo.yml --seeds 0-4 --workers 2 --out runs/ppo_helix_v1 \\
        --export benchmarks/agents/ppo_helix_v1 --results benchmarks/results/seeds/ppo_helix_v1
    python -m benchmarks.train_seeds ... --resume          # continue a killed run
    python -m benchmarks.train_seeds ... --backend ray --address HOST:6379

``--seeds`` is a count N (seeds 0..N-1), a range a-b or a list a,b,c. Bad input is refused
before any training starts with a one-line error and exit code 2.
"""

from __future__ import annotations

import argparse
import sys
import typing
from collections.abc import Sequence
from pathlib import Path

from benchmarks.training.config import ALGORITHMS
from benchmarks.training.evaluation import EVAL_SEEDS
from benchmarks.training.seeds import (
    DEFAULT_EVAL_EPISODES,
    TASK_SETS,
    SeedsOptions,
    parse_seeds,
    train_seeds,
)
from benchmarks.training.train import TrainOptions

HYPERPARAMS = Path(__file__).resolve().parents[1] / "hyperparams"


def _number(text: str) -> int:
    """Integers, also written as floats ("2e6"); fractions are an error, not truncated."""
    value = float(text)
    if value != int(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number")
    return int(value)


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> typing.NoReturn:
        """One line and exit code 2 (argparse prints the usage too)."""
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    from benchmarks.arguments import program_name
    from benchmarks.cli import HelpFormatter

    p = _Parser(prog=program_name("benchmarks.train_seeds"), description=__doc__.split("\n\n")[0],
                formatter_class=HelpFormatter)  # fmt: skip
    p.add_argument("--algo", choices=sorted(ALGORITHMS), default="ppo", help="RL algorithm")
    p.add_argument("--config", default=None,
                   help="RL-Zoo YAML (default benchmarks/hyperparams/<algo>.yml)")  # fmt: skip
    p.add_argument("--env-id", default="AUVPath3DSpeedLimit-v0",
                   help="Gymnasium id and YAML key (default: the 2.0 m/s surge limit)")  # fmt: skip
    p.add_argument("--seeds", required=True, help="count N, range a-b or list a,b,c")
    p.add_argument("--workers", type=int, default=2, help="seeds trained at once")
    p.add_argument("--backend", choices=("local", "ray"), default="local",
                   help="local processes or a Ray cluster")  # fmt: skip
    p.add_argument("--address", default=None, help="Ray cluster address (host:port)")
    p.add_argument("--out", required=True, help="multi-seed run directory")
    p.add_argument("--resume", action="store_true", help="continue every unfinished seed")
    p.add_argument("--n-timesteps", type=_number, default=None,
                   help="env steps per seed (default: the config's)")  # fmt: skip
    p.add_argument("--stop-at", type=_number, default=None,
                   help="pause every seed at the first rollout start at or after this many "
                   "env steps; schedules still run over --n-timesteps, and a later --resume "
                   "continues them bit for bit as if never paused")  # fmt: skip
    p.add_argument("--eval-seeds", default=",".join(map(str, EVAL_SEEDS)),
                   help="validation seeds (disjoint from the test seeds 0-9)")  # fmt: skip
    p.add_argument("--eval-duration", type=float, default=300.0, help="evaluation episode [s]")
    p.add_argument("--eval-freq", type=_number, default=100_000, help="env steps between evals")
    p.add_argument(
        "--checkpoint-freq",
        type=_number,
        default=100_000,
        help="env steps between checkpoints (a kill loses at most this many)",
    )
    p.add_argument("--keep-checkpoints", type=int, default=2,
                   help="newest checkpoints kept per seed")  # fmt: skip
    p.add_argument("--task-set", default="paper",
                   help=f"validation episodes: {sorted(TASK_SETS)} or a validation set of "
                   "benchmarks/tasks.toml (e.g. 'validation')")  # fmt: skip
    p.add_argument("--eval-episodes", type=int, default=DEFAULT_EVAL_EPISODES,
                   help="validation episodes taken from a task set (its first seeds)")  # fmt: skip
    p.add_argument("--vec-env", default="auto", choices=("auto", "native", "dummy"),
                   help="training envs: native vector env, SB3 DummyVecEnv, or auto")  # fmt: skip
    p.add_argument("--threads", type=int, default=1, help="torch/numba threads per seed")
    p.add_argument("--export", default=None, help="copy the selected agent here")
    p.add_argument(
        "--results", default=None, help="write every seed's test evaluation and learning curve here"
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def parse_args(argv: Sequence[str] | None = None) -> SeedsOptions:
    """SeedsOptions from the command line; bad input exits with code 2 and one line."""
    parser = build_parser()
    ns = parser.parse_args(argv)
    try:
        seeds = parse_seeds(ns.seeds)
        eval_seeds = tuple(int(s) for s in ns.eval_seeds.split(",") if s.strip())
    except ValueError as exc:
        parser.exit(2, f"{parser.prog}: error: {exc}\n")
    config = ns.config or str(HYPERPARAMS / f"{ns.algo}.yml")
    train = TrainOptions(
        algo=ns.algo, config=config, env_id=ns.env_id, n_timesteps=ns.n_timesteps,
        stop_at=ns.stop_at, checkpoint_freq=ns.checkpoint_freq,
        keep_checkpoints=ns.keep_checkpoints,
        eval_freq=ns.eval_freq, eval_seeds=eval_seeds, eval_duration=ns.eval_duration,
        vec_env=ns.vec_env, threads=ns.threads, progress_bar=False,
    )  # fmt: skip
    return SeedsOptions(
        train=train, seeds=seeds, out=ns.out, workers=ns.workers, backend=ns.backend,
        address=ns.address, resume=ns.resume, task_set=ns.task_set, export=ns.export,
        eval_episodes=ns.eval_episodes, results=ns.results, progress=not ns.quiet,
    )  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    opts = parse_args(argv)
    prog = "python -m benchmarks.train_seeds"
    try:
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
    print(f"selected seed {best['seed']} (validation); summary: {Path(opts.out) / 'summary.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
