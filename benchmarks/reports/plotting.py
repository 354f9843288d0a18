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
    "OKABE_ITO",
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

# One colour per policy, the same in every figure and every run, from colour-blind-safe palettes:
# the reference policies (the main job's eight and ppo_as_built) take the eight colours of Okabe &
# Ito (2008) and tableau-colorblind10's dark grey (Okabe–Ito's grey is its reddish purple for a
# deuteranope), told apart with each common colour-vision deficiency: classical in blues, green
# and black, agents in vermillion, orange, purple, grey and yellow (was: tab10's red beside a
# pink). The other presets take colours of Paul Tol's muted palette near their family's (FBSM's
# in blues, backstepping's in greens, PID's in greys and olive). Any other name takes a colour
# of `_HASH_PALETTE` by a stable hash of its name, probing past colours already taken in that
# figure so that no two policies of one figure share a colour.
OKABE_ITO = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky blue": "#56B4E9",
    "bluish green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish purple": "#CC79A7",
}
POLICY_COLOURS: dict[str, str] = {
    "fbsm": OKABE_ITO["blue"],
    "FBSM": OKABE_ITO["blue"],
    "fbsm_colos": OKABE_ITO["sky blue"],
    "backstepping": OKABE_ITO["bluish green"],
    "pid_los": OKABE_ITO["black"],
    "ppo_generalist": OKABE_ITO["vermillion"],
    "ppo_helix": OKABE_ITO["orange"],
    "ppo_residual": "#595959",  # dark grey (tableau-colorblind10)
    "sac_generalist": OKABE_ITO["reddish purple"],
    "ppo_as_built": OKABE_ITO["yellow"],
    # Tol's muted palette
    "fbsm_ilos": "#332288",  # indigo
    "fbsm_colos_lowpass": "#88CCEE",  # cyan
    "backstepping_ilos": "#117733",  # green
    "backstepping_colos": "#44AA99",  # teal
    "command_filtered": "#882255",  # wine
    "command_filtered_colos": "#AA4499",  # purple
    "pid_ilos": "#ABABAB",  # light grey (tableau-colorblind10)
    "pid_colos": "#999933",  # olive
    "pid_as_built": "#DDCC77",  # sand
    "pid_as_built_guarded": "#CC6677",  # rose
    # Tol's vibrant palette
    "pid_as_built_climb": "#EE7733",  # orange
    "pid_as_built_climb_guarded": "#EE3377",  # magenta
    # a bright blue, the farthest from every colour above among the named palettes' (14 ΔE from
    # its nearest, FBSM's blue, in simulated tritanopia)
    "pid_as_built_climb_soft_pitch": "#1A85FF",
    # Tol's dark palette's blue: the soft-pitch PID given the DVL's current, beside its bright blue
    "pid_as_built_dvl": "#222255",
    # Tol's dark palette: the as-built residual, beside the PIDs it rides on
    "ppo_residual_as_built": "#225522",  # dark green
}
# Paul Tol's bright and vibrant palettes without their greys (each colour-blind-safe in itself),
# then his light palette, for a figure of more than twelve such names.
_HASH_PALETTE = (
    "#4477AA",
    "#EE6677",
    "#228833",
    "#CCBB44",
    "#66CCEE",
    "#AA3377",
    "#EE7733",
    "#0077BB",
    "#33BBEE",
    "#EE3377",
    "#CC3311",
    "#009988",
    "#77AADD",
    "#EE8866",
    "#44BB99",
    "#BBCC33",
    "#AAAA00",
    "#EEDD88",
    "#FFAABB",
    "#99DDFF",
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
    failed: Mapping[str, str] | None = None,
) -> None:
    """Draw the path and tracks (name → (T, 3) NED positions [m]) in 3D plus x–y and x–z views,
    with the sea surface and seabed of ``envelope`` if given.

    Depth is plotted as −z so that "up" is up. The path is drawn up to arc length ``s_max`` [m]
    (the furthest the episodes got; a finite path ends sooner). Each policy has its
    `policy_colours` colour; a track that ends in a failure (``failed``: name → reason) ends in
    a cross and says so in the legend, the others in a dot. The horizontal view keeps x and y to
    one scale by widening its data limits, never by shrinking its panel (a 150-m line with 20-m
    turns was once a strip a tenth of the panel's height). The legend sits below the panels,
    where it covers no data.
    """
    failed = dict(failed or {})
    s_end = path.s_end if math.isfinite(path.s_end) else math.inf
    ref = path.evaluate(np.linspace(0.0, min(max(s_max, 1.0), s_end), 600))[0]
    ax3d = fig.add_subplot(1, 3, 1, projection="3d")
    ax_xy = fig.add_subplot(1, 3, 2)
    ax_xz = fig.add_subplot(1, 3, 3)
    ax3d.plot(ref[:, 0], ref[:, 1], -ref[:, 2], "k--", lw=1, label="path")
    ax_xy.plot(ref[:, 0], ref[:, 1], "k--", lw=1)
    ax_xz.plot(ref[:, 0], -ref[:, 2], "k--", lw=1)
    colours = policy_colours(list(tracks))
    for name, track in tracks.items():
        style = {"lw": 1.2, "color": colours[name], "alpha": 0.85}
        label = f"{name} (failed: {failed[name]})" if name in failed else name
        ax3d.plot(track[:, 0], track[:, 1], -track[:, 2], label=label, **style)
        ax_xy.plot(track[:, 0], track[:, 1], **style)
        ax_xz.plot(track[:, 0], -track[:, 2], **style)
        end = {"marker": "x", "s": 40} if name in failed else {"marker": "o", "s": 12}
        ax3d.scatter(*track[-1, :2], -track[-1, 2], color=colours[name], **end)
        for ax, (i, j, sign) in ((ax_xy, (0, 1, 1.0)), (ax_xz, (0, 2, -1.0))):
            if name in failed:
                ax.scatter(track[-1, i], sign * track[-1, j], color=colours[name], **end)
    draw_boundaries_3d(ax3d, envelope, *extent([ref, *tracks.values()]))
    draw_boundary_lines(ax_xz, envelope)
    ax3d.set(xlabel="x [m]", ylabel="y [m]", zlabel="−z [m]", title="3D path")
    ax_xy.set(xlabel="x [m]", ylabel="y [m]", title="horizontal projection")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xz.set(xlabel="x [m]", ylabel="−z [m]", title="vertical projection")
    for ax in (ax_xy, ax_xz):
        ax.grid(True, alpha=0.3)
    handles, labels = ax3d.get_legend_handles_labels()
    if failed:  # what the cross means, once
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], ls="", marker="x", color="k"))
        labels.append("end of a failed episode")
    fig.legend(
        handles, labels, loc="lower center", ncols=min(len(labels), 5), fontsize=8, frameon=False
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
