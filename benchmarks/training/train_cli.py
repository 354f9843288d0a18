"""Train an RL agent (PPO by default; ``--algo`` any algorithm of `controllers.algorithms`) from
an RL-Zoo hyper-parameter file (default: the paper helix under the 2.0 m/s surge limit,
`AUVPath3DSpeedLimit-v0`).

One seed on the paper's own task, the unlimited `AUVPath3D-v0` with its 15-entry observation
(the recipe of the retired helix specialist, docs/results.md "Retired: the helix specialist")::

    python -m benchmarks.training.train_cli --seed 1 \\
        --config benchmarks/hyperparams/ppo_helix.yml \\
        --env-id AUVPath3D-v0 --out runs/ppo_helix --export runs/ppo_helix/agent \\
        --curve runs/ppo_helix/curve

An interrupted run continues from its newest checkpoint (step counter intact) with the same
command plus ``--resume``. Watch it with ``tensorboard --logdir runs/ppo_helix/tb``. The learning
curve of a run (evaluation rms distance against env steps and wall time) is plotted with::

    python -m benchmarks.training.train_cli --out runs/ppo_helix --plot-only \\
        --curve runs/ppo_helix/curve

and an agent is evaluated on the paper scenario over the held-out seeds 0-9 (300 s; the result
goes to AGENT/held_out_evaluation.json, which ``--export`` also writes) with::

    python -m benchmarks.training.train_cli --evaluate runs/ppo_helix/agent

The same YAML file works with RL Zoo (optional, not a dependency of auv-gym)::

    python -m rl_zoo3.train --algo ppo --env AUVPath3D-v0 --gym-packages auv_gym \\
        -conf benchmarks/hyperparams/ppo_helix.yml

Outputs and file formats: see `benchmarks.training`; the agents load with
``controllers.make("agent", path=...)``.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from benchmarks.arguments import (
    ArgumentParser,
    exit_with_usage_error,
    locked_folder,
    program_name,
    writable_location,
)
from benchmarks.cli import HelpFormatter
from benchmarks.options import add_options, from_args, option
from benchmarks.reports.figures import plot_learning_curve
from benchmarks.training import TrainOptions, train, write_held_out_evaluation
from benchmarks.training.checkpoints import check_export_folder
from benchmarks.training.learning_curve import EVAL_FILE
from benchmarks.training.schedule import read_schedule
from benchmarks.training.seeds import MAX_SEED
from benchmarks.training.train import check_options, check_run_folder, default_config
from controllers.agent import METADATA_FILE, check_agent

FIXED = {"eval_env": {}}  # TrainOptions this CLI does not offer (paper eval)


@dataclass
class CommandOptions:
    """The options of this command beside `TrainOptions`: plotting and held-out evaluation."""

    curve: str | None = option(
        None, "write the learning curve to CURVE.csv and CURVE.png at the end"
    )
    plot_only: bool = option(False, "only plot the learning curve of --out (needs --curve)")
    evaluate: str | None = option(
        None,
        "only evaluate AGENT on the held-out seeds 0-9 (paper "
        "scenario, under the env id AGENT records) and write AGENT/held_out_evaluation.json",
        metavar="AGENT",
    )


def parse_args(argv: Sequence[str] | None = None) -> tuple[TrainOptions, CommandOptions]:
    """TrainOptions (every field the dataclass offers is an option) and the plotting options."""
    parser = ArgumentParser(
        prog=program_name("benchmarks.training.train_cli"),
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    command = add_options(parser, CommandOptions, negatable=False)
    names = add_options(parser, TrainOptions)
    ns = parser.parse_args(argv)
    if ns.config is None:
        try:
            ns.config = default_config(ns.algo)
        except ValueError as error:
            parser.error(str(error))
    extra = from_args(CommandOptions, ns, command)
    if extra.plot_only and not extra.curve:
        parser.error("--plot-only needs --curve")
    return from_args(TrainOptions, ns, names, **FIXED), extra


def check_outputs(opts: TrainOptions, extra: CommandOptions) -> None:
    """Everything this command will write or read later, checked before the first training
    step: the run folder, the export folder, the learning-curve files (which need
    evaluations), the agent to evaluate. OSError / ValueError naming the option otherwise."""
    if extra.evaluate:
        check_agent(Path(extra.evaluate))
        writable_location(extra.evaluate, "--evaluate")  # AGENT/held_out_evaluation.json
        return
    if not MAX_SEED >= opts.seed >= 0:
        raise ValueError(f"--seed must be an integer in [0, {MAX_SEED}], got {opts.seed}")
    if extra.plot_only:
        if not (Path(opts.out) / EVAL_FILE).is_file():
            raise FileNotFoundError(f"--plot-only: {Path(opts.out) / EVAL_FILE} does not exist")
    else:
        writable_location(opts.out, "--out")
        if opts.export:
            writable_location(opts.export, "--export")
            check_export_folder(opts.export, "--export", opts.out)
        if extra.curve and opts.eval_freq == 0:
            raise ValueError("--curve plots the evaluations, and --eval-freq 0 makes none")
    if extra.curve:
        for suffix in (".csv", ".png"):
            writable_location(Path(extra.curve).with_suffix(suffix), "--curve", folder=False)


def training_report(out: Path, export: str | None = None) -> str:
    """One summary line of a finished (or paused) run: the best evaluation, its step, score and
    terminations, and where the agent went; a loud warning when the best agent is the untrained
    network of step 0 (every later evaluation scored worse), which an export would ship."""
    best_file = Path(out) / "best" / METADATA_FILE
    if not best_file.is_file():
        return f"training: no evaluation ran (--eval-freq 0); the final agent is {out}/final" + (
            f", exported to {export}" if export else ""
        )
    best = json.loads(best_file.read_text()).get("best", {})
    summary, step = best.get("summary", {}), int(best.get("num_timesteps", 0))
    line = (
        f"training: best evaluation at step {step:,}: mean RMS distance "
        f"{summary.get('rms_distance_mean', float('nan')):.4g} m, "
        f"{summary.get('n_terminated', '?')} of {summary.get('n_episodes', '?')} episodes "
        f"ended early; " + (f"exported to {export}" if export else f"agent in {out}/best")
    )
    if step == 0:
        line += (
            "\nWARNING: the best agent is the UNTRAINED network of step 0 (no later evaluation "
            "scored better)"
            + (f"; {export} holds it" if export else "")
            + ". Train longer, or check the reward and the evaluation episodes."
        )
    return line


def refuse_schedule(config: str | Path) -> None:
    """ValueError when ``config`` holds a schedule: this command trains its env section once,
    and leaving the phases out without a word would train another recipe than the file's."""
    schedule = read_schedule(config)
    if schedule is not None:
        raise ValueError(
            f"{config} holds a schedule of {len(schedule.phases)} phase(s), which `auv-gym "
            f"train` does not run (it trains one section once): run the recipe with "
            f"`auv-gym train-seeds --config {config}`"
        )


