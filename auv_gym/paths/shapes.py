"""Parametric 3D paths p(s) with analytic p'(s) and p''(s) (docs/model.md §3.1, §3.5).

Every path is described to the numba kernels by an integer ``kind`` and a float64 ``data``
vector, and evaluated by the single function `path_eval`; the Python classes only build those
vectors and offer numpy conveniences. Positions are NED [m]; s is the path parameter (for the
helix it is not arc length: |p'(s)| = sqrt(R²ω² + c²)).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from auv_gym.paths.base import (
    KERNEL_KINDS,
    MAX_OMEGA,
    MAX_WAYPOINTS,
    MIN_CHORD,
    MIN_TANGENT,
    POSITION_BOUND,
    SCALE_BOUND,
    KernelKind,
    Path,
    SplineKind,
    check_tangent,
    path_turn_rates,
)
from auv_gym.paths.fit import FIT_TOLERANCE, MIN_FIT_SEGMENTS, FittedCurve, fit_curve
from auv_gym.paths.kernels import (
    HELIX,
    LINE,
    SPLINE,
    clamped_cubic_coefficients,
    natural_cubic_coefficients,
    path_eval,
    path_third_derivative,
    spline_data,
)
from auv_gym.support.validation import ArgumentTypeError, choice, is_real, real, vector

# Public names; those defined in `path_base` and `path_fit` are re-exported from here.
__all__ = [
    "FIT_TOLERANCE",
    "KERNEL_KINDS",
    "MIN_FIT_SEGMENTS",
    "PATHS",
    "FittedCurve",
    "Helix",
    "KernelKind",
    "Path",
    "Spline",
    "SplineKind",
    "StraightLine",
    "fit_curve",
    "make_path",
    "path_eval",
    "path_third_derivative",
    "path_turn_rates",
]


def _s_end(owner: str, value: float) -> float:
    """A path's end parameter: a positive real or math.inf (endless)."""
    if not is_real(value):
        raise ArgumentTypeError(f"{owner} must be a positive real number or inf, got {value!r}")
    if not float(value) > 0:
        raise ValueError(f"{owner} must be a positive real number or inf, got {value!r}")
    return float(value)


class Helix(Path):
    """The paper's helix (45): x = R cos(ωs) + x0, y = R sin(ωs) + y0, z = z0 − c s.

    Defaults R = 20 m, ω = π/20 rad per unit s, c = 1 m per unit s, (x0, y0, z0) = (10, 0, −8) m
    (docs/model.md §3.5: a 17.7° climb, one turn per Δs = 40). Both turning directions: ω > 0
    makes ψ_F grow, a starboard turn (clockwise seen from above: NED, z down), ω < 0 a port turn;
    c > 0 climbs (z decreases), c < 0 descends.
    """

    kind = HELIX

    def __init__(
        self,
        radius: float = 20.0,
        omega: float = math.pi / 20.0,
        climb: float = 1.0,
        center: Sequence[float] = (10.0, 0.0, -8.0),
        s_end: float = math.inf,
    ) -> None:
        radius = real("Helix radius", radius, 0.0, SCALE_BOUND, low_open=True, unit="m")
        omega = real("Helix omega", omega, -MAX_OMEGA, MAX_OMEGA, unit="rad per unit s")
        if omega == 0.0:
            raise ValueError(
                "Helix omega must be non-zero (> 0: starboard turn, < 0: port turn), "
                f"in [-{MAX_OMEGA:g}, {MAX_OMEGA:g}] rad per unit s, got {omega!r}"
            )
        climb = real("Helix climb", climb, -SCALE_BOUND, SCALE_BOUND, unit="m per unit s")
        center = vector("Helix center", center, 3, -POSITION_BOUND, POSITION_BOUND, "m")
        if math.hypot(radius * omega, climb) < MIN_TANGENT:
            raise ValueError(
                f"Helix: |p'(s)| = sqrt((radius·omega)² + climb²) must be >= {MIN_TANGENT} m per "
                f"unit s, got radius = {radius}, omega = {omega}, climb = {climb}"
            )
        self.radius, self.omega, self.climb = radius, omega, climb
        self.center = center
        self.s_end = _s_end("Helix s_end", s_end)
        self.data = np.array([radius, omega, climb, *center], dtype=np.float64)

    def default_start(self) -> tuple[np.ndarray, float]:
        """The paper's initial condition: (15, 5, 0) m, ψ = 0 (Section 6)."""
        if (self.radius, self.omega, self.climb, self.center) == (
            20.0,
            math.pi / 20,
            1.0,
            (10.0, 0.0, -8.0),
        ):
            return np.array([15.0, 5.0, 0.0]), 0.0
        return super().default_start()


