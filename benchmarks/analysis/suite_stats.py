"""Statistics of a test-suite evaluation (`benchmarks.runner.evaluate_suite`): stats.json, stats.md
and figures from OUT/episodes.csv and OUT/suite.json, with `benchmarks.analysis.stats` (rliable).

* **Score** of an episode: its RMS distance to the virtual point over the metrics window [m]. A
  failed episode (termination_reason in `auv_gym.sim.trajectory.FAILURE_REASONS`: corridor, pitch,
  non_finite, envelope, overspeed) scores its set's corridor half-width (30 m by default,
  docs/model.md §11.5), the distance at which the env declares the path lost: no episode that
  keeps the path scores worse. `failed` counts them in every table.
* **Per set and "aggregate"** (every set pooled, each set's episodes resampled within the set):
  IQM and mean with 95 % stratified bootstrap CIs over runs × episodes (one run for a
  controller: over episodes), `benchmarks.analysis.stats.summarize`; probability that a policy's
  score is below the reference's on the same episode (the report table's reference, or
  ``--reference``; also against its extra references that were evaluated); performance profiles
  (fraction of scores below τ [m]).
* **Target table**: per set, the ratio of a policy's mean score to the reference's, with a
  paired 95 % bootstrap CI (the same episodes resampled for both, each one's runs separately;
  the reference is the set's best by its point estimate, held fixed in every replicate). A set
  passes when the ratio's point estimate is ≤ the report's ``max_ratio`` (the target as stated;
  the CI says how far the verdict stands from chance), no episode failed and the largest
  surge speed of any episode is ≤ the top speed of the set's vehicle (`AUVParams.max_surge`,
  2.0 m/s for REMUS 100).
* **Smoothness** (`benchmarks.analysis.smoothness_stats`): paired RMS-distance differences of the
  report's (policy, base) pairs, and every policy's chattering (when episodes.csv has the
  column).

What is compared is data, the report table (`benchmarks.analysis.report_spec.ReportSpec`, default
``benchmarks/report.toml``); this module names no policy.
* **Learning curves** of the policies given as a multi-seed results directory (its
  ``seed_<k>_learning_curve.csv`` per run; columns num_timesteps, wall_time_s,
  rms_distance_mean, ...): IQM over the runs with CI band against env steps and against wall
  time [s] (`benchmarks.analysis.stats.learning_curve`). Runs are cut to the evaluations every run
  has; an evaluation without a finite rms_distance_mean (every episode terminated) scores the
  failure score of the default corridor.

Everything is written atomically; one bootstrap seed gives bit-identical output.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.sim.config import SimConfig
from auv_gym.sim.task import REMUS_TOP_SPEED
from auv_gym.sim.trajectory import FAILURE_REASONS
from auv_gym.support.files import jsonable, write_json, write_text
from benchmarks.analysis.report_spec import ReportSpec
from benchmarks.analysis.smoothness_stats import (
    chattering_table,
    metric_matrices,
    paired_table,
    smoothness_markdown,
)
from benchmarks.analysis.stats import (
    AGGREGATE,
    MAX_REPS,
    MIN_REPS,
    Interval,
    learning_curve,
    paired_difference,
    probability_of_improvement,
    summarize,
)
from benchmarks.analysis.suite_markdown import stats_markdown

__all__ = [
    "check_stats_options",
    "episode_matrices",
    "episode_score",
    "failure_matrices",
    "learning_curves",
    "read_episodes",
    "read_suite",
    "score_matrices",
    "target_table",
    "top_speeds",
    "write_stats",
]

DEFAULT_FAILURE_SCORE_M = SimConfig.from_kwargs().limits.corridor
CURVE_FILE = "seed_{}_learning_curve.csv"  # in a multi-seed results directory
FIGURES = "figures"


def check_stats_options(reps: int, seed: int) -> None:
    """ValueError naming the flag for a bootstrap count below `MIN_REPS` or a negative seed."""
    if not MIN_REPS <= reps <= MAX_REPS:
        raise ValueError(
            f"--reps must be an integer in [{MIN_REPS}, {MAX_REPS}] (bootstrap replicates), "
            f"got {reps}"
        )
    if seed < 0:
        raise ValueError(f"--bootstrap-seed must be an integer >= 0, got {seed}")


_INTEGER_COLUMNS = ("run", "seed", "window_samples")
_METRIC_COLUMNS = (
    "rms_distance",
    "rms_x_e",
    "rms_y_e",
    "rms_z_e",
    "max_distance",
    "max_surge",
    "overspeed_fraction",
    "duration",
)
_LATER_COLUMNS = ("chattering", "saturation_fraction", "max_roll", "mean_path_speed")  # optional


def _cell(path: Path, line: int, key: str, value: Any, parse: Callable[[str], Any]) -> Any:
    """``parse(value)``: ValueError naming the file, line and column when it is not a number or
    a negative one (every column is a count, distance, speed, fraction or duration; NaN
    stands for an empty metrics window)."""
    try:
        number = parse(value)
    except (TypeError, ValueError):
        raise ValueError(f"{path}: line {line}: {key} = {value!r} is not a number") from None
    if number < 0:
        raise ValueError(f"{path}: line {line}: {key} = {value!r} is negative")
    return number


def parsed_episode_rows(
    path: Path, header: Sequence[str], rows: Sequence[Mapping[str, Any]]
) -> list[dict[str, Any]]:
    """The numeric cells of `csv.DictReader` ``rows`` parsed ({column: number} per row; run,
    seed, window_samples as int); ValueError naming ``path`` and the line for a row of another
    width than ``header`` (a truncated file) or a cell that is not a number, or is a negative
    one. The rows themselves are left as they are."""
    numeric = [
        (key, int if key in _INTEGER_COLUMNS else float)
        for key in (*_INTEGER_COLUMNS, *_METRIC_COLUMNS, *_LATER_COLUMNS)
        if key in header
    ]
    parsed = []
    for line, row in enumerate(rows, start=2):
        if None in row or None in row.values():
            raise ValueError(
                f"{path}: line {line} has another number of cells than the header's "
                f"{len(header)} (a truncated or damaged file)"
            )
        parsed.append({key: _cell(path, line, key, row[key], parse) for key, parse in numeric})
    return parsed


def read_episodes(path: Path) -> list[dict[str, Any]]:
    """The rows of an episodes.csv, numbers parsed (`parsed_episode_rows`). ValueError naming
    the file for a missing column and the line of a damaged row."""
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        rows = list(reader)
        header = reader.fieldnames or []
    missing = [k for k in (*_INTEGER_COLUMNS, *_METRIC_COLUMNS) if k not in header]
    if missing:
        raise ValueError(f"{path}: no column {', '.join(missing)} (not an episodes.csv?)")
    for row, numbers in zip(rows, parsed_episode_rows(path, header, rows), strict=True):
        row.update(numbers)
    return rows


def read_suite_json(path: Path) -> dict[str, Any]:
    """A suite.json; ValueError naming the file when it is not a JSON object."""
    try:
        suite = json.loads(path.read_text())
    except (UnicodeDecodeError, ValueError) as error:
        raise ValueError(f"{path}: not a suite record ({error})") from None
    if not isinstance(suite, dict) or not isinstance(suite.get("sets"), dict):
        raise ValueError(f"{path}: not a suite record (no sets)")
    return suite


def read_suite(folder: Path, where: str) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(suite.json, episodes.csv rows) of a test-suite evaluation folder; ValueError starting
    with ``where`` when either file is missing, naming it when it is damaged."""
    for name in ("episodes.csv", "suite.json"):
        if not (folder / name).is_file():
            raise ValueError(f"{where}: no {name} (run `auv-gym suite` first)")
    return read_suite_json(folder / "suite.json"), read_episodes(folder / "episodes.csv")


