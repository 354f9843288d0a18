"""Time to a flying agent, with and without the jump start: two multi-seed schedule runs (one
from random weights, one whose first phase is a `jump_start`) side by side on the validation
episodes both were selected on, against the classical policies on the same episodes.

    python -m benchmarks.analysis.jump_start --scratch runs/jump_start/scratch \\
        --jump runs/jump_start/jump --out benchmarks/results/jump_start
    (several runs of a recipe, other seeds: --scratch A,B)

Each seed's validation curve is read from its phases' `evaluations.csv`; a jump-started seed's
wall clock and env steps run on from its jump-start phase into its PPO phase. The classical
policies fly the same validation episodes (the schedule's task set, its first `eval_episodes`
seeds, `eval_duration`), so every row compares on identical disturbances. Written to --out:
`curves.csv` (every evaluation of every seed), `summary.json`, `summary.md` (per seed: the
first evaluation that beats each classical policy with no failed episode, its env steps and
wall time, and the final one) and `curves.png`.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.arguments import parse_options, program_name, usage_errors
from benchmarks.options import option

__all__ = ["main", "seed_curves"]

REFERENCES = ("fbsm", "fbsm_colos")  # the classical policies every curve is measured against
EVAL_FILE = "evaluations.csv"


@dataclass
class JumpStartOptions:
    """The options of ``python -m benchmarks.analysis.jump_start``."""

    scratch: str = option("", "schedule runs from random weights (comma-separated folders)")
    jump: str = option("", "schedule runs with a jump_start phase first (comma-separated)")
    out: Path | None = option(None, "folder for the curves and summaries", parse=Path)  # noqa: RUF009


def seed_curves(run: Path) -> dict[int, list[dict[str, float]]]:
    """Seed → its validation evaluations in order across the run's phase folders: env steps
    and wall time [s] accumulate from one phase to the next."""
    folders = sorted(run.glob("phase_*_*"), key=lambda f: int(f.name.split("_")[1]))
    curves: dict[int, list[dict[str, float]]] = {}
    offsets: dict[int, tuple[float, float]] = {}
    for folder in folders:  # phase_<k>_<name>, in order (an unfinished one too)
        phase = folder.name.split("_", 2)[2]
        for seed_dir in sorted(folder.glob("seed_*")):
            if not (seed_dir / EVAL_FILE).is_file():
                continue
            seed = int(seed_dir.name.removeprefix("seed_"))
            steps0, wall0 = offsets.get(seed, (0.0, 0.0))
            with (seed_dir / EVAL_FILE).open(newline="") as f:
                rows = list(csv.DictReader(f))
            for r in rows:
                curves.setdefault(seed, []).append(
                    {
                        "phase": phase,
                        "env_steps": steps0 + float(r["num_timesteps"]),
                        "wall_time_s": wall0 + float(r["wall_time_s"]),
                        "rms_distance": float(r["rms_distance_mean"]),
                        "failed": int(r["n_terminated"]),
                    }
                )
            if rows:
                last = curves[seed][-1]
                offsets[seed] = (last["env_steps"], last["wall_time_s"])
    return curves


def merged_curves(runs: Sequence[Path]) -> dict[int, list[dict[str, float]]]:
    """`seed_curves` of several runs of one recipe (different seeds); a seed twice is an error."""
    merged: dict[int, list[dict[str, float]]] = {}
    for run in runs:
        for seed, curve in seed_curves(run).items():
            if seed in merged:
                raise ValueError(f"seed {seed} appears in two runs ({run})")
            merged[seed] = curve
    return merged


def validation_episodes(run: Path) -> tuple[str, list[int], float, dict[str, Any]]:
    """The run's validation task set, its seeds, the episode length [s] and the env."""
    from auv_gym import VARIANTS

    schedule = json.loads((run / "schedule.json").read_text())
    plan = schedule["phases"][0]["summary"]["plan"]
    duration = float(plan["eval_duration"])
    env = {**VARIANTS[plan["env_id"]], **dict(plan["eval_env"]), "max_time": duration}
    env.pop("observation", None)  # a classical policy reads the paper's observation
    return plan["task_set"], [int(s) for s in plan["eval_seeds"]], duration, env


def reference_scores(env: dict[str, Any], seeds: Sequence[int]) -> dict[str, dict[str, float]]:
    """Mean RMS distance [m] over the finished episodes and the failed count of each of
    `REFERENCES` on the validation episodes."""
    import controllers
    from benchmarks.training.evaluation import evaluate_policy_on_seeds

    scores = {}
    for name in REFERENCES:
        results = evaluate_policy_on_seeds(controllers.make(name, env=env), seeds, **env)
        finished = [r["rms_distance"] for r in results if r["termination_reason"] == ""]
        mean = sum(finished) / len(finished) if finished else math.inf
        scores[name] = {"rms_distance": mean, "failed": len(results) - len(finished)}
    return scores


def first_below(curve: Sequence[dict[str, float]], bound: float) -> dict[str, float] | None:
    """The first evaluation with no failed episode and a mean RMS distance below ``bound``."""
    return next((e for e in curve if e["failed"] == 0 and e["rms_distance"] < bound), None)


def summarise(
    runs: dict[str, dict[int, list[dict[str, float]]]], references: dict[str, dict[str, float]]
) -> dict[str, Any]:
    """Per run and seed: the first evaluation beating each reference, and the last one."""
    out: dict[str, Any] = {}
    for label, curves in runs.items():
        out[label] = {}
        for seed, curve in sorted(curves.items()):
            beats = {
                name: first_below(curve, ref["rms_distance"]) for name, ref in references.items()
            }
            out[label][str(seed)] = {"beats": beats, "final": curve[-1]}
    return out