class StraightLine(Path):
    """p(s) = p0 + s·d with d a unit direction, so s is arc length [m]."""

    kind = LINE

    def __init__(
        self,
        start: Sequence[float] = (0.0, 0.0, 0.0),
        direction: Sequence[float] = (1.0, 0.5, -0.2),
        length: float = math.inf,
    ) -> None:
        p0 = np.array(vector("StraightLine start", start, 3, -POSITION_BOUND, POSITION_BOUND, "m"))
        d = np.array(vector("StraightLine direction", direction, 3, -SCALE_BOUND, SCALE_BOUND))
        norm = float(np.linalg.norm(d))
        if norm < MIN_TANGENT:
            raise ValueError(
                f"StraightLine: direction must be non-zero (norm >= {MIN_TANGENT}), got {tuple(d)}"
            )
        self.s_end = _s_end("StraightLine length", length)
        self.data = np.r_[p0, d / norm]


class Spline(Path):
    """A C²-smooth cubic spline through 3D waypoints, parameterised by chord length [m].

    Natural (p″ = 0 at both ends) by default; ``end_tangents`` = (p′(0), p′(s_end)) clamps the
    end slopes instead (unit vectors for an arc-length-like parameter), which follows a track
    that ends inside a turn without the natural spline's straightening.

    A path that doubles back — a waypoint after which the next one lies straight behind, such
    as the survey line (0, 0, 0) → (100, 0, 0) → (0, 0, 0) — has p′(s) = 0 at the reversal,
    where neither its heading nor ṡ = u_p/|p′| is defined: the constructor refuses any spline
    whose |p′(s)| falls below `MIN_TANGENT` anywhere (a proven bound, `path_bounds`), naming
    the waypoint. Give such a path a turn instead: a waypoint beside the reversal, e.g.
    (0, 0, 0) → (100, 0, 0) → (110, 10, 0) → (100, 20, 0) → (0, 20, 0). Near-reversals whose
    turn is too tight for the virtual point are refused by the environment's turn-rate check.
    """

    kind = SPLINE
    knots_are_waypoints = True

    def __init__(
        self,
        waypoints: Sequence[Sequence[float]],
        end_tangents: Sequence[Sequence[float]] | None = None,
    ) -> None:
        pts = _waypoint_array(waypoints)
        chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(chords <= MIN_CHORD):
            raise ValueError("Spline: consecutive waypoints must be distinct")
        knots = np.r_[0.0, np.cumsum(chords)]
        if end_tangents is None:
            coeffs = natural_cubic_coefficients(knots, pts)  # (n_seg, 3, 4)
        else:
            if isinstance(end_tangents, (str, bytes)) or len(end_tangents) != 2:
                raise ArgumentTypeError(
                    f"Spline end_tangents must be two (x, y, z) vectors, got {end_tangents!r:.80}"
                )
            slopes = [
                np.array(
                    vector(
                        f"Spline end_tangents[{k}]", v, 3, -SCALE_BOUND, SCALE_BOUND, "m per unit s"
                    )
                )
                for k, v in enumerate(end_tangents)
            ]
            coeffs = clamped_cubic_coefficients(knots, pts, *slopes)
        if not np.all(np.isfinite(coeffs)):
            raise ValueError("Spline: the waypoints give a spline with non-finite coefficients")
        self.waypoints = pts
        self.s_end = float(knots[-1])
        self.data = spline_data(knots, coeffs)
        check_tangent("Spline", self.data, knots)


