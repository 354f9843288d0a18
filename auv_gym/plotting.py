"""Matplotlib figures of paths and tracks (imported lazily; uses the Agg backend)."""

from __future__ import annotations

import numpy as np

from auv_gym.paths import Path

__all__ = ["plot_track", "render_track"]


def _figure(width_in: float, height_in: float, dpi: int):
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), dpi=dpi)


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


def render_track(path: Path, track: np.ndarray, s_now: float) -> np.ndarray:
    """RGB picture (H, W, 3) uint8 of the path and one vehicle track."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = _figure(9.6, 3.2, 100)
    canvas = FigureCanvasAgg(fig)
    plot_track(fig, path, {"vehicle": track}, s_max=s_now + 10.0)
    fig.tight_layout()
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()