def episode_score(row: Mapping[str, Any], failure_score: float) -> float:
    """The score of an episode [m] (module doc); ValueError for an episode that did not fail
    but has no RMS distance (its metrics window is empty)."""
    if row["termination_reason"] in FAILURE_REASONS:
        return failure_score
    value = float(row["rms_distance"])
    if not math.isfinite(value):
        raise ValueError(
            f"policy {row['policy']!r}, run {row['run']}, set {row['set']!r}, seed "
            f"{row['seed']}: no rms_distance although the episode ended by "
            f"{row['termination_reason']!r}; evaluate with a longer duration or a "
            "shorter transient"
        )
    return value


def failure_scores(suite: Mapping[str, Any]) -> dict[str, float]:
    """Set → the score of a failed episode [m]: the corridor of the set's env."""
    return {
        name: SimConfig.from_kwargs(**entry["env"]).limits.corridor
        for name, entry in suite["sets"].items()
    }


def top_speeds(suite: Mapping[str, Any]) -> dict[str, float]:
    """Set → the top speed [m/s] of the set's vehicle (`AUVParams.max_surge` of its env)."""
    return {
        name: SimConfig.from_kwargs(**entry["env"]).params.max_surge
        for name, entry in suite["sets"].items()
    }


def episode_matrices(
    rows: Sequence[Mapping[str, Any]],
    sets: Sequence[str],
    value: Callable[[Mapping[str, Any]], Any],
) -> tuple[dict[str, np.ndarray], list[str], dict[str, list[int]]]:
    """({policy: (n_runs, n_episodes) ``value(row)``}, set of each episode column, {policy:
    runs}).

    Columns are (set, seed) in the order of ``sets``, then seed; every run of every policy must
    hold exactly these episodes (ValueError naming the first that does not)."""
    cells: dict[str, dict[int, dict[tuple[int, int], Any]]] = {}
    order = {name: k for k, name in enumerate(sets)}
    for row in rows:
        if row["set"] not in order:
            raise ValueError(f"episodes.csv: set {row['set']!r} is not in suite.json")
        key = (order[row["set"]], row["seed"])
        cell = cells.setdefault(row["policy"], {}).setdefault(row["run"], {})
        if key in cell:
            raise ValueError(
                f"episodes.csv: policy {row['policy']!r}, run {row['run']} has set "
                f"{row['set']!r} seed {row['seed']} twice"
            )
        cell[key] = value(row)
    if not cells:
        raise ValueError("episodes.csv holds no episode")
    columns = sorted(next(iter(next(iter(cells.values())).values())))
    matrices, runs = {}, {}
    for policy, by_run in cells.items():
        for run, cell in by_run.items():
            if sorted(cell) != columns:
                raise ValueError(
                    f"episodes.csv: policy {policy!r}, run {run} has other episodes "
                    "than the first policy: evaluate every policy on the same "
                    "sets"
                )
        runs[policy] = sorted(by_run)
        matrices[policy] = np.array([[by_run[r][c] for c in columns] for r in runs[policy]])
    return matrices, [sets[s] for s, _ in columns], runs


