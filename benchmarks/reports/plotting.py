"""Figure helpers, the path-and-tracks plot, and markdown metric tables.

matplotlib is imported lazily and only its object-oriented API is used (`Figure` with the Agg
canvas), so nothing here touches pyplot's global state or needs a display. `new_figure` and
`save_figure` (every PNG written atomically) are the helpers the figure modules build on
(`benchmarks.reports.episode_figures`: the paper's figures of recorded episodes;
`benchmarks.reports.figures`); `plot_track` draws a path with tracks; `metrics_table` formats
`auv_gym.metrics.compute_metrics` results side by side; `envelope_of`, `extent` and
`trajectory_points` size a figure and find the depth envelope its episodes ran in (the surface and
seabed are drawn by `auv_gym.envs.envelope_drawing`, as in the env's frames). Frames of a running
episode are `auv_gym.envs.rendering`'s job.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path as FilePath
from typing import TYPE_CHECKING, Any

import numpy as np

from auv_gym.envs.envelope_drawing import draw_boundaries_3d, draw_boundary_lines
from auv_gym.ocean.depth_envelope import DepthEnvelope
from auv_gym.paths import Path
from auv_gym.support.files import write_atomic
from benchmarks.reports.table_format import (
    FAILURE_CONVENTION,
    METRIC_INFO,
    display_scale,
    format_number,
    mark_best,
    markdown_table,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from auv_gym.sim.trajectory import Trajectory


__all__ = [
    "POLICY_COLOURS",
    "TABLE_METRICS",
    "envelope_of",
    "extent",
    "metrics_table",
    "new_figure",
    "plot_track",
    "policy_colours",
    "save_figure",
    "trajectory_points",
]

# Metrics of the markdown table: name → (label, unit, better); the one table lives in
# `benchmarks.reports.table_format`.
TABLE_METRICS = METRIC_INFO

# One colour per policy, the same in every figure and every run: the classical controllers and
# the reference agents have fixed colours (classical in blues/greens, agents in warm colours);
# any other name takes a colour from tab20 by a stable hash of its name, probing past colours
# already taken in that figure so that no two policies of one figure share a colour.
POLICY_COLOURS: dict[str, str] = {
    "fbsm": "#1f77b4",
    "FBSM": "#1f77b4",
    "fbsm_colos": "#17becf",
    "fbsm_colos_lowpass": "#9edae5",
    "fbsm_ilos": "#aec7e8",
    "backstepping": "#2ca02c",
    "backstepping_colos": "#98df8a",
    "backstepping_ilos": "#bcbd22",
    "pid_los": "#d6616b",
    "pid_ilos": "#e7969c",
    "pid_colos": "#cedb9c",
    "pid_as_built": "#8c564b",
    "command_filtered": "#006d2c",
    "command_filtered_colos": "#41ab5d",
    "ppo_generalist": "#d62728",
    "ppo_as_built": "#e377c2",
    "ppo_helix": "#ff7f0e",
    "ppo_residual": "#7f7f7f",
    "sac_helix": "#9467bd",
}
_HASH_PALETTE = (
    "#393b79",
    "#637939",
    "#8c6d31",
    "#843c39",
    "#7b4173",
    "#3182bd",
    "#e6550d",
    "#31a354",
    "#756bb1",
    "#636363",
    "#6baed6",
    "#fd8d3c",
    "#74c476",
    "#9e9ac8",
    "#969696",
    "#e7ba52",
    "#ad494a",
    "#a55194",
    "#5254a3",
    "#b5cf6b",
)


def policy_colours(names: Sequence[str]) -> dict[str, str]:
    """Name → colour for the policies of one figure: fixed for known names, stable otherwise.

    The colour of a known policy never depends on which other policies are drawn; an unknown
    name keeps its colour unless another policy of the same figure already holds it.
    """
    import zlib

    colours = {n: POLICY_COLOURS[n] for n in names if n in POLICY_COLOURS}
    taken = set(colours.values())
    for name in sorted(n for n in dict.fromkeys(names) if n not in POLICY_COLOURS):
        start = zlib.crc32(name.encode())
        for k in range(len(_HASH_PALETTE)):
            colour = _HASH_PALETTE[(start + k) % len(_HASH_PALETTE)]
            if colour not in taken:
                break
        colours[name] = colour
        taken.add(colour)
    return {n: colours[n] for n in names}


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


def plot_track(
    fig,
    path: Path,
    tracks: dict[str, np.ndarray],
    s_max: float,
    envelope: DepthEnvelope | None = None,
) -> None:
    """Draw the path and tracks (name → (T, 3) NED positions [m]) in 3D plus x–y and x–z views,
    with the sea surface and seabed of ``envelope`` if given.

    Depth is plotted as −z so that "up" is up. Each policy has its `policy_colours` colour;
    the legend sits below the panels, where it covers no data.
    """
    ref = path.sample(600, s_max=max(s_max, 1.0))
    ax3d = fig.add_subplot(1, 3, 1, projection="3d")
    ax_xy = fig.add_subplot(1, 3, 2)
    ax_xz = fig.add_subplot(1, 3, 3)
    ax3d.plot(ref[:, 0], ref[:, 1], -ref[:, 2], "k--", lw=1, label="path")
    ax_xy.plot(ref[:, 0], ref[:, 1], "k--", lw=1)
    ax_xz.plot(ref[:, 0], -ref[:, 2], "k--", lw=1)
    colours = policy_colours(list(tracks))
    for name, track in tracks.items():
        style = {"lw": 1.2, "color": colours[name], "alpha": 0.85}
        ax3d.plot(track[:, 0], track[:, 1], -track[:, 2], label=name, **style)
        ax_xy.plot(track[:, 0], track[:, 1], **style)
        ax_xz.plot(track[:, 0], -track[:, 2], **style)
        ax3d.scatter(*track[-1, :2], -track[-1, 2], s=12, color=colours[name])
    draw_boundaries_3d(ax3d, envelope, *extent([ref, *tracks.values()]))
    draw_boundary_lines(ax_xz, envelope)
    ax3d.set(xlabel="x [m]", ylabel="y [m]", zlabel="−z [m]", title="3D path")
    ax_xy.set(xlabel="x [m]", ylabel="y [m]", title="horizontal projection", aspect="equal")
    ax_xz.set(xlabel="x [m]", ylabel="−z [m]", title="vertical projection")
    for ax in (ax_xy, ax_xz):
        ax.grid(True, alpha=0.3)
    handles, labels = ax3d.get_legend_handles_labels()
    fig.legend(
        handles, labels, loc="lower center", ncols=min(len(labels), 6), fontsize=8, frameon=False
    )


def metrics_table(
    results: Mapping[str, Mapping[str, Any]], metrics: Sequence[str] | None = None
) -> str:
    """Markdown table: one row per metric (its unit in the second column), one column per policy.

    ``results`` maps a policy label to its `compute_metrics` dict. The conventions are
    `benchmarks.reports.table_format`'s: three significant figures, millimetres where metres would
    round to zero, "never" for a settling threshold not reached, "—" for an undefined value, and the
    best value in bold only among policies whose episode did not fail (its
    ``termination_reason`` is not a failure).
    """
    from auv_gym.sim.trajectory import FAILURE_REASONS

    names = list(results)
    # by default every metric some policy recorded (the propulsion rows need a propeller)
    recorded = [m for m in TABLE_METRICS if any(m in results[name] for name in names)]
    rows = list(metrics) if metrics is not None else recorded
    eligible = [results[n].get("termination_reason") not in FAILURE_REASONS for n in names]
    body = []
    for metric in rows:
        label, unit, better = TABLE_METRICS.get(metric, (metric, "", ""))
        values = [results[name].get(metric) for name in names]
        numeric = [_number(v) for v in values]
        unit, scale = display_scale(unit, [v for v in numeric if not math.isnan(v)])
        texts = [
            format_number(raw if math.isnan(v) else v * scale, metric=metric)
            for v, raw in zip(numeric, values, strict=True)
        ]
        if not any(math.isnan(v) for v in numeric):  # an undefined value: no winner
            texts = mark_best(texts, numeric, eligible, better)
        body.append([label, unit, *texts])
    return markdown_table(["metric", "unit", *names], body, ["l", "l", *["r"] * len(names)])


def metrics_table_note() -> str:
    """The one-paragraph reading key printed above `metrics_table`."""
    return FAILURE_CONVENTION


def _number(value: Any) -> float:
    """A metric value as a float for ranking; NaN for text, booleans and missing values."""
    if isinstance(value, (bool, np.bool_, str)) or value is None:
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def envelope_of(trajectories: Iterable[Trajectory]) -> DepthEnvelope | None:
    """The depth envelope the episodes were recorded with (their metadata's env arguments);
    None if they had none."""
    for tr in trajectories:
        spec = tr.metadata.get("env_kwargs", {}).get("depth_envelope")
        if spec is not None:
            return DepthEnvelope.from_spec(spec)
    return None


def extent(points: Iterable[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) corners [m] of (n, 3) point sets together."""
    stacked = np.concatenate([np.asarray(p).reshape(-1, 3) for p in points])
    stacked = stacked[np.isfinite(stacked).all(axis=1)]
    return stacked.min(axis=0), stacked.max(axis=0)


def trajectory_points(trajectories: Mapping[str, Trajectory]) -> list[np.ndarray]:
    """Every trajectory's positions, for `extent`."""
    return [tr.position for tr in trajectories.values()]
