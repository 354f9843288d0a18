"""Figure helpers, the path-and-tracks plot, and markdown metric tables.

matplotlib is imported lazily and only its object-oriented API is used (`Figure` with the Agg
canvas), so nothing here touches pyplot's global state or needs a display. `new_figure` and
`save_figure` (every PNG written atomically) are the helpers the figure modules build on
(`auv_gym.episode_figures`: the paper's figures of recorded episodes; `benchmarks.figures`);
`plot_track` draws a path with tracks; `metrics_table` formats `auv_gym.metrics.compute_metrics`
results side by side. Frames of a running episode are `auv_gym.rendering`'s job.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path as FilePath
from typing import TYPE_CHECKING, Any

import numpy as np

from auv_gym.files import write_atomic
from auv_gym.paths import Path

if TYPE_CHECKING:
    from matplotlib.figure import Figure


__all__ = ["TABLE_METRICS", "metrics_table", "new_figure", "plot_track", "save_figure"]

# Metrics of the markdown table: name → (label, unit, better: "min" / "max").
TABLE_METRICS: dict[str, tuple[str, str, str]] = {
    "rms_distance": ("RMS distance, t ≥ transient", "m", "min"),
    "rms_x_e": ("RMS x_e, t ≥ transient", "m", "min"),
    "rms_y_e": ("RMS y_e, t ≥ transient", "m", "min"),
    "rms_z_e": ("RMS z_e, t ≥ transient", "m", "min"),
    "max_distance_window": ("max distance, t ≥ transient", "m", "min"),
    "iae_distance": ("IAE distance (whole episode)", "m·s", "min"),
    "settling_time_0p5": ("settling time to 0.5 m", "s", "min"),
    "settling_time_0p1": ("settling time to 0.1 m", "s", "min"),
    "surge_overshoot": ("surge overshoot max(u − u_D)", "m/s", "min"),
    "rms_speed_error": ("RMS(u − u_D), t ≥ transient", "m/s", "min"),
    "max_surge": ("max surge u", "m/s", "min"),
    "overspeed_fraction": ("time with u > 2.0 m/s", "-", "min"),
    "control_effort": ("control effort ∫Σ(τ/τ_max)² dt", "s", "min"),
    "chattering": ("chattering TV(τ/τ_max) per s", "1/s", "min"),
    "saturation_fraction": ("saturated control steps", "-", "min"),
    "final_distance": ("final distance", "m", "min"),
    "success": ("success", "-", "max"),
    "termination_reason": ("episode end", "-", ""),
}

_DPI = 150  # default resolution [dots/in]


def new_figure(
    width_in: float, height_in: float, dpi: int = _DPI, layout: str | None = None
) -> Figure:
    """A matplotlib `Figure` of ``width_in`` × ``height_in`` inches, outside pyplot's state.

    ``layout``: matplotlib's layout engine ("constrained", "tight" or None).
    """
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), dpi=dpi, layout=layout)


def save_figure(fig: Figure, file: str | os.PathLike, dpi: int | None = None) -> FilePath:
    """Write ``fig`` as PNG atomically (temporary file in the same folder, then `os.replace`)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    dots = dpi if dpi is not None else fig.dpi
    return write_atomic(file, lambda fh: fig.savefig(fh, format="png", dpi=dots))


def plot_track(fig, path: Path, tracks: dict[str, np.ndarray], s_max: float) -> None:
    """Draw the path and tracks (name → (T, 3) NED positions [m]) in 3D plus x–y and x–z views.

    Depth is plotted as −z so that "up" is up.
    """
    ref = path.sample(600, s_max=max(s_max, 1.0))
    ax3d = fig.add_subplot(1, 3, 1, projection="3d")
    ax_xy = fig.add_subplot(1, 3, 2)
    ax_xz = fig.add_subplot(1, 3, 3)
    ax3d.plot(ref[:, 0], ref[:, 1], -ref[:, 2], "k--", lw=1, label="path")
    ax_xy.plot(ref[:, 0], ref[:, 1], "k--", lw=1)
    ax_xz.plot(ref[:, 0], -ref[:, 2], "k--", lw=1)
    for name, track in tracks.items():
        ax3d.plot(track[:, 0], track[:, 1], -track[:, 2], lw=1.5, label=name)
        ax_xy.plot(track[:, 0], track[:, 1], lw=1.5)
        ax_xz.plot(track[:, 0], -track[:, 2], lw=1.5)
        ax3d.scatter(*track[-1, :2], -track[-1, 2], s=12)
    ax3d.set(xlabel="x [m]", ylabel="y [m]", zlabel="−z [m]", title="3D path")
    ax3d.legend(loc="upper left", fontsize=7)
    ax_xy.set(xlabel="x [m]", ylabel="y [m]", title="horizontal projection", aspect="equal")
    ax_xz.set(xlabel="x [m]", ylabel="−z [m]", title="vertical projection")
    for ax in (ax_xy, ax_xz):
        ax.grid(True, alpha=0.3)


def _format(value: Any) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, str):
        return value or "–"
    if value is None:
        return "–"
    value = float(value)
    if math.isnan(value):
        return "–"
    if math.isinf(value):
        return "never" if value > 0 else "−inf"
    return f"{value:.4g}"


def metrics_table(
    results: Mapping[str, Mapping[str, Any]], metrics: Sequence[str] | None = None
) -> str:
    """Markdown table: one row per metric, one column per policy; the best value in bold.

    ``results`` maps a policy label to its `compute_metrics` dict. "never" marks a settling
    time that was not reached, "–" an undefined value (e.g. a window the episode did not reach).
    """
    names = list(results)
    rows = list(metrics) if metrics is not None else list(TABLE_METRICS)
    lines = [
        "| metric | unit | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for metric in rows:
        label, unit, better = TABLE_METRICS.get(metric, (metric, "", ""))
        values = [results[name].get(metric) for name in names]
        texts = [_format(v) for v in values]
        numeric = [
            float(v)
            for v in values
            if isinstance(v, (int, float, np.number)) and not isinstance(v, (bool, np.bool_))
        ]
        if better and len(names) > 1 and numeric and all(not math.isnan(v) for v in numeric):
            best = min(numeric) if better == "min" else max(numeric)
            if math.isfinite(best) and numeric.count(best) < len(numeric):
                texts = [
                    f"**{t}**" if _is(v, best) else t for t, v in zip(texts, values, strict=True)
                ]
        lines.append(f"| {label} | {unit} | " + " | ".join(texts) + " |")
    return "\n".join(lines) + "\n"


def _is(value: Any, best: float) -> bool:
    try:
        return float(value) == best
    except (TypeError, ValueError):
        return False
