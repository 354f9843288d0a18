"""A multi-seed agent on both plants, seed by seed: does every seed meet the transfer targets?

    python -m benchmarks.analysis.plant_seeds --policy plants --reference pid_as_built \\
        --suites-5dof runs/suite_seeds_2_3_5dof,runs/suite_seeds_4_5_5dof \\
        --suites-6dof runs/suite_seeds_2_3_6dof,runs/suite_seeds_4_5_6dof \\
        --out benchmarks/results/seeds/ppo_as_built_plants/plant_seeds

Reads test-suite evaluations (`auv-gym suite`) of the same sets flown on the 5-DOF plant and on
the 6-DOF plant (docs/model.md §15), in which ``--policy`` ran several training seeds (runs),
possibly spread over several folders (one per training pair), each folder also holding
``--reference`` (one classical policy, or several: the per-set target then takes the best of
them per set, the one with the lowest 5-DOF mean there). The folders of a plant must be one
experiment: the same sets (names, seeds, env settings, duration) and the reference's episodes
equal score for score. Per run and plant: the mean score [m] over all episodes (a failed episode
scores its set's corridor, `benchmarks.analysis.suite_stats.episode_score`) with a 95 %
bootstrap interval stratified by set, and the failed episodes; the ratio of the means 6-DOF /
5-DOF; per set, the 5-DOF mean over the reference's. Two targets per run (docs/results.md, "The
as-built agent on both plants"):

* plants: the 6-DOF mean ≤ ``--max-ratio`` × the 5-DOF mean, no failed episode on either plant;
* per set: on the 5-DOF plant, every set's mean ≤ ``--max-per-set`` × the reference's (the
  best reference's on that set), no failed episode.

Then how many runs meet each target, and the policy's means over all runs. Written to --out:
``plant_seeds.json``, ``plant_seeds.md`` and ``plant_seeds.png`` (each run's per-set ratios and
its 6-DOF / 5-DOF ratio against the two targets).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.arguments import comma_names, parse_options, program_name, usage_errors
from benchmarks.options import option

__all__ = [
    "PER_SET_TARGET",
    "PLANTS_TARGET",
    "PlantSuite",
    "figure",
    "main",
    "markdown",
    "plant_table",
    "read_plant",
]

# The as-built targets of docs/results.md: the 6-DOF mean at most PLANTS_TARGET × the 5-DOF mean,
# every 5-DOF set at most PER_SET_TARGET × the classical reference.
PLANTS_TARGET = 1.5
PER_SET_TARGET = 0.8

PLANTS = ("5dof", "6dof")
SEEDS_FILE = "plant_seeds.json"
# What makes two evaluations of a plant one experiment (suite.json entries).
SAME_EXPERIMENT = ("sets", "duration_s", "transient_s")


@dataclass
class PlantSeedsOptions:
    """The options of ``python -m benchmarks.analysis.plant_seeds``."""

    suites_5dof: str = option("", "comma-separated suite folders flown on the 5-DOF plant")
    suites_6dof: str = option("", "comma-separated suite folders flown on the 6-DOF plant")
    policy: str = option("", "the multi-seed policy of those evaluations")
    reference: str = option(
        "pid_as_built",
        "the per-set target's classical policy, or several (comma-separated): the best per set",
    )
    max_ratio: float = option(PLANTS_TARGET, "target: 6-DOF mean / 5-DOF mean at most this")
    max_per_set: float = option(
        PER_SET_TARGET, "target: every 5-DOF set at most this × the reference"
    )
    reps: int = option(2000, "bootstrap replicates")
    out: Path | None = option(None, "folder for the tables", parse=Path)  # noqa: RUF009


@dataclass(frozen=True)
class PlantSuite:
    """One plant's evaluations merged: scores and failures (runs, episodes) per policy, the set
    of each episode column, the sets in order, and the runs of each policy."""

    scores: dict[str, np.ndarray]
    failed: dict[str, np.ndarray]
    columns: list[str]
    sets: list[str]
    runs: dict[str, list[int]]


def _read_folder(folder: Path) -> tuple[dict[str, Any], PlantSuite]:
    from benchmarks.analysis.suite_stats import (
        failure_matrices,
        failure_scores,
        read_suite,
        score_matrices,
    )

    suite, rows = read_suite(folder, str(folder))
    sets = list(suite["sets"])
    scores, columns, runs = score_matrices(rows, sets, failure_scores(suite))
    return suite, PlantSuite(scores, failure_matrices(rows, sets), columns, sets, runs)


def _names(reference: str | Sequence[str]) -> list[str]:
    return [reference] if isinstance(reference, str) else list(reference)


def read_plant(folders: Sequence[Path], policy: str, reference: str | Sequence[str]) -> PlantSuite:
    """The runs of ``policy`` from every folder, with the ``reference`` policy or policies (from
    the first), after checking the folders are one experiment (module doc); ValueError naming
    the folder."""
    references = _names(reference)
    if not folders:
        raise ValueError("no suite folder given")
    loaded = [_read_folder(folder) for folder in folders]
    first_suite, first = loaded[0]
    runs: list[int] = []
    for folder, (suite, plant) in zip(folders, loaded, strict=True):
        for key in SAME_EXPERIMENT:
            if suite.get(key) != first_suite.get(key):
                raise ValueError(f"{folder}: its {key} differ from those of {folders[0]}")
        for name in (policy, *references):
            if name not in plant.scores:
                raise ValueError(f"{folder}: no policy {name!r}; policies: {sorted(plant.scores)}")
        for name in references:
            if not np.array_equal(plant.scores[name], first.scores[name]):
                raise ValueError(
                    f"{folder}: {name!r} scores differ from those in {folders[0]}: not the "
                    "same experiment"
                )
        repeated = sorted(set(runs) & set(plant.runs[policy]))
        if repeated:
            raise ValueError(f"{folder}: runs {repeated} of {policy!r} are in another folder too")
        runs += plant.runs[policy]
    order = np.argsort(runs, kind="stable")  # the policy's runs in order, whatever the folders'

    def stacked(field: str) -> np.ndarray:
        return np.concatenate([getattr(plant, field)[policy] for _, plant in loaded])[order]

    return PlantSuite(
        {policy: stacked("scores"), **{name: first.scores[name] for name in references}},
        {policy: stacked("failed"), **{name: first.failed[name] for name in references}},
        first.columns,
        first.sets,
        {policy: sorted(runs), **{name: first.runs[name] for name in references}},
    )


def plant_table(
    plants: Mapping[str, PlantSuite],
    policy: str,
    reference: str | Sequence[str],
    max_ratio: float = PLANTS_TARGET,
    max_per_set: float = PER_SET_TARGET,
    reps: int = 2000,
) -> dict[str, Any]:
    """Per run of ``policy`` on both plants, the targets and the counts (module doc); with
    several references, each set's per-set target is the best of them there."""
    from benchmarks.analysis.stats import mean_interval

    five, six = plants["5dof"], plants["6dof"]
    if five.columns != six.columns:
        raise ValueError("the 5-DOF and 6-DOF evaluations fly different sets or seeds")
    if five.runs[policy] != six.runs[policy]:
        raise ValueError(
            f"{policy!r} has runs {five.runs[policy]} on the 5-DOF plant and "
            f"{six.runs[policy]} on the 6-DOF plant"
        )
    columns = np.asarray(five.columns)

    def summary(plant: PlantSuite, name: str, k: int) -> dict[str, Any]:
        matrix = plant.scores[name][k : k + 1]
        interval = mean_interval(matrix, list(columns), key=f"{name}|{k}", reps=reps)
        return {
            "mean": [interval.value, interval.low, interval.high],
            "failed": int(plant.failed[name][k].sum()),
            "per_set": {s: float(matrix[0, columns == s].mean()) for s in five.sets},
        }

    references = _names(reference)
    summaries = {
        name: {plant: summary(plants[plant], name, 0) for plant in PLANTS} for name in references
    }
    best = {
        s: min(references, key=lambda name: summaries[name]["5dof"]["per_set"][s])
        for s in five.sets
    }
    bar = {s: summaries[best[s]]["5dof"]["per_set"][s] for s in five.sets}
    per_run = {}
    for k, run in enumerate(five.runs[policy]):
        entry = {plant: summary(plants[plant], policy, k) for plant in PLANTS}
        ratio = entry["6dof"]["mean"][0] / entry["5dof"]["mean"][0]
        set_ratios = {s: entry["5dof"]["per_set"][s] / bar[s] for s in five.sets}
        no_failure = entry["5dof"]["failed"] == 0 and entry["6dof"]["failed"] == 0
        per_run[str(run)] = {
            **entry,
            "ratio": ratio,
            "set_ratios_5dof": set_ratios,
            "meets_plants": bool(no_failure and ratio <= max_ratio),
            "meets_per_set": bool(
                entry["5dof"]["failed"] == 0 and max(set_ratios.values()) <= max_per_set
            ),
        }
    pooled = {
        plant: mean_interval(plants[plant].scores[policy], list(columns), key=policy, reps=reps)
        for plant in PLANTS
    }
    return {
        "policy": policy,
        "reference": ", ".join(references),
        "sets": five.sets,
        "max_ratio": max_ratio,
        "max_per_set": max_per_set,
        "reference_summary": summaries[references[0]],  # the first's, as one reference's was
        "reference_summaries": summaries,
        "per_set_reference": best,
        "runs": per_run,
        "meets_plants": sum(r["meets_plants"] for r in per_run.values()),
        "meets_per_set": sum(r["meets_per_set"] for r in per_run.values()),
        "pooled": {plant: list(pooled[plant]) for plant in PLANTS},
    }


