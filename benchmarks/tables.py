"""The tables of a benchmark run: episodes.csv, episodes.json and the markdown summary."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.files import environment, write_json, write_text

__all__ = ["SUMMARY_METRICS", "aggregate", "summarise", "write_tables"]

# Metrics in the summary table, with the direction that is better.
SUMMARY_METRICS = {
    "rms_distance": "min",
    "rms_y_e": "min",
    "rms_z_e": "min",
    "iae_distance": "min",
    "settling_time_0p5": "min",
    "surge_overshoot": "min",
    "rms_speed_error": "min",
    "max_surge": "min",
    "overspeed_fraction": "min",
    "control_effort": "min",
    "chattering": "min",
    "saturation_fraction": "min",
    "success": "max",
}


def write_tables(records: list[dict[str, Any]], out: Path, config: dict[str, Any]) -> str:
    """episodes.csv, episodes.json and summary.md; returns the markdown summary."""
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
    summary = summarise(records, config)
    write_text(out / "summary.md", summary)
    return summary


def aggregate(records: list[dict[str, Any]]) -> dict[tuple[str, str], dict[str, np.ndarray]]:
    """(scenario, policy) → metric → per-seed values (NaN where undefined)."""
    table: dict[tuple[str, str], dict[str, list[float]]] = {}
    for r in records:
        cell = table.setdefault((r["scenario"], r["policy"]), {})
        for metric in SUMMARY_METRICS:
            value = r["metrics"].get(metric)
            cell.setdefault(metric, []).append(np.nan if value is None else float(value))
    return {key: {m: np.asarray(v) for m, v in cell.items()} for key, cell in table.items()}


def summarise(records: list[dict[str, Any]], config: dict[str, Any]) -> str:
    """Markdown: mean ± std of each metric per policy per scenario; the best value in bold."""
    cells = aggregate(records)
    policies = list(dict.fromkeys(r["policy"] for r in records))
    scenarios = list(dict.fromkeys(r["scenario"] for r in records))
    lines = [
        "# Benchmark summary",
        "",
        f"Seeds per cell: {config['seeds']}; duration {config['duration']} s; metrics over "
        f"t ≥ {config['transient']} s where windowed. Mean ± std over seeds (n = finite "
        "values); **bold** marks the best policy per row. Settling times are `inf` when the "
        "distance never stays below the threshold.",
    ]
    for scenario in scenarios:
        lines += [
            "",
            f"## {scenario}",
            "",
            "| metric | " + " | ".join(policies) + " |",
            "|---|" + "---|" * len(policies),
        ]
        for metric, better in SUMMARY_METRICS.items():
            means = []
            texts = []
            for policy in policies:
                values = cells.get((scenario, policy), {}).get(metric, np.array([]))
                finite = values[np.isfinite(values)]
                if values.size and finite.size == 0:
                    means.append(np.inf if better == "min" else -np.inf)
                    texts.append("inf")
                elif finite.size:
                    mean = float(finite.mean())
                    means.append(mean)
                    std = float(finite.std())
                    suffix = f" (n={finite.size})" if finite.size < values.size else ""
                    texts.append(f"{mean:.4g} ± {std:.2g}{suffix}")
                else:
                    means.append(np.nan)
                    texts.append("–")
            finite_means = [m for m in means if not np.isnan(m)]
            if finite_means:
                best = min(finite_means) if better == "min" else max(finite_means)
                texts = [
                    f"**{t}**" if m == best and np.isfinite(m) else t
                    for t, m in zip(texts, means, strict=True)
                ]
            lines.append(f"| {metric} | " + " | ".join(texts) + " |")
    return "\n".join(lines) + "\n"
