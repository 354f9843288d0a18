"""A multi-seed policy on the whole test suite, seed by seed: does every seed beat the classics?

    python -m benchmarks.analysis.suite_seeds --suite benchmarks/results/reference_suite \\
        --policy ppo_generalist --out benchmarks/results/seeds/ppo_generalist_suite

Reads a test-suite evaluation (`benchmarks.runner.evaluate_suite`: OUT/episodes.csv and
OUT/suite.json) in which ``--policy`` ran several training seeds (runs). Per run: the IQM of its
scores over every set pooled, or over ``--sets`` (the suite's "aggregate": a failed episode
scores its set's corridor, `benchmarks.analysis.suite_stats.episode_score`) with a 95 %
stratified bootstrap interval over episodes, its failed episodes, and whether it beats each
reference: a lower aggregate IQM and no failed episode. Then how many runs beat each
reference, and the policy's aggregate over runs × episodes. Written to --out:
``suite_seeds.json`` and ``suite_seeds.md``.

``--suite A,B,...`` pools several evaluations, e.g. seeds trained and flown in pairs
(`pool_suites`): they must define the sets they share alike, and an episode flown in more than
one (a reference flown again with each pair) must have scored the same in each; it counts once.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.arguments import comma_names, parse_options, program_name, usage_errors
from benchmarks.options import option

__all__ = ["main", "pool_suites", "seed_table"]

SEEDS_FILE = "suite_seeds.json"


@dataclass
class SuiteSeedsOptions:
    """The options of ``python -m benchmarks.analysis.suite_seeds``."""

    suite: str = option("", "a test-suite evaluation folder, or several comma-separated to pool")
    policy: str = option("", "the multi-seed policy of that evaluation")
    references: str = option("fbsm,fbsm_colos", "comma-separated classical policies to beat")
    sets: str = option("", "comma-separated sets to pool (default: every set evaluated)")
    reps: int = option(2000, "bootstrap replicates")
    out: Path | None = option(None, "folder for the tables", parse=Path)  # noqa: RUF009


def seed_table(
    scores: Mapping[str, np.ndarray],
    groups: Sequence[str],
    runs: Mapping[str, Sequence[int]],
    failed: Mapping[str, np.ndarray],
    policy: str,
    references: Sequence[str],
    reps: int = 2000,
) -> dict[str, Any]:
    """Per run of ``policy``: aggregate IQM [m] with its interval, failed episodes, references
    beaten; the counts and the pooled aggregate (module doc). ``scores``/``failed``: (runs,
    episodes) arrays per policy in the columns ``groups`` (`suite_stats.score_matrices`)."""
    from benchmarks.analysis.stats import interval_estimates

    missing = [name for name in (policy, *references) if name not in scores]
    if missing:
        raise ValueError(f"not in the evaluation: {missing}; policies: {sorted(scores)}")
    labels = np.asarray(groups)

    def aggregate(matrix: np.ndarray, key: str) -> list[float]:
        interval = interval_estimates({key: matrix}, labels, reps=reps)["iqm"][key]
        return [interval.value, interval.low, interval.high]

    refs = {
        name: {"iqm": aggregate(scores[name], name), "failed": int(failed[name].sum())}
        for name in references
    }
    per_run = {}
    for k, run in enumerate(runs[policy]):
        iqm = aggregate(scores[policy][k : k + 1], f"{policy}|{run}")
        n_failed = int(failed[policy][k].sum())
        misses = sorted({groups[j] for j in np.flatnonzero(failed[policy][k])})
        per_run[str(run)] = {
            "iqm": iqm,
            "failed": n_failed,
            "failed_sets": misses,
            "beats": {name: n_failed == 0 and iqm[0] < ref["iqm"][0] for name, ref in refs.items()},
        }
    return {
        "policy": policy,
        "references": refs,
        "runs": per_run,
        "beat_counts": {n: sum(r["beats"][n] for r in per_run.values()) for n in refs},
        "failed_episodes": int(failed[policy].sum()),
        "episodes": int(failed[policy].size),
        "aggregate_iqm": aggregate(scores[policy], policy),
    }


_EPISODE_KEY = ("policy", "run", "set", "seed")
_EPISODE_OUTCOME = ("rms_distance", "termination_reason")


def pool_suites(folders: Sequence[Path]) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(suite.json, episodes.csv rows) of several test-suite evaluations pooled (module doc);
    ValueError naming the folders when their sets or a shared episode's outcome disagree."""
    from benchmarks.analysis.suite_stats import read_suite

    if not folders:
        raise ValueError("--suite: no evaluation folder")
    suite, rows = read_suite(folders[0], f"--suite {folders[0]}")
    suite = {**suite, "sets": dict(suite["sets"])}
    seen = {tuple(row[k] for k in _EPISODE_KEY): (row, folders[0]) for row in rows}
    for folder in folders[1:]:
        other, other_rows = read_suite(folder, f"--suite {folder}")
        for name, entry in other["sets"].items():
            if name in suite["sets"] and entry != suite["sets"][name]:
                raise ValueError(
                    f"--suite: set {name!r} is defined differently in {folders[0]} and {folder}"
                )
            suite["sets"].setdefault(name, entry)
        for row in other_rows:
            key = tuple(row[k] for k in _EPISODE_KEY)
            if key not in seen:
                seen[key] = (row, folder)
                rows.append(row)
                continue
            first, where = seen[key]
            # as text: a failed episode's RMS is NaN, which never equals itself as a float
            if any(str(first[k]) != str(row[k]) for k in _EPISODE_OUTCOME):
                policy, run, task, seed = key
                raise ValueError(
                    f"--suite: policy {policy!r} run {run}, set {task!r} seed {seed} scored "
                    f"{first['rms_distance']} m ({first['termination_reason']}) in {where} but "
                    f"{row['rms_distance']} m ({row['termination_reason']}) in {folder}"
                )
    return suite, rows


