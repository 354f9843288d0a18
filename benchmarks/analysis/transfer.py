"""How every reference policy transfers from the 5-DOF plant it was designed or trained on to the
6-DOF plant (docs/model.md §15, docs/results.md "Transfer to the 6-DOF plant"): the test suite on
both plants, the policies unchanged, side by side.

    python -m benchmarks.analysis.transfer --out benchmarks/results/transfer --workers 2
    python -m benchmarks.analysis.transfer --tables-only --out benchmarks/results/transfer

``--groups`` names the groups to fly; the tables cover those and every other group whose suites
on both plants are already in OUT (re-flying one group keeps the other's rows).

Two groups of sets and policies (`GROUPS`): the paper's task (the paper scenario, the nominal
helix, the test distribution and its held-out path families) with the classical controllers of
the paper and the agents trained for it, and the vehicle as built (propeller and fins, the
navigation filter, the ocean preset) with its classical controllers and agent. Each group runs
as one `auv-gym suite` per plant (``OUT/<group>_<plant>/``, resumable chunk by chunk); the
tables come from their episodes.csv files:

* ``transfer.csv`` — one row per (group, policy, set and "aggregate"): per plant the mean score
  [m] with its 95 % bootstrap interval over runs and episode seeds (`stats.mean_interval`; the
  agents are the shipped reference agents, one training seed each;
  a failed episode scores the set's corridor, as in the suite's statistics), failures, and the
  largest roll angle [deg] of the 6-DOF episodes; the ratio of the means 6-DOF / 5-DOF.
* ``transfer.md`` — the same as a table, and the targets: the best classical policy of each
  group (lowest 5-DOF aggregate mean among its classical policies) and its reference agent each
  within ``--max-ratio`` (1.5) of their 5-DOF mean with no failed episode.
* ``transfer.json`` — the targets, the commands and versions; ``transfer.png`` — the aggregate
  means per policy on both plants, with their intervals.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.sim.trajectory import FAILURE_REASONS
from auv_gym.support.files import environment, write_json, write_text
from benchmarks.analysis.stats import MAX_REPS, MIN_REPS, mean_interval
from benchmarks.analysis.suite_stats import failure_scores, read_episodes, score_matrices
from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

__all__ = ["GROUPS", "Group", "main", "table_groups", "transfer_rows"]

PLANTS = ("5dof", "6dof")
AGGREGATE = "aggregate"


@dataclass(frozen=True)
class Group:
    """Test sets and the policies designed or trained for them; ``classical`` and ``agent`` name
    the policies the targets judge."""

    sets: tuple[str, ...]
    policies: tuple[str, ...]  # `auv-gym suite --policies` entries
    classical: tuple[str, ...]
    agent: str


GROUPS = {
    "paper": Group(
        sets=(
            "scenario:paper",
            "scenario:nominal",
            "test_distribution",
            "test_tight_helix",
            "test_steep",
            "test_wide_helix",
        ),
        policies=(
            "fbsm",
            "fbsm_colos",
            "backstepping",
            "backstepping_colos",
            "ppo_generalist",
            "ppo_residual",
            "sac_generalist",
        ),
        classical=("fbsm", "fbsm_colos", "backstepping", "backstepping_colos"),
        agent="ppo_generalist",
    ),
    "as_built": Group(
        sets=(
            "scenario:as_built_helix",
            "scenario:as_built_survey",
            "scenario:as_built_coastal",
            "test_as_built_tight_deep",
            "test_as_built_strong_current",
        ),
        policies=(
            "fbsm_colos",
            "backstepping_colos",
            "pid_colos",
            "pid_as_built",
            "pid_as_built_climb",
            "pid_as_built_climb_soft_pitch",
            "command_filtered_colos",
            "ppo_as_built",
            "ppo_residual_as_built",
        ),
        classical=(
            "fbsm_colos",
            "backstepping_colos",
            "pid_colos",
            "pid_as_built",
            "pid_as_built_climb",
            "pid_as_built_climb_soft_pitch",
            "command_filtered_colos",
        ),
        agent="ppo_as_built",
    ),
}


@dataclass
class Options:
    """The command line of the transfer benchmark."""

    # A Path is immutable: one shared default is safe.
    out: Path = option(  # noqa: RUF009
        Path("out/transfer"), "output folder (resumes; committed: benchmarks/results/transfer)"
    )
    workers: int = option(2, "worker processes of each suite run")
    groups: str = option(",".join(GROUPS), f"comma-separated subset of {', '.join(GROUPS)}")
    duration: float = option(300.0, "episode length [s]")
    max_ratio: float = option(1.5, "the target: 6-DOF mean at most this times the 5-DOF mean")
    tables_only: bool = option(False, "tables from OUT's episodes.csv files, no simulation")
    reps: int = option(2000, "bootstrap replicates")


def _suite_folder(out: Path, group: str, plant: str) -> Path:
    return out / f"{group}_{plant}"


def run_group(out: Path, name: str, group: Group, workers: int, duration: float) -> None:
    """The group's suite on both plants (`benchmarks.runner.evaluate_suite`, resumable)."""
    from benchmarks.runner.evaluate_suite import main as suite

    for plant in PLANTS:
        print(f"transfer: {name} on the {plant} plant", flush=True)
        suite(
            [
                "--sets",
                ",".join(group.sets),
                "--policies",
                ",".join(group.policies),
                "--plant",
                plant,
                "--duration",
                str(duration),
                "--workers",
                str(workers),
                "--out",
                str(_suite_folder(out, name, plant)),
                "--no-stats",
            ]
        )


