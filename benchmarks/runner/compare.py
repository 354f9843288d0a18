"""Classical controllers and agents (any Policy) on the same seeded scenarios.

    python -m benchmarks.runner.compare \\
        --policies fbsm,backstepping,ppo_generalist,fbsm_ilos,backstepping_ilos \\
        --scenarios all --seeds 10 --duration 300 --workers 2 --out benchmarks/results/full

Jobs are (policy, scenario, seed) episodes (`benchmarks.runner.jobs`): each finished episode is
stored under ``OUT/episodes/`` with a fingerprint of everything that determines it, so an
interrupted run restarted with the same arguments reuses finished episodes, and results do not
depend on the number of workers or the backend. The time series (.npz) of the first seed, which
the figures draw, are kept beside the records; ``--trajectories all`` keeps every episode's.
Policies: `benchmarks.catalog.policies`; scenarios: `benchmarks/scenarios.toml`; tables:
`benchmarks.reports.tables` (summary.md opens with the overview and the list of figures);
figures: `benchmarks.reports.figures`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from auv_gym import VARIANTS
from auv_gym.metrics import check_window
from auv_gym.sim.config import SimConfig, TopSpeedError
from auv_gym.support.files import replace_outputs
from benchmarks.arguments import (
    ArgumentParser,
    EpisodeOptions,
    check_episode_arguments,
    comma_names,
    locked_folder,
    parse_checked,
    program_name,
    writable_folder,
)
from benchmarks.catalog.policies import (
    POLICY_SPEC_FORMS,
    check_policy_for_env,
    check_policy_spec,
    policy_env,
    policy_label,
    policy_names,
)
from benchmarks.catalog.scenarios import SCENARIOS_FILE, load_scenarios, select
from benchmarks.cli import HelpFormatter
from benchmarks.options import add_options, option
from benchmarks.reports.tables import overview, overview_note, write_tables
from benchmarks.runner.jobs import Job, run_jobs
from controllers.registry import NoFiveDofModelError

MAX_SEEDS = 100_000  # seeds per scenario
TABLES = ("episodes.csv", "episodes.json", "summary.md")  # `benchmarks.reports.tables.write_tables`
MAX_EPISODES = 1_000_000  # episodes of one run: each is a job held in memory and on disk


@dataclass
class CompareOptions(EpisodeOptions):
    """The options of `auv-gym compare` (and the episode runner's, `EpisodeOptions`)."""

    policies: str = option(
        "fbsm,backstepping,ppo_generalist",
        f"comma-separated: {', '.join(policy_names())}, {POLICY_SPEC_FORMS}",
    )
    scenarios: str = option("all", "comma-separated names of --scenario-file or 'all'")
    # A Path is immutable: one shared default is safe.
    scenario_file: Path = option(  # noqa: RUF009
        SCENARIOS_FILE, "TOML file of named scenarios (env keyword arguments)"
    )
    seeds: int = option(10, f"seeds 0..N-1 per scenario, 1 <= N <= {MAX_SEEDS}")
    out: Path = option(  # noqa: RUF009
        Path("out/compare"), "output folder; a rerun with the same arguments resumes"
    )
    figures: bool = option(True, "tables only", flag="--no-figures", invert=True)
    trajectories: str = option(
        "first",
        "time series (.npz) kept under OUT/episodes/: the first seed's (what the figures draw) "
        "or every episode's",
        choices=("first", "all"),
    )
    progress: bool = option(True, "no progress bar", flag="--quiet", invert=True)


def build_parser() -> argparse.ArgumentParser:
    """The parser of `CompareOptions` (each option's default and help from its field)."""
    parser = ArgumentParser(
        prog=program_name("benchmarks.runner.compare"),
        description=__doc__.split("\n\n")[0],
        epilog=f"scenarios of the shipped --scenario-file: {', '.join(load_scenarios())}",
        formatter_class=HelpFormatter,
    )
    add_options(parser, CompareOptions)
    return parser


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The arguments, every one checked before any episode runs (a bad one exits with code 2
    and a one-line message). Adds ``jobs``, ``scenario_table`` (name → Scenario) and
    ``transient`` (resolved)."""
    return parse_checked(build_parser(), argv, check_args)


def check_args(args: argparse.Namespace) -> None:
    """Validate ``args`` and resolve them into jobs; ValueError/OSError naming the argument."""
    try:
        scenarios = load_scenarios(args.scenario_file)
    except OSError as error:
        raise OSError(f"--scenario-file {str(args.scenario_file)!r}: {error.strerror}") from None
    names = select(args.scenarios, list(scenarios), "scenario")
    policies = comma_names(args.policies, "--policies")
    labels: dict[str, str] = {}
    env_ids: dict[str, str] = {}
    agent_envs: dict[str, dict[str, Any]] = {}
    for spec in policies:
        check_policy_spec(spec)
        env_ids[spec], agent_envs[spec] = policy_env(spec)
        label = policy_label(spec)
        if label in labels:  # both would write OUT/episodes/<scenario>/<label>/
            raise ValueError(f"--policies {labels[label]!r} and {spec!r} share the label {label!r}")
        labels[label] = spec
    if not 1 <= args.seeds <= MAX_SEEDS:
        raise ValueError(f"--seeds must be an integer in [1, {MAX_SEEDS}], got {args.seeds}")
    episodes = args.seeds * len(names) * len(policies)
    if episodes > MAX_EPISODES:  # refused before the jobs are listed: no memory, no silence
        raise ValueError(
            f"--seeds {args.seeds} × {len(names)} scenarios × {len(policies)} "
            f"policies = {episodes} episodes, more than {MAX_EPISODES}"
        )
    check_episode_arguments(args)
    not_applicable: dict[str, dict[str, str]] = {}  # scenario -> policy -> why
    for name in names:
        scenario = scenarios[name]
        env_kwargs = {**scenario.env, "max_time": args.duration}
        try:
            config = SimConfig.from_kwargs(**env_kwargs)
            # one metrics-window rule (docs/design.md §3.9); it must hold a metric everywhere
            transient = check_window(args.duration, args.transient, config.control_dt)
            for spec in policies:  # as each job's env will build it, before any episode
                env = {**VARIANTS[env_ids[spec]], **agent_envs[spec], **env_kwargs}
                try:
                    check_policy_for_env(spec, env, scenario.controller)
                except NoFiveDofModelError as error:  # FBSM on the torpedo: an n/a cell
                    not_applicable.setdefault(name, {})[spec] = str(error)
                except TopSpeedError as error:  # an agent trained under 2 m/s at 2 m/s: n/a
                    not_applicable.setdefault(name, {})[spec] = (
                        f"policy {spec!r} runs under its vehicle's top speed "
                        f"({error.top_speed:g} m/s), which the scenario's desired speed "
                        f"({error.u_desired:g} m/s) reaches"
                    )
        except (TypeError, ValueError) as error:
            raise ValueError(f"scenario {name!r}: {error}") from None
    for spec in policies:
        if all(spec in not_applicable.get(name, {}) for name in names):
            reason = not_applicable[names[0]][spec]
            raise ValueError(f"--policies {spec!r} flies none of the chosen scenarios: {reason}")
    writable_folder(args.out)  # last: a bad argument above creates no folder
    args.transient = transient
    args.policy_list = policies
    args.env_ids = env_ids
    args.agent_envs = {spec: env for spec, env in agent_envs.items() if env}
    args.scenario_table = {n: scenarios[n] for n in names}
    args.not_applicable = not_applicable
    args.jobs = [
        Job(
            policy,
            scenarios[name],
            seed,
            args.duration,
            args.transient,
            env_ids[policy],
            agent_envs[policy],
            keep_trajectory=args.trajectories == "all" or seed == 0,
        )
        for name in names
        for policy in policies
        if policy not in not_applicable.get(name, {})
        for seed in range(args.seeds)
    ]


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    args = parse_args(argv)
    scenarios = args.scenario_table
    config = {
        "policies": args.policy_list,
        "env_ids": args.env_ids,  # an agent runs under its training env
        **({"agent_envs": args.agent_envs} if args.agent_envs else {}),  # and its observation
        "scenarios": {n: asdict(s) for n, s in scenarios.items()},
        **(
            {"not_applicable": {n: sorted(p) for n, p in args.not_applicable.items()}}
            if args.not_applicable
            else {}
        ),
        "seeds": args.seeds,
        "duration": args.duration,
        "transient": args.transient,
        "command": " ".join(
            [
                Path(sys.executable).name,
                "-m",
                "benchmarks.runner.compare",
                *(argv if argv is not None else sys.argv[1:]),
            ]
        ),
    }
    # One run per folder: a second one is refused, a killed one's temporary files removed.
    with locked_folder(program_name("benchmarks.runner.compare"), args.out):
        records = run_jobs(
            args.jobs, args.out, args.workers, args.backend, args.address, progress=not args.quiet
        )
        figures: list[Path] = []
        captions = None
        if not args.no_figures:
            from benchmarks.reports.figures import comparison_figures, figure_captions

            figures = comparison_figures(records, args.out, scenarios=scenarios)
            captions = figure_captions(figures, args.out)
        write_tables(records, args.out, config, captions)  # the summary lists the figures
        written = [args.out / name for name in TABLES]
        replace_outputs(args.out, [*written, *figures])  # no figure of an earlier run beside
    print(overview_note(args.seeds, args.transient))
    print(overview(records, scenarios=list(scenarios)))
    for spec in args.policy_list:  # one line per policy not flown on some scenarios
        where = [name for name, refused in args.not_applicable.items() if spec in refused]
        if where:
            why = args.not_applicable[where[0]][spec].removeprefix(f"policy {spec!r}: ")
            print(f"n/a: {spec} on {', '.join(where)}: {why}")
    print(f"\nevery metric: {args.out / 'summary.md'}")
    print(f"every episode: {args.out / 'episodes.csv'} (and episodes.json)")
    if figures:
        print(f"figures ({len(figures)}): {args.out / 'figures'}")
    return records


if __name__ == "__main__":
    main()
