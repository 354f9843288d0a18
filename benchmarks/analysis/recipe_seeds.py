"""A recipe's seeds on their held-out test episodes: does the recipe reproduce, seed after seed?

    python -m benchmarks.analysis.recipe_seeds --runs runs/jump,runs/jump_b,runs/jump_c \\
        --out benchmarks/results/jump_start/ten_seeds

Reads every seed of one or more `train-seeds` runs of the same recipe (a schedule's last phase,
or a one-phase run): the agent its seed selected on validation, and that agent's held-out test
episodes (`held_out_evaluation.json`: the paper scenario, seeds 0-9, never used for selection).
FBSM and FBSM + CO-LOS fly the same episodes. Written to --out: `seeds.csv` (every seed's test
episodes), `summary.json` and `summary.md`: per seed its mean RMS distance [m], failed episodes
and whether it beats each classical policy (a lower mean and no failed episode), then the
recipe's IQM and mean over seeds × episodes with 95 % bootstrap intervals (`stats`: runs
resampled within episodes).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.arguments import parse_options, program_name, usage_errors
from benchmarks.options import option

__all__ = ["main", "seed_agents"]

REFERENCES = ("fbsm", "fbsm_colos")
SUMMARY_FILE = "summary.json"


@dataclass
class RecipeSeedsOptions:
    """The options of ``python -m benchmarks.analysis.recipe_seeds``."""

    runs: str = option("", "train-seeds runs of one recipe (comma-separated folders)")
    out: Path | None = option(None, "folder for the tables", parse=Path)  # noqa: RUF009


def _final_phase(run: Path) -> Path:
    """The folder whose `summary.json` lists the run's seeds: a schedule's last phase, or the run
    itself; ValueError naming the run if it has neither."""
    schedule = run / "schedule.json"
    if schedule.is_file():
        phases = json.loads(schedule.read_text())["phases"]
        folder = run / f"phase_{len(phases)}_{phases[-1]['name']}"
    else:
        folder = run
    if not (folder / SUMMARY_FILE).is_file():
        raise ValueError(f"{run}: no {SUMMARY_FILE} of a finished train-seeds run")
    return folder


def seed_agents(runs: Sequence[Path]) -> dict[int, dict[str, Any]]:
    """Every seed of the runs: its selected agent's held-out evaluation, wall time and steps;
    ValueError for a seed found twice or evaluated on other episodes than the first."""
    seeds: dict[int, dict[str, Any]] = {}
    episodes = None
    for run in runs:
        summary = json.loads((_final_phase(run) / SUMMARY_FILE).read_text())
        for entry in summary["seeds"]:
            seed = int(entry["seed"])
            if seed in seeds:
                raise ValueError(f"seed {seed} appears in two runs ({run})")
            held_out = json.loads((Path(entry["agent"]) / "held_out_evaluation.json").read_text())
            key = (held_out["scenario"], held_out["seeds"], held_out["duration_s"])
            if episodes is not None and key != episodes:
                raise ValueError(f"{run} seed {seed} was tested on other episodes: {key}")
            episodes = key
            seeds[seed] = {
                "results": held_out["results"],
                "wall_time_s": entry.get("wall_time_s"),
                "num_timesteps": entry.get("num_timesteps"),
                "duration_s": held_out["duration_s"],
                "transient_s": held_out["transient_s"],
                "episode_seeds": held_out["seeds"],
            }
    return dict(sorted(seeds.items()))


def _episode_scores(results: Sequence[dict[str, Any]], corridor: float) -> list[float]:
    """RMS distance [m] per episode, a failed one scoring the corridor (as the suite does)."""
    return [corridor if r["termination_reason"] else float(r["rms_distance"]) for r in results]


def classical_results(
    names: Sequence[str], seeds: Sequence[int], duration: float, transient: float
) -> dict[str, list[dict[str, Any]]]:
    """The classical policies on the held-out episodes of `AUVPath3DPreview-v0` (the paper
    scenario under the RL task's surge limit, the agents' env; the paper observation)."""
    import controllers
    from auv_gym import VARIANTS
    from benchmarks.training.evaluation import evaluate_policy_on_seeds

    env = {**VARIANTS["AUVPath3DPreview-v0"], "max_time": duration}
    env.pop("observation", None)
    return {
        name: evaluate_policy_on_seeds(
            controllers.make(name, env=env), seeds, transient=transient, **env
        )
        for name in names
    }


def summarise(
    seeds: dict[int, dict[str, Any]], classical: dict[str, list[dict[str, Any]]], corridor: float
) -> dict[str, Any]:
    """Per seed: mean RMS distance, failures and which references it beats; the aggregate."""
    from benchmarks.analysis.stats import interval_estimates

    refs = {
        name: {
            "rms_distance": float(np.mean(_episode_scores(results, corridor))),
            "failed": sum(1 for r in results if r["termination_reason"]),
        }
        for name, results in classical.items()
    }
    per_seed = {}
    for seed, entry in seeds.items():
        scores = _episode_scores(entry["results"], corridor)
        failed = sum(1 for r in entry["results"] if r["termination_reason"])
        mean = float(np.mean(scores))
        per_seed[str(seed)] = {
            "rms_distance": mean,
            "failed": failed,
            "beats": {
                name: failed == 0 and mean < ref["rms_distance"] for name, ref in refs.items()
            },
            "wall_time_s": entry["wall_time_s"],
            "num_timesteps": entry["num_timesteps"],
        }
    matrix = np.array([_episode_scores(e["results"], corridor) for e in seeds.values()])
    scores = {"recipe": matrix}
    scores.update({n: np.array([_episode_scores(r, corridor)]) for n, r in classical.items()})
    intervals = interval_estimates(scores)
    return {
        "references": refs,
        "seeds": per_seed,
        "beat_counts": {n: sum(s["beats"][n] for s in per_seed.values()) for n in refs},
        "failed_episodes": int(sum(s["failed"] for s in per_seed.values())),
        "episodes": int(matrix.size),
        "intervals": {
            stat: {name: list(interval[:3]) for name, interval in by_policy.items()}
            for stat, by_policy in intervals.items()
        },
    }


def write_markdown(record: dict[str, Any], path: Path) -> None:
    """`summary.md`: the per-seed table and the intervals."""
    n_seeds = len(record["seeds"])
    lines = [
        f"Held-out test: {record['scenario']}, episode seeds {record['episode_seeds']}, "
        f"{record['duration_s']:g} s (metrics from {record['transient_s']:g} s); a failed "
        f"episode scores the {record['corridor']:g}-m corridor.",
        "",
        "| seed | RMS distance [m] | failed | beats FBSM | beats FBSM + CO-LOS | steps "
        "| wall, last phase |",
        "|---|---:|---:|---|---|---:|---:|",
    ]
    for seed, s in record["seeds"].items():
        wall = s["wall_time_s"]
        lines.append(
            f"| {seed} | {s['rms_distance']:.4f} | {s['failed']} | "
            f"{'yes' if s['beats']['fbsm'] else 'no'} | "
            f"{'yes' if s['beats']['fbsm_colos'] else 'no'} | "
            f"{(s['num_timesteps'] or 0) / 1e6:.2f} M | "
            f"{'' if wall is None else f'{wall / 60:.1f} min'} |"
        )
    refs = record["references"]
    lines += [
        "",
        f"Classical policies on the same episodes: FBSM {refs['fbsm']['rms_distance']:.4f} m "
        f"({refs['fbsm']['failed']} failed), FBSM + CO-LOS "
        f"{refs['fbsm_colos']['rms_distance']:.4f} m ({refs['fbsm_colos']['failed']} failed).",
        f"Seeds beating FBSM: {record['beat_counts']['fbsm']} of {n_seeds}; FBSM + CO-LOS: "
        f"{record['beat_counts']['fbsm_colos']} of {n_seeds}; failed test episodes: "
        f"{record['failed_episodes']} of {record['episodes']}.",
        "",
        "| policy | IQM [m], 95 % CI | mean [m], 95 % CI |",
        "|---|---|---|",
    ]
    for name in record["intervals"]["iqm"]:
        iqm, mean = record["intervals"]["iqm"][name], record["intervals"]["mean"][name]
        label = f"recipe ({n_seeds} seeds)" if name == "recipe" else name
        lines.append(
            f"| {label} | {iqm[0]:.4f} [{iqm[1]:.4f}, {iqm[2]:.4f}] | "
            f"{mean[0]:.4f} [{mean[1]:.4f}, {mean[2]:.4f}] |"
        )
    path.write_text("\n".join(lines) + "\n")


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    from auv_gym.support.files import write_json

    args, parser = parse_options(
        RecipeSeedsOptions,
        argv,
        program_name("benchmarks.analysis.recipe_seeds"),
        __doc__.split("\n\n")[0],
    )
    with usage_errors(parser):
        runs = [Path(t) for t in args.runs.split(",") if t]
        if not runs:
            raise ValueError("--runs: give at least one train-seeds run folder")
        if args.out is None:
            raise ValueError("--out is required")
        seeds = seed_agents(runs)
    first = next(iter(seeds.values()))
    corridor = _corridor()
    classical = classical_results(
        REFERENCES, first["episode_seeds"], first["duration_s"], first["transient_s"]
    )
    record = {
        "runs": [r.name for r in runs],  # no machine paths in committed results
        "scenario": "paper helix under the RL task's surge limit (AUVPath3DPreview-v0)",
        "episode_seeds": first["episode_seeds"],
        "duration_s": first["duration_s"],
        "transient_s": first["transient_s"],
        "corridor": corridor,
        **summarise(seeds, classical, corridor),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    with (args.out / "seeds.csv").open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["policy", "seed", "episode_seed", "rms_distance", "termination_reason"])
        for seed, entry in seeds.items():
            for r in entry["results"]:
                writer.writerow(
                    ["recipe", seed, r["seed"], r["rms_distance"], r["termination_reason"]]
                )
        for name, results in classical.items():
            for r in results:
                writer.writerow([name, "", r["seed"], r["rms_distance"], r["termination_reason"]])
    write_json(args.out / SUMMARY_FILE, record, indent=1)
    write_markdown(record, args.out / "summary.md")
    print((args.out / "summary.md").read_text())
    return record


def _corridor() -> float:
    """The corridor [m] a failed episode scores (the env's default corridor)."""
    from auv_gym.sim.task import TaskLimits

    return float(TaskLimits().corridor)


if __name__ == "__main__":
    main()
