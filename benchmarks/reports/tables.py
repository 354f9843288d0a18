"""The tables of a benchmark run: episodes.csv, episodes.json and the markdown summary."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from auv_gym.sim.config import SimConfig
from auv_gym.sim.trajectory import FAILURE_REASONS
from auv_gym.support.files import environment, write_json, write_text
from benchmarks.reports.table_format import (
    FAILURE_CONVENTION,
    METRIC_INFO,
    NEVER_METRICS,
    Cell,
    display_scale,
    mark_best,
    markdown_table,
)

__all__ = [
    "SUMMARY_GROUPS",
    "SUMMARY_METRICS",
    "aggregate",
    "overview",
    "overview_note",
    "summarise",
    "write_tables",
]

# Metrics in the summary table, with the direction that is better, in the column groups that
# keep each table's rows within a screen: tracking, speed, effort, safety.
SUMMARY_GROUPS: dict[str, tuple[str, ...]] = {
    "tracking": ("rms_distance", "rms_y_e", "rms_z_e", "iae_distance", "settling_time_0p5"),
    "speed": (
        "surge_overshoot",
        "rms_speed_error",
        "max_surge",
        "overspeed_fraction",
        "mean_path_speed",
    ),
    "effort": ("control_effort", "chattering", "saturation_fraction"),
    "safety": ("episode_cost",),
    # the vehicle as built (propeller and fins): only scenarios with them show this group
    "propulsion": ("fin_rate_saturation", "mean_shaft_power", "energy_per_km"),
}
SUMMARY_METRICS = {m: METRIC_INFO[m][2] for group in SUMMARY_GROUPS.values() for m in group}
# Short column headers (the long labels are in `benchmarks.reports.table_format.METRIC_INFO`).
_HEADERS = {
    "rms_distance": "RMS d",
    "rms_y_e": "RMS y_e",
    "rms_z_e": "RMS z_e",
    "iae_distance": "IAE d",
    "settling_time_0p5": "settle 0.5 m",
    "surge_overshoot": "overshoot",
    "mean_path_speed": "pace u_p",
    "rms_speed_error": "RMS(u − u_D)",
    "max_surge": "max u",
    # the share of time above the vehicle's top speed; `_group_table` names that speed
    "overspeed_fraction": "time u > max_surge",
    "control_effort": "effort",
    "chattering": "chattering",
    "saturation_fraction": "saturated",
    "episode_cost": "episode cost",
    "fin_rate_saturation": "fin rate-limited",
    "mean_shaft_power": "shaft power",
    "energy_per_km": "energy per km",
}


def write_tables(
    records: list[dict[str, Any]],
    out: Path,
    config: dict[str, Any],
    figures: Sequence[tuple[str, str]] | None = None,
) -> str:
    """episodes.csv, episodes.json and summary.md; returns the markdown summary.

    ``figures``: (file relative to ``out``, one line on what it shows) of every figure the run
    drew, listed near the top of the summary (None: the run drew none)."""
    metric_names = sorted({k for r in records for k in r["metrics"]})
    header = ["scenario", "policy", "seed", *metric_names]

    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(header)
    for r in records:
        writer.writerow(
            [r["scenario"], r["policy"], r["seed"], *(r["metrics"].get(m) for m in metric_names)]
        )
    write_text(out / "episodes.csv", buffer.getvalue())
    payload = {"config": config, **environment(), "episodes": records}
    write_json(out / "episodes.json", payload, indent=1)
    summary = summarise(records, config, figures)
    write_text(out / "summary.md", summary)
    return summary


def aggregate(records: list[dict[str, Any]]) -> dict[tuple[str, str], dict[str, Cell]]:
    """(scenario, policy) → metric → `Cell`: the finished episodes' values and the failures."""
    table: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in records:
        table.setdefault((r["scenario"], r["policy"]), []).append(r["metrics"])
    cells = {}
    for key, episodes in table.items():
        finished = [m for m in episodes if m.get("termination_reason") not in FAILURE_REASONS]
        failed = len(episodes) - len(finished)
        cells[key] = {
            metric: Cell(tuple(_value(m, metric) for m in finished), failed)
            for metric in SUMMARY_METRICS
        }
    return cells


