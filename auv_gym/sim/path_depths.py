"""Where the path lies in the water column: below the surface where the ocean's depth-dependent
parts act, and inside a depth envelope's band for every drawn path (docs/model.md §12-13).

Checked at construction, so that no reset is ever refused:

- **Waves and a current profile act below the surface** (z ≥ 0, z down). Above it the wave
  kernel would apply the surface's orbital velocities all episode and the profile its surface
  speed, so a path, or its start, that reaches z < 0 within the arc an episode covers
  (u_desired·max_time) is refused with the ``path_offset`` that moves it down. A drawn path is
  bounded by its distribution: it starts at the offset and climbs at most the distribution's
  largest flight-path angle (+0.5°, the draw's own tolerance) over that arc.
- **Drawn paths under a depth envelope are drawn inside its band**: `draw_path` redraws (from
  the path's own generator, so the episode's current, noise and actuator draws are unchanged,
  and so is every path of a configuration whose first draw fits) until the path fits;
  `check_drawn_paths_fit` refuses at construction a configuration where none of `FIT_SAMPLES`
  draws fits, so that resets never exhaust `MAX_REDRAWS`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from auv_gym.ocean.depth_envelope import RANDOM_START_RISE, path_depth_range
from auv_gym.paths.offset import ShiftedPath, shift_path
from auv_gym.paths.shapes import Path

if TYPE_CHECKING:
    from auv_gym.sim.config import SimConfig

__all__ = [
    "FIT_SAMPLES",
    "MAX_REDRAWS",
    "check_below_the_surface",
    "check_drawn_paths_fit",
    "draw_path",
    "episode_surface_z",
]

FIT_SAMPLES = 64  # draws tried at construction; one must fit the depth envelope
# Redraws a reset may take: with one fitting draw in FIT_SAMPLES the chance to exhaust them is
# (63/64)^1000 ≈ 1.5e-7 per reset; typical configurations fit at the first draw.
MAX_REDRAWS = 1000
ANGLE_TOLERANCE_DEG = 0.5  # the draws' own flight-path-angle tolerance (`path_generator`)


def _surface_users(config: SimConfig) -> str:
    names = [n for n in ("waves", "current_profile") if getattr(config, n) is not None]
    return " and ".join(names)


def _episode_arc(config: SimConfig) -> float:
    """[m] the arc length an episode on schedule covers."""
    return config.u_desired * config.max_time


def check_below_the_surface(config: SimConfig) -> None:
    """ValueError naming ``path_offset`` when waves or a current profile are on and the path or
    its start can reach the surface z = 0 in an episode (module doc); ValueError naming
    ``surface_above_path`` when it is given with neither, the only parts that read the surface.
    """
    users = _surface_users(config)
    if not users and config.surface_above_path is not None:
        raise ValueError(
            f"surface_above_path = {config.surface_above_path:g} m places the sea surface for "
            "waves and a current profile, and neither is on: give waves or current_profile, or "
            "leave surface_above_path out"
        )
    if not users or config.surface_above_path is not None:  # the surface follows the path
        return
    rise = RANDOM_START_RISE if config.randomize_start else 0.0
    arc = _episode_arc(config)
    if isinstance(config.path, Path):
        top = _episode_top(config, config.path)
        given = config.start_position
        start_z = float((given if given is not None else config.path.default_start()[0])[2])
        highest = min(top, start_z - rise)
        what = "the path and its start"
    else:
        if config.depth_envelope is not None:  # drawn inside the band, below its margin
            return
        distribution = config.path
        start_depth = _start_depth(config)
        climb = math.radians(distribution.climb_angle_deg[1] + ANGLE_TOLERANCE_DEG)
        z0 = config.path_offset[2]
        highest = min(z0 - arc * math.sin(climb), z0 + start_depth - rise)
        what = "a drawn path (climbing at up to its largest flight-path angle) and its start"
    if highest < 0.0:
        move = math.ceil(-highest)
        # the remedy adds to the offset already given (a fixed path carries it, moved)
        given = config.path.offset if isinstance(config.path, ShiftedPath) else config.path_offset
        remedy = [_number(given[0]), _number(given[1]), _number(given[2] + move)]
        raise ValueError(
            f"{users} act below the sea surface z = 0, but {what} can reach z = {highest:.4g} m "
            f"over the {arc:g} m an episode covers: move the path at least {move} m further "
            f"down (path_offset = [{', '.join(remedy)}]), or place the surface above it "
            "(surface_above_path, without a depth envelope)"
        )


def _number(value: float) -> str:
    """A coordinate [m] as typed: 615 rather than 615.0."""
    value = float(value)
    return str(int(value)) if value.is_integer() and abs(value) < 1e15 else repr(value)


def episode_surface_z(config: SimConfig, path: Path, start_z: float) -> float:
    """[m] the NED z of the sea surface for an episode on ``path`` from ``start_z``:
    `surface_above_path` above the shallowest of the start and the path over the arc an episode
    covers (docs/model.md §13.8); 0 when the configuration has no such setting."""
    if config.surface_above_path is None:
        return 0.0
    return min(_episode_top(config, path), start_z) - config.surface_above_path


def _episode_top(config: SimConfig, path: Path) -> float:
    """[m] the smallest z of ``path`` over the arc an episode covers."""
    tangent = float(np.linalg.norm(path.evaluate(0.0)[1]))
    top, _ = path_depth_range(path, _episode_arc(config) / tangent)
    return top


def _start_depth(config: SimConfig) -> float:
    """[m] how far below its path's first point a drawn path's default start lies."""
    path = config.path.draw(np.random.default_rng(0))
    return float(path.default_start()[0][2] - path.evaluate(0.0)[0][2])


def _fits(config: SimConfig, path: Path) -> bool:
    try:
        config.check_depths(path, drawn=True)
    except ValueError:
        return False
    return True


def check_drawn_paths_fit(config: SimConfig) -> None:
    """ValueError at construction when no draw of `FIT_SAMPLES` fits the depth envelope's band
    (a drawn path with an envelope); nothing to check otherwise."""
    if config.depth_envelope is None or isinstance(config.path, Path):
        return
    rng = np.random.default_rng(0)
    last = None
    for _ in range(FIT_SAMPLES):
        path = shift_path(config.path.draw(rng), config.path_offset)
        try:
            config.check_depths(path, drawn=True)
            return
        except ValueError as error:
            last = error
    raise ValueError(
        f"depth_envelope: none of {FIT_SAMPLES} paths drawn from this distribution fits the "
        f"safe band ({last})"
    )


def draw_path(config: SimConfig, rng: np.random.Generator) -> Path:
    """A path of the configuration's distribution, moved by ``path_offset``, inside the depth
    envelope's band when there is one (redrawn from ``rng``; module doc)."""
    for _ in range(MAX_REDRAWS):
        path = shift_path(config.path.draw(rng), config.path_offset)
        if config.depth_envelope is None or _fits(config, path):
            return path
    raise RuntimeError(
        f"no path inside the depth envelope in {MAX_REDRAWS} draws (the construction-time check "
        f"found one in {FIT_SAMPLES}): please report this configuration"
    )