def score_matrices(
    rows: Sequence[Mapping[str, Any]], sets: Sequence[str], failure: Mapping[str, float]
) -> tuple[dict[str, np.ndarray], list[str], dict[str, list[int]]]:
    """`episode_matrices` of the episodes' scores (`episode_score`, a failed episode scoring
    its set's ``failure``)."""
    return episode_matrices(rows, sets, lambda row: episode_score(row, failure[row["set"]]))


def failure_matrices(
    rows: Sequence[Mapping[str, Any]], sets: Sequence[str]
) -> dict[str, np.ndarray]:
    """{policy: (runs, episodes) True where the episode failed}, in `score_matrices`' columns."""
    from auv_gym.sim.trajectory import FAILURE_REASONS

    return episode_matrices(rows, sets, lambda row: row["termination_reason"] in FAILURE_REASONS)[0]


def mean_pace(rows: Sequence[Mapping[str, Any]]) -> float:
    """Mean of the episodes' pace, the virtual point's mean speed ``mean_path_speed`` [m/s]
    (docs/design.md §3.3), over those that recorded one; NaN when none did (a file written before
    the column existed) or the list is empty."""
    paces = [
        r["mean_path_speed"] for r in rows if math.isfinite(r.get("mean_path_speed", math.nan))
    ]
    return float(np.mean(paces)) if paces else math.nan


