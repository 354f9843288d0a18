"""The depth envelope in figures: the sea surface and the seabed (`auv_gym.ocean.depth_envelope`).

Drawn by the live renderer (`auv_gym.envs.rendering`) and, so that every figure shows them alike,
by the benchmark's figures (`benchmarks.reports.plotting`, `benchmarks.reports.episode_figures`).
Heights are plotted as −z (NED, z down), so the surface is the plane −z = 0 and the seabed the
plane −z = −seabed_depth. Nothing is drawn without an envelope.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from auv_gym.ocean.depth_envelope import SURFACE_Z, DepthEnvelope

__all__ = ["depth_limits", "draw_boundaries_3d", "draw_boundary_lines", "set_boundaries_3d"]

# (label, colour, alpha) of the two boundaries; one look in every figure
_SURFACE = ("sea surface", "tab:blue", 0.15)
_SEABED = ("seabed", "saddlebrown", 0.3)


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
