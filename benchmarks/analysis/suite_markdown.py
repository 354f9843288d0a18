"""The Markdown of a suite evaluation's statistics (`benchmarks.analysis.suite_stats.write_stats`):
interval tables per policy group, probability of improvement, the target table and verdicts."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from auv_gym.sim.task import REMUS_TOP_SPEED
from benchmarks.analysis.smoothness_stats import column_chunks
from benchmarks.analysis.stats import Interval, markdown_table
from benchmarks.reports import table_format
from benchmarks.reports.table_format import format_number

__all__ = ["policy_group", "stats_markdown"]


def _by_policy(table: Mapping[str, Mapping[str, Interval]]) -> dict[str, dict[str, Interval]]:
    """{scope: {policy: x}} → {policy: {scope: x}} (rows = sets in the Markdown tables)."""
    out: dict[str, dict[str, Interval]] = {}
    for scope, row in table.items():
        for policy, value in row.items():
            out.setdefault(policy, {})[scope] = value
    return out


def stats_markdown(
    stats: Mapping[str, Any],
    summary: Mapping[str, Any],
    max_ratio: float,
    speeds: Mapping[str, float] | None = None,
) -> str:
    """The statistics as Markdown; ``max_ratio``: the target ratio of the report table;
    ``speeds``: set → its vehicle's top speed [m/s], the surge target (None: REMUS 100's)."""
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
    distinct = set((speeds or {}).values()) or {REMUS_TOP_SPEED}
    surge = (
        f"{distinct.pop():g} m/s" if len(distinct) == 1 else "the top speed of the set's vehicle"
    )
    target_refs = stats.get("target_references") or [ref]
    best = (
        f"{target_refs[0]}"
        if len(target_refs) == 1
        else f"the best of {', '.join(target_refs)} on each set"
    )
    lines += [
        f"## Target: mean RMS distance within {max_ratio:g}× {best}, no failed episode, max "
        f"surge ≤ {surge}\n",
    ]
    # the pace column only where the episodes recorded one (files before it have none)
    paced = any(math.isfinite(t.get("pace_m_s", math.nan)) for t in stats["target"])
    rows = []
    for t in stats["target"]:
        pace = (
            [f"{format_number(t['pace_m_s'])} / {format_number(t['reference_pace_m_s'])}"]
            if paced
            else []
        )
        failed = f"{t['failed']}/{t['episodes']}" + (
            f" ({', '.join(t['failures'])})" if t["failures"] else ""
        )
        reference = [] if len(target_refs) == 1 else [t.get("reference", ref)]
        rows.append(
            [
                t["set"],
                t["policy"],
                format_number(t["mean_m"]),
                *reference,
                format_number(t["reference_mean_m"]),
                f"{format_number(t['ratio'])} [{format_number(t['ratio_low'])}, "
                f"{format_number(t['ratio_high'])}]",
                failed,
                format_number(t["max_surge_m_s"]),
                *pace,
                "pass" if t["passed"] else "**FAIL**",
            ]
        )
    ref_columns = (
        [f"{target_refs[0]} mean [m]"] if len(target_refs) == 1 else ["reference", "its mean [m]"]
    )
    header = [
        "set",
        "policy",
        "mean [m]",
        *ref_columns,
        "ratio [95 % CI]",
        "failed",
        "max surge [m/s]",
        *(["pace [m/s], policy / reference"] if paced else []),
        "verdict",
    ]
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
