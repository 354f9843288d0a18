"""Record a classical policy's demonstrations for an agent recipe, as a Minari dataset.

    auv-gym demos --policy fbsm_colos --config benchmarks/hyperparams/ppo_generalist.yml \\
        --episodes 64 --out runs/demos/generalist_fbsm_colos
    auv-gym demos --policy pid_as_built --config benchmarks/hyperparams/ppo_as_built.yml \\
        --episodes 64 --out runs/demos/as_built_pid
    auv-gym demos --policy fbsm_colos --task train --observation preview_integral --out ...

The episodes are drawn from the training distribution of the recipe (``--config``: its env id,
env keyword arguments, observation, stages and action box; ``--phase``: a schedule phase's, by
default the first PPO phase's) or of a task set of role "train" (``--task``, with
``--observation``); the dataset holds the agent's observations and the policy's commands in the
agent's action space (`benchmarks.training.demonstrations`, docs/usage.md "Jump start"). A jump
start (``jump_start: {dataset: OUT}``) clones it. Bad arguments are refused before any episode
with a one-line error and exit code 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from benchmarks.arguments import ArgumentParser, program_name, usage_errors
from benchmarks.options import add_options, from_args, option

__all__ = ["DemosOptions", "main", "source_of"]


@dataclass
class DemosOptions:
    """The options of `auv-gym demos`."""

    policy: str = option("fbsm_colos", "classical policy recorded (a controllers.CLASSICAL name)")
    out: str = option("runs/demos", "dataset folder to create (Minari layout: OUT/data/...)")
    config: str | None = option(
        None, "agent recipe (hyper-parameter or schedule file) whose training env is flown"
    )
    env_id: str | None = option(
        None, "env id: the config's section (None: its only one; AUVPath3DPreview-v0 with --task)"
    )
    phase: str | None = option(None, "schedule phase whose env is flown (None: the first PPO one)")
    task: str | None = option(None, "instead of --config: a task set of role 'train'")
    observation: str = option("preview_integral", "the agent's observation with --task")
    episodes: int = option(64, "episodes recorded")
    seed: int = option(0, "recording seed: episode k starts from reset seed 5e8 + 1e6·seed + k")
    vehicles: int = option(32, "episodes flown at once (one batched simulator)")
    progress: bool = option(True, "no progress bar", flag="--quiet", invert=True)


def source_of(opts: DemosOptions):  # -> DemoSource
    """The `DemoSource` of the options; ValueError naming the option otherwise."""
    from auv_gym import PREVIEW_ENV_ID, VARIANTS
    from benchmarks.training.config import read_zoo_config
    from benchmarks.training.demonstrations import DemoSource

    if (opts.config is None) == (opts.task is None):
        raise ValueError("give one of --config (an agent recipe) or --task (a task set)")
    if opts.task is not None:
        from benchmarks.catalog.tasks import load_task_sets

        sets = load_task_sets()
        train = sorted(name for name, s in sets.items() if s.role == "train")
        if opts.task not in sets or sets[opts.task].role != "train":
            raise ValueError(
                f"--task {opts.task!r}: demonstrations are training data; task sets of role "
                f"'train': {train}"
            )
        if opts.phase is not None:
            raise ValueError("--phase names a phase of a --config schedule")
        env_id = opts.env_id or PREVIEW_ENV_ID
        if env_id not in VARIANTS:
            raise ValueError(f"--env-id {env_id!r} is not one of {list(VARIANTS)}")
        kwargs = {**sets[opts.task].env, "observation": opts.observation}
        from auv_gym.sim.config import SimConfig
        from auv_gym.sim.observation import ObservationConfig

        try:
            ObservationConfig.from_spec(opts.observation)
        except ValueError as error:
            raise ValueError(f"--observation: {error}") from None

        SimConfig.from_kwargs(**{**VARIANTS[env_id], **kwargs})
        return DemoSource(env_id, kwargs, recipe={"task_set": opts.task})
    import yaml

    from benchmarks.training.schedule import SCHEDULE_KEY, read_schedule

    path = Path(opts.config)
    if not path.is_file():
        problem = "is a folder, not a hyper-parameter file" if path.is_dir() else "does not exist"
        raise ValueError(f"--config {str(path)!r} {problem}")
    schedule = read_schedule(path)
    recipe = {"config_file": str(path)}
    if schedule is not None:
        names = [p.name for p in schedule.phases]
        first = next((p.name for p in schedule.phases if "jump_start" not in p.changes), None)
        name = opts.phase or first or names[0]
        if name not in names:
            raise ValueError(f"--phase {name!r} is not a phase of {path}: {names}")
        k = names.index(name)
        section = {
            key: value
            for key, value in schedule.phase_section(k).items()
            if key != "jump_start"  # the recipe's env, not its imitation
        }
        if opts.env_id not in (None, schedule.env_id):
            raise ValueError(f"--env-id {opts.env_id!r}: {path} trains on {schedule.env_id}")
        env_id = schedule.env_id
        import tempfile

        with tempfile.TemporaryDirectory() as folder:
            single = Path(folder) / path.name
            single.write_text(yaml.safe_dump({env_id: section}, sort_keys=False))
            cfg = read_zoo_config(single, env_id, schedule.options.get("algo", "ppo"))
        recipe["phase"] = name
    else:
        if opts.phase is not None:
            raise ValueError(f"--phase: {path} has no schedule")
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        envs = [key for key in data if key != SCHEDULE_KEY]
        env_id = opts.env_id or (envs[0] if len(envs) == 1 else None)
        if env_id is None:
            raise ValueError(f"--env-id: {path} has several env sections {envs}; name one")
        cfg = read_zoo_config(path, env_id)
    return DemoSource.from_config(cfg, env_id, recipe)


def build_parser() -> argparse.ArgumentParser:
    from benchmarks.cli import HelpFormatter

    parser = ArgumentParser(
        prog=program_name("benchmarks.training.demos_cli"),
        description=__doc__,
        formatter_class=HelpFormatter,
    )
    parser.set_defaults(_names=add_options(parser, DemosOptions))
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    from benchmarks.arguments import writable_location
    from benchmarks.training.demonstrations import (
        MAX_DEMO_SEED,
        SEED_STRIDE,
        record_demonstrations,
    )
    from benchmarks.training.expert import check_expert_name

    parser = build_parser()
    args = parser.parse_args(argv)
    opts = from_args(DemosOptions, args, args._names)
    with usage_errors(parser):
        import minari  # noqa: F401  (the rl extra: `auv-gym` names it when missing)

        check_expert_name(opts.policy, "--policy")
        if not 1 <= opts.episodes <= SEED_STRIDE:
            raise ValueError(f"--episodes must be 1-{SEED_STRIDE}, got {opts.episodes}")
        if not 0 <= opts.seed <= MAX_DEMO_SEED:
            raise ValueError(f"--seed must be 0-{MAX_DEMO_SEED}, got {opts.seed}")
        if opts.vehicles < 1:
            raise ValueError(f"--vehicles must be >= 1, got {opts.vehicles}")
        out = Path(opts.out)
        if out.exists() and (not out.is_dir() or any(out.iterdir())):
            raise ValueError(f"--out {str(out)!r} exists and is not an empty folder")
        writable_location(out, "--out")
        source = source_of(opts)
        from benchmarks.training.expert import ExpertLabels

        ExpertLabels(
            opts.policy,
            source.full_kwargs,
            source.obs_names,
            source.stages,
            source.action_bounds,
            "--policy",
        )
    result = record_demonstrations(
        source, opts.policy, out, opts.episodes, opts.seed, opts.vehicles, opts.progress
    )
    print(
        f"wrote {result['path']} ({result['dataset_id']}): {result['episodes']} episodes, "
        f"{result['steps']} steps, mean return {result['return_mean']:.1f}, "
        f"{result['terminated']} terminated, {result['bytes'] / 1e6:.1f} MB, "
        f"in {result['wall_s']:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
