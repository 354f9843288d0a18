"""Figures of a policy comparison (`benchmarks.compare`): track overlays, distance, metric bars.

Reads the per-episode records (metrics) and the stored `.npz` trajectories; writes PNG files
atomically. Matplotlib is imported lazily with the Agg backend.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.evaluation import Trajectory
from auv_gym.paths import make_path

__all__ = ["BAR_METRICS", "comparison_figures"]

# Metric → axis label of the bar charts.
BAR_METRICS = {
    "rms_distance": "RMS distance [m]",
    "rms_y_e": "RMS y_e [m]",
    "rms_z_e": "RMS z_e [m]",
    "settling_time_0p5": "settling time to 0.5 m [s]",
    "rms_speed_error": "RMS u − u_D [m/s]",
    "control_effort": "∫|τ/τ_max|² dt [s]",
    "chattering": "total variation of τ/τ_max per s [1/s]",
}


def _figure(width_in: float, height_in: float):
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), dpi=110)


def _save(fig, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.png")
    try:
        fig.savefig(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def comparison_figures(
    records: Sequence[Mapping[str, Any]], out: Path, scenarios: Mapping[str, Any]
) -> list[Path]:
    """Write per-scenario overlays (first seed) and per-metric bar charts; return the files.

    Each record holds "policy", "scenario", "seed", "metrics" and "trajectory", the path of its
    `.npz` relative to ``out``.
    """
    from auv_gym.plotting import plot_track

    written = []
    policies = list(dict.fromkeys(r["policy"] for r in records))
    first_seed = min(r["seed"] for r in records)
    for name, scenario in scenarios.items():
        trajectories = {}
        for r in records:
            if r["scenario"] == name and r["seed"] == first_seed:
                trajectories[r["policy"]] = Trajectory.load(out / r["trajectory"])
        if not trajectories:
            continue
        path = make_path(scenario.env.get("path", "helix"))
        s_max = max(float(np.nanmax(tr["s"])) for tr in trajectories.values())
        fig = _figure(13.0, 4.2)
        plot_track(fig, path, {p: tr.position for p, tr in trajectories.items()}, s_max=s_max)
        fig.suptitle(f"{name}: tracks, seed {first_seed}")
        fig.tight_layout()
        written.append(out / "figures" / f"track_{name}.png")
        _save(fig, written[-1])

        fig = _figure(9.0, 4.5)
        ax_lin, ax_log = fig.subplots(1, 2)
        for policy, tr in trajectories.items():
            for ax in (ax_lin, ax_log):
                ax.plot(tr.t, tr["distance"], lw=1.2, label=policy)
        ax_log.set_yscale("log")
        for ax in (ax_lin, ax_log):
            ax.set(xlabel="t [s]", ylabel="distance to virtual point [m]")
            ax.grid(True, alpha=0.3)
        ax_lin.legend()
        fig.suptitle(f"{name}: distance to the virtual point, seed {first_seed}")
        fig.tight_layout()
        written.append(out / "figures" / f"distance_{name}.png")
        _save(fig, written[-1])

    names = [n for n in scenarios if any(r["scenario"] == n for r in records)]
    for metric, label in BAR_METRICS.items():
        fig = _figure(max(6.0, 1.3 * len(names) + 2.0), 4.0)
        ax = fig.subplots()
        width = 0.8 / max(len(policies), 1)
        x = np.arange(len(names))
        for k, policy in enumerate(policies):
            means, stds = [], []
            for scenario in names:
                values = np.array(
                    [
                        np.nan if r["metrics"].get(metric) is None else float(r["metrics"][metric])
                        for r in records
                        if r["scenario"] == scenario and r["policy"] == policy
                    ]
                )
                finite = values[np.isfinite(values)]
                means.append(finite.mean() if finite.size else np.nan)
                stds.append(finite.std() if finite.size else 0.0)
            ax.bar(
                x + (k - (len(policies) - 1) / 2) * width,
                means,
                width,
                yerr=stds,
                capsize=3,
                label=policy,
            )
        ax.set_xticks(x, names, rotation=20)
        ax.set_ylabel(label)
        if metric.startswith("rms") or metric in ("chattering", "control_effort"):
            ax.set_yscale("log")
        ax.set_title(f"{metric}: mean ± std over seeds (non-finite values omitted)")
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        written.append(out / "figures" / f"bars_{metric}.png")
        _save(fig, written[-1])
    return written