def main(argv: Sequence[str] | None = None) -> None:
    args = list(sys.argv[1:] if argv is None else argv)
    opts, extra = parse_args(args)
    prog = program_name("benchmarks.training.train_cli")
    try:  # bad options: one line and exit code 2, before any training starts
        check_outputs(opts, extra)
        if not extra.plot_only and not extra.evaluate:
            check_options(opts)
            refuse_schedule(opts.config)
            check_run_folder(opts)
    except (ValueError, OSError) as exc:
        exit_with_usage_error(prog, exc)
    if extra.evaluate:
        # under the env id the agent records (its surge limit, its scenario label), as the
        # reproduction check re-evaluates it, never this command's --env-id default
        report = write_held_out_evaluation(extra.evaluate, opts.eval_duration)
        print(json.dumps(report["summary"], indent=2))
        return
    if not extra.plot_only:
        # One run per folder: a second one is refused, a killed one's temporary files removed.
        with locked_folder(prog, Path(opts.out)):
            out = train(opts, argv=["benchmarks.training.train_cli", *args])
        print(f"run directory: {out}")
        print(training_report(out, opts.export), file=sys.stderr)
    if extra.curve:
        plot_learning_curve(Path(opts.out), Path(extra.curve))


if __name__ == "__main__":
    main()
