"""Figures of the benchmark side: a policy comparison (`benchmarks.runner.compare`) and a learning
curve.

Built on `benchmarks.reports.plotting` (`new_figure`, `save_figure`, `plot_track`): matplotlib's
object-oriented API only, no pyplot and no global matplotlib state; every PNG written atomically.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

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
from benchmarks.reports.table_format import NEVER_METRICS, Cell
from benchmarks.reports.tables import aggregate
from benchmarks.training.learning_curve import EVAL_FILE, read_rows

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["BAR_METRICS", "comparison_figures", "figure_captions", "plot_learning_curve"]

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
    """Write per-scenario overlays (first seed) and per-metric bar charts; return the files
    (`figure_captions` says what each shows).

    Each record holds "policy", "scenario", "seed", "metrics" and "trajectory", the path of its
    `.npz` relative to ``out`` (the first seed's at least); ``scenarios`` maps a name to a
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


def figure_captions(files: Sequence[Path], out: Path, seed: int = 0) -> list[tuple[str, str]]:
    """(file relative to ``out``, one line on what it shows) for files of `comparison_figures`;
    ``seed``: the seed the track and distance figures draw (the run's first)."""
    captions = []
    for file in files:
        stem = Path(file).stem
        kind, _, name = stem.partition("_")
        if kind == "track":
            text = (
                f"{name}: every policy's track, seed {seed}, in 3-D, from above and from the "
                "side (× where an episode failed)"
            )
        elif kind == "distance":
            text = (
                f"{name}: distance to the virtual point over time, seed {seed}, linear and log "
                "scale (× where an episode failed)"
            )
        elif kind == "bars" and name in BAR_METRICS:
            text = (
                f"{BAR_METRICS[name]}: mean ± std over the finished episodes per scenario and "
                "policy (n = k/N: k of N finished; hatched: "
                + ("never settled or " if name in NEVER_METRICS else "")
                + "all failed)"
            )
        else:
            text = stem
        captions.append((Path(file).relative_to(out).as_posix(), text))
    return captions


def _failures(trajectories: Mapping[str, Trajectory]) -> dict[str, str]:
    """Policy → how its episode failed, for the episodes that failed."""
    return {
        p: tr.termination_reason
        for p, tr in trajectories.items()
        if tr.termination_reason in FAILURE_REASONS
    }


def _scenario_figures(
    name: str, path: Any, trajectories: Mapping[str, Trajectory], seed: int, folder: Path
) -> list[Path]:
    """track_<name>.png (3D and projections) and distance_<name>.png (linear and log)."""
    s_max = max(float(np.nanmax(tr["s"])) for tr in trajectories.values())
    failed = _failures(trajectories)
    entries = 1 + len(trajectories) + bool(failed)  # the path, the policies, the cross
    rows = -(-entries // 5)  # legend rows below the panels
    fig = new_figure(13.0, 4.4 + 0.25 * rows, _COMPARISON_DPI)
    plot_track(
        fig,
        path,
        {p: tr.position for p, tr in trajectories.items()},
        s_max=s_max,
        envelope=envelope_of(trajectories.values()),
        failed=failed,
    )
    fig.suptitle(f"{name}: tracks, seed {seed}")
    fig.tight_layout(rect=(0, 0.06 * rows, 1, 1))
    track = save_figure(fig, folder / f"track_{name}.png")

    distance = _distance_figure(name, trajectories, seed)
    return [track, save_figure(distance, folder / f"distance_{name}.png")]


def _distance_figure(name: str, trajectories: Mapping[str, Trajectory], seed: int) -> Figure:
    """The distance to the virtual point over time, on a linear and a log scale side by side
    (each panel titled with its scale), a cross where an episode failed."""
    failed = _failures(trajectories)
    colours = policy_colours(list(trajectories))
    rows = -(-len(trajectories) // 5)
    fig = new_figure(10.0, 4.4 + 0.25 * rows, _COMPARISON_DPI)
    ax_lin, ax_log = fig.subplots(1, 2)
    for policy, tr in trajectories.items():
        label = f"{policy} (failed: {failed[policy]})" if policy in failed else policy
        for ax in (ax_lin, ax_log):
            ax.plot(tr.t, tr["distance"], lw=1.1, color=colours[policy], label=label)
            if policy in failed:
                ax.plot(tr.t[-1], tr["distance"][-1], "x", ms=8, color=colours[policy])
    ax_log.set_yscale("log")
    for ax, scale in ((ax_lin, "linear scale"), (ax_log, "log scale")):
        ax.set(xlabel="t [s]", ylabel="distance to virtual point [m]", title=scale)
        ax.grid(True, alpha=0.3)
    handles, labels = ax_lin.get_legend_handles_labels()
    fig.legend(
        handles, labels, loc="lower center", ncols=min(len(labels), 5), fontsize=8, frameon=False
    )
    fig.suptitle(f"{name}: distance to the virtual point, seed {seed} (× an episode that failed)")
    fig.tight_layout(rect=(0, 0.06 * rows, 1, 1))
    return fig


# How a bar chart draws a cell that has no mean to draw as a bar: hatch, fill and legend text.
NO_BAR = {
    "never": ("///", "none", "never settled (in a finished episode): no settling time"),
    "failed": ("xxx", "0.85", "every episode failed: no value"),
}


def _no_bar_word(kind: str, cell: Cell) -> str:
    """The word across a hatched column: "failed", "never", or "never 3/10" where 3 of the
    cell's 10 episodes never settled (the others settled or failed)."""
    if kind != "never":
        return kind
    never = int(np.count_nonzero(np.isposinf(np.asarray(cell.values, dtype=float))))
    return "never" if never == cell.episodes else f"never {never}/{cell.episodes}"


def _bar_cell(cell: Cell) -> tuple[str, float, float]:
    """(kind, mean, std) of a cell: "value" (a bar), "never" (a finished episode never reached
    the threshold: the mean is +inf), "failed" (no finished episode) or "none" (no value)."""
    values = np.asarray(cell.values, dtype=float)
    values = values[~np.isnan(values)]
    if values.size == 0:
        return ("failed" if cell.failed else "none"), np.nan, np.nan
    if np.isposinf(values).any():
        return "never", np.inf, np.nan
    return "value", float(values.mean()), float(values.std())


def _bar_chart(
    cells: Mapping[tuple[str, str], Mapping[str, Cell]],
    policies: list[str],
    names: list[str],
    metric: str,
    label: str,
    folder: Path,
) -> Path:
    """bars_<metric>.png (`_bar_figure`)."""
    fig = _bar_figure(cells, policies, names, metric, label)
    return save_figure(fig, folder / f"bars_{metric}.png")


_BARS_PER_ROW = 56  # bars in a row of a bar chart; more scenarios wrap onto further rows


def _bar_figure(
    cells: Mapping[tuple[str, str], Mapping[str, Cell]],
    policies: list[str],
    names: list[str],
    metric: str,
    label: str,
) -> Figure:
    """Mean ± std over the finished episodes per scenario, one bar per policy.

    A linear axis (a bar's length is its value), or a log axis where the means span more than
    two decades (centimetres beside metres: on a linear axis the small bars vanish); the title
    says which scale. A mean over fewer than all the episodes of its cell (the others failed)
    says so above its bar ("n = 2/3"). A cell without a value to draw is never a bar: it is a
    hatched column over the whole height of the axes, in its policy's colour, with a word
    across it and a legend entry: "never" where a finished episode never settled (its settling
    time is off any scale; "never 3/10" where 3 of 10 did), "failed" where every episode
    failed. A policy not flown on a scenario reads "n/a" at its place. Scenarios beyond
    `_BARS_PER_ROW` bars wrap onto rows that share the y
    axis (19 scenarios of 7 policies were one 19-in strip, 4.6 in high). ``cells`` are
    `benchmarks.reports.tables.aggregate`'s.
    """
    from matplotlib.patches import Patch

    colours = policy_colours(policies)
    most = max(1, _BARS_PER_ROW // max(len(policies), 1))  # scenarios in a row, at most
    per_row = max(1, -(-len(names) // -(-len(names) // most))) if names else 1  # rows balanced
    rows = [names[k : k + per_row] for k in range(0, len(names), per_row)] or [[]]
    fig = new_figure(
        max(7.0, 0.12 * per_row * len(policies) + 3.0),
        4.6 + 3.4 * (len(rows) - 1),
        _COMPARISON_DPI,
    )
    axes = fig.subplots(len(rows), 1, sharey=True, squeeze=False)[:, 0]
    cell_of = {(p, n): cells.get((n, p), {}).get(metric, Cell(())) for p in policies for n in names}
    kinds = {key: _bar_cell(cell) for key, cell in cell_of.items()}
    for p, n in cell_of:  # a policy not flown on a scenario (FBSM on a vehicle without a 5-DOF
        if (n, p) not in cells:  # model): "n/a" at its place, not an empty slot that reads as 0
            kinds[(p, n)] = ("n/a", np.nan, np.nan)
    tops = [mean + std for kind, mean, std in kinds.values() if kind == "value"]
    positive = [mean for kind, mean, _ in kinds.values() if kind == "value" and mean > 0]
    log = bool(positive) and max(positive) > 100.0 * min(positive)
    partial = any(cell_of[key].sample_size() for key, k in kinds.items() if k[0] == "value")
    seen: set[str] = set()
    for ax, row in zip(axes, rows, strict=True):
        seen |= _draw_bars(ax, row, policies, colours, cell_of, kinds, per_row)
        ax.set_ylabel(label)
        ax.grid(True, axis="y", alpha=0.3)
    room = 0.2 if partial else 0.05  # of the axes' height, above the highest error bar
    if log:
        axes[0].set_yscale("log")
        bottom = min(positive) / 3.0
        decades = np.log10(max(tops) / bottom)
        axes[0].set_ylim(bottom, max(tops) * 10.0 ** (decades * room / (1.0 - room)))
    elif tops:
        axes[0].set_ylim(0.0, max(tops) / (1.0 - room) or 1.0)
    axes[0].set_title(
        f"{metric}: mean ± std over the finished episodes, {'log' if log else 'linear'} scale",
        fontsize=9,
    )
    handles = [Patch(facecolor=colours[p], label=p) for p in policies]
    for kind in ("never", "failed"):
        if kind in seen:
            hatch, face, text = NO_BAR[kind]
            handles.append(Patch(facecolor=face, hatch=hatch, edgecolor="0.3", label=text))
    if "n/a" in seen:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], ls="", label="n/a: not flown (needs a 5-DOF model)"))
    if partial:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], ls="", label="n = k/N: mean of the k of N that finished"))
    axes[0].legend(
        handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False
    )
    fig.tight_layout()
    return fig