def target_table(
    rows: Sequence[Mapping[str, Any]],
    scores: Mapping[str, np.ndarray],
    groups: Sequence[str],
    reference: str | Sequence[str],
    max_ratio: float,
    speeds: Mapping[str, float] | None = None,
    *,
    reps: int = 2000,
    seed: int = 0,
) -> list[dict[str, Any]]:
    """One entry per (set, policy other than the references): mean scores [m], their ratio to
    the best reference of the set with its paired bootstrap CI ("ratio_low", "ratio_high";
    ``reps`` replicates, ``seed``), failed episodes, largest surge [m/s], the policy's and that
    reference's pace (`mean_pace`, m/s: a ratio at unequal paces compares two tasks; reported,
    not judged) and whether the set passes: ratio ≤ ``max_ratio``, no failed episode, surge ≤
    the set's top speed in ``speeds`` [m/s] (`top_speeds`; a set it lacks: REMUS 100's
    `REMUS_TOP_SPEED`) (module doc).
    ``reference``: a policy, or several (those evaluated count), of which each set takes the
    one with the lowest mean ("the best classical policy")."""
    names = [reference] if isinstance(reference, str) else list(reference)
    names = [r for r in names if r in scores]
    if not names:
        raise ValueError(f"target references {reference!r}: none was evaluated")
    labels = np.asarray(groups)
    table = []
    for name in dict.fromkeys(groups):
        cols = labels == name
        top_speed = (speeds or {}).get(name, REMUS_TOP_SPEED)
        ref_means = {r: float(scores[r][:, cols].mean()) for r in names}
        best = min(ref_means, key=ref_means.__getitem__)
        reference_pace = mean_pace([r for r in rows if r["policy"] == best and r["set"] == name])
        for policy, x in scores.items():
            if policy in names:
                continue
            mine = [r for r in rows if r["policy"] == policy and r["set"] == name]
            failed = sorted(
                r["termination_reason"] for r in mine if r["termination_reason"] in FAILURE_REASONS
            )
            surge = max(r["max_surge"] for r in mine)
            mean = float(x[:, cols].mean())
            ratio = mean / ref_means[best]
            relative = paired_difference(
                x[:, cols],
                scores[best][:, cols],
                labels[cols],
                key=f"target|{policy}|{best}|{name}",
                reps=reps,
                seed=seed,
            )["relative"]
            table.append(
                {
                    "set": name,
                    "policy": policy,
                    "mean_m": mean,
                    "reference": best,
                    "reference_mean_m": ref_means[best],
                    "ratio": ratio,
                    # 1 + (mean − ref)/ref is mean/ref to a rounding: where the interval has
                    # collapsed onto the estimate (episodes that draw nothing), it must not
                    # exclude the ratio by that last bit
                    "ratio_low": min(1.0 + relative.low, ratio),
                    "ratio_high": max(1.0 + relative.high, ratio),
                    "failed": len(failed),
                    "failures": sorted(set(failed)),
                    "max_surge_m_s": surge,
                    "pace_m_s": mean_pace(mine),
                    "reference_pace_m_s": reference_pace,
                    "episodes": len(mine),
                    "passed": ratio <= max_ratio and not failed and surge <= top_speed,
                }
            )
    return table


def _read_curve(path: Path) -> dict[str, np.ndarray]:
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no evaluation")
    return {
        key: np.array([float(r[key]) for r in rows])
        for key in ("num_timesteps", "wall_time_s", "rms_distance_mean")
    }


def learning_curves(
    results: Path, runs: Sequence[int], reps: int, seed: int
) -> dict[str, dict[str, Any]]:
    """{"env steps": curve, "wall time [s]": curve} of one multi-seed results directory
    (`benchmarks.analysis.stats.learning_curve` outputs; module doc). FileNotFoundError naming a
    missing learning-curve file."""
    curves = []
    for run in runs:
        path = results / CURVE_FILE.format(run)
        if not path.is_file():
            raise FileNotFoundError(f"{path} does not exist")
        curves.append(_read_curve(path))
    n = min(len(c["num_timesteps"]) for c in curves)
    score = np.array([c["rms_distance_mean"][:n] for c in curves])
    score = np.where(np.isfinite(score), score, DEFAULT_FAILURE_SCORE_M)
    out = {}
    for label, key in (("env steps", "num_timesteps"), ("wall time [s]", "wall_time_s")):
        x = np.array([c[key][:n] for c in curves])
        out[label] = learning_curve(x, score, reps=reps, seed=seed)
    return out


def _intervals(table: Mapping[str, Mapping[str, Interval]]) -> dict[str, Any]:
    return {scope: {p: iv._asdict() for p, iv in row.items()} for scope, row in table.items()}


