"""Figures of recorded episodes (`auv_gym.sim.trajectory.Trajectory`), one line per controller.

`paper_figures` draws the equivalents of Figs. 3–9 of Liang et al. (2018) for a set of
trajectories (one per controller, same seed), plus the distance to the virtual point and the
adaptive-parameter norms; each builder of `PAPER_FIGURES` returns one matplotlib `Figure`
(object-oriented API only, no pyplot state). Heights are plotted as −z (NED, docs/model.md §2.0).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path as FilePath
from typing import TYPE_CHECKING, Any

import numpy as np

from auv_gym.envs.envelope_drawing import draw_boundaries_3d, draw_boundary_lines
from auv_gym.paths import Path
from benchmarks.reports.plotting import (
    envelope_of,
    extent,
    new_figure,
    policy_colours,
    save_figure,
    trajectory_points,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from auv_gym.sim.trajectory import Trajectory

__all__ = ["PAPER_FIGURES", "norm_series", "paper_figures"]

_DEG = 180.0 / math.pi
_WIDTH, _HEIGHT, _DPI = 7.0, 4.5, 150  # default figure size [in] and resolution


def _reference(trajectories: Mapping[str, Trajectory], path: Path | None) -> np.ndarray:
    """(n, 3) points of the desired path over the s range the episodes reached [m].

    Without ``path``, the locus of the virtual point p(s) of the episode that got furthest.
    """
    furthest = max(trajectories.values(), key=lambda tr: float(np.nanmax(tr["s"])))
    if path is None:
        return furthest.point
    s_max = float(np.nanmax(furthest["s"]))
    s_end = min(s_max, path.s_end) if math.isfinite(path.s_end) else s_max
    return path.evaluate(np.linspace(0.0, max(s_end, 1e-6), 800))[0]


def _styles(names: Sequence[str]) -> dict[str, dict[str, Any]]:
    colours = policy_colours(list(names))
    return {name: {"color": colours[name], "lw": 1.2} for name in names}


def _finish(fig: Figure, axes: Sequence[Axes], title: str) -> None:
    for ax in axes:
        if ax.name != "3d":
            ax.grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()


def figure_path_3d(
    trajectories: Mapping[str, Trajectory], path: Path | None = None, **_: Any
) -> Figure:
    """Fig. 3: the desired path and the vehicle tracks in 3D (height −z up) [m]."""
    fig = new_figure(_WIDTH, 5.5, _DPI)
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    ref = _reference(trajectories, path)
    ax.plot(ref[:, 0], ref[:, 1], -ref[:, 2], "k--", lw=1.0, label="desired path")
    styles = _styles(list(trajectories))
    for name, tr in trajectories.items():
        pos = tr.position
        ax.plot(pos[:, 0], pos[:, 1], -pos[:, 2], label=name, **styles[name])
        ax.scatter(pos[0, 0], pos[0, 1], -pos[0, 2], color="k", marker="o", s=12)
    envelope = envelope_of(trajectories.values())  # the surface and seabed, if any
    draw_boundaries_3d(ax, envelope, *extent([ref, *trajectory_points(trajectories)]))
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="−z (height) [m]")
    ax.legend(loc="upper left", fontsize=8)
    _finish(fig, [ax], "3D path following")
    return fig


def _projection(
    trajectories: Mapping[str, Trajectory],
    path: Path | None,
    axes_index: tuple[int, int],
    labels: tuple[str, str],
    title: str,
) -> Figure:
    fig = new_figure(_WIDTH, _HEIGHT + 1.0, _DPI)
    ax = fig.add_subplot(1, 1, 1)
    sign = np.array([1.0, 1.0, -1.0])  # plot height −z
    ref = _reference(trajectories, path) * sign
    i, j = axes_index
    ax.plot(ref[:, i], ref[:, j], "k--", lw=1.0, label="desired path")
    styles = _styles(list(trajectories))
    for name, tr in trajectories.items():
        pos = tr.position * sign
        ax.plot(pos[:, i], pos[:, j], label=name, **styles[name])
        ax.plot(pos[0, i], pos[0, j], "ko", ms=3)
    if j == 2:  # a height axis: the surface and seabed, if any
        draw_boundary_lines(ax, envelope_of(trajectories.values()))
    ax.set(xlabel=labels[0], ylabel=labels[1])
    if axes_index == (0, 1):
        ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)
    _finish(fig, [ax], title)
    return fig


def figure_horizontal(
    trajectories: Mapping[str, Trajectory], path: Path | None = None, **_: Any
) -> Figure:
    """Fig. 4: projection on the horizontal plane (x, y) [m]."""
    return _projection(trajectories, path, (0, 1), ("x [m]", "y [m]"), "Horizontal projection")


def figure_vertical(
    trajectories: Mapping[str, Trajectory], path: Path | None = None, **_: Any
) -> Figure:
    """Fig. 5: projection on the vertical plane (x, −z) [m]."""
    return _projection(
        trajectories, path, (0, 2), ("x [m]", "−z (height) [m]"), "Vertical projection"
    )


def _time_axes(fig: Figure, rows: int) -> list[Axes]:
    axes = [fig.add_subplot(rows, 1, 1)]
    for k in range(1, rows):
        axes.append(fig.add_subplot(rows, 1, k + 1, sharex=axes[0]))
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    axes[-1].set_xlabel("t [s]")
    return axes


def figure_errors(
    trajectories: Mapping[str, Trajectory], zoom_from: float | None = None, **_: Any
) -> Figure:
    """Fig. 6: path-following errors x_e, y_e, z_e (body frame, vehicle − virtual point) [m].

    With ``zoom_from`` [s] inside the episodes, a right-hand column repeats the errors for
    t ≥ zoom_from on their own scale, where the steady state would vanish under the transient.
    """
    t_end = max(float(tr.t[-1]) for tr in trajectories.values())
    zoom = zoom_from is not None and zoom_from < t_end
    fig = new_figure(10.0 if zoom else _WIDTH, _HEIGHT + 1.5, _DPI)
    styles = _styles(list(trajectories))
    columns = 2 if zoom else 1
    axes: list[Axes] = []
    for row, key in enumerate(("x_e", "y_e", "z_e")):
        for col in range(columns):
            share = axes[col] if row else None
            ax = fig.add_subplot(3, columns, row * columns + col + 1, sharex=share)
            axes.append(ax)
            for name, tr in trajectories.items():
                mask = tr.t >= zoom_from if col == 1 else slice(None)
                ax.plot(tr.t[mask], tr[key][mask], label=name, **styles[name])
            ax.axhline(0.0, color="k", lw=0.6)
            if col == 0:
                ax.set_ylabel(f"{key} [m]")
            if row < 2:
                ax.tick_params(labelbottom=False)
            else:
                ax.set_xlabel("t [s]")
    axes[0].legend(fontsize=8)
    if zoom:
        axes[1].set_title(f"t ≥ {zoom_from:g} s", fontsize=9)
    _finish(fig, axes, "Path-following errors")
    return fig


def figure_distance(trajectories: Mapping[str, Trajectory], **_: Any) -> Figure:
    """Distance to the virtual point on a log scale, with the 0.5-m and 0.1-m settling bands."""
    fig = new_figure(_WIDTH, _HEIGHT, _DPI)
    ax = fig.add_subplot(1, 1, 1)
    styles = _styles(list(trajectories))
    for name, tr in trajectories.items():
        ax.semilogy(tr.t, np.maximum(tr["distance"], 1e-4), label=name, **styles[name])
    for level in (0.5, 0.1):
        ax.axhline(level, color="k", ls=":", lw=0.8)
    ax.set(xlabel="t [s]", ylabel="distance to P [m]")
    ax.legend(fontsize=8)
    _finish(fig, [ax], "Distance to the virtual point")
    return fig


def figure_surge(trajectories: Mapping[str, Trajectory], **_: Any) -> Figure:
    """Fig. 7: surge speed u against the desired u_D [m/s]."""
    fig = new_figure(_WIDTH, _HEIGHT, _DPI)
    ax = fig.add_subplot(1, 1, 1)
    styles = _styles(list(trajectories))
    u_d = None
    for name, tr in trajectories.items():
        ax.plot(tr.t, tr["u"], label=name, **styles[name])
        u_d = tr.u_desired
    if u_d is not None:
        ax.axhline(u_d, color="k", ls="--", lw=1.0, label="u_D")
    ax.set(xlabel="t [s]", ylabel="u [m/s]")
    ax.legend(fontsize=8)
    _finish(fig, [ax], "Surge speed")
    return fig


def _unwrapped_heading(angle: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """``angle`` made continuous by expressing it relative to the unwrapped ψ_F [rad]."""
    return ref + np.angle(np.exp(1j * (angle - ref)))


def figure_attitude(trajectories: Mapping[str, Trajectory], **_: Any) -> Figure:
    """Fig. 8: pitch θ and heading ψ [deg] against the desired angles.

    θ_d and ψ_d come from the controllers' diagnostics (extras "theta_d", and "psi_d_rel" =
    ψ_d − ψ_F or "psi_d") when they expose them; the path angles θ_F and ψ_F (dashed) always.
    Headings are unwrapped along ψ_F.
    """
    fig = new_figure(_WIDTH, _HEIGHT + 1.0, _DPI)
    ax_th, ax_psi = _time_axes(fig, 2)
    styles = _styles(list(trajectories))
    for k, (name, tr) in enumerate(trajectories.items()):
        style = styles[name]
        psi_f = np.unwrap(tr["psi_F"])
        ax_th.plot(tr.t, tr["theta"] * _DEG, label=f"θ {name}", **style)
        ax_psi.plot(tr.t, _unwrapped_heading(tr["psi"], psi_f) * _DEG, label=f"ψ {name}", **style)
        if "theta_d" in tr.extras:
            ax_th.plot(
                tr.t_interval,
                tr.extras["theta_d"] * _DEG,
                ls=":",
                color=style["color"],
                lw=1.0,
                label=f"θ_d {name}",
            )
        psi_d = None
        if "psi_d_rel" in tr.extras:
            psi_d = psi_f[:-1] + tr.extras["psi_d_rel"]
        elif "psi_d" in tr.extras:
            psi_d = _unwrapped_heading(tr.extras["psi_d"], psi_f[:-1])
        if psi_d is not None:
            ax_psi.plot(
                tr.t_interval,
                psi_d * _DEG,
                ls=":",
                color=style["color"],
                lw=1.0,
                label=f"ψ_d {name}",
            )
        if k == 0:
            ax_th.plot(tr.t, tr["theta_F"] * _DEG, "k--", lw=0.8, label="θ_F")
            ax_psi.plot(tr.t, psi_f * _DEG, "k--", lw=0.8, label="ψ_F")
    ax_th.set_ylabel("θ [deg]")
    ax_psi.set_ylabel("ψ [deg]")
    for ax in (ax_th, ax_psi):
        ax.legend(fontsize=7, ncol=3)
    _finish(fig, [ax_th, ax_psi], "Attitude")
    return fig


def figure_controls(trajectories: Mapping[str, Trajectory], **_: Any) -> Figure:
    """Fig. 9: applied control inputs X [N], M and N [N·m] (means over each control period)."""
    fig = new_figure(_WIDTH, _HEIGHT + 1.5, _DPI)
    axes = _time_axes(fig, 3)
    styles = _styles(list(trajectories))
    limits = None
    for name, tr in trajectories.items():
        for ax, key in zip(axes, ("X", "M", "N"), strict=True):
            ax.plot(tr.t_interval, tr[key], label=name, **{**styles[name], "lw": 0.8})
        limits = tr.actuator_limits
    for ax, key, unit, limit in zip(axes, "XMN", ("N", "N·m", "N·m"), limits or (), strict=False):
        ax.axhline(limit, color="k", ls=":", lw=0.8)
        ax.axhline(-limit, color="k", ls=":", lw=0.8)
        ax.set_ylabel(f"{key} [{unit}]")
    axes[0].legend(fontsize=8)
    _finish(fig, axes, "Control inputs")
    return fig


def norm_series(tr: Trajectory) -> dict[str, np.ndarray]:
    """The adaptive-parameter norms among the extras: names starting with "norm_"."""
    out = {}
    for key, values in tr.extras.items():
        if key.startswith("norm_"):
            out[key[5:]] = values if values.ndim == 1 else np.linalg.norm(values, axis=1)
    return out


def figure_adaptive(trajectories: Mapping[str, Trajectory], **_: Any) -> Figure | None:
    """Norms of the adaptive parameters (extras "norm_*"); None if no controller has any."""
    series = {name: norm_series(tr) for name, tr in trajectories.items()}
    keys = sorted({k for s in series.values() for k in s})
    if not keys:
        return None
    fig = new_figure(_WIDTH, 1.6 + 1.3 * len(keys), _DPI)
    axes = _time_axes(fig, len(keys))
    styles = _styles(list(trajectories))
    for ax, key in zip(axes, keys, strict=True):
        for name, tr in trajectories.items():
            if key in series[name]:
                ax.plot(tr.t_interval, series[name][key], label=name, **styles[name])
        ax.set_ylabel(f"‖{key}‖", fontsize=8)
    axes[0].legend(fontsize=8)
    _finish(fig, axes, "Adaptive-parameter norms")
    return fig


# File stem → figure builder, in the paper's order (Figs. 3–9), then the extras.
PAPER_FIGURES: dict[str, Callable[..., Figure | None]] = {
    "fig3_path_3d": figure_path_3d,
    "fig4_horizontal": figure_horizontal,
    "fig5_vertical": figure_vertical,
    "fig6_errors": figure_errors,
    "fig7_surge": figure_surge,
    "fig8_attitude": figure_attitude,
    "fig9_controls": figure_controls,
    "fig10_adaptive_norms": figure_adaptive,
    "fig11_distance": figure_distance,
}


def paper_figures(
    trajectories: Mapping[str, Trajectory],
    out_dir: str | os.PathLike,
    path: Path | None = None,
    dpi: int = _DPI,
    zoom_from: float | None = None,
) -> dict[str, FilePath]:
    """Write the figures of `PAPER_FIGURES` as ``out_dir/<stem>.png``; return stem → file.

    Args:
        trajectories: label → episode, drawn in this order (e.g. {"FBSM": …, "backstepping": …});
            for a comparison give every controller the same seed.
        out_dir: folder, created if missing.
        path: the desired path, for the reference curve (default: the virtual point's locus).
        dpi: resolution; the figures are 7 in wide (1050 px at 150 dpi), the errors figure
            10 in when zoomed.
        zoom_from: start [s] of the zoomed steady-state column of the errors figure (None:
            no zoom), e.g. the metrics' transient.

    The adaptive-norm figure is skipped when no trajectory has "norm_*" extras.
    """
    if not trajectories:
        raise ValueError("paper_figures needs at least one trajectory")
    out = FilePath(out_dir)
    written = {}
    for stem, build in PAPER_FIGURES.items():
        fig = build(trajectories, path=path, zoom_from=zoom_from)
        if fig is not None:
            written[stem] = save_figure(fig, out / f"{stem}.png", dpi=dpi)
    return written
