"""Statistics of a test-suite evaluation (`benchmarks.evaluate_suite`): stats.json, stats.md and
figures from OUT/episodes.csv and OUT/suite.json, with `benchmarks.stats` (rliable).

* **Score** of an episode: its RMS distance to the virtual point over the metrics window [m]. A
  failed episode (termination_reason in `auv_gym.trajectory.FAILURE_REASONS`: corridor, pitch,
  non_finite, envelope, overspeed) scores its set's corridor half-width (30 m by default,
  docs/model.md §11.5), the distance at which the env declares the path lost: no episode that
  keeps the path scores worse. `failed` counts them in every table.
* **Per set and "aggregate"** (every set pooled, each set's episodes resampled within the set):
  IQM and mean with 95 % stratified bootstrap CIs over runs × episodes (one run for a
  controller: over episodes), `benchmarks.stats.summarize`; probability that a policy's score is
  below the reference's on the same episode (``--reference``, default fbsm; also against
  fbsm_colos when it was evaluated); performance profiles (fraction of scores below τ [m]).
* **Target table**: per set, the ratio of a policy's mean score to the reference's;
  a set passes when the ratio is ≤ `MAX_RATIO`, no episode failed and the largest surge speed
  of any episode is ≤ `auv_gym.task.SURGE_LIMIT` (2.0 m/s).
* **Smoothness** (`benchmarks.smoothness_stats`): paired RMS-distance differences of
  residual agents and the low-pass baseline against their base, and every policy's chattering
  (when episodes.csv has the column).
* **Learning curves** of the policies given as a multi-seed results directory (its
  ``seed_<k>_learning_curve.csv`` per run; columns num_timesteps, wall_time_s,
  rms_distance_mean, ...): IQM over the runs with CI band against env steps and against wall
  time [s] (`benchmarks.stats.learning_curve`). Runs are cut to the evaluations every run has;
  an evaluation without a finite rms_distance_mean (every episode terminated) scores the failure
  score of the default corridor.

Everything is written atomically; one bootstrap seed gives bit-identical output.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym import table_format
from auv_gym.config import SimConfig
from auv_gym.files import jsonable, write_json, write_text
from auv_gym.table_format import format_number
from auv_gym.task import SURGE_LIMIT
from auv_gym.trajectory import FAILURE_REASONS
from benchmarks.smoothness_stats import (
    chattering_table,
    column_chunks,
    metric_matrices,
    paired_table,
    smoothness_markdown,
)
from benchmarks.stats import (
    AGGREGATE,
    MIN_REPS,
    Interval,
    learning_curve,
    markdown_table,
    probability_of_improvement,
    summarize,
)

__all__ = [
    "MAX_RATIO",
    "SECOND_REFERENCE",
    "check_stats_options",
    "episode_score",
    "learning_curves",
    "read_episodes",
    "score_matrices",
    "target_table",
    "write_stats",
]

MAX_RATIO = 2.0  # generalist target: RMS distance within 2x the reference's (FBSM) on every set
SECOND_REFERENCE = "fbsm_colos"  # probability of improvement also against it, when evaluated
DEFAULT_FAILURE_SCORE_M = SimConfig.from_kwargs().limits.corridor
CURVE_FILE = "seed_{}_learning_curve.csv"  # in a multi-seed results directory
FIGURES = "figures"


def check_stats_options(reps: int, seed: int) -> None:
    """ValueError naming the flag for a bootstrap count below `MIN_REPS` or a negative seed."""
    if reps < MIN_REPS:
        raise ValueError(f"--reps must be an integer >= {MIN_REPS}, got {reps}")
    if seed < 0:
        raise ValueError(f"--bootstrap-seed must be an integer >= 0, got {seed}")


def read_episodes(path: Path) -> list[dict[str, Any]]:
    """The rows of an episodes.csv, numbers parsed (run, seed, window_samples as int)."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        for key in ("run", "seed", "window_samples"):
            row[key] = int(row[key])
        for key in (
            "rms_distance",
            "rms_x_e",
            "rms_y_e",
            "rms_z_e",
            "max_distance",
            "max_surge",
            "overspeed_fraction",
            "duration",
        ):
            row[key] = float(row[key])
        for key in ("chattering", "saturation_fraction"):  # absent from older files
            if key in row:
                row[key] = float(row[key])
    return rows


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