def write_stats(
    out: Path,
    reference: str | None = None,
    reps: int = 2000,
    seed: int = 0,
    figures: bool = True,
    report: ReportSpec | None = None,
) -> str:
    """Statistics of OUT/episodes.csv (module doc) → OUT/stats.json, OUT/stats.md and, with
    ``figures``, OUT/figures/*.png; returns the Markdown. ``report``: what to compare (None:
    `ReportSpec.read()`, the shipped table); ``reference`` replaces its reference. ValueError
    for a reference that was not evaluated or episodes that do not form complete score
    matrices."""
    report = (report or ReportSpec.read()).with_reference(reference)
    reference = report.reference
    out = Path(out)
    suite = read_suite_json(out / "suite.json")
    rows = read_episodes(out / "episodes.csv")
    failure = failure_scores(suite)
    scores, groups, runs = score_matrices(rows, list(suite["sets"]), failure)
    if reference not in scores:
        raise ValueError(f"--reference {reference!r} was not evaluated; policies: {list(scores)}")
    summary = summarize(scores, groups, reference=reference, reps=reps, seed=seed)
    improvement = {reference: summary["improvement"]}
    for other in report.extra_references:
        if other not in scores or other in improvement:
            continue
        labels = np.asarray(groups)
        improvement[other] = {}
        for scope in summary["scopes"]:
            cols = np.ones(labels.size, bool) if scope == AGGREGATE else labels == scope
            part = {p: a[:, cols] for p, a in scores.items()}
            improvement[other][scope] = probability_of_improvement(
                part, other, labels[cols], reps=reps, seed=seed
            )
    speeds = top_speeds(suite)
    target_refs = report.target_references or (reference,)
    target = target_table(
        rows, scores, groups, target_refs, report.max_ratio, speeds, reps=reps, seed=seed
    )
    verdicts = {}
    for policy in scores:
        mine = [t for t in target if t["policy"] == policy]
        if mine:
            verdicts[policy] = {
                "sets": len(mine),
                "passed": sum(t["passed"] for t in mine),
                "failing_sets": [t["set"] for t in mine if not t["passed"]],
            }
    curves, notes = {}, {}
    for name, entry in suite["policies"].items():
        if entry.get("results") and name in runs:
            try:
                curves[name] = learning_curves(Path(entry["results"]), runs[name], reps, seed)
                notes[name] = f"{curves[name]['env steps']['n_runs']} runs"
            except (OSError, ValueError) as error:
                notes[name] = f"not drawn: {error}"
    stats = {
        "command": suite["command"],
        "reference": reference,
        "reps": reps,
        "seed": seed,
        "confidence": summary["confidence"],
        "failure_score_m": failure,
        "n_runs": summary["n_runs"],
        "runs": runs,
        "scopes": summary["scopes"],
        "iqm": _intervals(summary["iqm"]),
        "mean": _intervals(summary["mean"]),
        "improvement": {r: _intervals(t) for r, t in improvement.items()},
        "profiles": summary["profiles"],
        "target_references": [r for r in target_refs if r in scores],
        "target": target,
        "verdicts": verdicts,
        "learning_curves": curves,
        "learning_curve_notes": notes,
    }
    if rows and "chattering" in rows[0]:
        chattering = metric_matrices(rows, list(suite["sets"]), "chattering", runs)
        stats["paired"] = paired_table(scores, groups, reps, seed, report.pairs, report.worse_ratio)
        stats["chattering"] = chattering_table(
            chattering, groups, reps, seed, report.smoothness_reference
        )
    kinds = {name: entry.get("kind", "agent") for name, entry in suite["policies"].items()}
    text = stats_markdown(
        {**stats, "improvement_tables": improvement, "kinds": kinds},
        summary,
        report.max_ratio,
        speeds,
    )
    if "chattering" in stats:
        text += "\n" + smoothness_markdown(
            stats["paired"], stats["chattering"], report.smoothness_reference, report.worse_ratio
        )
    write_json(out / "stats.json", jsonable(stats), indent=1)
    write_text(out / "stats.md", text)
    if figures:
        _figures(
            out / FIGURES,
            summary,
            improvement,
            curves,
            stats.get("chattering"),
            report.tradeoff_scopes,
        )
    return text


def _figures(
    folder: Path,
    summary: Mapping[str, Any],
    improvement: Mapping[str, Any],
    curves: Mapping[str, Mapping[str, Any]],
    chattering: Mapping[str, Any] | None = None,
    tradeoff_scopes: Sequence[str] = (),
) -> None:
    from benchmarks.analysis.stats_figures import (
        improvement_figure,
        interval_figure,
        learning_curve_figure,
        profile_figure,
        save_figure,
        tradeoff_figure,
    )

    if chattering:  # accuracy against smoothness where the paper's noise acts
        scopes = [s for s in tradeoff_scopes if s in chattering]
        fig = tradeoff_figure(summary, chattering, scopes)
        save_figure(fig, folder / "smoothness_tradeoff.png")

    save_figure(interval_figure(summary), folder / "intervals.png")
    for other, table in improvement.items() if len(summary["policies"]) > 1 else ():
        fig = improvement_figure({**summary, "reference": other, "improvement": table})
        save_figure(fig, folder / f"improvement_over_{other}.png")
    for scope in summary["scopes"]:
        name = scope.replace(":", "_")
        save_figure(profile_figure(summary, scope), folder / f"profile_{name}.png")
    if curves:
        panels: dict[str, dict[str, Any]] = {}
        for policy, by_x in curves.items():
            for xlabel, curve in by_x.items():
                panels.setdefault(xlabel, {})[policy] = curve
        save_figure(learning_curve_figure(panels), folder / "learning_curves.png")
