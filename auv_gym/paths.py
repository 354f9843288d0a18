"""Parametric 3D paths p(s) with analytic p'(s) and p''(s) (docs/model.md §3.1, §3.5).

Every path is described to the numba kernels by an integer ``kind`` and a float64 ``data``
vector, and evaluated by the single function `path_eval`; the Python classes only build those
vectors and offer numpy conveniences. Positions are NED [m]; s is the path parameter (for the
helix it is not arc length: |p'(s)| = sqrt(R²ω² + c²)).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from auv_gym.guidance import path_angles
from auv_gym.path_bounds import Bound, min_tangent_squared, spline_turn_rates
from auv_gym.path_kernels import (
    HELIX,
    LINE,
    SPLINE,
    clamped_cubic_coefficients,
    natural_cubic_coefficients,
    path_eval,
    path_third_derivative,
    spline_data,
)
from auv_gym.validation import ArgumentTypeError, choice, integer, is_real, real, vector

__all__ = [
    "PATHS",
    "FittedCurve",
    "Helix",
    "Path",
    "Spline",
    "StraightLine",
    "fit_curve",
    "make_path",
    "path_eval",
    "path_third_derivative",
    "path_turn_rates",
]

# Documented ranges of the path arguments: they keep every evaluation of p, p', p'' finite.
POSITION_BOUND = 1e6  # [m] |coordinate| of centres, starts and waypoints (1000 km)
SCALE_BOUND = 1e5  # [m] helix radius, |climb| per unit s
MAX_OMEGA = 1e3  # [rad per unit s] helix ω
MIN_TANGENT = 1e-6  # [m per unit s] smallest |p'(s)|: ṡ = u_p/|p'| stays finite
MAX_WAYPOINTS = 1000  # the natural spline solves a dense (n × n) system
MIN_CHORD = 1e-9  # [m] distance between consecutive waypoints


def _s_end(owner: str, value: float) -> float:
    """A path's end parameter: a positive real or math.inf (endless)."""
    if not is_real(value):
        raise ArgumentTypeError(f"{owner} must be a positive real number or inf, got {value!r}")
    if not float(value) > 0:
        raise ValueError(f"{owner} must be a positive real number or inf, got {value!r}")
    return float(value)