OVERVIEW_METRIC = "rms_distance"  # the benchmark's headline metric


def overview_note(seeds: int, transient: float) -> str:
    """The line that says what the overview's cells are."""
    return (
        f"RMS distance to the path [m], mean of {seeds} seed(s) after t = {transient:g} s; "
        "(n = k/N): the mean of the k of N episodes that did not fail (the others left the "
        "corridor, pitched over...)."
    )


def overview(
    records: list[dict[str, Any]],
    markdown: bool = False,
    scenarios: Sequence[str] | None = None,
) -> str:
    """One screen: a row per policy, a column per scenario, each cell the mean RMS distance [m]
    over the finished episodes with its sample size "(n = k/N)" when some failed, or
    "all N failed" (the benchmark's headline metric; every other one is in summary.md); "n/a"
    where the policy ran no episode (it cannot fly that scenario's vehicle).
    ``markdown``: as a markdown table (summary.md's first table) instead of aligned text.
    ``scenarios``: the columns, in order (the run's chosen scenarios, so one that no policy
    flies still shows, all "n/a"); None: the scenarios of ``records``."""
    cells = aggregate(records)
    policies = list(dict.fromkeys(r["policy"] for r in records))
    if scenarios is None:
        scenarios = list(dict.fromkeys(r["scenario"] for r in records))
    rows = []
    for policy in policies:
        row = [policy]
        for scenario in scenarios:
            cell = cells.get((scenario, policy), {}).get(OVERVIEW_METRIC)
            row.append("n/a" if cell is None else _overview_cell(cell))  # not flown there
        rows.append(row)
    header = ["policy", *scenarios]
    if markdown:
        return markdown_table(header, rows)
    widths = [max(len(r[k]) for r in [header, *rows]) for k in range(len(header))]

    def line(cols: list[str]) -> str:
        return "  ".join(
            c.ljust(w) if k == 0 else c.rjust(w)
            for k, (c, w) in enumerate(zip(cols, widths, strict=True))
        )

    return "\n".join([line(header), *(line(r) for r in rows)])


def _overview_cell(cell: Cell) -> str:
    mean = cell.mean()
    if math.isnan(mean):
        return f"all {cell.episodes} failed" if cell.failed else "-"
    size = cell.sample_size()
    return f"{mean:.3g}" + (f" ({size})" if size else "")


def _value(metrics: dict[str, Any], metric: str) -> float:
    """A recorded metric as a float: NaN when missing or undefined; a settling time stored as
    null (never reached: records hold no infinities) is +inf."""
    if metric not in metrics:
        return math.nan
    value = metrics[metric]
    if value is None:
        return math.inf if metric in NEVER_METRICS else math.nan
    return float(value)


