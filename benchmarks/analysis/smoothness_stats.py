"""Policies against the controller they are built on, on the test suite: the paired RMS-distance
difference with its CI, and the chattering of every policy. Which pairs, the chattering
reference and the "worse" threshold come from the report table (`benchmarks.analysis.report_spec`).

* **Paired difference** of a (policy, base) pair per set and "aggregate": mean score of the policy
  minus mean score of the base on the same episodes [m] (scores as
  `benchmarks.analysis.suite_stats`: RMS distance, a failed episode the corridor), relative to the
  base, with a 95 % stratified bootstrap CI (`benchmarks.analysis.stats.paired_difference`). A set
  is a **win** when the upper bound of the difference's CI is below zero, **worse** when the point
  estimate is more than ``worse_ratio`` above the base.
* **Chattering** [1/s] (`auv_gym.metrics`: total variation of the normalised action per second
  over the metrics window) of every policy per set, mean over runs × episodes with its CI; an
  episode that ended before the window has none and is left out. The ratio to the reference's
  (``reference``) says whether a policy halves it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from benchmarks.analysis.stats import AGGREGATE, Interval, mean_interval, paired_difference
from benchmarks.reports.table_format import EMPTY, format_number, markdown_table

__all__ = [
    "chattering_table",
    "metric_matrices",
    "paired_table",
    "smoothness_markdown",
]


def metric_matrices(
    rows: Sequence[Mapping[str, Any]],
    sets: Sequence[str],
    metric: str,
    runs: Mapping[str, Sequence[int]],
) -> dict[str, np.ndarray]:
    """{policy: (n_runs, n_episodes)} of an episodes.csv ``metric`` (NaN where missing), in the
    column order of `benchmarks.analysis.suite_stats.score_matrices` ((set, seed) by ``sets``)."""
    order = {name: k for k, name in enumerate(sets)}
    cells: dict[str, dict[int, dict[tuple[int, int], float]]] = {}
    for row in rows:
        value = row.get(metric)
        cell = cells.setdefault(row["policy"], {}).setdefault(row["run"], {})
        cell[(order[row["set"]], row["seed"])] = np.nan if value is None else float(value)
    out = {}
    for policy, by_run in cells.items():
        columns = sorted(next(iter(by_run.values())))
        out[policy] = np.array([[by_run[r][c] for c in columns] for r in runs[policy]])
    return out


def _scopes(groups: Sequence[str]) -> list[str]:
    return [*dict.fromkeys(groups), AGGREGATE]


def _columns(labels: np.ndarray, scope: str) -> np.ndarray:
    return np.ones(labels.size, bool) if scope == AGGREGATE else labels == scope


def paired_table(
    scores: Mapping[str, np.ndarray],
    groups: Sequence[str],
    reps: int,
    seed: int,
    pairs: Sequence[tuple[str, str]],
    worse_ratio: float,
) -> dict[str, dict[str, dict[str, Any]]]:
    """{"policy−base": {scope: {"difference", "relative" (Intervals as dicts), "win", "worse"}}}
    for every (policy, base) of ``pairs`` whose two policies were evaluated; "worse": the
    relative difference exceeds ``worse_ratio``."""
    labels = np.asarray(groups)
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for policy, base in pairs:
        if policy not in scores or base not in scores:
            continue
        name = f"{policy}−{base}"
        out[name] = {}
        for scope in _scopes(groups):
            cols = _columns(labels, scope)
            iv = paired_difference(
                scores[policy][:, cols],
                scores[base][:, cols],
                labels[cols],
                key=f"{name}|{scope}",
                reps=reps,
                seed=seed,
            )
            out[name][scope] = {
                "difference": iv["difference"]._asdict(),
                "relative": iv["relative"]._asdict(),
                "win": iv["difference"].high < 0.0,
                "worse": iv["relative"].value > worse_ratio,
            }
    return out


def chattering_table(
    chattering: Mapping[str, np.ndarray],
    groups: Sequence[str],
    reps: int,
    seed: int,
    reference: str,
) -> dict[str, dict[str, dict[str, Any]]]:
    """{scope: {policy: {"value", "low", "high", "ratio"}}}: mean chattering [1/s] with CI and
    its ratio to ``reference``'s (NaN when that was not evaluated)."""
    labels = np.asarray(groups)
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for scope in _scopes(groups):
        cols = _columns(labels, scope)
        row: dict[str, dict[str, Any]] = {}
        for policy, x in chattering.items():
            iv = mean_interval(
                x[:, cols], labels[cols], key=f"chattering|{policy}|{scope}", reps=reps, seed=seed
            )
            row[policy] = iv._asdict()
        ref = row.get(reference, {}).get("value", np.nan)
        for entry in row.values():
            entry["ratio"] = entry["value"] / ref if ref and np.isfinite(ref) else np.nan
        out[scope] = row
    return out


def smoothness_markdown(
    paired: Mapping[str, Any], chattering: Mapping[str, Any], reference: str, worse_ratio: float
) -> str:
    """The two tables of the module doc as Markdown (rows = sets), three policies per table;
    ``reference`` and ``worse_ratio`` as given to `chattering_table` and `paired_table`."""
    lines: list[str] = []
    if paired:
        lines += [
            "## Paired RMS-distance difference, policy − base [mm] (relative), 95 % CI\n",
            f"win: CI below zero; worse: more than {100 * worse_ratio:g} % above the base.\n",
        ]
        for names in column_chunks(list(paired), 3):
            rows = []
            for scope in paired[names[0]]:
                cells = []
                for name in names:
                    e = paired[name][scope]
                    d, r = Interval(**e["difference"]), Interval(**e["relative"])
                    tag = " **win**" if e["win"] else (" **worse**" if e["worse"] else "")
                    cells.append(
                        f"{1e3 * d.value:+.2f} [{1e3 * d.low:+.2f}, {1e3 * d.high:+.2f}]"
                        f" ({100 * r.value:+.1f} %){tag}"
                    )
                rows.append([scope, *cells])
            lines += [markdown_table(["set", *names], rows)]
    if chattering:
        policies = list(next(iter(chattering.values())))
        ratios = reference in policies  # a reference the run did not fly gives no ratios
        lines.append(
            f"## Chattering [1/s] (ratio to {reference}), 95 % CI\n"
            if ratios
            else f"## Chattering [1/s], 95 % CI (no ratios: {reference}, their reference, was "
            "not evaluated)\n"
        )
        for names in column_chunks(policies, 3):
            rows = [
                [scope, *(_chattering_cell(row[p], ratios) for p in names)]
                for scope, row in chattering.items()
            ]
            lines += [markdown_table(["set", *names], rows)]
    return "\n".join(lines) + "\n"


def _chattering_cell(entry: Mapping[str, float], ratio: bool = True) -> str:
    if not np.isfinite(entry["value"]):
        return EMPTY
    value, low, high = (format_number(entry[k]) for k in ("value", "low", "high"))
    cell = f"{value} [{low}, {high}]"
    return f"{cell} ({format_number(entry['ratio'])})" if ratio else cell


def column_chunks(names: list[str], most: int) -> list[list[str]]:
    """``names`` in consecutive chunks of at most ``most``, as even in size as possible."""
    if not names:
        return []
    count = -(-len(names) // most)
    size = -(-len(names) // count)
    return [names[i : i + size] for i in range(0, len(names), size)]
