"""FBSM vs backstepping vs PPO (and any Policy) on the same seeded scenarios.

    python -m benchmarks.compare --policies fbsm,backstepping,ppo,fbsm_ilos,backstepping_ilos \\
        --scenarios all --seeds 10 --duration 300 --workers 2 --out benchmarks/results/full

Jobs are (policy, scenario, seed) episodes (`benchmarks.jobs`): each finished episode is stored
under ``OUT/episodes/`` with a fingerprint of everything that determines it, so an interrupted
run restarted with the same arguments reuses finished episodes, and results do not depend on
the number of workers or the backend. Policies: `benchmarks.policies`; scenarios:
`benchmarks/scenarios.toml`; tables: `benchmarks.tables`; figures: `benchmarks.figures`.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from auv_gym.metrics import check_window, window_start
from benchmarks.cli import HelpFormatter
from benchmarks.jobs import Job, run_jobs
from benchmarks.policies import check_policy_spec
from benchmarks.scenarios import SCENARIOS_FILE, load_scenarios, select
from benchmarks.tables import write_tables
from controllers import REGISTRY


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    parser.add_argument(
        "--policies",
        default="fbsm,backstepping,ppo",
        help=f"comma-separated: {', '.join(REGISTRY)}, ppo:PATH, module:attribute",
    )
    parser.add_argument("--scenarios", default="all",
                        help="comma-separated names of --scenario-file or 'all'; the shipped "
                        f"file has: {', '.join(load_scenarios())}")  # fmt: skip
    parser.add_argument("--scenario-file", type=Path, default=SCENARIOS_FILE,
                        help="TOML file of named scenarios (env keyword arguments)")  # fmt: skip
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 per scenario")
    parser.add_argument("--duration", type=float, default=300.0, help="episode length [s]")
    parser.add_argument(
        "--transient",
        type=float,
        default=None,
        help="metrics window start [s]; None: min(100, duration/2) (docs/design.md §3.9)",
    )
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="local worker processes (results do not depend on it)")  # fmt: skip
    parser.add_argument("--backend", choices=("local", "ray"), default="local",
                        help="run the episodes in local processes or on a Ray cluster")  # fmt: skip
    parser.add_argument("--address", default=None, help="Ray cluster address to join")
    parser.add_argument("--out", type=Path, default=Path("out/compare"),
                        help="output folder; a rerun with the same arguments resumes")  # fmt: skip
    parser.add_argument("--no-figures", action="store_true", help="tables only")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    args = parse_args(argv)
    scenarios = load_scenarios(args.scenario_file)
    scenario_names = select(args.scenarios, list(scenarios), "scenario")
    policies = [p.strip() for p in args.policies.split(",") if p.strip()]
    for spec in policies:
        check_policy_spec(spec)  # every error before the first episode
    if args.seeds < 1 or not (math.isfinite(args.duration) and args.duration > 0):
        raise ValueError("--seeds must be >= 1 and --duration a positive number of seconds")
    transient = window_start(args.duration, args.transient)
    for name in scenario_names:  # the window must hold a metric at every scenario's period
        check_window(args.duration, transient, scenarios[name].env.get("control_dt", 0.05))
    jobs = [
        Job(policy, scenarios[name], seed, args.duration, transient)
        for name in scenario_names
        for policy in policies
        for seed in range(args.seeds)
    ]
    config = {
        "policies": policies,
        "scenarios": {n: asdict(scenarios[n]) for n in scenario_names},
        "seeds": args.seeds,
        "duration": args.duration,
        "transient": transient,
        "command": " ".join(
            [
                Path(sys.executable).name,
                "-m",
                "benchmarks.compare",
                *(argv if argv is not None else sys.argv[1:]),
            ]
        ),
    }
    records = run_jobs(
        jobs, args.out, args.workers, args.backend, args.address, progress=not args.quiet
    )
    summary = write_tables(records, args.out, config)
    if not args.no_figures:
        from benchmarks.figures import comparison_figures

        comparison_figures(records, args.out, scenarios={n: scenarios[n] for n in scenario_names})
    print(summary)
    return records


if __name__ == "__main__":
    try:
        main()
    except (ValueError, FileNotFoundError) as error:
        raise SystemExit(f"error: {error}") from None