def summarise(
    records: list[dict[str, Any]],
    config: dict[str, Any],
    figures: Sequence[tuple[str, str]] | None = None,
) -> str:
    """Markdown: the overview table (`overview`), the list of figures, then per scenario one row
    per policy, mean ± std over the finished episodes.

    ``figures``: (file, what it shows) of each figure of the run, linked relative to the summary
    (None: none drawn). Four tables per scenario (tracking, speed, effort, safety) and, with the
    propeller and fins, a fifth (propulsion: fin rate limit, shaft power, energy per km), each
    with the failed count; the conventions are `benchmarks.reports.table_format`'s.
    """
    cells = aggregate(records)
    policies = list(dict.fromkeys(r["policy"] for r in records))
    scenarios = _scenarios(records, config)
    lines = [
        "# Benchmark summary",
        "",
        overview_note(config["seeds"], config["transient"]),
        "",
        overview(records, markdown=True, scenarios=scenarios).rstrip(),
        "",
        "## Figures",
        "",
    ]
    if figures:
        lines += [f"- [`{Path(f).name}`]({Path(f).as_posix()}): {text}" for f, text in figures]
    else:
        lines += ["None: this run drew no figures."]
    lines += [
        "",
        "## Every metric",
        "",
        f"Seeds per cell: {config['seeds']}; duration {config['duration']} s; metrics over "
        f"t ≥ {config['transient']} s where windowed (IAE and settling time: the whole "
        "episode). Mean ± std over seeds. " + FAILURE_CONVENTION,
    ]
    for scenario in scenarios:
        lines += ["", f"## {scenario}"]
        if not any(r["scenario"] == scenario for r in records):
            lines += [
                "",
                "n/a: no policy ran an episode here (episodes.json lists why: "
                "config.not_applicable).",
            ]
            continue
        top_speed = _top_speed(config, scenario)
        for group, metrics in SUMMARY_GROUPS.items():
            if not _recorded(records, scenario, metrics):  # e.g. no propeller, no propulsion
                continue
            table = _group_table(cells, scenario, policies, metrics, top_speed).rstrip()
            lines += ["", f"{group}:", "", table]
    return "\n".join(lines).rstrip("\n") + "\n"


def _scenarios(records: list[dict[str, Any]], config: dict[str, Any]) -> list[str]:
    """The run's scenarios in order: those ``config["scenarios"]`` chose (one that every policy
    is n/a on has no record but keeps its column), then any other the records hold."""
    chosen = list(config.get("scenarios", {}))
    return list(dict.fromkeys([*chosen, *(r["scenario"] for r in records)]))


def _top_speed(config: dict[str, Any], scenario: str) -> float | None:
    """The top speed [m/s] of ``scenario``'s vehicle (`AUVParams.max_surge`: 2.0 for REMUS 100,
    2.5 for the torpedo), the speed its episodes' ``overspeed_fraction`` counts time above
    (`auv_gym.rollout`); None when ``config`` does not describe the scenario. The vehicle and
    its ``params`` are the scenario's env arguments (an env id's and an agent's add none)."""
    described = config.get("scenarios", {}).get(scenario)
    if described is None:
        return None
    try:  # a summary rewritten where its vehicle file no longer is: the generic header
        return SimConfig.from_kwargs(**described.get("env", {})).params.max_surge
    except (OSError, ValueError, TypeError):
        return None


def _recorded(records: list[dict[str, Any]], scenario: str, metrics: tuple[str, ...]) -> bool:
    """Whether any episode of ``scenario`` recorded one of ``metrics``."""
    return any(r["scenario"] == scenario and metrics[0] in r["metrics"] for r in records)


def _group_table(
    cells: dict[tuple[str, str], dict[str, Cell]],
    scenario: str,
    policies: list[str],
    metrics: tuple[str, ...],
    top_speed: float | None = None,
) -> str:
    """One group's table of ``scenario``; ``top_speed`` [m/s]: its vehicle's, named in the
    overspeed column's header ("time u > 2.5 m/s"; None: "time u > max_surge")."""
    present = [p for p in policies if (scenario, p) in cells]
    first = {p: cells[(scenario, p)][metrics[0]] for p in present}
    columns = [["failed", *(f"{first[p].failed}/{first[p].episodes}" for p in present)]]
    eligible = [first[p].failed == 0 for p in present]
    for metric in metrics:
        _, unit, better = METRIC_INFO[metric]
        row = [cells[(scenario, p)][metric] for p in present]
        means = [c.mean() for c in row]
        unit, scale = display_scale(unit, means)
        texts = [c.text(metric, scale) for c in row]
        header = f"{_HEADERS[metric]} [{unit}]" if unit != "-" else _HEADERS[metric]
        if metric == "overspeed_fraction" and top_speed is not None:
            header = f"time u > {top_speed:g} m/s"
        columns.append([header, *mark_best(texts, means, eligible, better)])
    header = ["policy", *(c[0] for c in columns)]
    rows = [[p, *(c[i + 1] for c in columns)] for i, p in enumerate(present)]
    return markdown_table(header, rows)
