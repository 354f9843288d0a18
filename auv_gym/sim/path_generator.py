"""Seeded procedural paths the vehicle can follow: the path distribution behind ``path="random"``.

A `PathDistribution` draws, from a numpy generator, one path of one of four families:

- ``helix``: radius R, flight-path angle γ (ascending or descending), starboard or port turn;
  parameterised by arc length, so its radius of curvature is R/cos²γ ≥ R;
- ``line``: a straight line in any horizontal direction with flight-path angle ±γ;
- ``spline``: a smooth random track — pieces of random length, each straight or turning with a
  random radius, its flight-path angle varying linearly between random values — sampled every
  `SAMPLE_SPACING` m (or a third of the smallest radius) and interpolated by the natural cubic
  `Spline` through those waypoints;
- ``lawnmower``: a survey pattern — parallel legs joined by half-circle turns of alternating
  direction, climbing or descending at ±γ — sampled and interpolated the same way.

Every path starts at the origin, p(0) = (0, 0, 0) m, and respects the limits the vehicle can follow
(docs/model.md §3.8): radius of curvature ≥ the distribution's smallest radius (never below
`MIN_TURN_RADIUS`; splines within `CURVATURE_SLACK`) and |γ| ≤ its largest angle (never above
`MAX_FLIGHT_PATH_ANGLE_DEG`; splines within 0.5°), checked on every drawn spline at 16 points
per segment (a draw outside is redrawn from the same generator, so a path is still a function
of the generator's state only). Every drawn path also has, proven on the whole path
(`auv_gym.paths.bounds`), |p'| >= `paths.MIN_TANGENT` and turn rates |dψ_F/ds|/|p'|,
|dθ_F/ds|/|p'| <= `MAX_TURN_RATE`, so it fits the observation bounds at any u_desired. If all
`_MAX_REDRAWS` natural splines miss the limits (a track that ends inside a turn, with ranges
too narrow to draw another), the same tracks are interpolated with their own end tangents
instead of the natural ends; measured over random configurations, that always succeeds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from auv_gym.paths.bounds import spline_turn_rates
from auv_gym.paths.shapes import Helix, Path, Spline, StraightLine
from auv_gym.sim.observation import PATH_RATE_BOUND, SPEED_BOUND
from auv_gym.support.validation import ArgumentTypeError, keys_within, real, vector

__all__ = [
    "FAMILIES",
    "MAX_FLIGHT_PATH_ANGLE_DEG",
    "MIN_TURN_RADIUS",
    "SAMPLE_SPACING",
    "PathDistribution",
    "curvature_and_angle",
    "overlaps",
]

FAMILIES = ("helix", "line", "spline", "lawnmower")
# The ranges each family draws from (`overlaps`).
FAMILY_RANGES = {
    "helix": ("radius", "climb_angle_deg"),
    "line": ("climb_angle_deg",),
    "spline": ("spline_radius", "climb_angle_deg", "piece_length"),
    "lawnmower": ("radius", "climb_angle_deg", "leg_length"),
}
# The families whose paths each setting changes (climb_angle_deg: all): besides FAMILY_RANGES,
# `radius` and `spline_radius` set the waypoint spacing of splines and lawnmowers (`spacing`),
# and `length` is the arc length of both (helices and lines are endless).
RANGE_USERS = {
    "radius": ("helix", "spline", "lawnmower"),
    "spline_radius": ("spline", "lawnmower"),
    "piece_length": ("spline",),
    "leg_length": ("lawnmower",),
    "length": ("spline", "lawnmower"),
}
# Vehicle limits (docs/model.md §3.8). At u = 1 m/s full yaw authority turns the REMUS 100 on a
# 4.0-m radius ("paper" and "fins" alike); generated paths keep twice that. Full fin authority
# holds a steady climb of γ = 25.6° at 1 m/s (θ = 25.0°); "paper" actuators hold any pitch.
MIN_TURN_RADIUS = 8.0  # [m]
MAX_FLIGHT_PATH_ANGLE_DEG = 25.0  # [deg]
SAMPLE_SPACING = 5.0  # [m] largest waypoint spacing of the spline and lawnmower families
MIN_SAMPLES_PER_RADIUS = 3.0  # spacing ≤ radius low / 3: the spline follows arcs to ≤ 5 %
MAX_RADIUS = 1e4  # [m]
LENGTH_RANGE = (50.0, 2000.0)  # [m] of spline and lawnmower paths
_INTEGRATION_STEP = 0.5  # [m] arc-length step of the heading/climb profiles
_SMOOTHING = 20.0  # [m] length of the curvature ramps between pieces
_CHECKS_PER_SEGMENT = 16
_MAX_REDRAWS = 20
VERTICAL_SHARE, HORIZONTAL_SHARE = 0.3, math.sqrt(1.0 - 0.3**2)
MIN_PIECE = 20.0  # [m] shortest spline piece or lawnmower leg: one curvature ramp long
# The spline through the track's samples follows its curvature ramps to within a few per cent
# (measured on 200 draws: ≤ 3.7 % above 1/R at 5-m spacing, 24 % at 10 m); the check allows 5 %.
CURVATURE_SLACK = 1.05
# [rad/m] Proven bound on every drawn path's |dψ_F/ds|/|p'| and |dθ_F/ds|/|p'|: the virtual point
# (u_p <= 2 u_D) then turns within the observation's ±PATH_RATE_BOUND for any u_desired, which
# is why the environment needs no turn-rate check for a distribution. Drawn paths keep far
# below it (about 1/R_low ≤ 1/8 m, cos γ/R for a helix).
MAX_TURN_RATE = PATH_RATE_BOUND / (2.0 * SPEED_BOUND)


def _range(name: str, value: Any, low: float, high: float, unit: str) -> tuple[float, float]:
    lo, hi = vector(name, value, 2, -math.inf, math.inf, unit)
    if lo > hi:
        raise ValueError(f"{name} must be (low, high) with low <= high, got {tuple(value)}")
    for x in (lo, hi):
        if not low <= x <= high:
            raise ValueError(f"{name} must lie in [{low:g}, {high:g}] {unit}, got {(lo, hi)}")
    return lo, hi


@dataclass(frozen=True)
class PathDistribution:
    """The seeded distribution of generated paths; `draw` returns one `Path`.

    Fields (ranges are (low, high), drawn uniformly; every path family uses the ranges that
    apply to it):

    - ``families``: the families drawn, with equal probability, among `FAMILIES`.
    - ``radius`` [m]: helix radius; turn radius of the lawnmower turns and (unless
      ``spline_radius`` is given) of the spline pieces. low ≥ `MIN_TURN_RADIUS` (8 m), high ≤ 1e4.
    - ``spline_radius`` [m]: turn radius of the spline pieces, the same limits; None (default):
      ``radius``. A family of its own lets a distribution draw tight splines while its helices
      stay wide (a test set of tight helices then stays held out, `overlaps`).
    - ``climb_angle_deg`` [deg]: |γ| of helices, lines, lawnmower legs and the spline's
      flight-path-angle profile (sign drawn: ascending or descending); high ≤
      `MAX_FLIGHT_PATH_ANGLE_DEG` (25°).
    - ``piece_length`` [m]: length of the spline's pieces, in [20, 1000].
    - ``leg_length`` [m]: lawnmower leg length, in [20, 1000].
    - ``length`` [m]: arc length of spline and lawnmower paths, in [50, 2000] (helix and line
      are endless); at u_D = 1 m/s a 300-s episode covers about 300 m.
    """

    families: tuple[str, ...] = FAMILIES
    radius: tuple[float, float] = (15.0, 40.0)
    spline_radius: tuple[float, float] | None = None
    climb_angle_deg: tuple[float, float] = (0.0, 20.0)
    piece_length: tuple[float, float] = (30.0, 80.0)
    leg_length: tuple[float, float] = (60.0, 150.0)
    length: float = 400.0

    def __post_init__(self) -> None:
        families = self.families
        if isinstance(families, str) or not isinstance(families, Sequence):
            raise ArgumentTypeError(
                f"PathDistribution families must be a list among "
                f"{list(FAMILIES)}, got {families!r:.80}"
            )
        unknown = [f for f in families if f not in FAMILIES]
        if unknown or not families or len(set(families)) != len(families):
            raise ValueError(
                f"PathDistribution families must be distinct names among "
                f"{list(FAMILIES)}, got {list(families)!r:.80}"
            )
        radius = _turn_radius("radius", self.radius)
        spline_radius = (
            radius
            if self.spline_radius is None
            else _turn_radius("spline_radius", self.spline_radius)
        )
        angle = vector("PathDistribution climb_angle_deg", self.climb_angle_deg, 2, unit="deg")
        if max(abs(angle[0]), abs(angle[1])) > MAX_FLIGHT_PATH_ANGLE_DEG:
            raise ValueError(
                f"PathDistribution climb_angle_deg {angle} exceeds the vehicle's largest "
                f"followable flight-path angle {MAX_FLIGHT_PATH_ANGLE_DEG:g}° (docs/model.md §3.8)"
            )
        angle = _range(
            "PathDistribution climb_angle_deg", angle, 0.0, MAX_FLIGHT_PATH_ANGLE_DEG, "deg"
        )
        piece = _range("PathDistribution piece_length", self.piece_length, MIN_PIECE, 1000.0, "m")
        leg = _range("PathDistribution leg_length", self.leg_length, MIN_PIECE, 1000.0, "m")
        length = real("PathDistribution length", self.length, *LENGTH_RANGE, unit="m")
        for name, value in (
            ("families", tuple(families)),
            ("radius", radius),
            ("spline_radius", spline_radius),
            ("climb_angle_deg", angle),
            ("piece_length", piece),
            ("leg_length", leg),
            ("length", length),
        ):
            object.__setattr__(self, name, value)

    @classmethod
    def from_spec(cls, spec: PathDistribution | Mapping[str, Any] | str) -> PathDistribution:
        """From itself, "random" (the defaults) or a dict of fields (e.g. a TOML table). A
        dict's range that no family of its ``families`` uses (`RANGE_USERS`) is refused."""
        if isinstance(spec, PathDistribution):
            return spec
        if spec == "random":
            return cls()
        names = [f.name for f in fields(cls)]
        given = {
            k: (tuple(v) if isinstance(v, list) else v)
            for k, v in keys_within("path", spec, names).items()
        }
        distribution = cls(**given)
        for name, users in RANGE_USERS.items():
            if name in given and not set(users) & set(distribution.families):
                drawn = list(distribution.families)
                if len(users) == 1:
                    what = f"the {users[0]} family, and families {drawn} does not draw it"
                    remedy = f"add {users[0]!r} to families"
                else:
                    names = f"{', '.join(users[:-1])} and {users[-1]}"
                    what = f"the {names} families, and families {drawn} draws none of them"
                    remedy = "add one of them to families"
                raise ValueError(
                    f"path {name} = {given[name]!r} shapes only {what}: leave {name} out or "
                    f"{remedy}"
                )
        return distribution

    @property
    def spacing(self) -> float:
        """Waypoint spacing of the spline and lawnmower families [m]: `SAMPLE_SPACING`, or a
        third of the smallest radius (of either) if that is shorter, rounded down to the
        integration step."""
        smallest = min(self.radius[0], self.spline_radius[0])
        wanted = min(SAMPLE_SPACING, smallest / MIN_SAMPLES_PER_RADIUS)
        return max(1, math.floor(wanted / _INTEGRATION_STEP)) * _INTEGRATION_STEP

    @property
    def max_waypoints(self) -> int:
        """Most waypoints of a generated spline (sizes the simulator's path table)."""
        return math.ceil(self.length / self.spacing) + 1

    @property
    def max_data_size(self) -> int:
        """Largest kernel vector of a drawn path (`Path.data`)."""
        sizes = [6]
        if {"spline", "lawnmower"} & set(self.families):
            sizes.append(2 + 13 * (self.max_waypoints - 1))
        return max(sizes)

    def draw(self, rng: np.random.Generator) -> Path:
        """One path, a function of the generator's state only; p(0) = (0, 0, 0) m."""
        family = self.families[int(rng.integers(len(self.families)))]
        if family == "helix":
            return self._helix(rng)
        if family == "line":
            return self._line(rng)
        tracks = []
        for _ in range(_MAX_REDRAWS):
            track, ends = self._spline_track(rng) if family == "spline" else self._lawnmower(rng)
            path = self._within_limits(track, family)
            if path is not None:
                path.family = family
                return path
            tracks.append((track, ends))
        # A natural spline straightens the track's ends (p'' = 0 there): a track that ends
        # inside a turn overshoots the curvature limit near its end, and a distribution whose
        # ranges are narrow draws such tracks every time. Clamping the end slopes to the
        # track's own tangents follows the turn; only draws that failed every natural attempt
        # come here, so the paths drawn before are unchanged.
        for track, ends in tracks:
            path = self._within_limits(track, family, ends)
            if path is not None:
                path.family = family
                return path
        raise RuntimeError(
            f"PathDistribution: no {family} path within the limits after "
            f"{_MAX_REDRAWS} draws: {self}"
        )

    def _within_limits(
        self, track: np.ndarray, family: str, ends: tuple[np.ndarray, np.ndarray] | None = None
    ) -> Spline | None:
        """The spline through ``track`` (natural, or with end slopes ``ends``) if it keeps the
        limits of the distribution's ``family`` (curvature and flight-path angle, sampled as
        documented) and the
        proven ones every environment needs (|p'| >= `paths.MIN_TANGENT`, turn rates <=
        `MAX_TURN_RATE`); else None."""
        try:
            path = Spline(track, end_tangents=ends)
        except ValueError:  # |p'| below the minimum somewhere
            return None
        kappa, gamma = curvature_and_angle(path)
        smallest = (self.spline_radius if family == "spline" else self.radius)[0]
        if kappa > CURVATURE_SLACK / smallest or gamma > math.radians(
            self.climb_angle_deg[1] + 0.5
        ):
            return None
        rates = spline_turn_rates(path.data, accept_below=MAX_TURN_RATE)
        return path if max(r.upper for r in rates) <= MAX_TURN_RATE else None

    def _angle(self, rng: np.random.Generator) -> float:
        """A signed flight-path angle [rad]: |γ| uniform in the range, sign ±1."""
        low, high = self.climb_angle_deg
        return math.radians(rng.uniform(low, high)) * (1.0 if rng.random() < 0.5 else -1.0)

    def _helix(self, rng: np.random.Generator) -> Path:
        radius = rng.uniform(*self.radius)
        gamma = self._angle(rng)
        turn = 1.0 if rng.random() < 0.5 else -1.0  # starboard / port
        # Arc length: |p'| = sqrt(R²ω² + c²) = 1 with ω = ±cos γ / R, c = sin γ (> 0 climbs).
        path = Helix(radius, turn * math.cos(gamma) / radius, math.sin(gamma), (-radius, 0.0, 0.0))
        path.family = "helix"
        return path

    def _line(self, rng: np.random.Generator) -> Path:
        heading = rng.uniform(-math.pi, math.pi)
        gamma = self._angle(rng)
        direction = (
            math.cos(gamma) * math.cos(heading),
            math.cos(gamma) * math.sin(heading),
            -math.sin(gamma),
        )
        path = StraightLine((0.0, 0.0, 0.0), direction)
        path.family = "line"
        return path

    def _spline_track(self, rng: np.random.Generator) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """Waypoints of a random track: pieces straight (⅓) or turning (⅔) at a random radius and
        side, the flight-path angle linear between random values at the piece ends."""
        lengths, curvatures, angles = [], [], [self._angle(rng)]
        # The climb may change at most VERTICAL_SHARE/R_low per metre, the heading turns at
        # most HORIZONTAL_SHARE/R: together a curvature of at most 1/R (shares squared sum to 1).
        pitch_rate = VERTICAL_SHARE / self.spline_radius[0]
        total = 0.0
        while total < self.length:
            lengths.append(rng.uniform(*self.piece_length))
            turning = rng.random() < 2.0 / 3.0
            side = 1.0 if rng.random() < 0.5 else -1.0
            curvatures.append(
                HORIZONTAL_SHARE * side / rng.uniform(*self.spline_radius) if turning else 0.0
            )
            step = pitch_rate * lengths[-1]
            angles.append(min(max(self._angle(rng), angles[-1] - step), angles[-1] + step))
            total += lengths[-1]
        heading0 = rng.uniform(-math.pi, math.pi)
        return _integrate(lengths, curvatures, angles, heading0, self.length, self.spacing)

    def _lawnmower(self, rng: np.random.Generator) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """Waypoints of a survey: legs of one length joined by half circles of alternating side."""
        leg = rng.uniform(*self.leg_length)
        radius = rng.uniform(*self.radius)
        gamma = self._angle(rng)
        first_side = 1.0 if rng.random() < 0.5 else -1.0
        heading0 = rng.uniform(-math.pi, math.pi)
        lengths, curvatures = [], []
        total, k = 0.0, 0
        while total < self.length:
            side = first_side * (1.0 if k % 2 == 0 else -1.0)
            lengths += [leg, math.pi * radius]
            curvatures += [0.0, side / radius]
            total += leg + math.pi * radius
            k += 1
        angles = [gamma] * (len(lengths) + 1)
        return _integrate(lengths, curvatures, angles, heading0, self.length, self.spacing)