def markdown(record: Mapping[str, Any]) -> str:
    """`plant_seeds.md`: the per-run table, the reference and the counts."""

    def cell(entry: Mapping[str, Any]) -> str:
        m = entry["mean"]
        return f"{m[0]:.3f} [{m[1]:.3f}, {m[2]:.3f}] ({entry['failed']})"

    sets = record["sets"]
    n_runs = len(record["runs"])
    summaries = record["reference_summaries"]
    several = len(summaries) > 1
    reference_label = f"best of {record['reference']}" if several else record["reference"]
    lines = [
        f"`{record['policy']}` on both plants, per training seed. Mean RMS distance [m] over "
        "every episode with its 95 % bootstrap interval (stratified by set), failed episodes "
        "in brackets (a failed episode scores its set's corridor). Sets: "
        + ", ".join(f"`{s}`" for s in sets)
        + ".",
        "",
        "| seed | 5-DOF | 6-DOF | 6-DOF / 5-DOF | 5-DOF per set / "
        f"{reference_label} | plants target | per-set target |",
        "|---|---|---|---:|---|---|---|",
    ]
    for run, entry in record["runs"].items():
        ratios = ", ".join(f"{entry['set_ratios_5dof'][s]:.2f}" for s in sets)
        lines.append(
            f"| {run} | {cell(entry['5dof'])} | {cell(entry['6dof'])} | {entry['ratio']:.2f} | "
            f"{ratios} | {'yes' if entry['meets_plants'] else 'no'} | "
            f"{'yes' if entry['meets_per_set'] else 'no'} |"
        )
    pooled = record["pooled"]
    lines += [
        f"| {name} | {cell(ref['5dof'])} | {cell(ref['6dof'])} | "
        f"{ref['6dof']['mean'][0] / ref['5dof']['mean'][0]:.2f} | — | | |"
        for name, ref in summaries.items()
    ]
    lines += [
        f"| all {n_runs} seeds | {pooled['5dof'][0]:.3f} [{pooled['5dof'][1]:.3f}, "
        f"{pooled['5dof'][2]:.3f}] | {pooled['6dof'][0]:.3f} [{pooled['6dof'][1]:.3f}, "
        f"{pooled['6dof'][2]:.3f}] | {pooled['6dof'][0] / pooled['5dof'][0]:.2f} | | | |",
        "",
        f"Seeds meeting the plants target (6-DOF ≤ {record['max_ratio']:g}× the 5-DOF mean, no "
        f"failed episode): {record['meets_plants']} of {n_runs}. Seeds meeting the per-set "
        f"target (every 5-DOF set ≤ {record['max_per_set']:g}× {reference_label}, no failed "
        f"episode): {record['meets_per_set']} of {n_runs}.",
    ]
    if several:
        lines.append(
            "The best reference per set: "
            + ", ".join(f"`{s}` {record['per_set_reference'][s]}" for s in sets)
            + "."
        )
    return "\n".join(lines) + "\n"


