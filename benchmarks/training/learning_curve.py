"""The learning curve of a run: RUN/evaluations.csv, one row per evaluation during training.

Columns: env steps, training wall time [s] (summed over resumed sessions), and the mean, std and
max rms distance [m], the number of terminated episodes and the largest surge speed [m/s]
over the evaluation seeds; a validation on several plants or actuators adds each one's mean rms
distance and terminated episodes (``rms_distance_mean_<value>``, ``n_terminated_<value>``,
e.g. ``_6dof``, ``_fins``). Rows are
appended and flushed to disk one by one; a resumed run first drops the rows past the checkpoint
it restarts from. `benchmarks.reports.figures.plot_learning_curve` draws it.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Any

from auv_gym.support.files import write_text

__all__ = ["EVAL_FILE", "EVAL_HEADER", "append_row", "read_rows", "truncate_rows"]

EVAL_FILE = "evaluations.csv"
EVAL_HEADER = [
    "num_timesteps",
    "wall_time_s",
    "rms_distance_mean",
    "rms_distance_std",
    "rms_distance_max",
    "n_terminated",
    "max_surge_max",
]


def append_row(path: Path, num_timesteps: int, wall_time: float, summary: dict[str, Any]) -> None:
    """Append one evaluation (a `benchmarks.training.evaluation.summarize` dict) to the curve."""
    row = [
        num_timesteps,
        f"{wall_time:.1f}",
        f"{summary['rms_distance_mean']:.6g}",
        f"{summary['rms_distance_std']:.6g}",
        f"{summary['rms_distance_max']:.6g}",
        summary["n_terminated"],
        f"{summary['max_surge_max']:.6g}",
    ]
    header = list(EVAL_HEADER)
    for variant, part in summary.get("per_variant", {}).items():
        header += [f"rms_distance_mean_{variant}", f"n_terminated_{variant}"]
        row += [f"{part['rms_distance_mean']:.6g}", part["n_terminated"]]
    new = not path.exists()
    with path.open("a", newline="") as f:
        writer = csv.writer(f)
        if new:
            writer.writerow(header)
        writer.writerow(row)
        f.flush()
        os.fsync(f.fileno())


def read_rows(path: Path) -> list[dict[str, str]]:
    """The rows of a learning curve as dicts (column → text)."""
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def truncate_rows(path: Path, max_steps: int) -> None:
    """Drop the rows past ``max_steps`` env steps (a resumed run restarts from there)."""
    if not path.exists():
        return
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    kept = [rows[0]] + [r for r in rows[1:] if r and int(r[0]) <= max_steps]
    buffer = io.StringIO()
    csv.writer(buffer).writerows(kept)
    write_text(path, buffer.getvalue())