class Path:
    """Base class: a path is a (kind, data) pair for the kernels plus a parameter range."""

    kind: int
    data: np.ndarray
    s_end: float = math.inf  # end of the path parameter; the episode ends there

    def evaluate(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """p(s), p'(s), p''(s) as arrays of shape (..., 3)."""
        s_arr = np.asarray(s, dtype=np.float64)
        flat = np.array([path_eval(self.kind, self.data, float(x)) for x in s_arr.ravel()])
        flat = flat.reshape(*s_arr.shape, 9)
        return flat[..., 0:3], flat[..., 3:6], flat[..., 6:9]

    def default_start(self) -> tuple[np.ndarray, float]:
        """Initial position [m] and heading ψ [rad]: ε(0) = (−15, 5, 8) m as in the paper."""
        p, dp, _ = self.evaluate(0.0)
        psi = math.atan2(dp[1], dp[0])
        c, s = math.cos(psi), math.sin(psi)
        return p + np.array([-15.0 * c - 5.0 * s, -15.0 * s + 5.0 * c, 8.0]), psi

    def sample(self, n: int = 400, s_max: float | None = None) -> np.ndarray:
        """n points along the path for plotting, shape (n, 3) [m]."""
        end = self.s_end if math.isfinite(self.s_end) else (s_max if s_max is not None else 100.0)
        return self.evaluate(np.linspace(0.0, end, n))[0]

    def check_kernel_data(self) -> None:
        """The kernel description is complete and finite (the kernels do not bounds-check)."""
        data = getattr(self, "data", None)
        ok = (
            isinstance(data, np.ndarray) and data.dtype == np.float64 and data.ndim == 1
            and self.kind in KERNEL_KINDS and data.size >= 6 and np.all(np.isfinite(data))
        )  # fmt: skip
        if not (ok and KERNEL_KINDS[self.kind].fits(data)):
            raise ValueError(
                f"path {type(self).__name__} has no valid kernel data (kind, data); "
                "build paths with Helix, StraightLine, Spline or make_path"
            )

    def turn_rate_bounds(self, accept_below: float = -math.inf) -> tuple[Bound, Bound]:
        """`path_turn_rates` with where each maximum lies (`path_bounds.Bound`)."""
        return KERNEL_KINDS[self.kind].turn_rate_bounds(self, accept_below)

    def turn_location(self, bound: Bound) -> str:
        """Where a turn-rate maximum lies, for an error message: "" or " (near s = …)"."""
        return KERNEL_KINDS[self.kind].location(self, bound)


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
            raise ValueError("Helix omega must be non-zero (> 0: starboard turn, < 0: port turn), "
                             f"in [-{MAX_OMEGA:g}, {MAX_OMEGA:g}] rad per unit s, got {omega!r}"
                             )  # fmt: skip
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
        if (self.radius, self.omega, self.climb, self.center) == (20.0, math.pi / 20, 1.0,
                                                                  (10.0, 0.0, -8.0)):  # fmt: skip
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
            raise ValueError(f"StraightLine: direction must be non-zero (norm >= {MIN_TANGENT}), "
                             f"got {tuple(d)}")  # fmt: skip
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
                raise ArgumentTypeError(f"Spline end_tangents must be two (x, y, z) vectors, "
                                        f"got {end_tangents!r:.80}")  # fmt: skip
            slopes = [np.array(vector(f"Spline end_tangents[{k}]", v, 3, -SCALE_BOUND,
                                      SCALE_BOUND, "m per unit s"))
                      for k, v in enumerate(end_tangents)]  # fmt: skip
            coeffs = clamped_cubic_coefficients(knots, pts, *slopes)
        if not np.all(np.isfinite(coeffs)):
            raise ValueError("Spline: the waypoints give a spline with non-finite coefficients")
        self.waypoints = pts
        self.s_end = float(knots[-1])
        self.data = spline_data(knots, coeffs)
        check_tangent("Spline", self.data, knots)


def check_tangent(owner: str, data: np.ndarray, knots: np.ndarray | None = None) -> None:
    """Raise ValueError if |p′(s)| of a SPLINE kernel vector falls below `MIN_TANGENT`
    anywhere (a proven lower bound, not samples), naming the waypoint nearest to where it does
    (``knots``: the waypoints' s) or its s."""
    low = min_tangent_squared(data, accept_above=MIN_TANGENT * MIN_TANGENT)
    if -low.upper >= MIN_TANGENT * MIN_TANGENT:
        return
    speed = math.sqrt(max(-low.reached, 0.0))
    where = f"s = {low.s:.6g}"
    if knots is not None:
        k = low.segment + int(low.s - knots[low.segment] > knots[low.segment + 1] - low.s)
        raise ValueError(
            f"{owner}: the path doubles back at waypoint {k} ({where} m: |p'(s)| = {speed:.3g} < "
            f"{MIN_TANGENT:g}); add a turn waypoint beside waypoint {k} (or split the path there)"
        )
    raise ValueError(
        f"{owner}: |p'(s)| must be >= {MIN_TANGENT:g} m per unit s everywhere, got {speed:.3g} "
        f"at {where}; the curve must not stop or double back"
    )


def _waypoint_array(waypoints: object) -> np.ndarray:
    """Waypoints as a float64 (n, 3) array [m], or a named error."""
    shape = f"(n, 3) with 2 <= n <= {MAX_WAYPOINTS}, coordinates in [-{POSITION_BOUND:g}, " \
        f"{POSITION_BOUND:g}] m"  # fmt: skip
    try:
        pts = np.asarray(waypoints)
    except (TypeError, ValueError):  # ragged nesting
        pts = np.asarray(None)
    if pts.dtype.kind not in "iuf":
        raise ArgumentTypeError(f"Spline waypoints must be real numbers of shape {shape}, "
                                f"got {waypoints!r:.80}")  # fmt: skip
    pts = pts.astype(np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or not 2 <= pts.shape[0] <= MAX_WAYPOINTS:
        raise ValueError(f"Spline: waypoints must have shape {shape}, got {pts.shape}")
    if not np.all(np.isfinite(pts)) or np.abs(pts).max() > POSITION_BOUND:
        raise ValueError(f"Spline: waypoints must be finite, in [-{POSITION_BOUND:g}, "
                         f"{POSITION_BOUND:g}] m")  # fmt: skip
    return pts


class KernelKind:
    """The Python side of a kernel path kind whose p' and p'' have constant norms and turn
    rates (helix, line): a data vector of 6 floats, turn rates from samples (exact), and the
    point a translation moves at ``data[origin : origin + 3]`` (helix centre, line start)."""

    def __init__(self, origin: int) -> None:
        self.origin = origin

    def fits(self, data: np.ndarray) -> bool:
        return data.size == 6

    def shifted(self, data: np.ndarray, offset: np.ndarray) -> np.ndarray:
        """The data vector of p(s) + offset [m]."""
        out = data.copy()
        out[self.origin : self.origin + 3] += offset
        return out

    def turn_rate_bounds(self, path: Path, accept_below: float) -> tuple[Bound, Bound]:
        samples = np.linspace(0.0, 100.0, 9)
        rates = np.empty((len(samples), 2))
        for k, s in enumerate(samples):
            _, _, _, dx, dy, dz, ddx, ddy, ddz = path_eval(path.kind, path.data, float(s))
            _, _, dpsi_ds, dtheta_ds, speed = path_angles(dx, dy, dz, ddx, ddy, ddz)
            rates[k] = abs(dpsi_ds) / speed, abs(dtheta_ds) / speed
        if not np.all(np.isfinite(rates)):
            raise ValueError(f"path {type(path).__name__}: p'(s) or p''(s) is not finite or zero")
        psi_rate, theta_rate = rates.max(axis=0)
        return Bound(float(psi_rate), float(psi_rate), 0, 0.0), Bound(
            float(theta_rate), float(theta_rate), 0, 0.0
        )

    def location(self, path: Path, bound: Bound) -> str:
        return ""


class SplineKind(KernelKind):
    """The cubic-spline kind: [n_seg, knots (n_seg + 1), 12 coefficients per segment]; proven
    turn-rate bounds per segment (`path_bounds.spline_turn_rates`); no single origin (a
    translation moves every segment's a0)."""

    def fits(self, data: np.ndarray) -> bool:
        n_seg = data[0]
        return bool(n_seg >= 1 and n_seg == int(n_seg) and data.size == 2 + 13 * int(n_seg))

    def shifted(self, data: np.ndarray, offset: np.ndarray) -> np.ndarray:
        """The constant coefficient a0 of every segment's x, y, z cubic moves (`path_eval`)."""
        out = data.copy()
        n_seg = int(data[0])
        base = 1 + (n_seg + 1) + 12 * np.arange(n_seg)
        for axis in range(3):
            out[base + 4 * axis] += offset[axis]
        return out

    def turn_rate_bounds(self, path: Path, accept_below: float) -> tuple[Bound, Bound]:
        bounds = spline_turn_rates(path.data, accept_below)
        if not all(math.isfinite(b.upper) for b in bounds):
            raise ValueError(f"path {type(path).__name__}: p'(s) is zero at s = "
                             f"{bounds[0].s:.6g}, where its heading is undefined")  # fmt: skip
        return bounds

    def location(self, path: Path, bound: Bound) -> str:
        knots = path.data[1 : int(path.data[0]) + 2]
        k = bound.segment + int(bound.s - knots[bound.segment]
                                > knots[bound.segment + 1] - bound.s)  # fmt: skip
        if isinstance(path, Spline):
            return f" (near s = {bound.s:.6g}, waypoint {k})"
        return f" (near s = {bound.s:.6g})"


# One entry per kernel path kind (`path_eval`): what the checks know of its data vector.
KERNEL_KINDS: dict[int, KernelKind] = {
    HELIX: KernelKind(origin=3),
    LINE: KernelKind(origin=0),
    SPLINE: SplineKind(origin=0),
}


def path_turn_rates(path: Path, accept_below: float = -math.inf) -> tuple[float, float]:
    """Largest |dψ_F/ds|/|p'(s)| and |dθ_F/ds|/|p'(s)| along the path [rad/m].

    ψ̇_F = dψ_F/ds · ṡ with ṡ = u_p/|p'| (docs/model.md §3.1, §3.3), so ψ̇_F = this rate × u_p.
    Exact for the helix (constant in s) and the line (0); for a spline a proven upper bound at
    most 0.1 % above the maximum (`path_bounds.spline_turn_rates`), or, with ``accept_below``,
    a bound at most that limit whenever the maximum is. A path whose p'(s) vanishes raises.
    """
    return tuple(b.upper for b in path.turn_rate_bounds(accept_below))  # type: ignore[return-value]


# fit_curve: the check points inside each segment and the finite-difference steps.
_CHECK_FRACTIONS = (0.25, 0.5, 0.75)
FIT_TOLERANCE = 1e-3  # [m] default largest position error of a fitted curve
MIN_FIT_SEGMENTS = 8


class FittedCurve(Path):
    """A user's parametric curve p(s), s in [0, s_end], as a clamped cubic spline in the SAME
    parameter s (kernel kind SPLINE); build it with `fit_curve`.

    ``position_error`` [m] is the largest |spline(s) − p(s)| and ``tangent_error`` [rad] the
    largest angle between the spline's tangent and p'(s) (central differences of the callable),
    both over three check points inside every segment (¼, ½, ¾ of it).
    """

    kind = SPLINE

    def __init__(self, knots: np.ndarray, coeffs: np.ndarray, position_error: float,
                 tangent_error: float) -> None:  # fmt: skip
        self.s_end = float(knots[-1])
        self.data = spline_data(knots, coeffs)
        self.position_error = position_error
        self.tangent_error = tangent_error
        self.segments = len(knots) - 1


def _curve_points(curve: Callable[[float], Sequence[float]], s: np.ndarray) -> np.ndarray:
    out = np.empty((len(s), 3))
    for k, x in enumerate(s):
        out[k] = vector(f"curve(s) at s = {x:.6g}", curve(float(x)), 3, -POSITION_BOUND,
                        POSITION_BOUND, "m")  # fmt: skip
    return out


def fit_curve(
    curve: Callable[[float], Sequence[float]],
    s_end: float,
    *,
    tolerance: float = FIT_TOLERANCE,
    max_segments: int = MAX_WAYPOINTS - 1,
) -> FittedCurve:
    """A kernel path of the user's curve ``curve(s) -> (x, y, z)`` [m], s in [0, s_end].

    The curve is sampled at uniform knots and interpolated by a C² cubic spline whose end slopes
    are the curve's (fourth-order one-sided differences), so the path parameter is the user's s
    and ṡ = u_p/|p'(s)| holds as for the built-in paths. The number of segments doubles from 8
    until the largest position error at the check points is at most ``tolerance`` [m]; a curve
    that needs more than ``max_segments`` raises ValueError with the error reached. Cubic
    interpolation errors fall as h⁴ (position) and h³ (tangent) with the knot spacing h: the
    default helix sampled over 200 units of s fits to 1 mm with 64 segments (docs/model.md §3.8).
    The fitted path's |p'(s)| >= `MIN_TANGENT` is checked everywhere (a proven bound,
    `check_tangent`), not only at the check points.
    """
    if not callable(curve):
        raise ArgumentTypeError(f"curve must be a callable s -> (x, y, z), got {curve!r:.80}")
    s_end = real("fit_curve s_end", s_end, 0.0, POSITION_BOUND, low_open=True, unit="unit s")
    tolerance = real("fit_curve tolerance", tolerance, 0.0, math.inf, low_open=True, unit="m")
    max_segments = integer("fit_curve max_segments", max_segments, MIN_FIT_SEGMENTS,
                           MAX_WAYPOINTS - 1)  # fmt: skip
    n = MIN_FIT_SEGMENTS
    while True:
        knots = np.linspace(0.0, s_end, n + 1)
        h = s_end / n
        pts = _curve_points(curve, knots)
        # Fourth-order one-sided differences for the end slopes, step h/4.
        d = h / 4.0
        ahead = _curve_points(curve, np.array([d, 2 * d, 3 * d, 4 * d]))
        behind = _curve_points(curve, s_end - np.array([d, 2 * d, 3 * d, 4 * d]))
        w = np.array([-25.0, 48.0, -36.0, 16.0, -3.0]) / (12.0 * d)
        slope0 = w[0] * pts[0] + w[1:] @ ahead
        slope1 = -(w[0] * pts[-1] + w[1:] @ behind)
        coeffs = clamped_cubic_coefficients(knots, pts, slope0, slope1)
        if not np.all(np.isfinite(coeffs)):
            raise ValueError("fit_curve: the curve's samples give non-finite coefficients")
        fitted = FittedCurve(knots, coeffs, math.nan, math.nan)
        check = (knots[:-1, None] + h * np.array(_CHECK_FRACTIONS)).ravel()
        p_fit, dp_fit, _ = fitted.evaluate(check)
        position_error = float(np.linalg.norm(p_fit - _curve_points(curve, check), axis=1).max())
        if position_error <= tolerance or 2 * n > max_segments:
            break
        n *= 2
    if position_error > tolerance:
        raise ValueError(
            f"fit_curve: {n} segments fit the curve to {position_error:.3g} m, above tolerance = "
            f"{tolerance:g} m; raise max_segments (<= {MAX_WAYPOINTS - 1}) or the tolerance"
        )
    check_tangent("fit_curve", fitted.data)  # the path the kernels follow, everywhere
    step = 1e-4 * h
    dp_true = (_curve_points(curve, np.minimum(check + step, s_end))
               - _curve_points(curve, np.maximum(check - step, 0.0))) / (2 * step)  # fmt: skip
    norms = np.linalg.norm(dp_true, axis=1) * np.linalg.norm(dp_fit, axis=1)
    if not np.all(norms >= MIN_TANGENT * MIN_TANGENT):
        raise ValueError(f"fit_curve: |p'(s)| must be >= {MIN_TANGENT} m per unit s everywhere")
    cosine = np.clip(np.einsum("ij,ij->i", dp_true, dp_fit) / norms, -1.0, 1.0)
    fitted.position_error = position_error
    fitted.tangent_error = float(np.arccos(cosine).max())
    return fitted


DEFAULT_WAYPOINTS = (
    (30.0, 0.0, -8.0), (60.0, 15.0, -14.0), (90.0, -10.0, -20.0), (120.0, 10.0, -16.0),
    (150.0, 0.0, -24.0), (180.0, 25.0, -30.0), (210.0, 5.0, -26.0), (240.0, -15.0, -34.0),
    (270.0, 5.0, -40.0), (300.0, 10.0, -36.0),
)  # fmt: skip

PATHS = {
    "helix": Helix,
    "line": StraightLine,
    "waypoints": lambda: Spline(DEFAULT_WAYPOINTS),
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
        try:
            return PATHS[kind](**arguments)
        except ArgumentTypeError:
            raise
        except TypeError as exc:  # an argument the path does not take
            raise ValueError(f"path {path!r:.80}: {exc}") from exc
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