def figure(record: Mapping[str, Any]) -> Any:
    """The targets drawn (a matplotlib Figure): left, each run's 5-DOF mean per set over the best
    reference's there (one marker per run, the runs side by side within a set) with the per-set
    target; right, each run's 6-DOF / 5-DOF ratio with the plants target. A run with a failed
    episode is drawn hollow."""
    from benchmarks.reports.plotting import new_figure, policy_colours

    sets, runs = list(record["sets"]), record["runs"]
    labels = [f"seed {run}" for run in runs]
    colours = policy_colours(labels)
    fig = new_figure(10.0, 4.0, layout="constrained")
    per_set, plants = fig.subplots(1, 2, width_ratios=[3, 1])
    width = 0.7 / max(len(runs), 1)
    for k, (label, entry) in enumerate(zip(labels, runs.values(), strict=True)):
        offset = (k - (len(runs) - 1) / 2) * width
        failed = entry["5dof"]["failed"] + entry["6dof"]["failed"] > 0
        face = "none" if failed else colours[label]
        ratios = [entry["set_ratios_5dof"][s] for s in sets]
        per_set.plot(
            np.arange(len(sets)) + offset, ratios, "o", color=colours[label], mfc=face, label=label
        )
        plants.plot([offset], [entry["ratio"]], "o", color=colours[label], mfc=face)
    per_set.axhline(record["max_per_set"], color="k", ls="--", lw=1, label="per-set target")
    per_set.set_xticks(range(len(sets)), [s.split(":")[-1] for s in sets], rotation=15)
    per_set.set_ylabel("5-DOF mean / best reference's")
    per_set.set_title("per set, 5-DOF plant", fontsize=10)
    per_set.legend(fontsize=7, ncols=2)
    plants.axhline(record["max_ratio"], color="k", ls="--", lw=1)
    plants.set_xticks([])
    plants.set_ylabel("6-DOF mean / 5-DOF mean")
    plants.set_title("both plants", fontsize=10)
    fig.suptitle(f"{record['policy']} seed by seed; reference: {record['reference']}", fontsize=9)
    return fig


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    from auv_gym.support.files import write_json, write_text
    from benchmarks.reports.plotting import save_figure

    args, parser = parse_options(
        PlantSeedsOptions,
        argv,
        program_name("benchmarks.analysis.plant_seeds"),
        __doc__.split("\n\n")[0],
    )
    with usage_errors(parser):
        if args.out is None or not args.policy:
            raise ValueError("--policy and --out are required")
        if not (args.max_ratio > 0 and args.max_per_set > 0):
            raise ValueError("--max-ratio and --max-per-set must be positive")
        folders = {
            "5dof": [Path(p) for p in comma_names(args.suites_5dof, "--suites-5dof")],
            "6dof": [Path(p) for p in comma_names(args.suites_6dof, "--suites-6dof")],
        }
        references = comma_names(args.reference, "--reference")
        plants = {plant: read_plant(folders[plant], args.policy, references) for plant in PLANTS}
        record = plant_table(
            plants, args.policy, references, args.max_ratio, args.max_per_set, args.reps
        )
    record = {  # folder names only: no machine paths in committed results
        "suites": {plant: [f.name for f in folders[plant]] for plant in PLANTS},
        **record,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    write_json(args.out / SEEDS_FILE, record, indent=1)
    text = markdown(record)
    write_text(args.out / "plant_seeds.md", text)
    save_figure(figure(record), args.out / "plant_seeds.png")
    print(text)
    return record


if __name__ == "__main__":
    main()
