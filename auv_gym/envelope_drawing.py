"""The depth envelope in figures: the sea surface and the seabed (`auv_gym.depth_envelope`).

Shared by the live renderer (`auv_gym.rendering`), the episode figures
(`auv_gym.episode_figures`) and the benchmark's track figures (`auv_gym.plotting.plot_track`).
Heights are plotted as −z (NED, z down), so the surface is the plane −z = 0 and the seabed the
plane −z = −seabed_depth. Nothing is drawn without an envelope.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from auv_gym.depth_envelope import SURFACE_Z, DepthEnvelope

if TYPE_CHECKING:
    from auv_gym.trajectory import Trajectory

__all__ = ["draw_boundaries_3d", "draw_boundary_lines", "envelope_of", "set_boundaries_3d"]

# (label, colour, alpha) of the two boundaries; one look in every figure
_SURFACE = ("sea surface", "tab:blue", 0.15)
_SEABED = ("seabed", "saddlebrown", 0.3)


def envelope_of(trajectories: Iterable[Trajectory]) -> DepthEnvelope | None:
    """The depth envelope the episodes were recorded with (their metadata's env arguments);
    None if they had none."""
    for tr in trajectories:
        spec = tr.metadata.get("env_kwargs", {}).get("depth_envelope")
        if spec is not None:
            return DepthEnvelope.from_spec(spec)
    return None


def _boundaries(envelope: DepthEnvelope | None) -> list[tuple[float, tuple[str, str, float]]]:
    """(z [m], style) of the surface and, if any, the seabed."""
    if envelope is None:
        return []
    found = [(SURFACE_Z, _SURFACE)]
    if envelope.seabed_depth is not None:
        found.append((envelope.seabed_depth, _SEABED))
    return found


def depth_limits(envelope: DepthEnvelope | None, z_lo: float, z_hi: float) -> tuple[float, float]:
    """The z range [m] (z_lo, z_hi) widened to show the boundaries."""
    for z, _ in _boundaries(envelope):
        z_lo, z_hi = min(z_lo, z), max(z_hi, z)
    return z_lo, z_hi


def _rectangle(lo: np.ndarray, hi: np.ndarray, z: float) -> list[np.ndarray]:
    x0, y0, x1, y1 = lo[0], lo[1], hi[0], hi[1]
    return [np.array([(x0, y0, -z), (x1, y0, -z), (x1, y1, -z), (x0, y1, -z)])]


def draw_boundaries_3d(
    ax: Any, envelope: DepthEnvelope | None, lo: np.ndarray, hi: np.ndarray, **kwargs: Any
) -> list[Any]:
    """Translucent planes of the surface and the seabed over x, y in [lo, hi] [m] on a 3-D
    axes (height −z); returns the artists (for `set_boundaries_3d`)."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    artists = []
    for z, (label, colour, alpha) in _boundaries(envelope):
        poly = Poly3DCollection(
            _rectangle(lo, hi, z),
            facecolor=colour,
            alpha=alpha,
            edgecolor=colour,
            label=label,
            **kwargs,
        )
        ax.add_collection3d(poly)
        artists.append(poly)
    return artists


def set_boundaries_3d(
    artists: list[Any], envelope: DepthEnvelope | None, lo: np.ndarray, hi: np.ndarray
) -> None:
    """Stretch the planes of `draw_boundaries_3d` over a new x, y extent [m]."""
    for poly, (z, _) in zip(artists, _boundaries(envelope), strict=True):
        poly.set_verts(_rectangle(lo, hi, z))


def draw_boundary_lines(ax: Any, envelope: DepthEnvelope | None) -> None:
    """Horizontal lines at the surface and the seabed on an axes whose y is the height −z."""
    for z, (label, colour, _) in _boundaries(envelope):
        ax.axhline(-z, color=colour, lw=1.2, label=label)


def extent(points: Iterable[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) corners [m] of (n, 3) point sets together."""
    stacked = np.concatenate([np.asarray(p).reshape(-1, 3) for p in points])
    stacked = stacked[np.isfinite(stacked).all(axis=1)]
    return stacked.min(axis=0), stacked.max(axis=0)


def trajectory_points(trajectories: Mapping[str, Trajectory]) -> list[np.ndarray]:
    """Every trajectory's positions, for `extent`."""
    return [tr.position for tr in trajectories.values()]