def table_groups(out: Path, names: Sequence[str]) -> list[str]:
    """The groups the tables cover, in `GROUPS` order: ``names`` (the command's), and every
    other group whose suites on both plants are in OUT, so that re-running one group keeps the
    other's rows in the tables."""
    present = [
        g
        for g in GROUPS
        if all((_suite_folder(out, g, plant) / "episodes.csv").is_file() for plant in PLANTS)
    ]
    return [g for g in GROUPS if g in names or g in present]


def _cells(folder: Path) -> tuple[dict[str, np.ndarray], list[str], list[dict[str, Any]]]:
    """(scores {policy: (runs, episodes)}, set of each column, episode rows) of one suite run."""
    suite = json.loads((folder / "suite.json").read_text())
    rows = read_episodes(folder / "episodes.csv")
    sets = list(suite["sets"])
    scores, columns, _ = score_matrices(rows, sets, failure_scores(suite))
    return scores, columns, rows


def _interval(scores: np.ndarray, columns: Sequence[str], keep: np.ndarray, key: str, reps: int):
    chosen = [c for c, k in zip(columns, keep, strict=True) if k]
    return mean_interval(scores[:, keep], chosen, key=key, reps=reps)


def transfer_rows(out: Path, name: str, group: Group, reps: int) -> list[dict[str, Any]]:
    """The group's rows of transfer.csv (module doc)."""
    plants = {plant: _cells(_suite_folder(out, name, plant)) for plant in PLANTS}
    policies = list(plants["5dof"][0])
    result = []
    for policy in policies:
        for scope in [*group.sets, AGGREGATE]:
            row: dict[str, Any] = {"group": name, "policy": policy, "set": scope}
            for plant, (scores, columns, episodes) in plants.items():
                keep = np.array([scope in (AGGREGATE, c) for c in columns])
                interval = _interval(scores[policy], columns, keep, f"{policy}|{scope}", reps)
                mine = [
                    e for e in episodes if e["policy"] == policy and scope in (AGGREGATE, e["set"])
                ]
                failed = sum(e["termination_reason"] in FAILURE_REASONS for e in mine)
                row[f"mean_{plant}"], row[f"low_{plant}"], row[f"high_{plant}"] = interval
                row[f"failures_{plant}"] = failed
                row[f"episodes_{plant}"] = len(mine)
                if plant == "6dof":
                    roll = np.array([float(e["max_roll"]) for e in mine])
                    row["max_roll_deg"] = float(np.degrees(roll.max()))
                    row["median_max_roll_deg"] = float(np.degrees(np.median(roll)))
            row["runs"] = int(scores[policy].shape[0])
            row["ratio"] = row["mean_6dof"] / row["mean_5dof"]
            result.append(row)
    return result


def targets(rows: Sequence[Mapping[str, Any]], max_ratio: float) -> list[dict[str, Any]]:
    """Per group: the best classical policy (lowest 5-DOF aggregate mean) and the agent, with
    their ratio, failures and whether they meet the target."""
    found = []
    aggregate = {(r["group"], r["policy"]): r for r in rows if r["set"] == AGGREGATE}
    for name, group in GROUPS.items():
        candidates = [aggregate[(name, p)] for p in group.classical if (name, p) in aggregate]
        if not candidates:
            continue
        best = min(candidates, key=lambda r: r["mean_5dof"])
        for role, row in (("best classical", best), ("agent", aggregate.get((name, group.agent)))):
            if row is None:
                continue
            met = row["ratio"] <= max_ratio and row["failures_6dof"] == 0
            found.append({"group": name, "role": role, **row, "met": bool(met)})
    return found