def write_markdown(record: Mapping[str, Any], path: Path) -> None:
    """`suite_seeds.md`: the per-run table, the counts and the pooled aggregate."""
    refs = list(record["references"])
    n_runs = len(record["runs"])
    head = " | ".join(f"beats {name}" for name in refs)
    lines = [
        f"`{record['policy']}` on the test suite ({record['episodes_per_run']} episodes per "
        f"training seed; a failed episode scores its set's corridor). Aggregate IQM RMS distance "
        "[m] over the sets pooled, 95 % stratified bootstrap interval over episodes. Sets: "
        + ", ".join(f"`{name}`" for name in record["sets"])
        + ".",
        "",
        f"| seed | aggregate IQM [m] | failed | {head} |",
        "|---|---|---:|" + "---|" * len(refs),
    ]

    def cell(v: Sequence[float]) -> str:
        return f"{v[0]:.4f} [{v[1]:.4f}, {v[2]:.4f}]"

    for run, entry in record["runs"].items():
        beats = " | ".join("yes" if entry["beats"][name] else "no" for name in refs)
        where = f" ({', '.join(entry['failed_sets'])})" if entry["failed_sets"] else ""
        lines.append(f"| {run} | {cell(entry['iqm'])} | {entry['failed']}{where} | {beats} |")
    lines += ["", "| policy | aggregate IQM [m] | failed |", "|---|---|---:|"]
    lines.append(
        f"| `{record['policy']}` ({n_runs} seeds) | {cell(record['aggregate_iqm'])} | "
        f"{record['failed_episodes']}/{record['episodes']} |"
    )
    for name, ref in record["references"].items():
        lines.append(f"| {name} | {cell(ref['iqm'])} | {ref['failed']} |")
    counts = ", ".join(f"{name} {k} of {n_runs}" for name, k in record["beat_counts"].items())
    lines += ["", f"Seeds that beat each reference (lower IQM, no failed episode): {counts}."]
    path.write_text("\n".join(lines) + "\n")


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    from auv_gym.support.files import write_json
    from benchmarks.analysis.suite_stats import failure_matrices, failure_scores, score_matrices

    args, parser = parse_options(
        SuiteSeedsOptions,
        argv,
        program_name("benchmarks.analysis.suite_seeds"),
        __doc__.split("\n\n")[0],
    )
    with usage_errors(parser):
        if not args.suite or args.out is None or not args.policy:
            raise ValueError("--suite, --policy and --out are required")
        folders = [Path(f) for f in comma_names(args.suite, "--suite")]
        suite, rows = pool_suites(folders)
        references = comma_names(args.references, "--references")
        sets = comma_names(args.sets, "--sets") if args.sets.strip() else list(suite["sets"])
        unknown = sorted(set(sets) - set(suite["sets"]))
        if unknown:
            raise ValueError(
                f"--sets: {unknown} not in the evaluation; sets: {list(suite['sets'])}"
            )
        rows = [row for row in rows if row["set"] in sets]
        scores, groups, runs = score_matrices(rows, sets, failure_scores(suite))
        failed = failure_matrices(rows, sets)
        record = seed_table(scores, groups, runs, failed, args.policy, references, args.reps)
    record = {
        "suite": ",".join(f.name for f in folders),  # no machine paths in committed results
        "sets": sets,
        "episodes_per_run": len(groups),
        **record,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    write_json(args.out / SEEDS_FILE, record, indent=1)
    write_markdown(record, args.out / "suite_seeds.md")
    print((args.out / "suite_seeds.md").read_text())
    return record


if __name__ == "__main__":
    main()