def _waypoint_array(waypoints: object) -> np.ndarray:
    """Waypoints as a float64 (n, 3) array [m], or a named error."""
    shape = (
        f"(n, 3) with 2 <= n <= {MAX_WAYPOINTS}, coordinates in [-{POSITION_BOUND:g}, "
        f"{POSITION_BOUND:g}] m"
    )
    try:
        pts = np.asarray(waypoints)
    except (TypeError, ValueError):  # ragged nesting
        pts = np.asarray(None)
    if pts.dtype.kind not in "iuf" or _holds_bool(waypoints):  # True would pass as 1
        if isinstance(waypoints, np.ndarray):
            got = f"an array of dtype {waypoints.dtype} and shape {waypoints.shape}"
        else:
            got = _one_line(waypoints) + (" (a bool)" if _holds_bool(waypoints) else "")
        raise ArgumentTypeError(
            f"Spline waypoints must be real numbers of shape {shape}, got {got}"
        )
    pts = pts.astype(np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or not 2 <= pts.shape[0] <= MAX_WAYPOINTS:
        raise ValueError(f"Spline: waypoints must have shape {shape}, got {pts.shape}")
    if not np.all(np.isfinite(pts)) or np.abs(pts).max() > POSITION_BOUND:
        raise ValueError(
            f"Spline: waypoints must be finite, in [-{POSITION_BOUND:g}, {POSITION_BOUND:g}] m"
        )
    return pts


def _holds_bool(value: object) -> bool:
    """True if a (nested) list or tuple holds a bool, which numpy would turn into 0 or 1."""
    if isinstance(value, (bool, np.bool_)):
        return True
    return isinstance(value, (list, tuple)) and any(map(_holds_bool, value))


def _one_line(value: object, width: int = 80) -> str:
    """repr(value) on one line (an array's repr spans several), cut to ``width`` characters."""
    text = " ".join(repr(value).split())
    return text if len(text) <= width else text[: width - 3] + "..."


DEFAULT_WAYPOINTS = (
    (30.0, 0.0, -8.0),
    (60.0, 15.0, -14.0),
    (90.0, -10.0, -20.0),
    (120.0, 10.0, -16.0),
    (150.0, 0.0, -24.0),
    (180.0, 25.0, -30.0),
    (210.0, 5.0, -26.0),
    (240.0, -15.0, -34.0),
    (270.0, 5.0, -40.0),
    (300.0, 10.0, -36.0),
)

PATHS = {
    "helix": Helix,
    "line": StraightLine,
    "waypoints": lambda: Spline(DEFAULT_WAYPOINTS),
}
# The keys a mapping {"kind": name, **arguments} may give each kind (`make_path`): its
# constructor's arguments; none for "waypoints", the default spline.
PATH_ARGUMENTS = {
    name: tuple(inspect.signature(factory).parameters) for name, factory in PATHS.items()
}


def make_path(path: str | Path | Mapping[str, Any] | Sequence[Sequence[float]]) -> Path:
    """A path from its registry name, a `Path` instance, a mapping {"kind": name, **arguments}
    (e.g. ``{"kind": "line", "direction": [1, 0, 0.25]}``, as a TOML scenario writes it) or a
    list of (x, y, z) waypoints [m] (a `Spline` through them); anything else raises a named
    error."""
    if isinstance(path, Path):
        return path
    if isinstance(path, str):
        if path in PATHS:
            return PATHS[path]()
        raise ValueError(
            f"unknown path {path!r}; valid names are {sorted(PATHS)}, a Path instance, "
            "a mapping with 'kind' or a list of (x, y, z) waypoints"
        )
    if isinstance(path, Mapping):
        arguments = dict(path)
        kind = choice("path kind", arguments.pop("kind", None), PATHS)
        valid = PATH_ARGUMENTS[kind]
        unknown = [key for key in arguments if key not in valid]
        if unknown:
            takes = f"valid keys: {sorted(valid)}" if valid else "it takes no other key"
            hint = (
                " (a spline through other waypoints is the list of them, path=[(x, y, z), ...])"
                if kind == "waypoints"
                else ""
            )
            raise ValueError(
                f"path kind {kind!r} got an unexpected keyword argument {unknown[0]!r}; "
                f"{takes}{hint}"
            )
        return PATHS[kind](**arguments)
    if isinstance(path, (Sequence, np.ndarray)) and not isinstance(path, bytes):
        try:
            return Spline(path)
        except ValueError as exc:  # ArgumentTypeError too: the same type, the argument named
            raise type(exc)(f"path as a list of (x, y, z) waypoints: {exc}") from None
    if callable(path):
        raise ArgumentTypeError(
            f"path {path!r:.60} is a callable: turn a curve p(s) into a path with "
            "auv_gym.paths.fit_curve(p, s_end) and pass that"
        )
    raise ArgumentTypeError(
        f"path must be one of {sorted(PATHS)}, a Path instance, a mapping with 'kind' or a list "
        f"of (x, y, z) waypoints, got {path!r:.80}"
    )