def score_matrices(
    rows: Sequence[Mapping[str, Any]], sets: Sequence[str], failure: Mapping[str, float]
) -> tuple[dict[str, np.ndarray], list[str], dict[str, list[int]]]:
    """({policy: (n_runs, n_episodes) scores}, set of each episode column, {policy: runs}).

    Columns are (set, seed) in the order of ``sets``, then seed; every run of every policy must
    hold exactly these episodes (ValueError naming the first that does not)."""
    cells: dict[str, dict[int, dict[tuple[int, int], float]]] = {}
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
        cell[key] = episode_score(row, failure[row["set"]])
    if not cells:
        raise ValueError("episodes.csv holds no episode")
    columns = sorted(next(iter(next(iter(cells.values())).values())))
    scores, runs = {}, {}
    for policy, by_run in cells.items():
        for run, cell in by_run.items():
            if sorted(cell) != columns:
                raise ValueError(
                    f"episodes.csv: policy {policy!r}, run {run} has other episodes "
                    "than the first policy: evaluate every policy on the same "
                    "sets"
                )
        runs[policy] = sorted(by_run)
        scores[policy] = np.array([[by_run[r][c] for c in columns] for r in runs[policy]])
    return scores, [sets[s] for s, _ in columns], runs


def target_table(
    rows: Sequence[Mapping[str, Any]],
    scores: Mapping[str, np.ndarray],
    groups: Sequence[str],
    reference: str,
) -> list[dict[str, Any]]:
    """One entry per (set, policy other than the reference): mean scores [m], their ratio,
    failed episodes, largest surge [m/s] and whether the set passes (module doc)."""
    labels = np.asarray(groups)
    table = []
    for name in dict.fromkeys(groups):
        cols = labels == name
        ref_mean = float(scores[reference][:, cols].mean())
        for policy, x in scores.items():
            if policy == reference:
                continue
            mine = [r for r in rows if r["policy"] == policy and r["set"] == name]
            failed = sorted(
                r["termination_reason"] for r in mine if r["termination_reason"] in FAILURE_REASONS
            )
            surge = max(r["max_surge"] for r in mine)
            mean = float(x[:, cols].mean())
            ratio = mean / ref_mean
            table.append(
                {
                    "set": name,
                    "policy": policy,
                    "mean_m": mean,
                    "reference_mean_m": ref_mean,
                    "ratio": ratio,
                    "failed": len(failed),
                    "failures": sorted(set(failed)),
                    "max_surge_m_s": surge,
                    "episodes": len(mine),
                    "passed": ratio <= MAX_RATIO and not failed and surge <= SURGE_LIMIT,
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
    (`benchmarks.stats.learning_curve` outputs; module doc). FileNotFoundError naming a
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


def _by_policy(table: Mapping[str, Mapping[str, Interval]]) -> dict[str, dict[str, Interval]]:
    """{scope: {policy: x}} → {policy: {scope: x}} (rows = sets in the Markdown tables)."""
    out: dict[str, dict[str, Interval]] = {}
    for scope, row in table.items():
        for policy, value in row.items():
            out.setdefault(policy, {})[scope] = value
    return out


def _markdown(stats: Mapping[str, Any], summary: Mapping[str, Any]) -> str:
    ref, ci = stats["reference"], f"{100 * stats['confidence']:g} %"
    runs = ", ".join(f"{p}: {n}" for p, n in stats["n_runs"].items())
    lines = [
        "# Test-suite statistics\n",
        f"`{stats['command']}`\n",
        f"Score: RMS distance [m] over the metrics window; a failed episode scores its set's "
        f"corridor ({', '.join(sorted({f'{v:g} m' for v in stats['failure_score_m'].values()}))})."
        f" {ci} stratified bootstrap intervals ({stats['reps']} replicates, seed "
        f"{stats['seed']}) over runs × episodes. Runs: {runs}.\n",
    ]
    kinds = stats.get("kinds", {})
    for name, title in (("iqm", "IQM"), ("mean", "Mean")):
        lines.append(f"## {title} RMS distance [m]\n")
        lines += _split_tables(_by_policy(summary[name]), kinds)
    for other, table in stats["improvement_tables"].items():
        lines.append(f"## Probability of a smaller RMS distance than {other} (ties ½)\n")
        lines += _split_tables(_by_policy(table), kinds)
    lines += [
        f"## Target: mean RMS distance within {MAX_RATIO:g}× {ref}, no failed episode, max "
        f"surge ≤ {SURGE_LIMIT:g} m/s\n",
    ]
    rows = []
    for t in stats["target"]:
        failed = f"{t['failed']}/{t['episodes']}" + (
            f" ({', '.join(t['failures'])})" if t["failures"] else ""
        )
        rows.append([t["set"], t["policy"], format_number(t["mean_m"]),
                     format_number(t["reference_mean_m"]), format_number(t["ratio"]), failed,
                     format_number(t["max_surge_m_s"]),
                     "pass" if t["passed"] else "**FAIL**"])  # fmt: skip
    header = ["set", "policy", "mean [m]", f"{ref} mean [m]", "ratio", "failed",
              "max surge [m/s]", "verdict"]  # fmt: skip
    lines += [table_format.markdown_table(header, rows, ["l"] * len(header))]
    for policy, verdict in stats["verdicts"].items():
        failing = ", ".join(verdict["failing_sets"]) or "none"
        lines.append(
            f"- **{policy}**: passes {verdict['passed']} of {verdict['sets']} sets; "
            f"failing: {failing}"
        )
    lines.append("")
    for policy, note in stats["learning_curve_notes"].items():
        lines.append(f"- learning curve of {policy}: {note}")
    return "\n".join(lines) + "\n"


# Policies per table: four interval columns keep a row within about 110 characters.
_COLUMNS_PER_TABLE = 4
_GROUP_TITLES = {"classical": "classical", "rl": "RL", "hybrid": "hybrid (classical + RL residual)"}


def policy_group(name: str, kind: str) -> str:
    """ "classical", "hybrid" (a residual agent on a classical controller) or "rl"."""
    if kind == "classical":
        return "classical"
    return "hybrid" if "residual" in name else "rl"


def _split_tables(
    table: Mapping[str, Mapping[str, Interval]], kinds: Mapping[str, str]
) -> list[str]:
    """One markdown table per policy group, at most `_COLUMNS_PER_TABLE` policies each."""
    groups: dict[str, list[str]] = {}
    for policy in table:
        groups.setdefault(policy_group(policy, kinds.get(policy, "agent")), []).append(policy)
    out = []
    for group in ("classical", "rl", "hybrid"):
        names = groups.get(group, [])
        for chunk in column_chunks(names, _COLUMNS_PER_TABLE):
            out += [
                f"{_GROUP_TITLES[group]}:\n",
                markdown_table({p: table[p] for p in chunk}, corner="set"),
            ]
    return out


def write_stats(
    out: Path, reference: str = "fbsm", reps: int = 2000, seed: int = 0, figures: bool = True
) -> str:
    """Statistics of OUT/episodes.csv (module doc) → OUT/stats.json, OUT/stats.md and, with
    ``figures``, OUT/figures/*.png; returns the Markdown. ValueError for a reference that was not
    evaluated or episodes that do not form complete score matrices."""
    out = Path(out)
    suite = json.loads((out / "suite.json").read_text())
    rows = read_episodes(out / "episodes.csv")
    failure = failure_scores(suite)
    scores, groups, runs = score_matrices(rows, list(suite["sets"]), failure)
    if reference not in scores:
        raise ValueError(f"--reference {reference!r} was not evaluated; policies: {list(scores)}")
    summary = summarize(scores, groups, reference=reference, reps=reps, seed=seed)
    improvement = {reference: summary["improvement"]}
    if SECOND_REFERENCE in scores and SECOND_REFERENCE != reference:
        labels = np.asarray(groups)
        improvement[SECOND_REFERENCE] = {}
        for scope in summary["scopes"]:
            cols = np.ones(labels.size, bool) if scope == AGGREGATE else labels == scope
            part = {p: a[:, cols] for p, a in scores.items()}
            improvement[SECOND_REFERENCE][scope] = probability_of_improvement(
                part, SECOND_REFERENCE, labels[cols], reps=reps, seed=seed
            )
    target = target_table(rows, scores, groups, reference)
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
        "target": target,
        "verdicts": verdicts,
        "learning_curves": curves,
        "learning_curve_notes": notes,
    }
    if rows and "chattering" in rows[0]:
        chattering = metric_matrices(rows, list(suite["sets"]), "chattering", runs)
        stats["paired"] = paired_table(scores, groups, reps, seed)
        stats["chattering"] = chattering_table(chattering, groups, reps, seed)
    kinds = {name: entry.get("kind", "agent") for name, entry in suite["policies"].items()}
    text = _markdown({**stats, "improvement_tables": improvement, "kinds": kinds}, summary)
    if "chattering" in stats:
        text += "\n" + smoothness_markdown(stats["paired"], stats["chattering"])
    write_json(out / "stats.json", jsonable(stats), indent=1)
    write_text(out / "stats.md", text)
    if figures:
        _figures(out / FIGURES, summary, improvement, curves, stats.get("chattering"))
    return text


def _figures(
    folder: Path,
    summary: Mapping[str, Any],
    improvement: Mapping[str, Any],
    curves: Mapping[str, Mapping[str, Any]],
    chattering: Mapping[str, Any] | None = None,
) -> None:
    from benchmarks.stats_figures import (
        improvement_figure,
        interval_figure,
        learning_curve_figure,
        profile_figure,
        save_figure,
        tradeoff_figure,
    )

    if chattering:  # accuracy against smoothness where the paper's noise acts
        scopes = [s for s in ("scenario:paper", "test_distribution", AGGREGATE) if s in chattering]
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
