"""Figures of the benchmark side: a policy comparison (`benchmarks.runner.compare`) and a learning
curve.

Built on `benchmarks.reports.plotting` (`new_figure`, `save_figure`, `plot_track`): matplotlib's
object-oriented API only, no pyplot and no global matplotlib state; every PNG written atomically.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.metrics import window_start
from auv_gym.sim.config import SimConfig
from auv_gym.sim.randomization import task_for_seed
from auv_gym.sim.trajectory import FAILURE_REASONS, Trajectory
from auv_gym.support.files import write_atomic
from benchmarks.reports.plotting import (
    envelope_of,
    new_figure,
    plot_track,
    policy_colours,
    save_figure,
)
from benchmarks.reports.table_format import Cell
from benchmarks.reports.tables import aggregate
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
    `.npz` relative to ``out``; ``scenarios`` maps a name to a
    `benchmarks.catalog.scenarios.Scenario`.
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
    policies = list(dict.fromkeys(r["policy"] for r in records))
    cells = aggregate(records)  # the summary table's cells: finished episodes and failures
    for metric, label in BAR_METRICS.items():
        written.append(_bar_chart(cells, policies, names, metric, label, out / "figures"))
    return written


def _scenario_figures(
    name: str, path: Any, trajectories: Mapping[str, Trajectory], seed: int, folder: Path
) -> list[Path]:
    """track_<name>.png (3D and projections) and distance_<name>.png (linear and log)."""
    s_max = max(float(np.nanmax(tr["s"])) for tr in trajectories.values())
    rows = -(-len(trajectories) // 6)  # legend rows below the panels
    fig = new_figure(13.0, 4.4 + 0.25 * rows, _COMPARISON_DPI)
    plot_track(
        fig,
        path,
        {p: tr.position for p, tr in trajectories.items()},
        s_max=s_max,
        envelope=envelope_of(trajectories.values()),
    )
    fig.suptitle(f"{name}: tracks, seed {seed}")
    fig.tight_layout(rect=(0, 0.06 * rows, 1, 1))
    track = save_figure(fig, folder / f"track_{name}.png")

    colours = policy_colours(list(trajectories))
    fig = new_figure(10.0, 4.4 + 0.25 * rows, _COMPARISON_DPI)
    ax_lin, ax_log = fig.subplots(1, 2)
    for policy, tr in trajectories.items():
        failed = tr.termination_reason in FAILURE_REASONS
        label = f"{policy} (failed: {tr.termination_reason})" if failed else policy
        for ax in (ax_lin, ax_log):
            ax.plot(tr.t, tr["distance"], lw=1.1, color=colours[policy], label=label)
            if failed:
                ax.plot(tr.t[-1], tr["distance"][-1], "x", ms=8, color=colours[policy])
    ax_log.set_yscale("log")
    for ax in (ax_lin, ax_log):
        ax.set(xlabel="t [s]", ylabel="distance to virtual point [m]")
        ax.grid(True, alpha=0.3)
    handles, labels = ax_lin.get_legend_handles_labels()
    fig.legend(
        handles, labels, loc="lower center", ncols=min(len(labels), 6), fontsize=8, frameon=False
    )
    fig.suptitle(f"{name}: distance to the virtual point, seed {seed} (× an episode that failed)")
    fig.tight_layout(rect=(0, 0.06 * rows, 1, 1))
    return [track, save_figure(fig, folder / f"distance_{name}.png")]


def _bar_chart(
    cells: Mapping[tuple[str, str], Mapping[str, Cell]],
    policies: list[str],
    names: list[str],
    metric: str,
    label: str,
    folder: Path,
) -> Path:
    """bars_<metric>.png: mean ± std over the finished episodes per scenario, one bar per policy.

    A linear axis (a bar's length is its value), or a log axis where the means span more than
    two decades (centimetres beside metres: on a linear axis the small bars vanish; the title
    says which). Failed episodes are left out of the mean and
    counted above the bar ("✕n"); a policy whose episodes all failed gets a hatched empty bar.
    ``cells`` are `benchmarks.reports.tables.aggregate`'s.
    """
    colours = policy_colours(policies)
    fig = new_figure(max(7.0, 0.12 * len(names) * len(policies) + 3.0), 4.6, _COMPARISON_DPI)
    ax = fig.subplots()
    width = 0.8 / max(len(policies), 1)
    x = np.arange(len(names))
    bars = {}
    for policy in policies:
        for scenario in names:
            cell = cells.get((scenario, policy), {}).get(metric, Cell(()))
            values = np.asarray(cell.values, dtype=float)
            bars[(policy, scenario)] = (values[np.isfinite(values)], cell.failed)
    top = max((v.mean() + v.std() for v, _ in bars.values() if v.size), default=1.0)
    for k, policy in enumerate(policies):
        offset = (k - (len(policies) - 1) / 2) * width
        for i, scenario in enumerate(names):
            values, failed = bars[(policy, scenario)]
            xi = x[i] + offset
            if values.size:
                ax.bar(
                    xi,
                    values.mean(),
                    width,
                    yerr=values.std(),
                    capsize=2,
                    color=colours[policy],
                    label=policy if i == 0 else None,
                )
            elif failed:
                ax.bar(
                    xi,
                    top,
                    width,
                    fill=False,
                    hatch="///",
                    edgecolor=colours[policy],
                    label=policy if i == 0 else None,
                )
            if failed:
                height = values.mean() + values.std() if values.size else top
                ax.text(xi, height, f"✕{failed}", ha="center", va="bottom", fontsize=7, color="C3")
    ax.set_xticks(x, names, rotation=20)
    ax.set_ylabel(label)
    positive = [v.mean() for v, _ in bars.values() if v.size and v.mean() > 0]
    log = bool(positive) and max(positive) > 100.0 * min(positive)
    if log:
        ax.set_yscale("log")
        ax.set_ylim(bottom=min(positive) / 3.0)
    else:
        ax.set_ylim(bottom=0)
    ax.set_title(
        f"{metric}: mean ± std over finished episodes{' (log axis)' if log else ''}; "
        "✕n: n failed episodes, hatched: all failed",
        fontsize=9,
    )
    ax.grid(True, axis="y", alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    fig.tight_layout()
    return save_figure(fig, folder / f"bars_{metric}.png")


def plot_learning_curve(run: Path, prefix: Path) -> None:
    """Copy RUN/evaluations.csv to PREFIX.csv and plot it to PREFIX.png.

    Two panels share the y axis (mean RMS distance over the metrics window of the evaluation
    episodes, log scale): against env steps and against training wall time. Evaluations in
    which an episode ended early are drawn as crosses at the RMS over what was flown (or at the
    corridor width when no episode reached the window). The title, the episode length and the
    window come from the run's recorded settings (RUN/best/metadata.json) when it has them.
    """
    source = Path(run) / EVAL_FILE
    if not source.is_file():
        raise FileNotFoundError(f"no learning curve {source}")
    rows = read_rows(source)
    if not rows:
        raise ValueError(f"{source} has no evaluations")
    settings = _run_settings(Path(run))
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
    duration = settings.get("eval_duration")
    ran = f"every episode ran {duration:g} s" if duration else "no episode ended early"
    for ax, x, label in (
        (axes[0], steps / 1e6, "env steps [millions]"),
        (axes[1], wall / 60.0, "training wall time [min]"),
    ):
        ax.plot(x, shown, "-", color="0.6", lw=1)
        ax.plot(x[~failed], shown[~failed], "o", ms=4, label=ran)
        ax.plot(x[failed], shown[failed], "x", ms=6, color="C3", label="an episode ended early")
        ax.axhline(1.0, ls="--", color="k", lw=0.8, label="1 m")
        ax.set_xlabel(label)
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    window = f"t ≥ {window_start(duration):g} s" if duration else "metrics window"
    axes[0].set_ylabel(f"evaluation mean RMS distance, {window} [m]")
    axes[0].legend(fontsize=8)
    fig.suptitle(settings.get("title", f"learning curve of {Path(run).name}"))
    save_figure(fig, prefix.with_suffix(".png"))


def _run_settings(run: Path) -> dict[str, Any]:
    """Title and evaluation length of a training run from its best agent's metadata, if any."""
    import json

    file = run / "best" / "metadata.json"
    try:
        meta = json.loads(file.read_text())
    except (OSError, ValueError):
        return {}
    options = meta.get("options") if isinstance(meta.get("options"), dict) else {}
    duration = options.get("eval_duration")
    seeds = meta.get("eval_seeds") or []
    algo = str(meta.get("algo", "agent")).upper()
    where = options.get("task_set") or "evaluation"
    title = f"{algo} on {meta.get('env_id', '?')}: {len(seeds)} {where} episodes per evaluation"
    return {"title": title, "eval_duration": float(duration) if duration else None}
