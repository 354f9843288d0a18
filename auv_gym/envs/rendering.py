"""Frames of a running episode for `render_mode="rgb_array"` and videos (`EpisodeRenderer`).

A frame (960 × 320 px by default) shows the path and the vehicle's track in 3-D (height −z up,
NED, docs/model.md §2.0) and the path-following errors x_e, y_e, z_e over time on a symmetric
log scale (linear within ±0.1 m); the vehicle is a dot at the head of its track.

Speed: one figure per renderer, built once. Everything that does not change from frame to frame
(axes, ticks, labels, the path) is drawn once into a cached background; a frame restores it and
draws only what moved (matplotlib's blitting). The track and the error lines only grow, so the
stretch drawn so far is kept in that cached layer and a frame draws just the new stretch and the
vehicle marker: its cost does not grow with the episode. The background is redrawn
only when the view must grow (the track leaves the 3-D limits, or the virtual point nears the
end of the drawn stretch of path; both grow geometrically, so this happens a handful of times
per episode). ``fast=False`` draws the whole figure for every frame instead: the reference the
fast path is tested against
(`tests/test_rendering.py`); `benchmarks/speed/render.py` measures both.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from auv_gym.envs.envelope_drawing import depth_limits, draw_boundaries_3d, set_boundaries_3d

if TYPE_CHECKING:
    from auv_gym.ocean.depth_envelope import DepthEnvelope
    from auv_gym.paths.shapes import Path

__all__ = ["ERROR_LIMIT_M", "EpisodeRenderer"]

ERROR_LIMIT_M = 30.0  # [m] error axis ±limit: the default corridor, beyond which episodes end
_LINEAR_M = 0.1  # [m] the error axis is linear within ±this, logarithmic outside
_LOOKAHEAD = 10.0  # path parameter drawn ahead of the virtual point [-]
_PAD = 0.08  # relative margin around the 3-D content
_GROW = 1.5  # factor by which the 3-D view grows when it must
_ERROR_COLORS = ("C0", "C3", "C2")


class _Buffer:
    """Append-only rows of floats in a growing array (amortised O(1) appends, no per-frame
    conversion of a list)."""

    def __init__(self, width: int, capacity: int = 1024) -> None:
        self._data = np.empty((capacity, width))
        self.size = 0

    def clear(self) -> None:
        self.size = 0

    def append(self, row: np.ndarray | tuple[float, ...]) -> None:
        if self.size == self._data.shape[0]:
            self._data = np.concatenate([self._data, np.empty_like(self._data)])
        self._data[self.size] = row
        self.size += 1

    @property
    def rows(self) -> np.ndarray:
        return self._data[: self.size]


class EpisodeRenderer:
    """Draws frames of one vehicle's episode; `reset` at a new episode, `append` every step.

    Args:
        path: the desired path (`auv_gym.paths.Path`).
        max_time: episode length [s], the span of the time axis.
        width_px, height_px, dpi: frame size [px] and resolution [dots/in].
        fast: blit the moving artists over a cached background (default), or redraw everything.
        envelope: the depth envelope, drawn as the sea surface and seabed planes (None: none).
    """

    def __init__(
        self,
        path: Path,
        max_time: float,
        width_px: int = 960,
        height_px: int = 320,
        dpi: int = 100,
        fast: bool = True,
        envelope: DepthEnvelope | None = None,
    ) -> None:
        if not (math.isfinite(max_time) and max_time > 0):
            raise ValueError(f"max_time must be a positive time in s, got {max_time}")
        if not (16 <= width_px <= 8192 and 16 <= height_px <= 8192):
            raise ValueError(f"frame size must be 16-8192 px, got {width_px} × {height_px}")
        self.path, self.max_time, self.fast = path, float(max_time), bool(fast)
        self._size = (int(width_px), int(height_px), int(dpi))
        self.envelope = envelope
        self._positions = _Buffer(4)  # t [s], x, y, z [m]
        self._errors = _Buffer(4)  # t [s], x_e, y_e, z_e [m]
        self._s = 0.0  # path parameter of the virtual point
        self._s_drawn = -math.inf  # the path is drawn over s in [0, _s_drawn]
        self._path_points = np.zeros((1, 3))
        self._limits: tuple[np.ndarray, np.ndarray] | None = None  # 3-D view, NED [m]
        self._figure = None  # built at the first frame
        self._layer = None  # fast path: the saved background with the lines drawn so far
        self._drawn = 0  # points of the track and error lines already in the layer
        self._stale = True  # the background must be redrawn

    # ----------------------------------------------------------------------------- episode data
    def reset(
        self,
        position: np.ndarray,
        errors: np.ndarray,
        s: float,
        t: float = 0.0,
        path: Path | None = None,
    ) -> None:
        """Start a new episode at ``position`` (x, y, z) [m] with errors (x_e, y_e, z_e) [m];
        ``path``: the episode's path when it changes per episode (``path="random"``)."""
        if path is not None and path is not self.path:
            self.path = path
            self._figure = None  # the background shows the path: build it again
        self._positions.clear()
        self._errors.clear()
        self._s_drawn = -math.inf
        self._limits = None
        self._stale = True
        self.append(position, errors, s, t)

    def append(self, position: np.ndarray, errors: np.ndarray, s: float, t: float) -> None:
        """Record one control step: NED position [m], body-frame errors [m], s, time [s].

        A step whose values are not finite (an episode ending as "non_finite") is not drawn.
        """
        if not (np.isfinite(position[:3]).all() and np.isfinite(errors[:3]).all()):
            return
        self._positions.append((t, *position[:3]))
        self._errors.append((t, *errors[:3]))
        self._s = float(s)

    # ----------------------------------------------------------------------------------- frames
    def frame(self) -> np.ndarray:
        """The current frame, RGB (height_px, width_px, 3) uint8."""
        if self._positions.size == 0:
            raise RuntimeError("EpisodeRenderer.frame before reset")
        if self._figure is None:
            self._build()
        self._update_view()
        if self.fast and not self._stale and self._positions.size - self._drawn < 100:
            return self._draw()
        # matplotlib simplifies lines of 128 points or more; a line drawn in short stretches is
        # never simplified, so neither is one drawn whole (rare on the fast path: rc_context
        # costs about as much as a frame).
        from matplotlib import rc_context

        with rc_context({"path.simplify": False}):
            return self._draw()

    def _draw(self) -> np.ndarray:
        canvas = self._canvas
        if not self.fast:
            self._set_growing(0)
            self._set_current()
            canvas.draw()
            return np.asarray(canvas.buffer_rgba())[..., :3].copy()
        if self._stale:
            canvas.draw()  # the animated artists are not part of this drawing
            self._drawn = 0
            self._stale = False
        else:
            canvas.restore_region(self._layer)
        # The track and the error lines only grow: draw the new stretch onto the layer that
        # already holds the old one, so a frame costs the same at t = 1 s and at t = 300 s.
        self._set_growing(max(self._drawn - 1, 0))
        for artist in self._growing:
            artist.axes.draw_artist(artist)
        self._layer = canvas.copy_from_bbox(self._figure.bbox)
        self._drawn = self._positions.size
        self._set_current()
        self._ax3d.draw_artist(self._vehicle)
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()

    def _set_growing(self, start: int) -> None:
        """Give the track and the error lines their points from index ``start`` on."""
        pos, err = self._positions.rows[start:], self._errors.rows[start:]
        self._track_line.set_data_3d(pos[:, 1], pos[:, 2], -pos[:, 3])
        for j, line in enumerate(self._error_lines):
            line.set_data(err[:, 0], err[:, j + 1])

    def _set_current(self) -> None:
        """The vehicle marker at the last recorded position."""
        pos = self._positions.rows[-1]
        self._vehicle.set_data_3d(pos[1:2], pos[2:3], -pos[3:4])

    def _build(self) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        width, height, dpi = self._size
        fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        self._canvas = FigureCanvasAgg(fig)
        ax3d = fig.add_axes((0.0, 0.02, 0.42, 0.96), projection="3d")
        ax_err = fig.add_axes((0.52, 0.16, 0.46, 0.72))
        ax3d.set(xlabel="x [m]", ylabel="y [m]", zlabel="−z [m]")
        for axis in (ax3d.xaxis, ax3d.yaxis, ax3d.zaxis):
            axis.label.set_size(7)
        ax3d.tick_params(labelsize=6, pad=0)
        ax3d.computed_zorder = False  # draw in zorder, as the fast path does: track over path
        ax_err.set_xlim(0.0, self.max_time)
        ax_err.set_yscale("symlog", linthresh=_LINEAR_M)
        ax_err.set_ylim(-ERROR_LIMIT_M, ERROR_LIMIT_M)
        ax_err.axhline(0.0, color="k", lw=0.6, zorder=1)
        ax_err.grid(True, alpha=0.3)
        ax_err.tick_params(labelsize=7)
        ax_err.set_xlabel("t [s]", fontsize=8)
        ax_err.set_ylabel("error [m]", fontsize=8)
        animated = self.fast
        (self._path_line,) = ax3d.plot([], [], [], "k--", lw=0.8, zorder=1)
        # Round caps and joins: a line drawn in stretches then matches the line drawn whole.
        style = {"solid_capstyle": "round", "solid_joinstyle": "round", "animated": animated}
        (self._track_line,) = ax3d.plot([], [], [], color="C1", lw=1.3, zorder=3, **style)
        (self._vehicle,) = ax3d.plot([], [], [], "o", color="C1", ms=4, zorder=4, animated=animated)
        self._error_lines = [
            ax_err.plot([], [], color=color, lw=1.0, label=name, **style)[0]
            for color, name in zip(_ERROR_COLORS, ("x_e", "y_e", "z_e"), strict=True)
        ]
        # The legend above the plot, where no line passes (the fast path draws lines last).
        # No text changes from frame to frame: glyphs cost more than all the lines together;
        # the time is where the error lines end.
        ax_err.legend(
            loc="lower right",
            bbox_to_anchor=(1.0, 1.0),
            fontsize=7,
            ncol=3,
            frameon=False,
            borderaxespad=0.2,
        )
        ax_err.set_title("body-frame errors, vehicle − virtual point", loc="left", fontsize=8)
        self._growing = [self._track_line, *self._error_lines]
        self._boundaries = draw_boundaries_3d(
            ax3d, self.envelope, np.zeros(3), np.ones(3), zorder=0
        )
        self._figure, self._ax3d = fig, ax3d

    def _update_view(self) -> None:
        """Grow the 3-D view and the drawn stretch of path when the episode needs it."""
        s_needed = self._s + _LOOKAHEAD
        if s_needed > self._s_drawn and self._s_drawn < self.path.s_end:
            s_hi = min(max(2.0 * s_needed, 40.0), self.path.s_end)
            ref = self.path.evaluate(np.linspace(0.0, s_hi, 400))[0]
            self._path_line.set_data_3d(ref[:, 0], ref[:, 1], -ref[:, 2])
            self._s_drawn, self._path_points = s_hi, ref
            self._limits = None
        track = self._positions.rows[:, 1:]
        lo, hi = track.min(axis=0), track.max(axis=0)
        if (
            self._limits is not None
            and np.all(lo >= self._limits[0])
            and np.all(hi <= self._limits[1])
        ):
            return
        lo = np.minimum(lo, self._path_points.min(axis=0))
        hi = np.maximum(hi, self._path_points.max(axis=0))
        if self._limits is not None:  # grow geometrically, so that this stays rare
            centre, half = (lo + hi) / 2, (hi - lo) / 2
            old_half = (self._limits[1] - self._limits[0]) / 2
            half = np.maximum(half, _GROW * old_half)
            lo, hi = centre - half, centre + half
        lo[2], hi[2] = depth_limits(self.envelope, lo[2], hi[2])
        span = np.maximum(hi - lo, 1.0)
        lo, hi = lo - _PAD * span, hi + _PAD * span
        self._limits = (lo, hi)
        set_boundaries_3d(self._boundaries, self.envelope, lo, hi)
        ax = self._ax3d
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(-hi[2], -lo[2])  # height −z
        self._stale = True
