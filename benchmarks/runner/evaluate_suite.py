"""Every policy and every training seed on the whole test suite: episodes.csv, then statistics.

    python -m benchmarks.runner.evaluate_suite --workers 2 --out benchmarks/results/suite \\
        --policies fbsm,fbsm_colos,ppo_generalist=runs/ppo_generalist/results
    python -m benchmarks.runner.evaluate_suite --stats-only --out benchmarks/results/suite

Policies (``--policies``, comma-separated):

* classical controllers and their presets by name, as `benchmarks.runner.compare` takes them; on a
  scenario set the scenario's controller keyword arguments apply, exactly as in compare;
* reference agents by name (`benchmarks.catalog.policies.REFERENCE_AGENTS`), "agent:PATH",
  "module:attribute";
* NAME=DIR: DIR is one agent directory (one run, named by the training seed its metadata.json
  records; an ensemble's folder, `auv-gym ensemble`, by its first member's) or a multi-seed
  results directory (``benchmarks.training.seeds_cli --results``) holding one agent per training
  seed, ``DIR/agent_seed_<k>/`` (model.zip, vecnormalize.npz,
  metadata.json): one run per seed; its ``seed_<k>_learning_curve.csv`` files give the learning
  curves of the statistics.

Episodes: every test set of the tasks file (`benchmarks.catalog.tasks.test_suite`: the test
distribution, the held-out families, one set per benchmark scenario), each on its seeds, for
``--duration`` seconds. An agent runs under the env id its metadata.json records (the fixed
arguments of `auv_gym.VARIANTS`, e.g. AUVPath3DSpeedLimit-v0's 2.0 m/s surge limit, under which
a faster agent terminates "overspeed"), every other policy under AUVPath3D-v0, the benchmark's
env; the ``env_id`` column says which.

The work is split in chunks (policy, run, set): the set's episodes in one batched
`auv_gym.rollout.evaluate` call. A finished chunk is stored atomically under ``OUT/chunks/`` with a
fingerprint of everything that determines it (the agent's files and the simulator and controller
sources included, `benchmarks.runner.jobs`), so a killed run continued with the same command keeps
its finished chunks. Results depend neither on ``--workers`` nor on the order of chunks.

Outputs in OUT: ``episodes.csv`` (one row per policy × run × set × episode seed, metrics at full
precision), ``suite.json`` (command, configuration, agents, versions), then the statistics of
`benchmarks.analysis.suite_stats` (stats.json, stats.md, figures/), which ``--stats-only``
recomputes from episodes.csv and suite.json without simulating.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from auv_gym.metrics import check_window
from auv_gym.sim.config import FIVE_DOF_PLANT, PLANTS, SimConfig
from auv_gym.support.files import (
    environment,
    replace_outputs,
    write_json,
    write_text,
)
from auv_gym.support.validation import choice
from benchmarks.analysis.report_spec import DEFAULT_REPORT, ReportSpec
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
    PolicySpec,
    check_policy_for_env,
    policy_label,
)
from benchmarks.catalog.scenarios import select
from benchmarks.catalog.tasks import TASKS_FILE, TaskSet, test_suite
from benchmarks.cli import HelpFormatter
from benchmarks.options import add_options, option
from benchmarks.runner.cache import run_resumable
from benchmarks.runner.jobs import agent_digest, code_digest
from benchmarks.runner.suite_chunks import (  # the unit of work; importable from here too
    CHUNKS,
    METRICS,
    Chunk,
    Run,
    SuitePolicy,
    episodes_csv,
    resolve_policy,
    run_chunk,
)

__all__ = [
    "EPISODES_FILE",
    "METRICS",
    "SUITE_FILE",
    "Chunk",
    "Run",
    "SuitePolicy",
    "main",
    "resolve_policy",
    "run_chunk",
]

EPISODES_FILE = "episodes.csv"
SUITE_FILE = "suite.json"
DEFAULT_POLICIES = "fbsm,backstepping,ppo_generalist"


@dataclass
class SuiteOptions(EpisodeOptions):
    """The options of `auv-gym suite` (and the episode runner's, `EpisodeOptions`)."""

    policies: str = option(
        DEFAULT_POLICIES,
        f"comma-separated: controller or reference agent names (as compare), "
        f"{POLICY_SPEC_FORMS}, or NAME=DIR (an agent or a multi-seed results directory of "
        "agent_seed_<k>/ folders)",
    )
    sets: str = option("all", "comma-separated test sets of --tasks-file, or 'all'")
    plant: str = option(
        FIVE_DOF_PLANT,
        f"the plant every set runs on: {' or '.join(PLANTS)} (docs/model.md §15); the policies "
        "stay as designed or trained",
    )
    # A Path is immutable: one shared default is safe.
    tasks_file: Path = option(  # noqa: RUF009
        TASKS_FILE, "TOML file of named task sets (benchmarks.catalog.tasks)"
    )
    out: Path = option(  # noqa: RUF009
        Path("out/suite"),
        "output folder; a rerun with the same arguments resumes (the committed results: "
        "benchmarks/results/suite)",
    )
    stats_only: bool = option(
        False,
        "recompute the statistics from OUT/episodes.csv, no simulation (the evaluation options "
        "above are not used)",
    )
    stats: bool = option(True, "episodes.csv only", flag="--no-stats", invert=True)
    figures: bool = option(True, "statistics without figures", flag="--no-figures", invert=True)
    report: Path = option(  # noqa: RUF009
        DEFAULT_REPORT,
        "TOML report table: references, target ratio, (policy, base) pairs of the statistics",
    )
    reference: str | None = option(
        None,
        "policy the probability of improvement and the target ratio refer to (default: the "
        "report table's)",
    )
    reps: int = option(2000, "bootstrap replicates")
    bootstrap_seed: int = option(0, "seed of the bootstrap (one seed: bit-identical intervals)")
    progress: bool = option(True, "no progress bar", flag="--quiet", invert=True)


def build_parser() -> argparse.ArgumentParser:
    """The parser of `SuiteOptions` (each option's default and help from its field)."""
    parser = ArgumentParser(
        prog=program_name("benchmarks.runner.evaluate_suite"),
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    add_options(parser, SuiteOptions, negatable=False)
    return parser


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The arguments, every one checked before any episode runs (a bad one exits with code 2
    and a one-line message). Adds ``policy_list`` (SuitePolicy), ``set_list`` (TaskSet),
    ``chunks`` and ``transient`` (resolved)."""
    return parse_checked(build_parser(), argv, check_args)


def check_args(args: argparse.Namespace) -> None:
    """Validate ``args`` and resolve them into chunks; ValueError/OSError naming the argument."""
    if args.stats_only and args.no_stats:
        raise ValueError("--stats-only and --no-stats exclude each other")
    if not args.no_stats:  # the statistics need the stats extra (rliable); --no-stats does not
        from benchmarks.analysis.suite_stats import check_stats_options

        check_stats_options(args.reps, args.bootstrap_seed)
        args.report_spec = ReportSpec.read(args.report).with_reference(args.reference)
        args.reference = args.report_spec.reference
    if args.stats_only:
        for name in (EPISODES_FILE, SUITE_FILE):
            if not (args.out / name).is_file():
                raise FileNotFoundError(
                    f"--stats-only: {args.out / name} does not exist; run the evaluation first"
                )
        from benchmarks.analysis.suite_stats import read_episodes, read_suite_json

        read_suite_json(args.out / SUITE_FILE)  # a damaged record: its file and line named
        read_episodes(args.out / EPISODES_FILE)
        writable_folder(args.out)
        return
    try:
        suite = test_suite(args.tasks_file)
    except OSError as error:
        raise OSError(f"--tasks-file {str(args.tasks_file)!r}: {error.strerror}") from None
    if not suite:
        raise ValueError(f"--tasks-file {str(args.tasks_file)!r} has no test set")
    by_name = {s.name: s for s in suite}
    sets = [by_name[n] for n in select(args.sets, list(by_name), "set")]
    choice("--plant", args.plant, PLANTS)
    if args.plant != FIVE_DOF_PLANT:
        sets = [replace(s, env={**s.env, "plant": args.plant}) for s in sets]
    names = comma_names(args.policies, "--policies")
    policies = [resolve_policy(spec) for spec in names]
    labels: dict[str, str] = {}
    for policy in policies:
        label = policy_label(policy.name)
        if label in labels:  # both would write OUT/chunks/<label>/
            raise ValueError(
                f"--policies {labels[label]!r} and {policy.name!r} share the label {label!r}"
            )
        labels[label] = policy.name
    if not args.no_stats and args.reference not in [p.name for p in policies]:
        raise ValueError(
            f"--reference {args.reference!r} is not among --policies "
            f"{[p.name for p in policies]} (or pass --no-stats)"
        )
    check_episode_arguments(args)
    chunks = []
    transient = args.transient
    for task in sets:
        for policy in policies:
            for run in policy.runs:
                chunk = Chunk(policy.name, run, task, args.duration, 0.0)
                try:
                    config = SimConfig.from_kwargs(**chunk.env_kwargs)
                    transient = check_window(args.duration, args.transient, config.control_dt)
                    # as each chunk will build it, before any episode
                    check_policy_for_env(run.spec, chunk.env_kwargs, task.controller)
                except (TypeError, ValueError) as error:
                    where = f"task set {task.name!r}"
                    if not str(error).startswith("policy "):  # it names the policy itself
                        where += f", policy {policy.name!r}"
                    raise ValueError(f"{where}: {error}") from None
                chunks.append(chunk)
    writable_folder(args.out)  # last: a bad argument above creates no folder
    args.transient = transient
    args.policy_list, args.set_list = policies, sets
    args.chunks = [
        Chunk(c.policy, c.run, c.task, c.duration, transient)
        for c in sorted(chunks, key=lambda c: _order(c, policies, sets))
    ]


def _order(chunk: Chunk, policies: list[SuitePolicy], sets: list[TaskSet]) -> tuple[int, int, int]:
    """Row order of episodes.csv: policy as given, run, set as in the tasks file."""
    p = next(i for i, policy in enumerate(policies) if policy.name == chunk.policy)
    s = next(i for i, task in enumerate(sets) if task.name == chunk.task.name)
    return p, chunk.run.run, s


def _set_entry(task: TaskSet) -> dict[str, Any]:
    entry = asdict(task)
    entry["seeds"] = {"first": task.seeds.start, "count": len(task.seeds)}
    entry["kind"] = (
        "scenario"
        if task.name.startswith("scenario:")
        else "held_out"
        if task.held_out
        else "distribution"
    )
    return entry


def run_suite(args: argparse.Namespace, argv: Sequence[str] | None) -> list[dict[str, Any]]:
    """Evaluate every chunk, then write episodes.csv and suite.json (atomically)."""
    records = run_resumable(
        args.chunks,
        args.out,
        args.out / CHUNKS,
        run_chunk,
        workers=args.workers,
        backend=args.backend,
        address=args.address,
        progress=not args.quiet,
        desc="suite episodes",
        sizes=[len(c.task.seeds) for c in args.chunks],
    )
    # A record is filed under its policy's label, which its fingerprint leaves out: a folder of
    # chunks copied under a new label is reused, and its rows carry the label of this run.
    records = [{**r, "policy": c.policy} for c, r in zip(args.chunks, records, strict=True)]
    command = [
        Path(sys.executable).name,
        "-m",
        "benchmarks.runner.evaluate_suite",
        *(argv if argv is not None else sys.argv[1:]),
    ]
    suite = {
        "command": " ".join(command),
        "duration_s": args.duration,
        "transient_s": args.transient,
        "tasks_file": str(args.tasks_file),
        "policies": {p.name: asdict(p) for p in args.policy_list},
        "agents": {
            r.spec: agent_digest(PolicySpec.parse(r.spec).files)
            for p in args.policy_list
            for r in p.runs
            if p.kind == "agent"
        },
        "sets": {s.name: _set_entry(s) for s in args.set_list},
        "code": code_digest(),
        "chunk_wall_time_s": {
            f"{r['policy']}|{r['run']}|{r['set']}": r["wall_time_s"] for r in records
        },
        **environment(),
    }
    write_text(args.out / EPISODES_FILE, episodes_csv(records))
    write_json(args.out / SUITE_FILE, _portable(suite), indent=1)
    return records


CHECKOUT = Path(__file__).resolve().parents[2]  # the project root: paths below it are relative


def _portable(value: Any) -> Any:
    """``value`` with every path inside the checkout written relative to it (a reference agent is
    named by its absolute folder; a committed suite.json must hold no machine path)."""
    if isinstance(value, str):
        return value.replace(f"{CHECKOUT}/", "")
    if isinstance(value, dict):
        return {_portable(k): _portable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_portable(v) for v in value]
    return value


# What `benchmarks.analysis.suite_stats.write_stats` writes, with figures/.
STATS_FILES = ("stats.json", "stats.md")


def _files(folder: Path) -> dict[Path, int]:
    """file → inode of the files in ``folder`` (none if it does not exist)."""
    return {f: f.stat().st_ino for f in folder.iterdir() if f.is_file()} if folder.is_dir() else {}


def main(argv: Sequence[str] | None = None) -> None:
    args = parse_args(argv)
    # One run per folder: a second one is refused, a killed one's temporary files removed.
    with locked_folder(program_name("benchmarks.runner.evaluate_suite"), args.out):
        before = _files(args.out / "figures")
        if not args.stats_only:
            run_suite(args, argv)
        written = [args.out / EPISODES_FILE, args.out / SUITE_FILE]
        if not args.no_stats:
            from benchmarks.analysis.suite_stats import FIGURES, write_stats

            text = write_stats(
                args.out,
                reps=args.reps,
                seed=args.bootstrap_seed,
                figures=not args.no_figures,
                report=args.report_spec,
            )
            written += [args.out / name for name in STATS_FILES]
            after = _files(args.out / FIGURES)  # written atomically: a new inode each
            written += [f for f, inode in after.items() if before.get(f) != inode]
        # Statistics and figures of an earlier run (other policies, or stats of other
        # episodes) do not stay beside this run's episodes.csv.
        replace_outputs(args.out, written)
    if not args.no_stats:
        print(text)


if __name__ == "__main__":
    main()