def _turn_radius(name: str, value: Any) -> tuple[float, float]:
    """A (low, high) turn-radius range [m] within [`MIN_TURN_RADIUS`, `MAX_RADIUS`]."""
    radius = vector(f"PathDistribution {name}", value, 2, unit="m")
    if radius[0] <= 0.0:
        raise ValueError(f"PathDistribution {name} must be positive, got {radius} m")
    if radius[0] < MIN_TURN_RADIUS:
        raise ValueError(
            f"PathDistribution {name} {radius} m starts below the vehicle's smallest "
            f"followable turn radius {MIN_TURN_RADIUS:g} m (docs/model.md §3.8)"
        )
    return _range(f"PathDistribution {name}", radius, MIN_TURN_RADIUS, MAX_RADIUS, "m")


def _integrate(
    lengths: list[float],
    curvatures: list[float],
    angles: list[float],
    heading0: float,
    total: float,
    spacing: float,
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """Waypoints every ``spacing`` m (a multiple of the integration step) of arc length along
    a track whose heading turns at the given horizontal curvature per piece [1/m] and whose
    flight-path angle goes linearly between the given values [rad]; starts at the origin with
    heading ``heading0`` [rad]. Also the track's unit tangents at the first and last
    waypoint."""
    edges = np.r_[0.0, np.cumsum(lengths)]
    ell = np.arange(0.0, total + _INTEGRATION_STEP / 2, _INTEGRATION_STEP)
    piece = np.clip(np.searchsorted(edges, ell, side="right") - 1, 0, len(lengths) - 1)
    into = ell - edges[piece]
    # The piecewise-constant curvature, averaged over `_SMOOTHING` m: its jumps become ramps
    # (clothoid-like transitions) that the cubic spline follows without overshoot, and the
    # average never exceeds the largest curvature.
    kappa = np.asarray(curvatures)[piece]
    width = round(_SMOOTHING / _INTEGRATION_STEP)
    kappa = np.convolve(kappa, np.ones(width) / width, mode="same")
    heading = heading0 + np.r_[0.0, np.cumsum(0.5 * (kappa[1:] + kappa[:-1]))] * _INTEGRATION_STEP
    a = np.asarray(angles)
    gamma = a[piece] + (a[piece + 1] - a[piece]) * into / np.asarray(lengths)[piece]
    tangent = np.stack(
        [np.cos(gamma) * np.cos(heading), np.cos(gamma) * np.sin(heading), -np.sin(gamma)], axis=1
    )
    # Trapezoidal integration of the unit tangent.
    steps = 0.5 * (tangent[1:] + tangent[:-1]) * _INTEGRATION_STEP
    points = np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    every = round(spacing / _INTEGRATION_STEP)
    last = (len(points) - 1) // every * every
    return points[::every], (tangent[0], tangent[last])


def curvature_and_angle(path: Path, per_segment: int = _CHECKS_PER_SEGMENT) -> tuple[float, float]:
    """Largest curvature κ = |p' × p''|/|p'|³ [1/m] and largest |γ| = asin(|z'|/|p'|) [rad] of a
    path, sampled ``per_segment`` times per spline segment (helix, line: exact)."""
    if isinstance(path, Spline):
        dp, ddp = _spline_derivatives(path.data, per_segment)
    else:
        _, dp, ddp = path.evaluate(np.array([0.0, 1.0]))
    speed = np.linalg.norm(dp, axis=1)
    kappa = np.linalg.norm(np.cross(dp, ddp), axis=1) / speed**3
    gamma = np.arcsin(np.clip(np.abs(dp[:, 2]) / speed, 0.0, 1.0))
    return float(kappa.max()), float(gamma.max())


def _spline_derivatives(data: np.ndarray, per_segment: int) -> tuple[np.ndarray, np.ndarray]:
    """p' and p'' of a SPLINE kernel vector at ``per_segment`` points in every segment and at
    the end, vectorised (the same cubics `paths.path_eval` evaluates one point at a time)."""
    n_seg = int(data[0])
    knots = data[1 : n_seg + 2]
    coeffs = data[n_seg + 2 :].reshape(n_seg, 3, 4)
    fractions = np.arange(per_segment) / per_segment
    segment = np.r_[np.repeat(np.arange(n_seg), per_segment), n_seg - 1]
    ds = np.r_[
        np.tile(fractions, n_seg) * np.repeat(np.diff(knots), per_segment), knots[-1] - knots[-2]
    ]
    a = coeffs[segment]  # (points, 3 axes, 4)
    d = ds[:, None]
    dp = a[..., 1] + d * (2.0 * a[..., 2] + 3.0 * d * a[..., 3])
    ddp = 2.0 * a[..., 2] + 6.0 * d * a[..., 3]
    return dp, ddp


def overlaps(a: PathDistribution, b: PathDistribution) -> list[str]:
    """The families ``a`` draws that ``b`` could draw too: drawn by both, and every range the
    family uses (`FAMILY_RANGES`) overlapping; [] means no path of ``a`` lies in ``b``'s support."""
    common = []
    for family in a.families:
        if family in b.families and all(
            getattr(a, r)[0] <= getattr(b, r)[1] and getattr(b, r)[0] <= getattr(a, r)[1]
            for r in FAMILY_RANGES[family]
        ):
            common.append(family)
    return common