def _markdown(rows: Sequence[Mapping[str, Any]], goals: Sequence[Mapping], max_ratio: float) -> str:
    def cell(r: Mapping[str, Any], plant: str) -> str:
        return f"{r[f'mean_{plant}']:.3f} [{r[f'low_{plant}']:.3f}, {r[f'high_{plant}']:.3f}]"

    out = io.StringIO()
    out.write("# Transfer from the 5-DOF plant to the 6-DOF plant\n\n")
    out.write(
        "Mean score [m] (RMS distance to the virtual point over t ≥ 100 s; a failed episode "
        "scores the corridor) with 95 % bootstrap intervals over episode seeds (one run per "
        "classical controller and per shipped agent); failed episodes; the largest |roll| of "
        "the 6-DOF episodes (median of the episodes' largest). Policies unchanged: designed or "
        "trained on the 5-DOF.\n\n"
    )
    out.write(f"## Targets (6-DOF mean ≤ {max_ratio} × 5-DOF mean, no failure)\n\n")
    out.write("| group | role | policy | 5-DOF | 6-DOF | ratio | failures 6-DOF | met |\n")
    out.write("|---|---|---|---|---|---|---|---|\n")
    for g in goals:
        out.write(
            f"| {g['group']} | {g['role']} | {g['policy']} | {cell(g, '5dof')} | "
            f"{cell(g, '6dof')} | {g['ratio']:.2f} | {g['failures_6dof']}/"
            f"{g['episodes_6dof']} | {'yes' if g['met'] else 'no'} |\n"
        )
    for name in GROUPS:
        mine = [r for r in rows if r["group"] == name]
        if not mine:
            continue
        out.write(f"\n## {name}\n\n")
        out.write(
            "| policy | set | runs | 5-DOF | 6-DOF | ratio | failures 5/6 | max roll [°] "
            "(median) |\n|---|---|---|---|---|---|---|---|\n"
        )
        for r in mine:
            out.write(
                f"| {r['policy']} | {r['set']} | {r['runs']} | {cell(r, '5dof')} | "
                f"{cell(r, '6dof')} | {r['ratio']:.2f} | {r['failures_5dof']}/"
                f"{r['failures_6dof']} of {r['episodes_6dof']} | {r['max_roll_deg']:.1f} "
                f"({r['median_max_roll_deg']:.1f}) |\n"
            )
    return out.getvalue()


def _csv(rows: Sequence[Mapping[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})
    return buffer.getvalue()


def _figure(rows: Sequence[Mapping[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from benchmarks.reports.plotting import save_figure

    groups = [g for g in GROUPS if any(r["group"] == g for r in rows)]
    fig, axes = plt.subplots(1, len(groups), figsize=(6.5 * len(groups), 4.2), squeeze=False)
    for ax, name in zip(axes[0], groups, strict=True):
        mine = [r for r in rows if r["group"] == name and r["set"] == AGGREGATE]
        x = np.arange(len(mine))
        for k, (plant, color) in enumerate((("5dof", "tab:blue"), ("6dof", "tab:orange"))):
            mean = np.array([r[f"mean_{plant}"] for r in mine])
            err = np.array(
                [
                    [
                        r[f"mean_{plant}"] - r[f"low_{plant}"],
                        r[f"high_{plant}"] - r[f"mean_{plant}"],
                    ]
                    for r in mine
                ]
            ).T
            ax.bar(x + (k - 0.5) * 0.38, mean, 0.38, yerr=err, color=color, label=plant.upper())
        ax.set_yscale("log")
        ax.set_xticks(x, [r["policy"] for r in mine], rotation=30, ha="right")
        ax.set_ylabel("mean score [m] (log)")
        ax.set_title(f"{name}: all sets, 95 % intervals")
        ax.legend()
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> None:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.analysis.transfer"), __doc__
    )
    names = [n.strip() for n in args.groups.split(",")]
    unknown = [n for n in names if n not in GROUPS]
    if unknown or not names:
        parser.error(f"--groups: unknown {unknown}; valid: {', '.join(GROUPS)}")
    if not MIN_REPS <= args.reps <= MAX_REPS:
        parser.error(f"--reps must be an integer in [{MIN_REPS}, {MAX_REPS}], got {args.reps}")
    if not (math.isfinite(args.max_ratio) and args.max_ratio > 0):
        parser.error(f"--max-ratio must be a finite number > 0, got {args.max_ratio}")
    if not args.tables_only:
        for name in names:
            run_group(args.out, name, GROUPS[name], args.workers, args.duration)
    tabled = table_groups(args.out, names)
    rows = [r for name in tabled for r in transfer_rows(args.out, name, GROUPS[name], args.reps)]
    goals = targets(rows, args.max_ratio)
    write_text(args.out / "transfer.csv", _csv(rows))
    text = _markdown(rows, goals, args.max_ratio)
    write_text(args.out / "transfer.md", text)
    write_json(
        args.out / "transfer.json",
        {"targets": goals, "max_ratio": args.max_ratio, "groups": tabled, **environment()},
    )
    _figure(rows, args.out / "transfer.png")
    print(text)


if __name__ == "__main__":
    main()