def _draw_bars(
    ax: Any,
    names: list[str],
    policies: list[str],
    colours: Mapping[str, str],
    cell_of: Mapping[tuple[str, str], Cell],
    kinds: Mapping[tuple[str, str], tuple[str, float, float]],
    slots: int,
) -> set[str]:
    """One row of `_bar_figure`: the scenarios ``names`` in ``slots`` places; returns the kinds
    of hatched columns drawn."""
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import blended_transform_factory

    column = blended_transform_factory(ax.transData, ax.transAxes)  # x in data, y in [0, 1]
    width = 0.8 / max(len(policies), 1)
    seen = set()
    for k, policy in enumerate(policies):
        offset = (k - (len(policies) - 1) / 2) * width
        for i, scenario in enumerate(names):
            kind, mean, std = kinds[(policy, scenario)]
            xi = i + offset
            if kind == "value":
                ax.bar(xi, mean, width, yerr=std, capsize=2, color=colours[policy])
                size = cell_of[(policy, scenario)].sample_size()
                if size:
                    ax.annotate(
                        size,
                        (xi, mean + std),
                        xytext=(0, 2),
                        textcoords="offset points",
                        ha="center",
                        va="bottom",
                        rotation=90,
                        fontsize=6.5,
                    )
            elif kind == "n/a":
                seen.add(kind)
                ax.text(
                    xi,
                    0.02,
                    "n/a",
                    transform=column,
                    rotation=90,
                    ha="center",
                    va="bottom",
                    fontsize=7,
                    color=colours[policy],
                )
            elif kind in NO_BAR:
                seen.add(kind)
                hatch, face, _ = NO_BAR[kind]
                ax.add_patch(
                    Rectangle(
                        (xi - width / 2, 0.0),
                        width,
                        1.0,
                        transform=column,
                        facecolor=face,
                        hatch=hatch,
                        edgecolor=colours[policy],
                        linewidth=0.8,
                    )
                )
                ax.text(
                    xi,
                    0.5,
                    _no_bar_word(kind, cell_of[(policy, scenario)]),
                    transform=column,
                    rotation=90,
                    ha="center",
                    va="center",
                    fontsize=7,
                    bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none"},
                )
    ax.set_xticks(np.arange(len(names)), names, rotation=20)
    ax.set_xlim(-0.5, slots - 0.5)  # every row at the same bar width
    return seen


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
