"""A vehicle's start at a reset: the configured or the path's default start, or a draw from the
training distribution (``randomize_start``), from the vehicle's reset generator in fixed order."""

from __future__ import annotations

import math

import numpy as np

from auv_gym.paths.shapes import Path
from auv_gym.sim.config import START_OFFSET, SimConfig

__all__ = ["MAX_START_SURGE", "START_SURGE_SHARE", "draw_start"]

MAX_START_SURGE = 1.5  # [m/s] the fastest surge of a start drawn on the first turn
# The drawn surge stays below this share of `surge_limit`, so that no episode starts as
# "overspeed" (0.75 × 2 m/s: the speed-limited ids keep 1.5 m/s, their draws bit for bit).
START_SURGE_SHARE = 0.75


def draw_start(
    cfg: SimConfig, rng: np.random.Generator, path: Path
) -> tuple[np.ndarray, float, float, float]:
    """Start position [m], heading ψ [rad], path parameter s0 and surge speed u0 [m/s]."""
    position, heading = path.default_start()
    if cfg.start_position is not None:
        position = np.asarray(cfg.start_position)
    if cfg.start_heading is not None:
        heading = float(cfg.start_heading)
    if cfg.randomize_start:
        # Training distribution: half the episodes near the path's default start (heading error
        # within ±start_heading_spread), half anywhere on the first turn of the path, with a
        # random heading error and speed. A drawn rotation comes after every other draw.
        draws = rng.uniform(-1.0, 1.0, size=7)
        if draws[0] >= 0.0:
            return _on_the_first_turn(cfg, rng, path, draws)
        position = position + START_OFFSET * draws[1:4]
        heading = heading + cfg.start_heading_spread * draws[4]
    rotation = _rotation(cfg, rng)
    if rotation != 0.0:  # the whole start turns about p(0); 0.0 keeps earlier starts bit for bit
        position, heading = _rotated(position, heading, rotation, path.evaluate(0.0)[0])
    return position, heading, 0.0, 0.0


def _on_the_first_turn(
    cfg: SimConfig, rng: np.random.Generator, path: Path, draws: np.ndarray
) -> tuple[np.ndarray, float, float, float]:
    """A start anywhere on the first turn: up to 8 m off the path, ±60° of heading error and
    0–1.5 m/s of surge (at most 0.75 `surge_limit`); a rotation turns only its heading (it lies
    along the path)."""
    s_span = min(40.0, path.s_end) if math.isfinite(path.s_end) else 40.0
    s0 = 0.5 * (draws[1] + 1.0) * 0.9 * s_span
    p, dp, _ = path.evaluate(s0)
    path_heading = math.atan2(dp[1], dp[0])
    position = p + 8.0 * rng.uniform(-1.0, 1.0, size=3)
    rotation = _rotation(cfg, rng)
    if rotation != 0.0:
        path_heading = path_heading + rotation
    # 0-1.5 m/s, below a surge limit under 2 m/s: the start must not end the episode
    top = min(MAX_START_SURGE, START_SURGE_SHARE * cfg.limits.surge_limit)
    return position, path_heading + (math.pi / 3) * draws[5], s0, 0.5 * top * (draws[6] + 1.0)


def _rotation(cfg: SimConfig, rng: np.random.Generator) -> float:
    """The episode's start rotation [rad]: `start_rotation`, or a uniform draw from its
    (low, high) range (the generator is only drawn from for a range)."""
    rotation = cfg.start_rotation
    if isinstance(rotation, tuple):
        return float(rng.uniform(rotation[0], rotation[1]))
    return rotation


def _rotated(
    position: np.ndarray, heading: float, angle: float, pivot: np.ndarray
) -> tuple[np.ndarray, float]:
    """The start turned by ``angle`` [rad] about the vertical through ``pivot`` [m]: its
    horizontal offset from the pivot and its heading, so that its geometry relative to the path
    turns with it (the depth is unchanged)."""
    c, s = math.cos(angle), math.sin(angle)
    dx, dy = position[0] - pivot[0], position[1] - pivot[1]
    turned = np.array([pivot[0] + c * dx - s * dy, pivot[1] + s * dx + c * dy, position[2]])
    return turned, heading + angle
