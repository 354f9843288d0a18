"""Figures of the benchmark side: a policy comparison (`benchmarks.compare`) and a learning curve.

Built on `auv_gym.plotting` (`new_figure`, `save_figure`, `plot_track`): matplotlib's
object-oriented API only, no pyplot and no global matplotlib state; every PNG written atomically.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.config import SimConfig
from auv_gym.files import write_atomic
from auv_gym.plotting import new_figure, plot_track, save_figure
from auv_gym.randomization import task_for_seed
from auv_gym.trajectory import Trajectory
from benchmarks.training.learning_curve import EVAL_FILE, read_rows

__all__ = ["BAR_METRICS", "comparison_figures", "plot_learning_curve"]

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
_COMPARISON_DPI = 110


def comparison_figures(
    records: Sequence[Mapping[str, Any]], out: Path, scenarios: Mapping[str, Any]
) -> list[Path]:
    """Write per-scenario overlays (first seed) and per-metric bar charts; return the files.

    Each record holds "policy", "scenario", "seed", "metrics" and "trajectory", the path of its
    `.npz` relative to ``out``; ``scenarios`` maps a name to a `benchmarks.scenarios.Scenario`.
    """
    written = []
    first_seed = min(r["seed"] for r in records)
    for name, scenario in scenarios.items():
        trajectories = {
            r["policy"]: Trajectory.load(out / r["trajectory"])
            for r in records
            if r["scenario"] == name and r["seed"] == first_seed
        }
        if trajectories:
            # The path of that seed's episode (a random-path scenario draws one per seed).
            path = task_for_seed(SimConfig.from_kwargs(**scenario.env), first_seed).path
            written += _scenario_figures(name, path, trajectories, first_seed, out / "figures")
    names = [n for n in scenarios if any(r["scenario"] == n for r in records)]
    for metric, label in BAR_METRICS.items():
        written.append(_bar_chart(records, names, metric, label, out / "figures"))
    return written


def _scenario_figures(
    name: str, path: Any, trajectories: Mapping[str, Trajectory], seed: int, folder: Path
) -> list[Path]:
    """track_<name>.png (3D and projections) and distance_<name>.png (linear and log)."""
    s_max = max(float(np.nanmax(tr["s"])) for tr in trajectories.values())
    fig = new_figure(13.0, 4.2, _COMPARISON_DPI)
    plot_track(fig, path, {p: tr.position for p, tr in trajectories.items()}, s_max=s_max)
    fig.suptitle(f"{name}: tracks, seed {seed}")
    fig.tight_layout()
    track = save_figure(fig, folder / f"track_{name}.png")

    fig = new_figure(9.0, 4.5, _COMPARISON_DPI)
    ax_lin, ax_log = fig.subplots(1, 2)
    for policy, tr in trajectories.items():
        for ax in (ax_lin, ax_log):
            ax.plot(tr.t, tr["distance"], lw=1.2, label=policy)
    ax_log.set_yscale("log")
    for ax in (ax_lin, ax_log):
        ax.set(xlabel="t [s]", ylabel="distance to virtual point [m]")
        ax.grid(True, alpha=0.3)
    ax_lin.legend()
    fig.suptitle(f"{name}: distance to the virtual point, seed {seed}")
    fig.tight_layout()
    return [track, save_figure(fig, folder / f"distance_{name}.png")]


def _bar_chart(
    records: Sequence[Mapping[str, Any]], names: list[str], metric: str, label: str, folder: Path
) -> Path:
    """bars_<metric>.png: mean ± std over seeds per scenario, one bar per policy."""
    policies = list(dict.fromkeys(r["policy"] for r in records))
    fig = new_figure(max(6.0, 1.3 * len(names) + 2.0), 4.0, _COMPARISON_DPI)
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
        offset = (k - (len(policies) - 1) / 2) * width
        ax.bar(x + offset, means, width, yerr=stds, capsize=3, label=policy)
    ax.set_xticks(x, names, rotation=20)
    ax.set_ylabel(label)
    if metric.startswith("rms") or metric in ("chattering", "control_effort"):
        ax.set_yscale("log")
    ax.set_title(f"{metric}: mean ± std over seeds (non-finite values omitted)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, folder / f"bars_{metric}.png")


def plot_learning_curve(run: Path, prefix: Path) -> None:
    """Copy RUN/evaluations.csv to PREFIX.csv and plot it to PREFIX.png.

    Two panels share the y axis (mean rms distance over t ≥ 100 s of the evaluation seeds,
    log scale): against env steps and against training wall time. Evaluations in which an
    episode terminated are drawn as crosses at their rms over the part that was flown (or at
    the corridor width when no episode reached 100 s).
    """
    source = Path(run) / EVAL_FILE
    if not source.is_file():
        raise FileNotFoundError(f"no learning curve {source}")
    rows = read_rows(source)
    if not rows:
        raise ValueError(f"{source} has no evaluations")
    steps = np.array([float(r["num_timesteps"]) for r in rows])
    wall = np.array([float(r["wall_time_s"]) for r in rows])
    rms = np.array([float(r["rms_distance_mean"]) for r in rows])
    failed = np.array([int(r["n_terminated"]) > 0 for r in rows])
    shown = np.where(np.isfinite(rms), rms, 30.0)
    prefix = Path(prefix)
    data = source.read_bytes()
    write_atomic(prefix.with_suffix(".csv"), lambda fh: fh.write(data))
    fig = new_figure(10, 3.8, 120, layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for ax, x, label in ((axes[0], steps / 1e6, "env steps [millions]"),
                         (axes[1], wall / 60.0, "training wall time [min]")):  # fmt: skip
        ax.plot(x, shown, "-", color="0.6", lw=1)
        ax.plot(x[~failed], shown[~failed], "o", ms=4, label="all episodes ran 300 s")
        ax.plot(x[failed], shown[failed], "x", ms=6, color="C3", label="some episode terminated")
        ax.axhline(1.0, ls="--", color="k", lw=0.8, label="target 1 m")
        ax.set_xlabel(label)
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("eval mean rms distance, t ≥ 100 s [m]")
    axes[0].legend(fontsize=8)
    fig.suptitle("PPO on AUVPath3D-v0, paper scenario (white noise ±35), evaluation seeds")
    save_figure(fig, prefix.with_suffix(".png"))