def _when(e: dict[str, float] | None) -> str:
    if e is None:
        return "not reached"
    return f"{e['env_steps'] / 1e6:.2f} M steps, {e['wall_time_s'] / 60:.1f} min ({e['phase']})"


def write_markdown(
    summary: dict[str, Any],
    references: dict[str, dict[str, float]],
    task: tuple[str, int, float],
    path: Path,
) -> None:
    """summary.md: the references, then a row per run and seed."""
    task_set, episodes, duration = task
    lines = [
        f"Validation: the first {episodes} episodes of `{task_set}` ({duration:g} s), the "
        "episodes both runs were selected on. Classical policies on the same episodes:",
        "",
        *(
            f"- `{n}`: {r['rms_distance']:.4g} m RMS distance, {r['failed']} failed"
            for n, r in references.items()
        ),
        "",
        "| run | seed | "
        + " | ".join(f"first below `{n}`" for n in references)
        + " | last: RMS [m], failed, steps, wall |",
        "|---|---|" + "---|" * len(references) + "---|",
    ]
    for label, seeds in summary.items():
        for seed, row in seeds.items():
            last = row["final"]
            lines.append(
                f"| {label} | {seed} | "
                + " | ".join(_when(row["beats"][n]) for n in references)
                + f" | {last['rms_distance']:.4g}, {last['failed']}, "
                f"{last['env_steps'] / 1e6:.2f} M, {last['wall_time_s'] / 60:.1f} min |"
            )
    path.write_text("\n".join(lines) + "\n")


def plot(
    runs: dict[str, dict[int, list[dict[str, float]]]],
    references: dict[str, dict[str, float]],
    path: Path,
) -> None:
    """Validation RMS distance against wall time, every seed of both runs, the references as
    horizontal lines; a cross where an evaluation had failed episodes."""
    from benchmarks.reports.plotting import new_figure, save_figure

    fig = new_figure(7.5, 4.2)
    ax = fig.subplots()
    colours = {"scratch": "#0072B2", "jump start": "#D55E00"}
    for label, curves in runs.items():
        for k, (_, curve) in enumerate(sorted(curves.items())):
            minutes = [e["wall_time_s"] / 60 for e in curve]
            rms = [
                min(e["rms_distance"], 30.0) if math.isfinite(e["rms_distance"]) else 30.0
                for e in curve
            ]
            ax.plot(minutes, rms, "-", color=colours[label], label=label if k == 0 else None)
            bad = [(m, r) for m, r, e in zip(minutes, rms, curve, strict=True) if e["failed"]]
            if bad:
                ax.plot(*zip(*bad, strict=True), "x", color=colours[label], ms=6)
    for style, (name, ref) in zip(("--", ":"), references.items(), strict=False):
        ax.axhline(ref["rms_distance"], color="0.3", ls=style, label=f"{name} (same episodes)")
    ax.set_yscale("log")
    ax.set_xlabel("training wall time [min] (one thread per seed, two seeds at once)")
    ax.set_ylabel("validation RMS distance [m], log scale")
    ax.set_title(
        "Time to a flying agent: PPO from scratch and after a DAgger jump start", fontsize=9
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, title="× : an episode failed", title_fontsize=7)
    fig.tight_layout()
    save_figure(fig, path)


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        JumpStartOptions,
        argv,
        program_name("benchmarks.analysis.jump_start"),
        __doc__.split("\n\n")[0],
    )
    with usage_errors(parser):
        folders = {}
        for flag, text in (("--scratch", args.scratch), ("--jump", args.jump)):
            folders[flag] = [Path(t) for t in text.split(",") if t]
            bad = [f for f in folders[flag] if not (f / "schedule.json").is_file()]
            if not folders[flag] or bad:
                raise ValueError(f"{flag}: {bad or text!r} is not a train-seeds schedule run")
        if args.out is None:
            raise ValueError("--out is required")
    runs = {
        "scratch": merged_curves(folders["--scratch"]),
        "jump start": merged_curves(folders["--jump"]),
    }
    every = [*folders["--scratch"], *folders["--jump"]]
    task_set, seeds, duration, env = validation_episodes(every[0])
    for run in every[1:]:  # one comparison: the same validation episodes for every run
        if validation_episodes(run) != (task_set, seeds, duration, env):
            parser.error(f"{run} was validated on other episodes than {every[0]}")
    references = reference_scores(env, seeds)
    summary = summarise(runs, references)
    args.out.mkdir(parents=True, exist_ok=True)
    with (args.out / "curves.csv").open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(
            ["run", "seed", "phase", "env_steps", "wall_time_s", "rms_distance", "failed"]
        )
        for label, curves in runs.items():
            for seed, curve in sorted(curves.items()):
                for e in curve:
                    writer.writerow(
                        [
                            label,
                            seed,
                            e["phase"],
                            int(e["env_steps"]),
                            e["wall_time_s"],
                            e["rms_distance"],
                            e["failed"],
                        ]
                    )
    record = {
        "task_set": task_set,
        "seeds": seeds,
        "duration": duration,
        "references": references,
        "runs": summary,
    }
    (args.out / "summary.json").write_text(json.dumps(record, indent=1) + "\n")
    write_markdown(summary, references, (task_set, len(seeds), duration), args.out / "summary.md")
    plot(runs, references, args.out / "curves.png")
    print((args.out / "summary.md").read_text())
    return record


if __name__ == "__main__":
    main()
